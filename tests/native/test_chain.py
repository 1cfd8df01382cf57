"""The C twin of the joint-chain closure (``pkmkit.native.kernels.chain_rows``, twin of
:func:`pkmkit.solve.chain_kernel._solve_rows`: the direct model's closure and the inverse model
of a complete machine) against the Numba kernel — the same bits on every row, statuses and
iteration counts included — and, through ``m.ik``/``m.fk``, against the NumPy engine (the
independent oracle: :func:`pkmkit.solve.chains.solve_closure` /
:func:`~pkmkit.solve.chains.solve_machine_inverse` on batched NumPy): the Tripteor X7 and the
TriMule 600, nominal and with incompatible defects, cold, warm and non-finite starts, actuator
values no assembly has and bisected ones on the edge of assembly, grid and far tool targets, the
engine's options, two threads at once; the checks of its arguments; the dispatch."""

from __future__ import annotations

import subprocess
import sys
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.calibration import random_defects  # noqa: F401  (the defects' module, loaded)
from pkmkit.exceptions import StrokeWarning
from pkmkit.geometric_errors.model import defect_set
from pkmkit.model.defect_rule import add_defects
from pkmkit.solve import chain_rows
from pkmkit.status import Status

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
numba_kernel = pytest.importorskip("pkmkit.solve.chain_kernel")

NAMES = ["tripteor-x7", "trimule-600"]
BACKENDS = {"native": {"PKMKIT_COMPILED": "auto", "PKMKIT_NATIVE": "1"},
            "numba": {"PKMKIT_COMPILED": "auto", "PKMKIT_NATIVE": "0"},
            "numpy": {"PKMKIT_COMPILED": "0", "PKMKIT_NATIVE": "0"}}
SRC = Path(pkmkit.__file__).resolve().parents[1]


def _same_bits(a, b):
    """The same float64 (or int64) values bit for bit, NaN for NaN (any payload)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    if a.dtype.kind != "f":
        np.testing.assert_array_equal(a, b)
        return
    nan = np.isnan(a)
    np.testing.assert_array_equal(nan, np.isnan(b))
    np.testing.assert_array_equal(a[~nan].view(np.int64), b[~nan].view(np.int64))


def _twice(monkeypatch, call):
    """``call()`` through the C twin, then through the Numba kernel; both results."""
    outs = []
    for function in (_kernels.chain_rows, numba_kernel._solve_rows):
        monkeypatch.setattr(chain_rows, "_rows_kernel", lambda f=function: f)
        outs.append(call())
    return outs


def _assert_twins(outs, *, statuses):
    for c_part, numba_part in zip(*outs, strict=True):
        _same_bits(c_part, numba_part)
    seen = set(outs[0][1].tolist())
    assert statuses <= seen, seen


@pytest.fixture(scope="module", params=NAMES)
def machines(request):
    """The nominal machine and one with random (incompatible) defects."""
    m = pkmkit.machine(request.param)
    rng = np.random.default_rng(4)
    return m, add_defects(m, rng.normal(0.0, 1.0, len(defect_set(m)))
                          * np.where(np.array(defect_set(m).units) == "m", 1e-4, 1e-3))


def _closure_rows(machine, rng, n):
    """Known values and starts: default (cold) starts, warm ones, a non-finite start, an
    actuator value no assembly has, a start far off; then 20 pairs of configurations on the
    edge of assembly (one actuator bisected between an assembled configuration and one 5 units
    away, by the statuses of the closure), with their default starts."""
    q = machine.measurement_configurations(n, rng)
    values = machine.full_values(q)
    u0 = machine._default_start(q, values)
    u0[n // 2:] += rng.normal(0.0, 1e-3, u0[n // 2:].shape)
    u0[3, 2] = np.nan
    u0[4, 0] = np.inf
    values[5, machine._actuated[0]] += 5.0
    u0[6, 6:] += 2.0
    good, bad = values[10:30].copy(), values[10:30].copy()
    bad[:, machine._actuated[0]] += 5.0
    for _ in range(40):
        mid = 0.5 * (good + bad)
        closed = _closure_status(machine, mid) == Status.OK
        good[closed] = mid[closed]
        bad[~closed] = mid[~closed]
    edge = np.concatenate([good, bad])
    edge_u0 = machine._default_start(edge[:, machine._actuated], edge)
    return np.concatenate([values, edge]), np.concatenate([u0, edge_u0])


def _closure_status(machine, values):
    u0 = machine._default_start(values[:, machine._actuated], values)
    return chain_rows.solve(machine.model, values, u0, machine.passive_variables,
                            damping=1e-8)[1]


@pytest.mark.parametrize("which", [0, 1], ids=["nominal", "defects"])
@pytest.mark.parametrize("options", [{}, {"xtol": 1e-6, "max_iter": 7}], ids=["default", "short"])
def test_closure_c_writes_the_numba_kernels_bits(machines, which, options, monkeypatch):
    """``chain_rows.solve`` (the direct model's closure) through C and through Numba: u,
    status, residual, iterations bit for bit on every row."""
    machine = machines[which]
    values, u0 = _closure_rows(machine, np.random.default_rng(1 + which), 60)
    outs = _twice(monkeypatch, lambda: chain_rows.solve(
        machine.model, values, u0, machine.passive_variables, damping=1e-8, **options))
    expected = {Status.INVALID_INPUT} | ({Status.OK} if which == 0 and not options else set())
    _assert_twins(outs, statuses=expected | {Status.NOT_CONVERGED if options else
                                             (Status.OK if which == 0 else
                                              Status.INCONSISTENT)})
    assert outs[0][3].max() >= 3
    if which == 0 and not options:  # the edge rows straddle the assembly's edge
        edge = outs[0][1][-40:]
        assert (edge[:20] == Status.OK).all() and (edge[20:] != Status.OK).all()
        assert np.abs(values[-40:-20] - values[-20:]).max() < 1e-9


def _inverse_rows(m, rng):
    """Tool targets: a 7-point-per-edge grid of the default box and far targets (strokeless
    legs reach them all: the inverse's reach is its strokes'), a non-finite start."""
    lo, hi = m.default_box()
    g = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names, resolution=7)
    far = g.points[:20].copy()
    far[:, :3] += rng.normal(0.0, 3.0, (20, 3))
    targets = np.concatenate([g.points, far])
    u0 = _inverse_starts(m, len(targets))
    u0[3] = np.nan
    return targets, u0


def _inverse_starts(m, n):
    return np.concatenate([np.tile(m.home_platform, (n, 1)), np.tile(m.home_values, (n, 1))],
                          axis=1)


@pytest.mark.parametrize("name", NAMES)
def test_inverse_c_writes_the_numba_kernels_bits(name, monkeypatch):
    """``chain_rows.solve_inverse`` (legs, platform and head) through C and through Numba on
    a grid and far targets: the same bits on every row."""
    m = pkmkit.machine(name)
    targets, u0 = _inverse_rows(m, np.random.default_rng(5))
    lengths = np.full(len(targets), m.tool_length)
    outs = _twice(monkeypatch, lambda: chain_rows.solve_inverse(m.model, targets, u0, lengths))
    _assert_twins(outs, statuses={Status.OK, Status.INVALID_INPUT})
    assert outs[0][3].max() >= 5


def test_two_threads_at_once():
    """The C kernel releases the GIL with its own scratch per call: two threads solving halves
    of a batch at once write what one call writes."""
    m = pkmkit.machine("trimule-600")
    targets, u0 = _inverse_rows(m, np.random.default_rng(6))
    lengths = np.full(len(targets), m.tool_length)
    args = chain_rows.model_arrays(m.model, np.arange(m.model.n_variables))

    def run(rows, out):
        u = np.array(u0[rows], order="C")  # a copy: solved in place
        status = np.empty(len(u), dtype=np.int64)
        residual = np.full(len(u), np.nan)
        iterations = np.zeros(len(u), dtype=np.int64)
        _kernels.chain_rows(*args, np.zeros((1, m.model.n_variables)), u,
                            float(m.model.characteristic_length), 60, 1e-14, 1e-14, 1e-12,
                            0.01, 1e-9, 1e-4, status, residual, iterations,
                            np.array(m.model.head, dtype=np.int64),
                            np.ascontiguousarray(targets[rows]),
                            np.ascontiguousarray(lengths[rows]), True)
        out.extend([u, status, residual, iterations])

    whole, first, second = [], [], []
    run(slice(None), whole)
    half = len(targets) // 2
    threads = [threading.Thread(target=run, args=(slice(0, half), first)),
               threading.Thread(target=run, args=(slice(half, None), second))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for part, a, b in zip(whole, first, second, strict=True):
        _same_bits(part, np.concatenate([a, b]))


@pytest.mark.parametrize("name", NAMES)
def test_ik_and_fk_native_numba_numpy_agree(name, monkeypatch):
    """``m.ik`` of 300 poses and ``m.fk`` of 200 configurations (out of stroke, unreachable and
    invalid rows among them) through C, Numba and the NumPy engine: C and Numba the same bits
    in every field; the engine the same statuses and values to 1e-9."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(8)
    home = np.asarray(m.home_pose, dtype=float)
    x = home + np.concatenate([rng.uniform(-0.05, 0.05, (300, 3)),
                               rng.uniform(-0.2, 0.2, (300, len(home) - 3))], axis=1)
    x[0] = np.nan
    x[1, :3] += 3.0  # beyond reach
    q = m.home_q + rng.uniform(-0.04, 0.04, (200, m.n_actuators))
    q[0] = np.nan
    results = {}
    for backend, env in BACKENDS.items():
        for key, value in env.items():
            monkeypatch.setenv(key, value)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StrokeWarning)
            results[backend] = (m.ik(x, full_output=True, strokes="flag"),
                                m.fk(q, full_output=True, strokes="flag"))
    fields = ("q", "pose", "status", "iterations", "residual", "platform", "passive",
              "closure_residual", "out_of_stroke")
    for native, numba_, numpy_ in zip(*results.values(), strict=True):
        compared = [f for f in fields if getattr(native, f, None) is not None]
        assert len(compared) >= 5
        for field in compared:
            _same_bits(getattr(native, field), getattr(numba_, field))
        np.testing.assert_array_equal(native.status, numpy_.status)
        ok = native.status == Status.OK
        assert ok.sum() > 50 and (~ok).any()
        for field in ("q", "pose", "passive"):
            if getattr(native, field, None) is not None:
                np.testing.assert_allclose(getattr(native, field)[ok],
                                           getattr(numpy_, field)[ok], rtol=0, atol=1e-9)


def _valid_call(m):
    args = list(chain_rows.model_arrays(m.model, m.passive_variables))
    n = 6 + len(m.passive_variables)
    return [*args, np.zeros((1, m.model.n_variables)), np.zeros((2, n)), 1.0, 5, 1e-14, 1e-14,
            1e-12, 0.01, 1e-9, 1e-4, np.empty(2, dtype=np.int64), np.empty(2),
            np.empty(2, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros((1, 6)),
            np.zeros(1), False]


def _bad(which, value):
    def change(args):
        args[which] = value(args[which]) if callable(value) else value
    return change


@pytest.mark.parametrize("change,error", [
    (_bad(0, lambda a: a[:, :3, :].copy()), ValueError),          # frames not (E, 4, 4)
    (_bad(1, lambda a: a.astype(np.int32)), TypeError),           # types not int64
    (_bad(1, lambda a: np.where(np.arange(len(a)) == 1, 3, a)), ValueError),  # type 3
    (_bad(3, lambda a: a + 10_000), ValueError),                   # element out of range
    (_bad(4, lambda a: a[::-1].copy()), ValueError),               # offsets decreasing
    (_bad(5, lambda a: a + 100), ValueError),                      # a column beyond u
    (_bad(6, np.zeros((1, 3))), ValueError),                       # known not (., n_var)
    (_bad(7, lambda a: np.zeros((2, 5))), ValueError),             # u with < 6 columns
    (_bad(7, lambda a: a.astype(np.float32)), TypeError),          # u not float64
    (_bad(7, lambda a: np.asfortranarray(np.zeros((2, 9)))[:, 1:]), TypeError),  # layout
    (_bad(16, np.empty(3, dtype=np.int64)), ValueError),           # status rows ≠ N
    (_bad(19, lambda a: np.array([10_000], dtype=np.int64)), ValueError),  # head element
    (_bad(22, True), ValueError),                                  # inverse: 1 target < N
])
def test_the_c_kernel_refuses_bad_arguments(change, error):
    """Wrong types, shapes, layouts and indices that would read or write out of bounds: a
    TypeError or ValueError, nothing solved."""
    args = _valid_call(pkmkit.machine("tripteor-x7"))
    change(args)
    args[16][:] = -5
    with pytest.raises(error):
        _kernels.chain_rows(*args)
    assert (args[16] == -5).all()
    with pytest.raises(TypeError, match="23 positional"):
        _kernels.chain_rows(*args[:22])


def test_jit_dispatch(monkeypatch):
    """``jit.kernel`` gives the C twin when built, the Numba kernel with ``PKMKIT_NATIVE=0``;
    ``PKMKIT_COMPILED=0`` keeps the NumPy engine."""
    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    monkeypatch.delenv("PKMKIT_NATIVE", raising=False)
    assert chain_rows._rows_kernel() is _kernels.chain_rows
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert chain_rows._rows_kernel() is numba_kernel._solve_rows
    from pkmkit.solve.chains import _compiled_closure_applies

    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert not _compiled_closure_applies(10, {"compute_rank": False})


@pytest.mark.ci  # a fresh process (1-4 s of CPU): .ci/run's second stage
def test_a_fresh_chain_batch_does_not_import_numba(tmp_path):
    """``pkmkit ik tripteor-x7 --input`` (the machine inverse) and ``pkmkit fk trimule-600
    --input`` (the closure) in fresh processes: the C kernel, no Numba."""
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(0)
    x = np.asarray(m.home_pose, dtype=float) + rng.uniform(-0.02, 0.02, (300, 6))
    x[:, 3:] = np.degrees(x[:, 3:])
    poses = tmp_path / "x.csv"
    poses.write_text("x,y,z,i,j,k\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in x))
    t = pkmkit.machine("trimule-600")
    q = t.home_q + rng.uniform(-0.02, 0.02, (100, t.n_actuators))
    q[:, 3:] = np.degrees(q[:, 3:])
    configurations = tmp_path / "q.csv"
    configurations.write_text(",".join(t.actuator_names) + "\n"
                              + "\n".join(",".join(f"{v:.6f}" for v in r) for r in q))
    code = ("import sys\nfrom pkmkit.cli.main import main\n"
            "sys.argv = ['pkmkit', *sys.argv[1:]]\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert e.code in (0, 3, None), e.code\n"
            "print('numba' in sys.modules, 'pkmkit.native.kernels' in sys.modules)")
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    for args in (["ik", "tripteor-x7", "--input", str(poses)],
                 ["fk", "trimule-600", "--input", str(configurations)]):
        out = subprocess.run([sys.executable, "-c", code, *args, "--output",
                              str(tmp_path / "out.csv")], capture_output=True, text=True,
                             env=env, timeout=300, check=True).stdout
        assert out.strip().splitlines()[-1] == "False True", args
        assert (tmp_path / "out.csv").read_text().count("\n") >= 100
