"""The compiled direct model of full-pose machines (issue 22 §1–2) against the batched NumPy
engine it replaces (the independent oracle: the same Levenberg–Marquardt rules written as
vectorised NumPy over the batch), on random configurations, near-singular ones and
configurations without an assembly; one configuration per call against the batch row; the
same refusals."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, NoAssemblyError, OutOfStrokeError, StrokeWarning
from pkmkit.machines.full_pose_direct import DirectKernel
from pkmkit.status import Status
from tests.conftest import near_parallel_singular_poses

pytest.importorskip("numba")

NAMES = ["gough-stewart", "verne", "dietmaier-hexapod"]


def _configurations(m, n, seed, spread=0.02):
    """Random actuator values around home, two invalid rows, some far beyond any assembly."""
    rng = np.random.default_rng(seed)
    q = m.home_q + rng.normal(scale=spread, size=(n, m.n_actuators))
    q[0] = np.nan
    q[1, 0] = 2e9
    q[2:12] *= 3.0  # struts three times longer: no assembly (or another one) for many
    return q


def _both(m, q, monkeypatch, **options):
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    engine = m.fk(q, full_output=True, strokes="ignore", **options)
    monkeypatch.setenv("PKMKIT_COMPILED", "auto")
    kernel = m.fk(q, full_output=True, strokes="ignore", **options)
    return engine, kernel


@pytest.mark.parametrize("name", NAMES)
def test_compiled_direct_model_is_the_engine_on_random_configurations(name, monkeypatch):
    m = pkmkit.machine(name)
    q = _configurations(m, 400, seed=1)
    engine, kernel = _both(m, q, monkeypatch)
    np.testing.assert_array_equal(kernel.status, engine.status)
    assert kernel.status[0] == kernel.status[1] == Status.INVALID_INPUT
    ok = engine.status == Status.OK
    assert ok.sum() > 350 and (~ok).sum() >= 2
    np.testing.assert_allclose(kernel.pose[ok], engine.pose[ok], rtol=0, atol=1e-12)
    assert np.isnan(kernel.pose[~ok]).all()
    np.testing.assert_array_equal(kernel.iterations[ok], engine.iterations[ok])
    np.testing.assert_allclose(kernel.residual[ok], engine.residual[ok], rtol=0, atol=1e-14)


def test_compiled_direct_model_near_parallel_singularities(monkeypatch):
    """Hexapod poses whose parallel measure μ (σ_min/σ_max of the unit-row A) is below 1e-2
    (down to ~1e-5): a rounding-level residual moves the solution by ~1/μ times as much, so
    kernel and engine agree row by row to 1e-12/μ (m, rad), both close every rod to 1e-12 m,
    and the statuses agree exactly — from the first-order guess and from a warm start."""
    rng = np.random.default_rng(1)
    m, x, measure = near_parallel_singular_poses(300, rng)
    q = m.ik(x, strokes="ignore")
    warm = x + rng.normal(scale=1e-4, size=x.shape)
    for options in ({}, {"x0": warm}):
        engine, kernel = _both(m, q, monkeypatch, **options)
        np.testing.assert_array_equal(kernel.status, engine.status)
        ok = engine.status == Status.OK
        assert ok.sum() > 200
        gap = np.abs(kernel.pose[ok] - engine.pose[ok]).max(axis=1)
        assert (gap <= 1e-12 / measure[ok]).all()
        assert (kernel.residual[ok] <= 1e-12).all() and (engine.residual[ok] <= 1e-12).all()


@pytest.mark.parametrize("name", NAMES)
def test_one_configuration_is_the_batch_row(name):
    m = pkmkit.machine(name)
    q = _configurations(m, 60, seed=2, spread=0.01)[12:]
    batch = m.fk(q, strokes="ignore")
    rows = np.flatnonzero(np.isfinite(batch).all(axis=1))
    assert len(rows) > 40
    for k in rows:
        for given in (q[k], q[k].tolist(), tuple(q[k].tolist())):
            one = m.fk(given, strokes="ignore")
            assert one.shape == (6,)
            np.testing.assert_array_equal(one, batch[k])


def test_one_configuration_refusals_are_those_of_the_batch_path():
    m = pkmkit.machine("gough-stewart")
    apart = m.home_q.copy()
    apart[0] += 1.0  # one strut a metre longer than the others: the rods do not meet
    assert m.fk(apart[None], full_output=True, strokes="ignore").status[0] == Status.NO_ASSEMBLY
    with pytest.raises(NoAssemblyError):
        m.fk(apart, strokes="ignore")
    for bad in ([np.nan] * 6, [0.0] * 5, [1e300] * 6, np.full(6, np.inf)):
        with pytest.raises(InputError):
            m.fk(bad)
    beyond = m.home_q + 0.9 * (m.model.q_max - m.home_q) + 0.2  # assembles, past the strokes
    assert np.isfinite(m.fk(beyond, strokes="ignore")).all()
    with pytest.warns(StrokeWarning):
        m.fk(beyond)
    with pytest.raises(OutOfStrokeError):
        m.fk(beyond, strokes="refuse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m.fk(m.home_q)


def test_kernel_start_is_the_first_order_guess():
    """Without x0 the kernel starts from home ⊕ J(home)(q − q_home): with a budget of zero
    iterations it returns that guess, which the machine computes independently with scipy."""
    m = pkmkit.machine("gough-stewart")
    q = _configurations(m, 50, seed=3)[12:]
    kernel = DirectKernel.of(m.model, m.home_pose, m.home_q, m._home_jacobian)
    pose, status, iterations, _ = kernel.solve(q, None, {"max_iter": 0})
    assert (status == Status.NOT_CONVERGED).all() and (iterations == 0).all()
    np.testing.assert_allclose(pose, m.first_order_pose(q), rtol=0, atol=1e-15)


@pytest.mark.ci
def test_a_one_shot_call_does_not_import_numba():
    """Without the C extension (``PKMKIT_NATIVE=0``), the first single fk of a fresh process
    takes the NumPy engine (no Numba import, which costs ≈ 0.4 s: the command line makes one
    call); the second imports Numba and runs the compiled solve; both give the same pose
    (with the extension neither imports Numba: tests/native)."""
    import subprocess
    import sys
    from pathlib import Path

    code = ("import sys, numpy as np, pkmkit\n"
            "m = pkmkit.machine('gough-stewart')\n"
            "q = m.home_q + 0.01\n"
            "a = m.fk(q)\n"
            "first = 'numba' in sys.modules\n"
            "b = m.fk(q)\n"
            "print(first, 'numba' in sys.modules, float(np.abs(a - b).max()))\n")
    src = str(Path(pkmkit.__file__).resolve().parents[1])
    env = {"PYTHONPATH": src, "PATH": "/usr/bin:/bin", "PKMKIT_NATIVE": "0"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True).stdout.split()
    assert out[:2] == ["False", "True"]
    assert float(out[2]) <= 1e-12


@pytest.mark.parametrize("options", [{"max_iter": 2}, {"atol": 1e-3}, {"gtol": 0.5},
                                     {"xtol": 1e-6, "damping": 1.0}, {"stall": 0.9}])
def test_engine_options_mean_the_same_to_the_kernel(options, monkeypatch):
    """Iteration limit, tolerances, damping and the crawl test change the kernel's answers as
    they change the engine's: the same statuses, iterations and poses."""
    m = pkmkit.machine("verne")
    q = _configurations(m, 200, seed=4)
    engine, kernel = _both(m, q, monkeypatch, **options)
    np.testing.assert_array_equal(kernel.status, engine.status)
    ok = engine.status == Status.OK
    np.testing.assert_array_equal(kernel.iterations[ok], engine.iterations[ok])
    np.testing.assert_allclose(kernel.pose[ok], engine.pose[ok], rtol=0, atol=1e-12)
    assert len(set(kernel.status.tolist())) >= 2
