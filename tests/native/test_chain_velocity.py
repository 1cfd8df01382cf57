"""The C twins of the joint chains' velocity kernels (``pkmkit.native.kernels``,
native/chain_velocity.c): ``chain_jacobian_rows`` (twin of
:func:`pkmkit.solve.chain_kernel._jacobian_rows`, the closure's Jacobian) and ``closure_rates``
(twin of :func:`pkmkit.solve.chain_linalg._closure_rates_rows`: ``dU = −C_U⁺ C_q``, the rank
and the singularity measure of C_U) against the Numba kernels — the same bits on every row,
ranks included — and against the independent oracles: the NumPy closure
(:func:`pkmkit.solve.chains.closure`) and LAPACK's pseudo-inverse and SVD; random, singular
(rank-deficient, nearly so, a zero column) and failing (non-finite) rows on the Tripteor X7
and the TriMule 600, nominal and with defects; ``m.jacobian(q=...)`` through C, Numba and
NumPy; the argument checks; the dispatch; a fresh process's velocity batch without Numba."""

from __future__ import annotations

import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects  # noqa: F401  (the defects' module, loaded)
from pkmkit.geometric_errors.model import defect_set
from pkmkit.machines.chain_jacobians import _pinv_and_singular_values
from pkmkit.machines.chain_velocity_record import RANK_RCOND
from pkmkit.model.defect_rule import add_defects
from pkmkit.solve import chain_rows
from pkmkit.solve.chains import closure
from pkmkit.spatial.rotation import rotvec_to_matrix
from pkmkit.status import Status

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "closure_rates"),
                                reason="pkmkit.native.kernels was not built")
numba_kernel = pytest.importorskip("pkmkit.solve.chain_kernel")
numba_linalg = pytest.importorskip("pkmkit.solve.chain_linalg")

NAMES = ["tripteor-x7", "trimule-600"]
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


@pytest.fixture(scope="module", params=NAMES)
def machines(request):
    """The nominal machine and one with random (incompatible) defects."""
    m = pkmkit.machine(request.param)
    rng = np.random.default_rng(4)
    return m, add_defects(m, rng.normal(0.0, 1.0, len(defect_set(m)))
                          * np.where(np.array(defect_set(m).units) == "m", 1e-4, 1e-3))


def _configurations(m, rng, n=80):
    """Every joint variable and the platform pose of ``n`` configurations: solved closures
    near home, then rows that close nothing (random joint values and platform poses: the
    Jacobian is defined anyway), a large rotation, and non-finite entries."""
    q = m.home_q + rng.uniform(-0.04, 0.04, (n, m.n_actuators))
    direct = m.fk(q, full_output=True, strokes="ignore")
    values = m.full_values(q)
    values[:, m.passive_variables] = np.nan_to_num(direct.passive)
    platform = np.nan_to_num(direct.platform)
    values[n // 2:] += rng.normal(0.0, 0.3, values[n // 2:].shape)
    platform[n // 2:] += rng.normal(0.0, 0.3, platform[n // 2:].shape)
    platform[n // 2, 3:] = [2.9, -1.0, 0.5]  # |φ| near π
    platform[n // 2 + 1, 3:] = [1e-6, 0.0, 2e-6]  # the series below 1e-4 rad
    values[1, m.passive_variables[0]] = np.nan
    platform[2, 4] = np.inf
    return values, platform


def _variables(m):
    loop_act = [int(i) for i in m._actuated if m.model.loop_variables[i]]
    return np.concatenate([m.passive_variables, loop_act]).astype(int)


def _jacobians(m, values, platform, kernel, variables=None):
    variables = _variables(m) if variables is None else variables
    args = chain_rows.model_arrays(m.model, variables)
    u = np.empty((len(values), 6 + len(variables)))
    u[:, :6] = platform
    u[:, 6:] = values[:, variables]
    out = np.full((len(values), 6 * len(m.model.legs), u.shape[1]), -7.0)
    kernel(*args, np.ascontiguousarray(values), u, float(m.model.characteristic_length), out)
    return out


@pytest.mark.parametrize("which", [0, 1], ids=["nominal", "defects"])
def test_closure_jacobian_c_writes_the_numba_kernels_bits(machines, which):
    """``chain_jacobian_rows`` and ``_jacobian_rows`` on solved, random, near-π, small-angle
    and non-finite rows: the same bits in every entry; equal to the NumPy closure's Jacobian
    (the oracle) to 1e-12 of the largest entry on solved rows, 1e-9 of each one's on the others;
    every entry written."""
    m = machines[which]
    values, platform = _configurations(m, np.random.default_rng(10 + which))
    c_out = _jacobians(m, values, platform, _kernels.chain_jacobian_rows)
    numba_out = _jacobians(m, values, platform, numba_kernel._jacobian_rows)
    _same_bits(c_out, numba_out)
    assert not (c_out == -7.0).any()
    assert np.isnan(c_out[1]).any() and np.isnan(c_out[2]).any()
    # the actuators known (read from each row's values, not from u): the same bits too
    passive = m.passive_variables
    _same_bits(_jacobians(m, values, platform, _kernels.chain_jacobian_rows, passive),
               _jacobians(m, values, platform, numba_kernel._jacobian_rows, passive))
    rot = rotvec_to_matrix(platform[:, 3:]).transpose(1, 2, 0)
    ref = closure(m.model, rot, platform[:, :3].T, values.T)
    full = np.concatenate([ref.platform, ref.variables[:, _variables(m)]], axis=1)
    solved = [k for k in range(len(values) // 2) if k not in (1, 2)]
    np.testing.assert_allclose(c_out[solved], full.transpose(2, 0, 1)[solved], rtol=0,
                               atol=1e-12 * np.abs(c_out[solved]).max())
    # far from any closure the rotation rows hold 1/c² (c = cos²(angle/2) of the legs'
    # mismatch), up to 1e5 here (rounding ~ 1/c relative): to 1e-9 of each configuration's largest
    far = slice(len(values) // 2, None)
    error = np.abs(c_out[far] - full.transpose(2, 0, 1)[far]).max(axis=(1, 2))
    assert (error <= 1e-9 * np.abs(c_out[far]).max(axis=(1, 2))).all()


def _rates_rows(m, rng):
    """``(cu, cq, expected)`` of closure Jacobians at solved and random configurations, then
    made singular: a repeated column, a zero column, a column within 1e-9 relative of another
    (below ``RANK_RCOND`` · σ_max: rank-deficient by the cutoff), within 1e-7 (regular but
    beyond the QR bound: the Jacobi path), all-zero rows, non-finite C_U and C_q entries."""
    values, platform = _configurations(m, rng)
    keep = [k for k in range(len(values)) if k not in (1, 2)]
    full = _jacobians(m, values[keep], platform[keep], _kernels.chain_jacobian_rows)
    n_u = 6 + len(m.passive_variables)
    cu, cq = full[:, :, :n_u].copy(), full[:, :, n_u:].copy()
    cu[3, :, 7] = cu[3, :, 2]
    cu[4, :, 6] = 0.0
    cu[5, :, 8] = cu[5, :, 1] * (1 + 1e-9) + 1e-12
    cu[6, :, 8] = cu[6, :, 1] + 1e-7 * np.abs(cu[6]).max() * rng.normal(size=cu.shape[1])
    cu[7] = 0.0
    cu[8, 0, 0] = np.nan
    cq[9, 3, 1] = -np.inf
    cu[10] *= 1e-200  # tiny entries: the norms underflow in the sums of squares
    cu[11] *= 1e150  # huge ones: the sums of squares overflow
    return np.ascontiguousarray(cu), np.ascontiguousarray(cq)


def _rates(kernel, cu, cq, tol, expected):
    n, _, c = cu.shape
    du = np.full((n, c, cq.shape[2]), -7.0)
    rank = np.full(n, -7, dtype=np.int64)
    ratio = np.full(n, -7.0)
    kernel(cu, cq, RANK_RCOND, float(tol), int(expected), du, rank, ratio)
    return du, rank, ratio


@pytest.mark.parametrize("which", [0, 1], ids=["nominal", "defects"])
@pytest.mark.parametrize("tol", [1e-6, 1e-2], ids=["tol-default", "tol-large"])
def test_closure_rates_c_writes_the_numba_kernels_bits(machines, which, tol):
    """``closure_rates`` and ``_closure_rates_rows`` on regular, singular, nearly singular,
    zero, scaled and non-finite rows, with the home rank and one less (every row by Jacobi):
    dU, rank and ratio bit for bit; both paths (QR and Jacobi) taken."""
    m = machines[which]
    cu, cq = _rates_rows(m, np.random.default_rng(20 + which))
    c = cu.shape[2]
    for expected in (c, c - 1):
        c_out = _rates(_kernels.closure_rates, cu, cq, tol, expected)
        numba_out = _rates(numba_linalg._closure_rates_rows, cu, cq, tol, expected)
        for a, b in zip(c_out, numba_out, strict=True):
            _same_bits(a, b)
        du, rank, ratio = c_out
        assert not (du == -7.0).any() and not (rank == -7).any()
        assert rank[8] == rank[9] == 0 and np.isnan(du[8]).all() and np.isnan(ratio[9])
        assert rank[3] == rank[4] == c - 1 and rank[7] == 0
        if expected == c:  # the QR bound settles most regular rows
            qr = np.isin(np.arange(len(cu)), [3, 4, 5, 6, 7, 8, 9], invert=True) & (rank == c)
            assert qr.sum() > 20


@pytest.mark.parametrize("which", [0, 1], ids=["nominal", "defects"])
def test_closure_rates_agree_with_lapack(machines, which):
    """The oracle: LAPACK's pseudo-inverse and SVD (``_pinv_and_singular_values``, the batch
    path's NumPy branch): the same ranks, dU to 1e-13 κ of its size, the ratio σ_min/σ_max where
    the Jacobi path ran and a lower bound of it (within a factor c) where the QR bound did."""
    m = machines[which]
    cu, cq = _rates_rows(m, np.random.default_rng(30 + which))
    finite = np.isfinite(cu).all(axis=(1, 2)) & np.isfinite(cq).all(axis=(1, 2))
    rows = np.flatnonzero(finite & (np.abs(cu).max(axis=(1, 2)) > 0))
    rows = rows[(rows != 10) & (rows != 11)]
    c = cu.shape[2]
    du, rank, ratio = _rates(_kernels.closure_rates, cu[rows], cq[rows], 1e-6, c)
    pinv, sv = _pinv_and_singular_values(cu[rows], RANK_RCOND)
    np.testing.assert_array_equal(rank, (sv > RANK_RCOND * sv[:, :1]).sum(axis=1))
    expected_du = -pinv @ cq[rows]
    size = np.abs(expected_du).max(axis=(1, 2))[:, None, None]
    regular = rank == c
    exact = sv[:, -1] / sv[:, 0]
    # rounding grows with the condition number κ = 1 / exact (1e7 on the nearly singular row)
    error = np.abs(du - expected_du).max(axis=(1, 2))
    assert (error[regular] <= 1e-13 * size[regular, 0, 0] / exact[regular]).all()
    assert regular.sum() > 30
    # ‖R‖_F ≤ √c σ_max and ‖R⁻¹‖_F ≤ √c / σ_min: the bound lies within a factor c below
    assert (ratio[regular] <= exact[regular] * (1 + 1e-6)).all()
    assert (ratio[regular] >= exact[regular] / c * (1 - 1e-6)).all()


def test_jacobian_native_numba_numpy_agree(machines, monkeypatch):
    """``m.jacobian(q=...)`` of 120 configurations (out of assembly and non-finite rows among
    them) through C, Numba and NumPy (LAPACK): C and Numba the same bits in every field; NumPy
    the same statuses and ranks, J to 1e-9."""
    m = machines[0]
    rng = np.random.default_rng(40)
    q = m.home_q + rng.uniform(-0.04, 0.04, (120, m.n_actuators))
    q[0] = np.nan
    q[1, 0] += 5.0  # no assembly
    results = {}
    for backend, env in {"native": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "1"},
                         "numba": {"PKMKIT_COMPILED": "1", "PKMKIT_NATIVE": "0"},
                         "numpy": {"PKMKIT_COMPILED": "0", "PKMKIT_NATIVE": "0"}}.items():
        for key, value in env.items():
            monkeypatch.setenv(key, value)
        results[backend] = m.jacobian(q=q)
    native, numba_, numpy_ = results.values()
    for field in ("J", "J_homogeneous", "singular_values", "condition", "passive_rates",
                  "closure_rank", "status"):
        _same_bits(getattr(native, field), getattr(numba_, field))
    np.testing.assert_array_equal(native.status, numpy_.status)
    np.testing.assert_array_equal(native.closure_rank, numpy_.closure_rank)
    ok = native.status == Status.OK
    assert ok.sum() > 100 and (~ok).sum() >= 2
    np.testing.assert_allclose(native.J[ok], numpy_.J[ok], rtol=0, atol=1e-9)


def test_two_threads_at_once():
    """Both kernels release the GIL with their own scratch per call: two threads on halves of
    a batch write what one call writes."""
    m = pkmkit.machine("trimule-600")
    cu, cq = _rates_rows(m, np.random.default_rng(50))
    values, platform = _configurations(m, np.random.default_rng(51))
    whole = (*_rates(_kernels.closure_rates, cu, cq, 1e-6, cu.shape[2]),
             _jacobians(m, values, platform, _kernels.chain_jacobian_rows))
    parts = [None, None]
    half, jac_half = len(cu) // 2, len(values) // 2

    def run(k, rows, jac_rows):
        parts[k] = (*_rates(_kernels.closure_rates, cu[rows].copy(), cq[rows].copy(), 1e-6,
                            cu.shape[2]),
                    _jacobians(m, values[jac_rows].copy(), platform[jac_rows].copy(),
                               _kernels.chain_jacobian_rows))

    threads = [threading.Thread(target=run, args=(0, slice(0, half), slice(0, jac_half))),
               threading.Thread(target=run, args=(1, slice(half, None), slice(jac_half, None)))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, part in enumerate(whole):
        _same_bits(part, np.concatenate([parts[0][k], parts[1][k]]))


def _jacobian_call(m):
    variables = _variables(m)
    args = list(chain_rows.model_arrays(m.model, variables))
    n = 6 + len(variables)
    return [*args, np.zeros((2, m.model.n_variables)), np.zeros((2, n)), 1.0,
            np.zeros((2, 6 * len(m.model.legs), n))]


def _bad(which, value):
    def change(args):
        args[which] = value(args[which]) if callable(value) else value
    return change


@pytest.mark.parametrize("change,error", [
    (_bad(0, lambda a: a[:, :3, :].copy()), ValueError),          # frames not (E, 4, 4)
    (_bad(1, lambda a: a.astype(np.int32)), TypeError),           # types not int64
    (_bad(1, lambda a: np.where(np.arange(len(a)) == 1, 3, a)), ValueError),  # type 3
    (_bad(2, lambda a: a[:-1].copy()), ValueError),                # evar not (E,)
    (_bad(3, lambda a: a + 10_000), ValueError),                   # element out of range
    (_bad(4, lambda a: a[::-1].copy()), ValueError),               # offsets decreasing
    (_bad(5, lambda a: a + 100), ValueError),                      # a column beyond u
    (_bad(6, np.zeros((2, 3))), ValueError),                       # values not (., n_var)
    (_bad(7, lambda a: np.zeros((2, 5))), ValueError),             # u with < 6 columns
    (_bad(7, lambda a: np.zeros((3, a.shape[1]))), ValueError),    # u rows ≠ values rows
    (_bad(7, lambda a: a.astype(np.float32)), TypeError),          # u not float64
    (_bad(9, lambda a: a[:, :-1].copy()), ValueError),             # out rows ≠ 6L
    (_bad(9, lambda a: a[:, :, :-1].copy()), ValueError),          # out columns ≠ n
    (_bad(9, lambda a: a[:1].copy()), ValueError),                 # out rows ≠ N
    (_bad(9, lambda a: np.asfortranarray(a)), TypeError),          # out layout
])
def test_the_jacobian_kernel_refuses_bad_arguments(change, error):
    """Wrong types, shapes, layouts and indices that would read or write out of bounds: a
    TypeError or ValueError, nothing written."""
    args = _jacobian_call(pkmkit.machine("tripteor-x7"))
    change(args)
    out = args[9]
    if isinstance(out, np.ndarray) and out.flags.writeable:
        out[...] = -5.0
    with pytest.raises(error):
        _kernels.chain_jacobian_rows(*args)
    if isinstance(out, np.ndarray):
        assert (out == -5.0).all()
    with pytest.raises(TypeError, match="10 positional"):
        _kernels.chain_jacobian_rows(*args[:9])


def _rates_call():
    return [np.zeros((2, 18, 16)), np.zeros((2, 18, 3)), 1e-9, 1e-6, 16,
            np.zeros((2, 16, 3)), np.zeros(2, dtype=np.int64), np.zeros(2)]


@pytest.mark.parametrize("change,error", [
    (_bad(0, lambda a: np.zeros((2, 15, 16))), ValueError),       # wide C_U (r < c)
    (_bad(0, lambda a: a[:, :, :0].copy()), ValueError),          # no column
    (_bad(1, lambda a: np.zeros((2, 17, 3))), ValueError),        # C_q rows ≠ C_U rows
    (_bad(1, lambda a: np.zeros((3, 18, 3))), ValueError),        # C_q configurations
    (_bad(4, 17), ValueError),                                    # expected beyond c
    (_bad(4, -16), ValueError),                                   # expected far below
    (_bad(5, lambda a: np.zeros((2, 16, 2))), ValueError),        # du columns ≠ k
    (_bad(5, lambda a: np.zeros((2, 15, 3))), ValueError),        # du rows ≠ c
    (_bad(6, lambda a: np.zeros(1, dtype=np.int64)), ValueError),  # rank rows
    (_bad(6, lambda a: np.zeros(2, dtype=np.int32)), TypeError),  # rank not int64
    (_bad(7, lambda a: np.zeros(3)), ValueError),                 # ratio rows
    (_bad(0, lambda a: a.astype(np.float32)), TypeError),         # C_U not float64
    (_bad(5, lambda a: np.asfortranarray(a)), TypeError),         # du layout
])
def test_the_rates_kernel_refuses_bad_arguments(change, error):
    args = _rates_call()
    change(args)
    with pytest.raises(error):
        _kernels.closure_rates(*args)
    with pytest.raises(TypeError, match="8 positional"):
        _kernels.closure_rates(*args[:7])


def test_jit_dispatch(monkeypatch):
    """``jit.kernel`` gives the C twins when built, the Numba kernels with
    ``PKMKIT_NATIVE=0``; with ``PKMKIT_COMPILED=0`` the velocity model keeps LAPACK."""
    from pkmkit.machines.chain_jacobians import _compiled_velocity
    from pkmkit.numerics import jit

    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    monkeypatch.delenv("PKMKIT_NATIVE", raising=False)
    assert jit.kernel(chain_rows.KERNEL, "_jacobian_rows") is _kernels.chain_jacobian_rows
    assert jit.kernel(chain_rows.LINALG, "_closure_rates_rows") is _kernels.closure_rates
    assert chain_rows.velocity_native() and _compiled_velocity(2)
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert jit.kernel(chain_rows.KERNEL, "_jacobian_rows") is numba_kernel._jacobian_rows
    assert jit.kernel(chain_rows.LINALG, "_closure_rates_rows") is \
        numba_linalg._closure_rates_rows
    assert not chain_rows.velocity_native()
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert not _compiled_velocity(100_000)


def test_a_fresh_chain_velocity_batch_does_not_import_numba():  # one process, ≈ 1.5 s
    """``m.jacobian(q=...)`` of 200 Tripteor configurations and 100 TriMule ones in a fresh
    process: the closure, its Jacobian and its rates through the C kernels (no Numba), the
    same bits as in this process (Numba or C, whichever ran here: the same bits)."""
    code = (
        "import sys, numpy as np, pkmkit\n"
        "for name, n in (('tripteor-x7', 200), ('trimule-600', 100)):\n"
        "    m = pkmkit.machine(name)\n"
        "    q = m.home_q + np.random.default_rng(0).uniform(-0.03, 0.03, (n, m.n_actuators))\n"
        "    jac = m.jacobian(q=q)\n"
        "    sys.stdout.write(jac.passive_rates.tobytes().hex()[:4000] + '\\n')\n"
        "print('numba' in sys.modules, 'pkmkit.native.kernels' in sys.modules)\n")
    env = {"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=300, check=True).stdout.strip().splitlines()
    assert out[-1] == "False True"
    for line, (name, n) in zip(out[:2], (("tripteor-x7", 200), ("trimule-600", 100)),
                               strict=True):
        m = pkmkit.machine(name)
        q = m.home_q + np.random.default_rng(0).uniform(-0.03, 0.03, (n, m.n_actuators))
        assert m.jacobian(q=q).passive_rates.tobytes().hex()[:4000] == line
