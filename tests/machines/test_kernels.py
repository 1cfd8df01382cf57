"""Compiled kernels against the NumPy reference paths, on the same inputs.

The NumPy code (``PKMKIT_COMPILED=0``) is the reference; the compiled kernels (forced with
``PKMKIT_COMPILED=1``) must give the same numbers to rounding, the same NaN rows, the same
singularity flags — including the rows the velocity kernel leaves to the reference (near
parallel singularities, coinciding singular values) and hostile rows (NaN, inf, huge values).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit
from tests.conftest import PRESETS, random_poses

pytest.importorskip("numba")

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def machines():
    out = [pkmkit.machine(name) for name in PRESETS]
    out.append(pkmkit.load(EXAMPLES / "strut-tripod.toml"))
    return out


@pytest.fixture(params=range(len(PRESETS) + 1), ids=[*PRESETS, "strut-tripod"])
def machine(request):
    return machines()[request.param]


def hostile_poses(m: pkmkit.Machine, n: int, seed: int) -> np.ndarray:
    """Poses in and far beyond the workspace, with NaN, ±inf and huge rows mixed in."""
    rng = np.random.default_rng(seed)
    x = random_poses(m, n, seed)
    spread = 2.0 * float(m.model.leg_length.max())
    x[: n // 4] = m.home_pose + rng.uniform(-spread, spread, (n // 4, m.dims))
    x[5] = np.nan
    x[6, 0] = np.inf
    x[7, -1] = -np.inf
    x[8] = 1e200
    x[9] = 1e-300
    return x


def with_mode(monkeypatch, value: str, func):
    monkeypatch.setenv("PKMKIT_COMPILED", value)
    return func()


def test_mode_switch(monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert not jit.use_compiled(10**9)
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    assert jit.use_compiled(1)
    monkeypatch.setenv("PKMKIT_COMPILED", "auto")
    assert not jit.use_compiled(jit.MIN_ROWS - 1)
    assert jit.use_compiled(jit.MIN_ROWS) == jit.numba_available()


def test_inverse_kernel_matches_reference(machine, monkeypatch):
    x = hostile_poses(machine, 5000, seed=3)
    branches = machine.model.leg_branch
    ref = machine._closed.inverse_numpy(x, branches)
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    q, bad = machine._closed.inverse_counted(x, branches)
    np.testing.assert_array_equal(np.isnan(q), np.isnan(ref))
    assert bad == np.count_nonzero(~np.isfinite(ref))
    assert 0 < bad < q.size  # both reachable and unreachable rows were exercised
    # the same operations in the same order: the same bits (a strut's length was summed in
    # another order by the kernel, which changed the last bit of some rows)
    np.testing.assert_array_equal(q, ref)


def test_inverse_kernel_other_branches(machine, monkeypatch):
    x = random_poses(machine, 3000, seed=4)
    flipped = -machine.model.leg_branch
    ref = machine._closed.inverse_numpy(x, flipped)
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    q = machine._closed.inverse(x, flipped)
    np.testing.assert_allclose(q, ref, rtol=1e-13, atol=1e-13)


def test_numba_is_imported_for_the_inverse_only_when_it_pays(monkeypatch):
    """The closed-form inverse of rod legs runs on NumPy until Numba is imported (its import
    and first call cost tens of millions of poses of the difference); ``=1`` still forces it."""
    import sys

    monkeypatch.setenv("PKMKIT_COMPILED", "auto")
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    assert not jit.use_compiled(10**8, imports=False)
    assert jit.use_compiled(10**8)
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    assert jit.use_compiled(1, imports=False)


@pytest.mark.parametrize("compiled", ["0", "1"])
def test_inverse_full_is_the_separate_calls_bit_for_bit(machine, monkeypatch, compiled):
    """q, the shortfalls and det A in one pass: the numbers of ``inverse_counted``,
    ``shortfall`` and ``batched_det`` of ``jacobians``' A, on both paths and both branches."""
    from pkmkit.numerics.linalg import batched_det

    closed = machine._closed
    if not closed.fuses:
        assert closed.crank.any()  # the Delta robot's cranks: ik takes the separate calls
        return
    x = hostile_poses(machine, 5000, seed=8)
    monkeypatch.setenv("PKMKIT_COMPILED", compiled)
    for branches in (machine.model.leg_branch, -machine.model.leg_branch):
        q, bad, short, det = closed.inverse_full(x, branches)
        ref_q, ref_bad = closed.inverse_counted(x, branches)
        np.testing.assert_array_equal(q, ref_q)
        assert bad == ref_bad
        np.testing.assert_array_equal(short, closed.shortfall(x))
        ok = np.isfinite(q).all(axis=1)
        np.testing.assert_array_equal(det[ok], batched_det(closed.jacobians(x[ok], q[ok])[0]))


@pytest.mark.parametrize("strokes", ["flag", "refuse", "ignore"])
def test_ik_full_output_modes_and_shortfalls_as_before(machine, monkeypatch, strokes):
    """``ik(full_output=True)`` takes its modes and shortfalls from the inverse's pass: the
    same as the sign of det A at (x, q) and ``shortfall(x)`` computed apart."""
    x = np.concatenate([hostile_poses(machine, 3000, seed=9),
                        near_parallel_poses(machine, 3000, seed=10)])
    for compiled in ("0", "1"):
        res = with_mode(monkeypatch, compiled, lambda: machine.ik(x, full_output=True,
                                                                  strokes=strokes))
        np.testing.assert_array_equal(res.mode, machine._mode_of(x, res.q))
        np.testing.assert_array_equal(res.shortfall, machine._closed.shortfall(x))
        assert (res.mode == 0).any() and (res.mode != 0).any()  # failed and solved rows


def test_ik_status_same_both_ways(machine, monkeypatch):
    x = hostile_poses(machine, 5000, seed=5)
    ref = with_mode(monkeypatch, "0", lambda: machine.ik(x, full_output=True))
    res = with_mode(monkeypatch, "1", lambda: machine.ik(x, full_output=True))
    np.testing.assert_array_equal(res.status, ref.status)
    np.testing.assert_allclose(res.q, ref.q, rtol=1e-13, atol=1e-13)


FIELDS = ("singular_values", "condition", "det_A", "serial_measure", "singularity", "mode",
          "parallel_measure", "J", "A", "B", "J_inv", "det_B", "q")


def near_parallel_poses(m: pkmkit.Machine, n: int, seed: int) -> np.ndarray:
    """Poses on segments from home towards far points, so that some cross det A = 0."""
    rng = np.random.default_rng(seed)
    far = m.home_pose + rng.uniform(-1.5, 1.5, (n, m.dims)) * float(m.model.leg_length.max())
    t = rng.uniform(0, 1, (n, 1))
    return m.home_pose + t * (far - m.home_pose)


@pytest.mark.parametrize("tol", [1e-6, 0.05])
def test_velocity_kernel_matches_reference(machine, monkeypatch, tol):
    x = np.concatenate([hostile_poses(machine, 3000, seed=6),
                        near_parallel_poses(machine, 3000, seed=7)])
    ref = with_mode(monkeypatch, "0", lambda: machine.jacobian(x, tol=tol))
    ref = {f: getattr(ref, f) for f in FIELDS}
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    jac = machine.jacobian(x, tol=tol)
    assert np.isfinite(ref["condition"]).sum() > 1000
    for field in FIELDS:
        got = getattr(jac, field)
        assert got.shape == ref[field].shape, field
        np.testing.assert_array_equal(np.isnan(got), np.isnan(ref[field]), err_msg=field)
        if got.dtype.kind == "f":
            np.testing.assert_allclose(got, ref[field], rtol=1e-11, atol=1e-14, err_msg=field)
        else:
            np.testing.assert_array_equal(got, ref[field], err_msg=field)


def test_velocity_kernel_hands_hard_rows_to_reference(monkeypatch):
    """Near a parallel singularity and where singular values coincide the kernel defers."""
    from pkmkit.machines import kernels

    m = pkmkit.machine("orthoglide")
    # on the diagonal x = y = z two singular values are equal (symmetry); home is isotropic
    x = np.array([[0.03, 0.03, 0.03], m.home_pose, [0.05, -0.02, 0.01]])
    q = m.ik(x)
    closed = m._closed
    out = [np.empty(3), np.empty((3, 3)), np.empty(3), np.empty(3), np.empty(3, dtype=bool)]
    kernels.velocity3(x, np.ascontiguousarray(q.T), closed.centre0, closed.axis,
                      closed.slide > 0, m.model.leg_length, 1e-2, *out)
    np.testing.assert_array_equal(out[-1], [True, False, False])
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    jac = m.jacobian(x)
    for k in range(3):
        np.testing.assert_allclose(jac.singular_values[k], np.linalg.svd(jac.J[k])[1],
                                   rtol=1e-14)
    np.testing.assert_allclose(out[1][:, 1:].T, jac.singular_values[1:], rtol=1e-14)


def test_single_pose_and_replace(monkeypatch):
    """The lazy result behaves like the dataclass: single rows, dataclasses.replace."""
    import dataclasses

    m = pkmkit.machine("linear-delta")
    jac = m.jacobian([0.05, 0.1, 0.2])
    assert jac.J.shape == (3, 3) and jac.condition.shape == () and jac.tolerance == 1e-6
    changed = dataclasses.replace(jac, condition=np.float64(2.0))
    assert changed.condition == 2.0
    np.testing.assert_array_equal(changed.J, jac.J)
    from pkmkit.machines.results import Jacobians

    assert isinstance(jac, Jacobians)
    assert "LazyJacobians" in repr(jac)
