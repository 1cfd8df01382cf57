"""The optional C extension ``pkmkit.native.kernels`` (issue 22 §5) against the Numba kernels
it twins and the NumPy reference paths (the independent oracle: vectorised NumPy over the batch),
three ways on the same rows: the full-pose inverse model (statuses, q) on random poses with
invalid, unreachable, inconsistent and beyond-stroke rows; the one-mode direct model (statuses,
iterations, poses, residuals) on random, unassembled and near-singular configurations, with the
engine's options; the checks of its arguments; the dispatch of :mod:`pkmkit.numerics.jit`."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines.full_pose import FullPoseMachine
from pkmkit.machines.full_pose_direct import DirectKernel
from pkmkit.machines.full_pose_forms import FullPoseForms
from pkmkit.numerics import jit
from pkmkit.status import Status
from tests.conftest import near_parallel_singular_poses

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler: allowed, except in CI (first test)
    _kernels = None

built = pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
NAMES = ["gough-stewart", "verne", "delta6"]
BACKENDS = {"native": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "1"},
            "numba": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "0"},
            "numpy": {"PKMKIT_COMPILED": "0", "PKMKIT_NATIVE": "0"}}


def test_the_extension_is_built_in_ci():
    """A failed build is only a warning at install time (``optional=True``), so in CI (``CI``
    set, as by CI services), where the image has a compiler and the Python headers, the
    extension must be there: otherwise it would vanish silently and every comparison below
    be skipped."""
    if os.environ.get("CI", "").strip().lower() in ("", "0", "false"):  # as tests/conftest.py
        pytest.skip("outside CI an install without a compiler is allowed")
    assert _kernels is not None, "pkmkit.native.kernels was not built: see pip's build log"


def _machine(name):
    if name != "delta6":
        return pkmkit.machine(name)
    from pkmkit.model.rods import build_rod_model, leg_specs

    delta = pkmkit.machine("delta")  # its six forearm rods on a free platform: cranks
    model = build_rod_model(leg_specs(delta.model), dims=6, actuator_names=("q1", "q2", "q3"),
                            home_pose=(*delta.home_pose, 0.0, 0.0, 0.0))
    return FullPoseMachine(id="delta6", name="delta6", kind=None, params={}, model=model)


def _poses(m, n, seed):
    """Poses of every kind: reachable ones (the direct model of random actuator values, so
    that machines with fewer than six actuators reach them), slightly moved ones (the rods of
    one actuator then disagree), far ones (a rod cannot close), invalid rows, and rows beyond
    the strokes."""
    rng = np.random.default_rng(seed)
    q = m.home_q + rng.normal(scale=0.02, size=(n, m.n_actuators))
    with np.errstate(invalid="ignore"):
        x = m.fk(q, strokes="ignore", full_output=True).pose.copy()  # records: read-only
    x[~np.isfinite(x).all(axis=1)] = m.home_pose
    quarter = n // 2 - n // 4  # moved by 1e-13 to 1e-3: the rods' spread straddles the tolerance
    scale = 10.0 ** rng.uniform(-13, -3, (quarter, 1))
    x[n // 4: n // 2] += scale * rng.normal(size=(quarter, 6))
    x[n // 2: n // 2 + 50, :3] += rng.uniform(-2.0, 2.0, (50, 3))
    x[_edge(n)] = _boundary(m, x[-40:], rng)
    x[0] = np.nan
    x[1, 2] = 2e9
    x[2, 4] = np.inf
    beyond = m.home_q + 1.3 * (m.model.q_max - m.home_q)  # past every stroke, may close
    with np.errstate(invalid="ignore"):
        x[3] = m.fk(beyond, strokes="ignore", full_output=True).pose[0]
    return x


def _edge(n):
    """The rows of :func:`_poses` on the edge of reach."""
    mask = np.zeros(n, dtype=bool)
    mask[n // 2 + 50: n // 2 + 90] = True
    return mask


def _boundary(m, inside, rng):
    """Poses on the edge of reach (a rod exactly stretched: where the kernels' boundary
    tolerance decides), by bisection with the NumPy reference between reachable poses and far
    ones: 20 just inside and 20 just outside."""
    forms = FullPoseForms(m.model)
    inside = inside[:20].copy()
    outside = inside.copy()
    outside[:, :3] += rng.normal(scale=2.0, size=(20, 3))
    with np.errstate(invalid="ignore"):
        for _ in range(60):
            mid = 0.5 * (inside + outside)
            ok = np.isfinite(forms.rod_coordinates_numpy(mid, forms.rod_branch)).all(axis=1)
            inside[ok] = mid[ok]
            outside[~ok] = mid[~ok]
    return np.concatenate([inside, outside])


def _env(monkeypatch, backend):
    for key, value in BACKENDS[backend].items():
        monkeypatch.setenv(key, value)


@built
@pytest.mark.parametrize("name", NAMES)
def test_inverse_native_numba_numpy_agree(name, monkeypatch):
    """``m.ik(X, full_output=True)`` through the C kernel, the Numba kernel and the NumPy
    path: the same statuses row by row (OK, unreachable, invalid, out of stroke) and the same
    actuator values to 1e-12 (poses on the edge of reach: C and Numba only)."""
    m = _machine(name)
    x = _poses(m, 5000, seed=1)
    results = {}
    for backend in BACKENDS:
        _env(monkeypatch, backend)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StrokeWarning)
            results[backend] = m.ik(x, full_output=True, strokes="flag")
    native = results["native"]
    statuses = set(native.status.tolist())
    assert {Status.OK, Status.INVALID_INPUT} <= statuses
    assert Status.UNREACHABLE in statuses or name == "gough-stewart"  # struts always close
    assert native.out_of_stroke.any() or name != "gough-stewart"
    # on the edge of reach rounding decides: the NumPy path (other operations) may differ
    rows = {"numba": slice(None), "numpy": ~_edge(len(x))}
    for other, keep in rows.items():
        np.testing.assert_array_equal(native.status[keep], results[other].status[keep])
        np.testing.assert_allclose(native.q[keep], results[other].q[keep], rtol=0, atol=1e-12,
                                   equal_nan=True)
        np.testing.assert_array_equal(native.out_of_stroke[keep],
                                      results[other].out_of_stroke[keep])


@built
@pytest.mark.parametrize("name", NAMES)
def test_inverse_kernel_twins_agree_on_every_row(name):
    """The kernels called on the same arguments (those ``inverse_compiled`` passes), with the
    machine's branches and the opposite ones (crank angles wrapped, slides on the other
    side), and with every rod its own actuator (no consistency test: on the edge of reach the
    boundary tolerance alone decides): the C twin writes the Numba kernel's statuses and
    values (to 1e-12)."""
    from pkmkit.machines import full_pose_kernels

    m = _machine(name)
    x = _poses(m, 3000, seed=2)
    forms = FullPoseForms(m.model)
    own = _inverse_args(forms, x, forms.rod_branch, m._consistency_tol())
    rods = np.arange(m.model.n_rods)
    own[14:17] = rods[:, None], np.ones_like(rods), m.model.rod_kind == 2  # one rod each
    cases = [(_inverse_args(forms, x, forms.rod_branch, m._consistency_tol()), 1000),
             (_inverse_args(forms, x, -forms.rod_branch, m._consistency_tol()), 0),
             (own, 1000)]
    for args, least in cases:
        outs = []
        for kernel in (full_pose_kernels.inverse_poses, _kernels.inverse_poses):
            q = np.empty((len(x), len(args[15])))
            status = np.empty(len(x), dtype=np.int64)
            kernel(*args, q, status)
            outs.append((q, status))
        np.testing.assert_array_equal(outs[0][1], outs[1][1])
        assert (outs[0][1] == 0).sum() >= least and (outs[0][1] != 0).sum() >= 3
        np.testing.assert_allclose(outs[0][0], outs[1][0], rtol=0, atol=1e-12, equal_nan=True)


def _inverse_args(forms, x, sigma, tol):
    """The arguments ``forms.inverse_compiled`` passes to its kernel, but ``q`` and
    ``status``."""
    from unittest import mock

    seen = {}

    def capture(*args):
        seen["args"] = list(args[:-2])

    with mock.patch.object(jit, "kernel", lambda module, name: capture):
        forms.inverse_compiled(x, sigma, tol)
    return seen["args"]


@built
def test_inverse_on_threads_is_the_inverse_on_one(monkeypatch):
    """The C kernel releases the GIL and is run in chunks on threads
    (:func:`pkmkit.numerics.jit.run_chunks`): the rows do not depend on the thread count."""
    m = pkmkit.machine("verne")
    _env(monkeypatch, "native")
    x = _poses(m, 2 * jit.THREAD_ROWS + 11, seed=3)
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = m.ik(x, full_output=True, strokes="ignore")
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    two = m.ik(x, full_output=True, strokes="ignore")
    np.testing.assert_array_equal(one.status, two.status)
    np.testing.assert_array_equal(one.q, two.q)
    assert (one.status == Status.OK).sum() > 1000 and (one.status != Status.OK).sum() > 1000


def _configurations(m, n, seed, spread=0.02):
    """Random actuator values around home, two invalid rows, some far beyond any assembly."""
    rng = np.random.default_rng(seed)
    q = m.home_q + rng.normal(scale=spread, size=(n, m.n_actuators))
    q[0] = np.nan
    q[1, 0] = 2e9
    q[2:12] *= 3.0  # struts three times longer: no assembly (or another one) for many
    q[12:20, 0] += 2.0  # one actuator two metres away from the others: the rods do not meet
    return q


def _direct_three_ways(m, q, monkeypatch, **options):
    results = {}
    for backend in BACKENDS:
        _env(monkeypatch, backend)
        results[backend] = m.fk(q, full_output=True, strokes="ignore", **options)
    return results


def _assert_direct_agree(results, atol=1e-12):
    native = results["native"]
    for other in ("numba", "numpy"):
        ref = results[other]
        np.testing.assert_array_equal(native.status, ref.status)
        ok = ref.status == Status.OK
        np.testing.assert_allclose(native.pose[ok], ref.pose[ok], rtol=0, atol=atol)
        np.testing.assert_array_equal(native.iterations[ok], ref.iterations[ok])
        np.testing.assert_allclose(native.residual[ok], ref.residual[ok], rtol=0, atol=1e-14)
        assert np.isnan(native.pose[~ok]).all()


@built
@pytest.mark.parametrize("name", ["gough-stewart", "verne", "dietmaier-hexapod", "delta6"])
def test_direct_native_numba_numpy_agree(name, monkeypatch):
    """``m.fk(Q, full_output=True)`` by the C solve, the Numba solve and the NumPy engine:
    the same statuses (with invalid and unassembled rows), iterations, poses to 1e-12."""
    m = _machine(name)
    results = _direct_three_ways(m, _configurations(m, 300, seed=1), monkeypatch)
    status = results["native"].status
    assert status[0] == status[1] == Status.INVALID_INPUT
    assert (status == Status.OK).sum() > 250 and (status == Status.NO_ASSEMBLY).sum() >= 1
    _assert_direct_agree(results)


@built
@pytest.mark.parametrize("options", [{"max_iter": 2}, {"atol": 1e-3}, {"gtol": 0.5},
                                     {"xtol": 1e-6, "damping": 1.0}, {"stall": 0.9}])
def test_direct_options_mean_the_same_to_the_c_solve(options, monkeypatch):
    """Iteration limit, tolerances, damping and the crawl test: the same statuses, iterations
    and poses by all three."""
    m = pkmkit.machine("verne")
    results = _direct_three_ways(m, _configurations(m, 150, seed=4), monkeypatch, **options)
    assert len(set(results["native"].status.tolist())) >= 2
    _assert_direct_agree(results)


@built
def test_direct_near_parallel_singularities(monkeypatch):
    """Hexapod poses with parallel measure μ below 1e-2 (down to ~1e-5), from the first-order
    guess and from warm starts: the C and Numba solves give the same statuses, iterations and
    poses to 1e-12 (the same operations); against the NumPy engine the statuses agree and the
    poses within 1e-12/μ (a rounding-level residual moves the solution by ~1/μ)."""
    rng = np.random.default_rng(1)
    m, x, measure = near_parallel_singular_poses(200, rng)
    q = m.ik(x, strokes="ignore")
    for options in ({}, {"x0": x + rng.normal(scale=1e-4, size=x.shape)}):
        results = _direct_three_ways(m, q, monkeypatch, **options)
        native, numba, engine = results["native"], results["numba"], results["numpy"]
        np.testing.assert_array_equal(native.status, numba.status)
        np.testing.assert_array_equal(native.iterations, numba.iterations)
        np.testing.assert_allclose(native.pose, numba.pose, rtol=0, atol=1e-12, equal_nan=True)
        np.testing.assert_array_equal(native.status, engine.status)
        ok = engine.status == Status.OK
        assert ok.sum() > 150
        gap = np.abs(native.pose[ok] - engine.pose[ok]).max(axis=1)
        assert (gap <= 1e-12 / measure[ok]).all()


@built
def test_one_configuration_is_the_batch_row_and_imports_no_numba():
    """A fresh process's single ``m.fk(q)`` calls run the C solve from the first (no Numba
    import at all) and give the bits of the batch row."""
    import subprocess
    import sys
    from pathlib import Path

    code = ("import sys, numpy as np, pkmkit\n"
            "m = pkmkit.machine('gough-stewart')\n"
            "q = m.home_q + np.linspace(-0.01, 0.02, 6)\n"
            "a, b = m.fk(q), m.fk(q.tolist())\n"
            "batch = m.fk(np.stack([q, q + 1e-3]))\n"
            "print('numba' in sys.modules, bool((a == batch[0]).all() and (b == a).all()))\n")
    src = str(Path(pkmkit.__file__).resolve().parents[1])
    env = {"PYTHONPATH": src, "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, check=True).stdout.split()
    assert out == ["False", "True"]


@built
def test_direct_kernel_start_is_the_first_order_guess(monkeypatch):
    """With a budget of zero iterations the C solve returns its start, home ⊕ J(home)(q −
    q_home), which the machine computes independently with scipy."""
    m = pkmkit.machine("gough-stewart")
    q = _configurations(m, 50, seed=3)[12:]
    _env(monkeypatch, "native")
    kernel = DirectKernel.of(m.model, m.home_pose, m.home_q, m._home_jacobian)
    pose, status, iterations, _ = kernel.solve(q, None, {"max_iter": 0})
    assert (status == Status.NOT_CONVERGED).all() and (iterations == 0).all()
    np.testing.assert_allclose(pose, m.first_order_pose(q), rtol=0, atol=1e-15)


@built
def test_direct_twins_refuse_a_start_whose_jacobian_is_not_finite():
    """A start where a platform joint sits exactly on its base joint: the residual is finite
    but the rod direction (and so the Jacobian) is not; both solves stop before stepping and
    flag the row, as the engine does, and solve the other rows alike."""
    from pkmkit.machines import full_pose_direct_kernel

    kernel = DirectKernel.of(*_direct_data())
    geom = kernel.geom.copy()
    geom[0, 0:6] = 0.0  # rod 0: base and platform joints at the origins of their frames
    q = np.tile(pkmkit.machine("gough-stewart").home_q, (3, 1))
    u0 = np.zeros((3, 6))  # pose 0: the platform frame on the base frame
    u0[1:] = kernel.home[:6]
    outs = []
    for solve in (full_pose_direct_kernel.solve_rows, _kernels.solve_rows):
        out = np.empty((3, 9))
        solve(q, u0, True, geom, kernel.home, DirectKernel.options({}), out)
        outs.append(out)
    assert outs[0][0, 6] == outs[1][0, 6] == Status.INVALID_INPUT
    assert outs[1][0, 7] == 0 and np.isnan(outs[1][0, 8])
    np.testing.assert_allclose(outs[1], outs[0], rtol=0, atol=1e-12, equal_nan=True)


@built
def test_bad_arguments_are_refused_before_any_memory_is_read():
    """Wrong types, shapes, layouts and out-of-range indices raise (never a read or write out
    of bounds)."""
    kernel = DirectKernel.of(*_direct_data())
    geom, home = kernel.geom, kernel.home
    opts = DirectKernel.options({})
    q = np.zeros((4, 6))
    out = np.empty((4, 9))
    _kernels.solve_rows(q, np.empty((4, 6)), False, geom, home, opts, out)  # well formed
    cases = [
        ((q.astype(np.float32), np.empty((4, 6)), False, geom, home, opts, out), TypeError),
        ((np.zeros((4, 12))[:, ::2], np.empty((4, 6)), False, geom, home, opts, out),
         TypeError),
        ((q, np.empty((3, 6)), False, geom, home, opts, out), ValueError),
        ((q, np.empty((4, 6)), False, geom, home[:-1], opts, out), ValueError),
        ((q, np.empty((4, 6)), False, geom, home, opts, np.empty((4, 8))), ValueError),
        ((q, np.empty((4, 6)), False, geom, home, opts, _read_only(out)), TypeError),
        ((q, np.empty((4, 6)), False, _bad_actuator(geom), home, opts, out), ValueError),
        ((q, np.empty((4, 6)), False, geom, home, opts), TypeError),
    ]
    for args, error in cases:
        with pytest.raises(error):
            _kernels.solve_rows(*args)
    with pytest.raises(ValueError):
        _kernels.solve_one(q, np.empty(6), False, geom, home, opts, np.empty(9))


def _direct_data():
    m = pkmkit.machine("gough-stewart")
    return m.model, m.home_pose, m.home_q, m._home_jacobian


def _read_only(a):
    b = a.copy()
    b.setflags(write=False)
    return b


def _bad_actuator(geom):
    g = geom.copy()
    g[2, 14] = 6.0
    return g


@built
def test_bad_inverse_arguments_are_refused():
    m = pkmkit.machine("verne")
    forms = FullPoseForms(m.model)
    x = np.tile(m.home_pose, (5, 1))
    q, status = forms.inverse_compiled(x, forms.rod_branch, 1e-9)  # well formed
    assert (status == Status.OK).all()
    args = [*_inverse_args(forms, x, forms.rod_branch, 1e-9), q, status]
    groups = args[14].copy()
    groups[0, 0] = 99
    bad_kind = args[1].copy()
    bad_kind[0] = 3
    for index, value, error in ((14, groups, ValueError), (1, bad_kind, ValueError),
                                (16, args[16].astype(np.int64), TypeError),
                                (0, x[:, :5].copy(), ValueError),
                                (19, np.empty(5, dtype=np.int32), TypeError)):
        broken = list(args)
        broken[index] = value
        with pytest.raises(error):
            _kernels.inverse_poses(*broken)


@built
def test_dispatch_chooses_native_then_numba_then_numpy(monkeypatch):
    """:mod:`pkmkit.numerics.jit` is the one place: the C twin by default, the Numba kernel
    with ``PKMKIT_NATIVE=0``, NumPy with ``PKMKIT_COMPILED=0``; kernels without a twin stay
    Numba's; with the extension the per-pose solvers run at every size."""
    from pkmkit.machines import full_pose_direct_kernel, full_pose_kernels

    monkeypatch.delenv("PKMKIT_NATIVE", raising=False)
    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    assert jit.kernel(full_pose_kernels.__name__, "inverse_poses") is _kernels.inverse_poses
    assert jit.kernel(full_pose_direct_kernel.__name__, "solve_one") is _kernels.solve_one
    assert jit.kernel(full_pose_kernels.__name__, "rod_coordinates") \
        is full_pose_kernels.rod_coordinates
    assert jit.use_compiled_solver(1, native=True)
    assert jit.use_compiled(jit.MIN_ROWS, native=True)
    assert not jit.use_compiled(jit.MIN_ROWS - 1, native=True)
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert jit.native_kernels() is None
    assert jit.kernel(full_pose_direct_kernel.__name__, "solve_rows") \
        is full_pose_direct_kernel.solve_rows
    monkeypatch.setenv("PKMKIT_NATIVE", "1")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert jit.native_kernels() is None
    assert not jit.use_compiled_solver(1000, native=True)
    assert not jit.use_compiled(10**6, native=True)
