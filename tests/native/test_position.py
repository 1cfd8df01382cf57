"""The C twin of the position inverse (``pkmkit.native.kernels.position_rows``, twin of
:func:`pkmkit.machines.full_pose_position_kernel.solve_rows`: the Verne-type module, whose three
actuators command the position and whose rods set the orientation) against the Numba kernel —
the same bits on every row, statuses and iteration counts included — and, through ``m.ik``,
against the NumPy engine (:func:`pkmkit.solve.rod_closure.solve_position_inverse`, the
independent oracle: batched NumPy with its own operations): random, unreachable, beyond-stroke,
edge-of-reach (bisected) and invalid positions, with and without a start, with and without
the early stop, on 1 and 2 threads; the checks of its arguments; the dispatch of
:mod:`pkmkit.numerics.jit`."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import full_pose_position as position
from pkmkit.machines.full_pose_position_solve import KERNEL, solve
from pkmkit.numerics import jit
from pkmkit.status import Status
from tests.machines.test_full_pose import _full_pose_delta

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
numba_kernel = pytest.importorskip("pkmkit.machines.full_pose_position_kernel")

NAMES = ["verne", "delta6"]
BACKENDS = {"native": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "1"},
            "numba": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "0"},
            "numpy": {"PKMKIT_COMPILED": "0", "PKMKIT_NATIVE": "0"}}
SPREAD = {"verne": 0.9, "delta6": 0.4}
SRC = Path(pkmkit.__file__).resolve().parents[1]


def _machine(name):
    return _full_pose_delta() if name == "delta6" else pkmkit.machine(name)


def _reaches(m, positions):
    """Whether the Numba kernel solves each position (status OK) from its first-order
    start: the oracle of the bisection below (any consistent one serves: the rows it leaves
    are those where a rounding decides)."""
    _, status, _, _ = numba_kernel.solve(*_arguments(m, positions))
    return status == Status.OK


def _arguments(m, positions):
    """``(geom, positions, None, opts)`` and the keywords ``ik`` passes (its early stop)."""
    data = m.direct_kernel()
    crawl = (position.POSITION_CRAWL[0],
             position.POSITION_CRAWL[1] * (1.0 + float(m.model.rod_length.max())))
    options = {"max_iter": position.POSITION_MAX_ITER, "compute_rank": False}
    opts = np.concatenate([data.options(options), crawl])
    return data.geom, positions, None, opts


def _edge(m, inside, rng, count=20):
    """Positions on the edge of reach, by bisection between solved positions and far ones:
    ``count`` just inside and ``count`` just outside."""
    inside = inside[:count].copy()
    direction = rng.normal(size=inside.shape)
    outside = inside + 5.0 * direction / np.linalg.norm(direction, axis=1)[:, None]  # far
    for _ in range(50):
        mid = 0.5 * (inside + outside)
        ok = _reaches(m, mid)
        inside[ok] = mid[ok]
        outside[~ok] = mid[~ok]
    return np.concatenate([inside, outside])


def _positions(m, n, seed):
    """Random positions around home (most reachable, some not), far ones, edge-of-reach ones,
    positions reached only beyond the strokes, and invalid rows (NaN, inf, beyond 1e9)."""
    rng = np.random.default_rng(seed)
    p = m.home_pose[:3] + rng.uniform(-SPREAD[m.id], SPREAD[m.id], (n, 3))
    p[n // 2: n // 2 + 50] += rng.uniform(-3.0, 3.0, (50, 3))
    reached = p[:n // 2][_reaches(m, p[:n // 2])]
    p[n // 2 + 50: n // 2 + 90] = _edge(m, reached, rng)
    beyond = m.home_q + np.linspace(1.1, 1.5, 20)[:, None] * (m.model.q_max - m.home_q)
    with np.errstate(invalid="ignore"):
        far = m.fk(beyond, strokes="ignore", full_output=True).pose[:, :3]
    p[n // 2 + 90: n // 2 + 110] = np.where(np.isfinite(far), far, m.home_pose[:3])
    p[0] = np.nan
    p[1, 2] = 2e9
    p[2, 0] = -np.inf
    p[3, 1] = 1e300
    return p


def _same_bits(a, b):
    """The same float64 bits, NaN for NaN (any payload)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    np.testing.assert_array_equal(a[~nan].view(np.int64), b[~nan].view(np.int64))


@pytest.fixture(scope="module", params=NAMES)
def case(request):
    m = _machine(request.param)
    return m, _positions(m, 3000, seed=7)


def _starts(m, p):
    """Given starts ``(N, 6)``: the first-order ones moved a little, NaN in a few rows."""
    rng = np.random.default_rng(3)
    data = m.direct_kernel()
    jt_inv = np.linalg.inv(m._home_jacobian[:3])
    u0 = np.empty((p.shape[0], 6))
    for k in range(p.shape[0]):
        numba_kernel.first_order(np.nan_to_num(p[k]), data.home, jt_inv, u0[k])
    u0 += rng.normal(scale=1e-3, size=u0.shape)
    u0[5:9] = np.nan
    u0[9, 4] = np.inf
    return u0


def _struts(m):
    """``m``'s kernel geometry with every slide made a strut of variable length (kind 1) fixed
    where its slide's joint sits at home (length ℓ − q_home): the same home assembly, so that
    the strut branches of the kernels are compared too (the library has no three-strut
    position-controlled machine)."""
    geom = m.direct_kernel().geom.copy()
    q_home = m.home_q[geom[:, 14].astype(int)]
    geom[:, 0:3] += q_home[:, None] * geom[:, 6:9]
    geom[:, 12] -= q_home
    geom[:, 13] = 1.0
    return geom


@pytest.mark.parametrize("guess", [False, True])
@pytest.mark.parametrize("crawl", [True, False])
def test_c_writes_the_numba_kernels_bits(case, guess, crawl):
    """The kernels on the same arguments (those ``ik`` passes: first-order starts from home,
    hopeless and invalid rows skipped; or given starts, some not finite): every output —
    u, status, iterations, residual — the same bits, row by row, with and without the early
    stop (``crawl``)."""
    m, p = case
    _compare_bits(m, p, _arguments(m, p)[0], guess, crawl)


@pytest.mark.parametrize("guess", [False, True])
@pytest.mark.parametrize("crawl", [True, False])
def test_c_writes_the_numba_kernels_bits_on_struts(guess, crawl):
    """As above with struts in place of the Verne module's slides (:func:`_struts`)."""
    m = pkmkit.machine("verne")
    p = _positions(m, 2000, seed=5)
    _compare_bits(m, p, _struts(m), guess, crawl)


def _compare_bits(m, p, geom, guess, crawl):
    data = m.direct_kernel()
    opts = _arguments(m, p)[3]
    if not crawl:
        opts = opts.copy()
        opts[7:] = (0.0, np.inf)
    u0 = _starts(m, p) if guess else None
    with np.errstate(over="ignore"):
        hopeless = m._surely_unreachable(p)
    skip = ~np.isfinite(p).all(axis=1) | (np.abs(p) > 1e9).any(axis=1) | hopeless
    jt_inv = np.linalg.inv(m._home_jacobian[:3])
    outs = [solve(geom, p, u0, opts, skip=skip, home=data.home, jt_inv=jt_inv, function=f)
            for f in (_kernels.position_rows, numba_kernel.solve_rows)]
    for c_part, numba_part in zip(*outs, strict=True):
        _same_bits(c_part, numba_part)
    status, iterations = outs[0][1], outs[0][2]
    seen = set(status.tolist())
    assert {Status.OK, Status.INVALID_INPUT} <= seen and len(seen) >= 3
    assert iterations.max() >= 5


def test_edge_rows_straddle_the_reach(case):
    """The bisected rows are where rounding decides: some solved, some not (else the edge
    rows of the other tests would test nothing)."""
    m, p = case
    edge = p[len(p) // 2 + 50: len(p) // 2 + 90]
    ok = _reaches(m, edge)
    assert ok[:20].all() and not ok[20:].any()
    np.testing.assert_array_less(np.abs(edge[:20] - edge[20:]).max(axis=1), 1e-9)


@pytest.mark.parametrize("threads", [1, 2])
def test_ik_native_numba_numpy_agree(case, threads, monkeypatch):
    """``m.ik(P, full_output=True)`` through the C kernel, the Numba kernel and the NumPy
    engine, on 1 and 2 threads (small chunks, so that 2 threads share the batch): C and Numba
    the same bits in q, pose, statuses, iterations and residuals on every row; NumPy the
    same statuses (edge rows excepted: other operations) and q, pose to 1e-12 where OK."""
    m, p = case
    monkeypatch.setenv("PKMKIT_THREADS", str(threads))
    monkeypatch.setattr(jit, "THREAD_ROWS", 256)
    results = {}
    for backend, env in BACKENDS.items():
        for key, value in env.items():
            monkeypatch.setenv(key, value)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StrokeWarning)
            results[backend] = m.ik(p, full_output=True, strokes="flag")
    native, numba_, numpy_ = results["native"], results["numba"], results["numpy"]
    for field in ("q", "pose", "status", "iterations", "residual", "mode", "shortfall"):
        _same_bits(getattr(native, field), getattr(numba_, field))
    np.testing.assert_array_equal(native.out_of_stroke, numba_.out_of_stroke)
    seen = set(native.status.tolist())
    assert {Status.OK, Status.INVALID_INPUT, Status.UNREACHABLE} <= seen
    assert native.out_of_stroke.any()
    keep = np.ones(len(p), dtype=bool)
    keep[len(p) // 2 + 50: len(p) // 2 + 90] = False  # the edge of reach
    np.testing.assert_array_equal(native.status[keep], numpy_.status[keep])
    ok = keep & (native.status == Status.OK)
    np.testing.assert_allclose(native.q[ok], numpy_.q[ok], rtol=0, atol=1e-12)
    np.testing.assert_allclose(native.pose[ok], numpy_.pose[ok], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(native.out_of_stroke[keep], numpy_.out_of_stroke[keep])


def test_threads_do_not_change_the_bits(monkeypatch):
    """The C kernel over 1 thread and over 2 threads (chunks of 256 rows): the same bits."""
    m = pkmkit.machine("verne")
    p = _positions(m, 3000, seed=11)
    monkeypatch.setattr(jit, "THREAD_ROWS", 256)
    outs = []
    for threads in ("1", "2"):
        monkeypatch.setenv("PKMKIT_THREADS", threads)
        outs.append(solve(*_arguments(m, p), function=_kernels.position_rows))
    for one, two in zip(*outs, strict=True):
        _same_bits(one, two)


def _valid_call(m):
    p = m.home_pose[:3] + np.zeros((4, 3))
    data = m.direct_kernel()
    geom, _, _, opts = _arguments(m, p)
    return [p, np.empty((4, 6)), False, np.zeros(4, dtype=bool), geom, data.home,
            np.eye(3), opts, np.empty((4, 9))]


@pytest.mark.parametrize("which,value,error", [
    (0, np.zeros((4, 3), dtype=np.float32), TypeError),   # p not float64
    (0, np.zeros((4, 2)), ValueError),                     # p not (N, 3)
    (0, np.zeros((4, 6))[:, :3], TypeError),               # p not contiguous
    (1, np.zeros((3, 6)), ValueError),                     # u0 rows ≠ N
    (3, np.zeros(4, dtype=np.int64), TypeError),           # skip not bool
    (3, np.zeros(5, dtype=bool), ValueError),              # skip rows ≠ N
    (4, np.zeros((4, 15)), ValueError),                    # geom not (m, 16)
    (5, np.zeros(26), ValueError),                         # home not (27,)
    (6, np.eye(2), ValueError),                            # jt_inv not (3, 3)
    (7, np.zeros(7), ValueError),                          # opts not (9,): the direct one's
    (8, np.zeros((4, 9))[::-1], TypeError),                # out not contiguous
    (8, np.zeros((5, 9)), ValueError),                     # out rows ≠ N
    (8, None, TypeError),                                  # out read-only (made below)
])
def test_the_c_kernel_refuses_bad_arguments(which, value, error):
    """Wrong types, shapes, layouts: a TypeError or ValueError, never a read or write out of
    bounds; nothing written into ``out``."""
    args = _valid_call(pkmkit.machine("verne"))
    if value is None:  # a read-only out
        value = np.zeros((4, 9))
        value.setflags(write=False)
    args[which] = value
    with pytest.raises(error):
        _kernels.position_rows(*args)


@pytest.mark.parametrize("column,value", [(14, 3.0), (14, -1.0), (14, np.nan), (13, 3.0),
                                          (13, np.nan)])
def test_the_c_kernel_refuses_rods_out_of_range(column, value):
    """A rod whose actuator index is not 0, 1 or 2 (the kernel writes its Jacobian column) or
    whose kind is outside 0..2: ValueError naming the rod; ``out`` untouched."""
    args = _valid_call(pkmkit.machine("verne"))
    args[4] = args[4].copy()
    args[4][2, column] = value
    args[8][:] = 5.0
    with pytest.raises(ValueError, match="rod 2"):
        _kernels.position_rows(*args)
    assert (args[8] == 5.0).all()
    with pytest.raises(TypeError, match="9 positional"):
        _kernels.position_rows(*args[:8])


def test_jit_dispatch(monkeypatch):
    """``jit.kernel`` gives the C twin when built, the Numba kernel with ``PKMKIT_NATIVE=0``
    or from an extension built before the twin existed; ``PKMKIT_COMPILED=0`` takes the
    NumPy engine (the compiled position inverse is not chosen)."""
    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    monkeypatch.delenv("PKMKIT_NATIVE", raising=False)
    m = pkmkit.machine("verne")
    assert jit.kernel(KERNEL, "solve_rows") is _kernels.position_rows
    assert m._compiled_positions({}, 1)  # C: at every size, as the direct solve
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert jit.kernel(KERNEL, "solve_rows") is numba_kernel.solve_rows
    monkeypatch.delenv("PKMKIT_NATIVE")
    monkeypatch.setattr(jit, "_native", type(sys)("older_kernels"))  # no position_rows
    assert jit.kernel(KERNEL, "solve_rows") is numba_kernel.solve_rows
    monkeypatch.setattr(jit, "_native", False)
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert not m._compiled_positions({}, 10_000)


@pytest.mark.ci  # a fresh process (1-4 s of CPU): .ci/run's second stage
def test_a_fresh_position_batch_does_not_import_numba(tmp_path):
    """A fresh process's ``m.ik`` of 5,000 positions of the Verne module (the compiled solve,
    then the working-mode check) and ``pkmkit ik verne --input``: the C kernel, no Numba."""
    table = tmp_path / "p.csv"
    rng = np.random.default_rng(0)
    rows = rng.uniform(-0.05, 0.05, (5000, 3))
    table.write_text("x,y,z\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows))
    code = ("import sys, numpy as np, pkmkit; m = pkmkit.machine('verne'); "
            "r = m.ik(np.random.default_rng(0).uniform(-0.05, 0.05, (5000, 3)), "
            "full_output=True); assert (r.status == 0).sum() > 4000; "
            "from pkmkit.cli.main import main; sys.argv = ['pkmkit', 'ik', 'verne', '--input', "
            f"{str(table)!r}, '--output', {str(tmp_path / 'q.csv')!r}]\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print('numba' in sys.modules, 'pkmkit.native.kernels' in sys.modules)")
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=300, check=True).stdout
    assert out.strip().splitlines()[-1] == "False True"
    assert (tmp_path / "q.csv").read_text().count("\n") >= 5000
