"""The vectorised full-pose inverse kernel of ``pkmkit.native`` (``native/inverse_simd.c``,
``inverse_block.h``; issue 22 §2: eight poses per AVX-512 block, four per AVX2 one, for
machines of slides and struts) against the scalar C kernel (``kernels.simd(False)``), the
Numba kernel and the NumPy path.

The vectorised kernel computes sin and cos by its own sincos (not libm's, which cost half the
kernel) — and for rotations up to 1 rad sin/θ and cos by their Taylor series in θ², with no
square root, reduction or division but the one of (1 − cos θ)/θ²: both are tested against
mpmath (the sincos at most 1 ulp on [0, 2π], q of the series path against an exact q), so q may
differ from the libm-based paths in its last bits — within 4 ulp of the leg here (measured:
3 ulp over 10⁷ hexapod poses, the same distance as the scalar C kernel's from the NumPy path;
``bench/full_pose.py --accuracy``). Everything else is bit for bit: rows without a rotation
(no sin or cos) give the scalar kernel's bits, both widths give the same bits, and a row's
bits do not depend on where it falls in the batch (block remainders, offsets, threads);
statuses are the scalar kernel's except on the edge of reach."""

from __future__ import annotations

import platform
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.full_pose_forms import FullPoseForms
from tests.native.test_kernels import _edge, _inverse_args, _kernels, _poses

NAMES = ["gough-stewart", "verne"]


def _cpu_flags() -> str:
    cpuinfo = Path("/proc/cpuinfo")
    if platform.machine() not in ("x86_64", "AMD64") or not cpuinfo.exists():
        return ""
    return cpuinfo.read_text()


def _has_avx2() -> bool:
    return " avx2" in _cpu_flags()


def _widths() -> list[int]:
    """The block widths this CPU runs: 4 (AVX2), and 8 where it has AVX-512 F and DQ."""
    flags = _cpu_flags()
    return [4] + ([8] if " avx512f" in flags and " avx512dq" in flags else [])


vectorised = pytest.mark.skipif(_kernels is None or not _has_avx2(),
                                reason="no pkmkit.native.kernels, or a CPU without AVX2")

#: Largest difference of q between the vectorised kernel (its own sincos) and the libm-based
#: paths, in ulps of the leg (module docstring).
LEG_ULPS = 4.0


@pytest.fixture
def simd():
    """The extension with its vectorised path on, switched back on after the test."""
    _kernels.simd(True)
    yield _kernels
    _kernels.simd(True)


def _rotation_rows(m, rng):
    """Rows where the rotation's branches and inputs are odd: rotation vectors of norm 0,
    1e-300, just under and over the series' switch (1e-8), around the switch from the Taylor
    series of sin/θ and cos to the sincos (1 rad), in each quadrant of the sincos'
    reduction, π, beyond 2π, around its switch to libm (1e5); signed zeros; coordinates at
    ±1e9 (valid) and just over (invalid); NaN and ±inf in each of the six columns in turn (a
    lane or column mixed up in the block's transposition shows)."""
    home = np.asarray(m.home_pose, dtype=float)
    rows = []
    for norm in (0.0, 1e-300, 1e-9, np.nextafter(1e-8, 0), 1e-8, 2e-8, 1e-3, 0.3, 0.9,
                 np.nextafter(1.0, 0), 1.0, np.nextafter(1.0, 2), 1.2, 2.0, np.pi, 4.0, 5.0, 7.0,
                 1e5, np.nextafter(1e5, 2e5), 3e5):
        direction = rng.normal(size=3)
        rows.append(np.concatenate([home[:3], norm * direction / np.linalg.norm(direction)]))
    rows.append(np.concatenate([home[:3], [-0.0, 0.0, -0.0]]))
    for value in (1e9, -1e9, np.nextafter(1e9, 2e9), np.nan, np.inf, -np.inf):
        for column in range(6):
            row = home.copy()
            row[column] = value
            rows.append(row)
    return np.array(rows)


def _run(kernel, args, x):
    q = np.empty((len(x), len(args[15])))
    status = np.empty(len(x), dtype=np.int64)
    kernel(x, *args[1:], q, status)
    return q, status


def _same_bits(a, b):
    """q arrays equal bit for bit (NaN included), statuses equal."""
    np.testing.assert_array_equal(a[1], b[1])
    np.testing.assert_array_equal(a[0].view(np.int64), b[0].view(np.int64))


def _leg_scale(m, args):
    """Per actuator, the length against which q's ulps are counted: its first rod's length."""
    return m.model.rod_length[np.asarray(args[14])[:, 0]]


def _close(a, b, scale, edge=None):
    """Statuses equal (but on the ``edge`` rows), NaN on the same rows, q within
    :data:`LEG_ULPS` ulps of the leg (the larger of |q| and ``scale``)."""
    keep = np.ones(len(a[1]), dtype=bool) if edge is None else ~edge
    np.testing.assert_array_equal(a[1][keep], b[1][keep])
    both = (a[1] == 0) & (b[1] == 0)
    np.testing.assert_array_equal(np.isnan(a[0][both]), np.isnan(b[0][both]))
    np.testing.assert_array_equal(np.isnan(a[0][~both & keep]), True)
    ulp = np.spacing(np.maximum(np.abs(b[0][both]), scale))
    assert np.all(np.abs(a[0][both] - b[0][both]) <= LEG_ULPS * ulp)


@vectorised
def test_the_vectorised_path_is_in_use(simd):
    """On an x86-64 CPU the extension runs the widest blocks it has (a build where a path was
    compiled out, or a broken CPU check, shows here); ``simd(4)`` / ``simd(8)`` ask for a
    width (0 where the CPU lacks it), ``simd(False)`` switches it off, anything else is
    refused."""
    widths = _widths()
    assert simd.simd() == max(widths)
    assert simd.simd(4) == 4
    assert simd.simd(8) == (8 if 8 in widths else 0)
    assert simd.simd(False) == 0
    assert simd.simd(True) == max(widths)
    with pytest.raises(ValueError, match="choice"):
        simd.simd(3)
    assert simd.simd() == max(widths)


def _angles(rng):
    """Angles where a sincos goes wrong: uniform over [0, 2π] (every quadrant), the doubles
    nearest multiples of π/2 (the reduction's cancellation) and just under, tiny ones, large
    ones up to the switch to libm (1e5) and beyond it."""
    near = np.arange(1, 400) * (np.pi / 2)
    return np.concatenate([rng.uniform(0, 2 * np.pi, 3000), near, np.nextafter(near, 0),
                           rng.uniform(0, 1e-3, 200), [0.0, 5e-324, 1e-300, 1e-8],
                           rng.uniform(2 * np.pi, 1e5, 500), [1e5, np.nextafter(1e5, 2e5)],
                           rng.uniform(1e5, 1e9, 50)])


@vectorised
def test_the_vectorised_sincos_against_mpmath(simd):
    """The kernel's own sin and cos (``simd_sincos``) against mpmath at 200 bits (an
    independent oracle): at most 1 ulp on [0, 2π] — every rotation of norm up to 2π —, 2.1 ulp
    up to 1e5, never more than 1.4e-16 absolute; libm's bits beyond 1e5; both widths the same
    bits."""
    mpmath = pytest.importorskip("mpmath")
    t = _angles(np.random.default_rng(11))
    got = {}
    for width in _widths():
        assert simd.simd(width) == width
        s, c = np.empty_like(t), np.empty_like(t)
        assert simd.simd_sincos(t, s, c) == width
        got[width] = (s, c)
    s, c = got[4]
    for width in _widths():
        np.testing.assert_array_equal(got[width][0].view(np.int64), s.view(np.int64))
        np.testing.assert_array_equal(got[width][1].view(np.int64), c.view(np.int64))
    far = t > 1e5
    np.testing.assert_array_equal(s[far], np.sin(t[far]))
    np.testing.assert_array_equal(c[far], np.cos(t[far]))
    with mpmath.workprec(200):
        exact_s = np.array([float(mpmath.sin(mpmath.mpf(v))) for v in t[~far]])
        exact_c = np.array([float(mpmath.cos(mpmath.mpf(v))) for v in t[~far]])
    turn = t[~far] <= 2 * np.pi
    for value, exact in ((s[~far], exact_s), (c[~far], exact_c)):
        gap = np.abs(value - exact)
        ulps = gap / np.spacing(np.abs(exact))
        assert ulps[turn].max() <= 1.0
        assert ulps.max() <= 2.1
        assert gap.max() <= 1.4e-16


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_vectorised_scalar_and_numba(name, simd):
    """On the arguments ``inverse_compiled`` passes (the machine's branches, the opposite
    ones, every rod its own actuator: the consistency test off), rows of every kind: the
    vectorised kernel (each width) gives the scalar C kernel's and the Numba kernel's statuses
    but on the edge of reach, and q within :data:`LEG_ULPS` ulps of the leg; without a
    rotation (no sin or cos) their very bits; both widths the same bits."""
    from pkmkit.machines import full_pose_kernels

    m = pkmkit.machine(name)
    rng = np.random.default_rng(7)
    x = np.concatenate([_poses(m, 3000, seed=4), _rotation_rows(m, rng)])
    edge = np.concatenate([_edge(3000), np.zeros(len(x) - 3000, dtype=bool)])
    still = x.copy()
    still[:, 3:] = np.where(np.isfinite(x[:, 3:]) & (np.abs(x[:, 3:]) < 1e5), 0.0, x[:, 3:])
    forms = FullPoseForms(m.model)
    tol = m._consistency_tol()
    own = _inverse_args(forms, x, forms.rod_branch, tol)
    rods = np.arange(m.model.n_rods)
    own[14:17] = rods[:, None], np.ones_like(rods), np.zeros(m.model.n_rods, dtype=bool)
    for args in (_inverse_args(forms, x, forms.rod_branch, tol),
                 _inverse_args(forms, x, -forms.rod_branch, tol), own):
        simd.simd(False)
        scalar, scalar_still = _run(simd.inverse_poses, args, x), _run(simd.inverse_poses,
                                                                       args, still)
        simd.simd(True)
        numba = _run(full_pose_kernels.inverse_poses, args, x)
        _same_bits(scalar, numba)
        simd.simd(4)
        four = _run(simd.inverse_poses, args, x)
        for width in _widths():
            simd.simd(width)
            vector = _run(simd.inverse_poses, args, x)
            _close(vector, scalar, _leg_scale(m, args), edge)
            _same_bits(_run(simd.inverse_poses, args, still), scalar_still)
            _same_bits(vector, four)
            assert {0, 4} <= set(vector[1].tolist())
            assert (vector[1] == 4).sum() == 3 + 6 * 4  # _poses' three, 4 invalid × 6 columns
        simd.simd(True)
    statuses = _run(simd.inverse_poses, _inverse_args(forms, x, forms.rod_branch, tol), x)[1]
    assert (statuses == 1).sum() >= 50 or name == "gough-stewart"  # struts always close


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_vectorised_against_the_numpy_path(name, simd, monkeypatch):
    """``m.ik(X, full_output=True)`` by the vectorised C kernel and by the NumPy path (the
    independent oracle, other operations): the same statuses, q within
    :data:`LEG_ULPS` ulps of the leg (on the edge of reach, where rounding decides, the same
    statuses are not required)."""
    m = pkmkit.machine(name)
    x = _poses(m, 4000, seed=5)
    out = {}
    for compiled in ("1", "0"):
        monkeypatch.setenv("PKMKIT_COMPILED", compiled)
        monkeypatch.setenv("PKMKIT_NATIVE", compiled)
        out[compiled] = m.ik(x, full_output=True, strokes="ignore")
    keep = ~_edge(len(x))
    np.testing.assert_array_equal(out["1"].status[keep], out["0"].status[keep])
    first = [int(np.flatnonzero(m.model.rod_actuator == k)[0]) for k in range(m.n_actuators)]
    _close((np.asarray(out["1"].q), out["1"].status), (np.asarray(out["0"].q), out["0"].status),
           m.model.rod_length[first], _edge(len(x)))
    assert (out["1"].status == 0).sum() > 1000


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_every_block_remainder_and_offset(name, simd):
    """Batches of 0 to 19 rows starting at every offset 0 to 9 (the last block partial, padded
    into a whole one; unaligned starts): each row's bits are those it has in the whole batch,
    wherever it falls in a block, at each width."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(8)
    x = np.concatenate([_poses(m, 200, seed=6), _rotation_rows(m, rng)])
    x = x[rng.permutation(len(x))]  # rows of every kind in each window
    forms = FullPoseForms(m.model)
    args = _inverse_args(forms, x, forms.rod_branch, m._consistency_tol())
    for width in _widths():
        simd.simd(width)
        whole = _run(simd.inverse_poses, args, x)
        for start in range(10):
            for rows in range(20):
                window = slice(start * 31, start * 31 + rows)  # views: the buffer starts anywhere
                part = _run(simd.inverse_poses, args, x[window])
                _same_bits(part, (whole[0][window], whole[1][window]))


@vectorised
@pytest.mark.parametrize("threads", ["1", "2"])
def test_vectorised_on_threads(threads, simd, monkeypatch):
    """``m.ik`` of a batch cut into chunks on one and two threads (odd chunk ends: block
    remainders inside the batch): the bits of the kernel run on the whole batch at once, and
    the scalar kernel's statuses and q within :data:`LEG_ULPS` ulps with the path off."""
    from pkmkit.numerics import jit

    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    monkeypatch.setenv("PKMKIT_NATIVE", "1")
    monkeypatch.setenv("PKMKIT_THREADS", threads)
    for name in NAMES:
        m = pkmkit.machine(name)
        x = _poses(m, 2 * jit.THREAD_ROWS + 7, seed=9)
        on = m.ik(x, full_output=True, strokes="ignore")
        forms = FullPoseForms(m.model)
        args = _inverse_args(forms, x, forms.rod_branch, m._consistency_tol())
        _same_bits((np.asarray(on.q), on.status), _run(simd.inverse_poses, args, x))
        simd.simd(False)
        off = m.ik(x, full_output=True, strokes="ignore")
        simd.simd(True)
        _close((np.asarray(on.q), on.status), (np.asarray(off.q), off.status),
               _leg_scale(m, args), _edge(len(x)))
        assert (on.status == 0).sum() > 1000


def _exact_strut_q(m, row, mpmath):
    """q of every strut of ``m`` at pose ``row`` in mpmath (the caller's precision): Rodrigues'
    rotation from mpmath's sin and cos, |p + R b − a| − L."""
    px, py, pz, wx, wy, wz = (mpmath.mpf(float(v)) for v in row)
    theta = mpmath.sqrt(wx * wx + wy * wy + wz * wz)
    a = mpmath.sin(theta) / theta if theta else mpmath.mpf(1)
    b = (1 - mpmath.cos(theta)) / theta**2 if theta else mpmath.mpf(1) / 2
    w = (wx, wy, wz)
    skew = [[0, -wz, wy], [wz, 0, -wx], [-wy, wx, 0]]
    rot = [[(i == j) + a * skew[i][j] + b * (w[i] * w[j] - (i == j) * theta**2)
            for j in range(3)] for i in range(3)]
    out = []
    rods = zip(m.model.rod_base, m.model.rod_platform, m.model.rod_length, strict=True)
    for base, plat, length in rods:
        v = [(px, py, pz)[i] + sum(rot[i][j] * mpmath.mpf(float(plat[j])) for j in range(3))
             - mpmath.mpf(float(base[i])) for i in range(3)]
        out.append(float(mpmath.sqrt(sum(c * c for c in v)) - mpmath.mpf(float(length))))
    return np.array(out)


@vectorised
def test_the_series_rotation_against_mpmath(simd):
    """Rotations of norm up to 1 rad (the Taylor series of sin/θ and cos, no sincos) and just
    beyond (the sincos): the hexapod's q (six struts, one per actuator) at each width within
    :data:`LEG_ULPS` ulps of the leg of q computed in mpmath at 120 bits (an independent
    oracle: mpmath's sin and cos, the rotation matrix from its axis-angle form) — as the scalar
    kernel (libm) is; both widths the same bits."""
    mpmath = pytest.importorskip("mpmath")
    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(12)
    norms = np.concatenate([rng.uniform(0, 1, 150), 10.0 ** rng.uniform(-8, 0, 60),
                            np.nextafter(1.0, [0.0, 2.0]), [1.0, 0.999, 1.001, 1.05]])
    direction = rng.normal(size=(len(norms), 3))
    x = np.empty((len(norms), 6))
    x[:, :3] = m.home_pose[:3] + rng.uniform(-0.05, 0.05, (len(norms), 3))
    x[:, 3:] = norms[:, None] * direction / np.linalg.norm(direction, axis=1)[:, None]
    forms = FullPoseForms(m.model)
    args = _inverse_args(forms, x, forms.rod_branch, m._consistency_tol())
    with mpmath.workprec(120):
        exact = np.array([_exact_strut_q(m, row, mpmath) for row in x])
    scale = np.spacing(np.maximum(np.abs(exact), m.model.rod_length))
    simd.simd(False)
    scalar = _run(simd.inverse_poses, args, x)
    got = {}
    for width in _widths():
        simd.simd(width)
        got[width] = _run(simd.inverse_poses, args, x)
    simd.simd(True)
    for q, status in (scalar, *got.values()):
        assert (status == 0).all()
        assert np.all(np.abs(q - exact) <= LEG_ULPS * scale)
    for width in _widths():
        _same_bits(got[width], got[4])


@pytest.mark.parametrize("threads", ["1", "2"])
def test_a_plain_ik_skips_the_statuses(threads, monkeypatch):
    """``inverse_compiled(..., statuses=False)`` (a plain ``m.ik(X)``: nothing reads the
    statuses) gives None for them and q bit for bit as with the statuses, over several
    thread pieces with rows of every kind; ``m.ik(X)`` equals ``m.ik(X, full_output=True).q``."""
    from pkmkit.numerics import jit

    monkeypatch.setenv("PKMKIT_THREADS", threads)
    for name in NAMES:
        m = pkmkit.machine(name)
        x = _poses(m, 2 * jit.THREAD_ROWS + 13, seed=14)
        forms = FullPoseForms(m.model)
        sigma, tol = forms.rod_branch, m._consistency_tol()
        q, status = forms.inverse_compiled(x, sigma, tol)
        bare, none = forms.inverse_compiled(x, sigma, tol, statuses=False)
        assert none is None and {0, 4} <= set(status.tolist())  # OK and invalid rows
        _same_bits((bare, status), (q, status))
        plain = m.ik(x, strokes="ignore")
        _same_bits((plain, status), (np.asarray(m.ik(x, full_output=True, strokes="ignore").q),
                                     status))
