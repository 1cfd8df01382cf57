"""The C velocity summaries of square translational rod-leg machines (``pkmkit.native.kernels``
``rod_velocity3``, ``rod_velocity2``, ``native/rod_velocity.c``; issue 22 §5) against their
Numba twins (:func:`pkmkit.machines.kernels.velocity3`, ``velocity2``) **bit for bit** on every
output (det A, singular values, condition, serial measure, the rows left to the reference),
at random poses in and far beyond the workspace, on segments crossing parallel singularities
and at poses bisected onto them (det A changing sign), at coinciding singular values, and on
invalid rows (NaN, ±inf, huge, tiny); ``m.jacobian`` of a large batch through the C kernel
against the NumPy reference (the independent oracle); the polynomial shared with the Numba
kernel; the arguments refused (a fresh process: tests/native/test_fresh_commands.py)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.velocity import NEAR_PARALLEL
from pkmkit.numerics import jit
from tests.conftest import PRESETS, random_poses

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = [pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "rod_velocity3"),
                                 reason="pkmkit.native.kernels was not built"),
              pytest.mark.filterwarnings("ignore::pkmkit.exceptions.StrokeWarning")]

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def _machines() -> dict[str, pkmkit.Machine]:
    out = {name: pkmkit.machine(name) for name in PRESETS}
    out["strut-tripod"] = pkmkit.load(EXAMPLES / "strut-tripod.toml")
    # the kernels take slides and struts (machines with cranks keep the NumPy path)
    return {k: m for k, m in out.items() if not m._closed.crank.any()}


MACHINES = _machines()


def _poses(m: pkmkit.Machine, n: int, seed: int) -> np.ndarray:
    """Random poses in the workspace, far beyond it, on segments from home that cross
    parallel singularities, and invalid rows."""
    rng = np.random.default_rng(seed)
    x = random_poses(m, n, seed)
    spread = 2.0 * float(m.model.leg_length.max())
    x[: n // 4] = m.home_pose + rng.uniform(-spread, spread, (n // 4, m.dims))
    far = m.home_pose + rng.uniform(-1.5, 1.5, (n // 4, m.dims)) * spread / 2.0
    x[n // 4: n // 2] = m.home_pose + rng.uniform(0, 1, (n // 4, 1)) * (far - m.home_pose)
    x[5] = np.nan
    x[6, 0] = np.inf
    x[7, -1] = -np.inf
    x[8] = 1e200
    x[9] = 1e-300
    x[10] = m.home_pose
    return x


def _run(kernel, m: pkmkit.Machine, x: np.ndarray, q: np.ndarray, limit: float) -> list:
    closed, n, size = m._closed, m.dims, x.shape[0]
    out = [np.full(size, 7.0), np.full((n, size), 7.0), np.full(size, 7.0),
           np.full(size, 7.0), np.zeros(size, dtype=bool)]
    kernel(np.ascontiguousarray(x), np.ascontiguousarray(q.T),
           np.ascontiguousarray(closed.centre0), np.ascontiguousarray(closed.axis),
           np.ascontiguousarray(closed.slide > 0),
           np.ascontiguousarray(m.model.leg_length, dtype=float), limit, *out)
    return out


def _compare(m: pkmkit.Machine, x: np.ndarray, q: np.ndarray, limit: float, where: str):
    from pkmkit.machines import kernels

    name = "velocity3" if m.dims == 3 else "velocity2"
    got = _run(getattr(_kernels, "rod_" + name), m, x, q, limit)
    want = _run(getattr(kernels, name), m, x, q, limit)
    for label, g, w in zip(("det", "sv", "cond", "serial", "hard"), got, want, strict=True):
        if g.dtype == bool:
            assert np.array_equal(g, w), (where, label, np.flatnonzero(g != w)[:5])
        else:
            same = g.view(np.int64) == w.view(np.int64)
            assert same.all(), (where, label, np.argwhere(~same)[:5], g[~same][:5],
                                w[~same][:5])
    return got


@pytest.mark.parametrize("name", list(MACHINES))
@pytest.mark.parametrize("limit", [NEAR_PARALLEL, 1e-6, 0.05])
def test_bits_of_numba(name, limit):
    m = MACHINES[name]
    x = _poses(m, 4000, seed=len(name))
    q = m.ik(x)
    got = _compare(m, x, q, limit, name)
    hard, det = got[4], got[0]
    finite = np.isfinite(q).all(axis=1) & np.isfinite(x).all(axis=1)
    assert finite.sum() > 1000 and (~hard & finite).sum() > 1000
    assert hard.any() or limit < 0.05  # rows left to the reference
    assert np.isnan(det[~np.isfinite(x).all(axis=1)]).all()
    # q chosen freely: rows whose actuators do not close (A and B still defined)
    rng = np.random.default_rng(9)
    q_free = q.copy()
    q_free[::3] = rng.uniform(-2, 2, q_free[::3].shape)
    q_free[4] = np.nan
    q_free[11, 0] = np.inf
    # degenerate rows: sums that overflow from finite inputs (B's entries, not A's), and a
    # pose on a leg's joint (a zero row of A: the bound is 0/0)
    closed = m._closed
    q_free[12:15] = 0.1
    x[12] = 1.5e308
    x[13] = -1.5e308
    x[13, 0] = 1.5e308
    x[14] = closed.centre0[0] + q_free[14, 0] * closed.axis[0]
    got = _compare(m, x, q_free, limit, name + " free q")
    assert got[4][14] and np.isnan(got[0][12]) and np.isnan(got[3][12])


@pytest.mark.parametrize("name", list(MACHINES))
def test_bits_at_bisected_parallel_singularities(name):
    """Poses bisected to where det A changes sign along segments from home (1e-13 of the
    segment apart; the actuators held at home's, so that every machine's segments cross
    det A = 0), and where two singular values coincide (Orthoglide's diagonal)."""
    m = MACHINES[name]
    rng = np.random.default_rng(31)
    spread = 3.0 * float(m.model.leg_length.max())
    ends = m.home_pose + rng.uniform(-spread, spread, (600, m.dims))
    q_home = np.tile(m.ik(m.home_pose[None]), (len(ends), 1))

    def det_at(t):
        x = m.home_pose + t[:, None] * (ends - m.home_pose)
        return _run(_kernels.rod_velocity3 if m.dims == 3 else _kernels.rod_velocity2, m, x,
                    q_home[: len(x)], NEAR_PARALLEL)[0], x

    ts = np.linspace(0.0, 1.0, 41)
    dets = np.stack([det_at(np.full(len(ends), t))[0] for t in ts])
    lo, hi = np.zeros(len(ends)), np.full(len(ends), np.nan)
    for k in range(1, len(ts)):
        flip = np.isnan(hi) & (np.sign(dets[k]) * np.sign(dets[k - 1]) < 0)
        lo[flip], hi[flip] = ts[k - 1], ts[k]
    keep = np.isfinite(hi)
    assert keep.sum() >= 10, name
    lo, hi, ends, q_home = lo[keep], hi[keep], ends[keep], q_home[keep]
    d_lo = det_at(lo)[0]
    for _ in range(45):
        mid = 0.5 * (lo + hi)
        d_mid = det_at(mid)[0]
        same = np.sign(d_mid) == np.sign(d_lo)
        lo, d_lo = np.where(same, mid, lo), np.where(same, d_mid, d_lo)
        hi = np.where(same, hi, mid)
    x = np.concatenate([m.home_pose + lo[:, None] * (ends - m.home_pose),
                        m.home_pose + hi[:, None] * (ends - m.home_pose)])
    got = _compare(m, x, np.concatenate([q_home, q_home]), NEAR_PARALLEL, name + " bisected")
    assert got[4][np.isfinite(got[0])].all()  # all left to the reference there
    if name == "orthoglide":
        diag = np.linspace(-0.05, 0.05, 101)[:, None] * np.ones(3)
        got = _compare(m, diag, m.ik(diag), NEAR_PARALLEL, "diagonal")
        assert got[4].sum() >= 90  # coinciding singular values: left to the reference


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta-ch3", "five-bar-biglide",
                                  "strut-tripod"])
def test_jacobian_batch_against_the_numpy_reference(name, monkeypatch):
    """``m.jacobian`` of a batch large enough for the kernel, through the C kernel (Numba not
    imported, as in a fresh process), against the NumPy reference (``PKMKIT_COMPILED=0``)."""
    m = MACHINES[name]
    x = _poses(m, jit.MIN_ROWS + 100, seed=3)
    monkeypatch.delitem(sys.modules, "numba", raising=False)  # put back after the test
    calls = []
    real = jit.kernel

    def spy(module, kernel_name):
        function = real(module, kernel_name)
        calls.append(function)
        return function

    monkeypatch.setattr(jit, "kernel", spy)
    jac = m.jacobian(x)
    fields = {f: getattr(jac, f) for f in ("singular_values", "condition", "det_A",
                                          "serial_measure", "singularity")}
    # the velocity kernel's C twin, after the inverse model's (rod_batch.c) where x alone
    # was given: every kernel taken is a C twin
    assert calls[-1] is (_kernels.rod_velocity3 if m.dims == 3 else _kernels.rod_velocity2)
    assert all(getattr(_kernels, f.__name__, None) is f for f in calls), calls
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    ref = m.jacobian(x)
    assert np.isfinite(fields["condition"]).sum() > 1000
    for f, got in fields.items():
        want = getattr(ref, f)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=f)
        if got.dtype.kind == "f":
            np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-14, err_msg=f)
        else:
            np.testing.assert_array_equal(got, want, err_msg=f)


def test_velocity3_twin_only_until_numba_is_imported(monkeypatch):
    """The planar twin runs at Numba's speed and is always taken; the spatial one is slower
    than Numba's vectorised loop once both are loaded, so Numba's is taken after its import
    (the same bits, test_bits_of_numba)."""
    from pkmkit.machines import kernels

    assert "numba" in sys.modules  # imported by the module above
    assert jit.kernel("pkmkit.machines.kernels", "velocity3") is kernels.velocity3
    assert jit.kernel("pkmkit.machines.kernels", "velocity2") is _kernels.rod_velocity2
    monkeypatch.delitem(sys.modules, "numba")
    assert jit.kernel("pkmkit.machines.kernels", "velocity3") is _kernels.rod_velocity3


def test_polynomial_is_the_numba_kernels():
    from pkmkit.machines import cos_third, kernels

    assert kernels._COS_THIRD is cos_third.COEFFICIENTS
    assert cos_third.COEFFICIENTS.shape == (13,) and cos_third.COEFFICIENTS.dtype == float
    h = np.linspace(-1, 1, 2001)
    c = np.array([kernels._cos_third(v) for v in h])
    # exact to rounding after the Newton steps, but at h = -1 (slope 0: the polynomial, 2e-12)
    np.testing.assert_allclose(c[1:], np.cos(np.arccos(h[1:]) / 3.0), rtol=0, atol=1e-15)
    assert abs(c[0] - 0.5) < 2e-12


def test_refused_arguments():
    m = MACHINES["orthoglide"]
    closed = m._closed
    x = np.zeros((4, 3))
    q = np.zeros((3, 4))
    legs = (np.ascontiguousarray(closed.centre0), np.ascontiguousarray(closed.axis),
            np.ascontiguousarray(closed.slide > 0),
            np.ascontiguousarray(m.model.leg_length, dtype=float))
    out = [np.empty(4), np.empty((3, 4)), np.empty(4), np.empty(4), np.empty(4, dtype=bool)]
    _kernels.rod_velocity3(x, q, *legs, 1e-3, *out)
    with pytest.raises(ValueError):
        _kernels.rod_velocity3(x, np.zeros((3, 5)), *legs, 1e-3, *out)
    with pytest.raises(ValueError):
        _kernels.rod_velocity2(x, q, *legs, 1e-3, *out)  # 3 columns, 2 legs
    with pytest.raises(ValueError):
        _kernels.rod_velocity3(x, q, *legs, 1e-3, out[0], np.empty((2, 4)), *out[2:])
    with pytest.raises(TypeError):
        _kernels.rod_velocity3(x, q, *legs[:2], legs[2].astype(float), legs[3], 1e-3, *out)
    with pytest.raises(TypeError):
        _kernels.rod_velocity3(x, q, *legs, "tol", *out)
    with pytest.raises(TypeError):
        _kernels.rod_velocity3(x, q, *legs, 1e-3, *out[:4], np.empty(4))  # hard: bool
    with pytest.raises(TypeError):
        _kernels.rod_velocity3(np.zeros((3, 4)).T, q, *legs, 1e-3, *out)  # not C-ordered
    with pytest.raises(TypeError):
        _kernels.rod_velocity3(x, q, *legs, 1e-3)
