"""The vectorised full-pose inverse kernel of ``pkmkit.native`` (``native/inverse_simd.c``,
issue 22 §2: four poses per AVX2 block for machines of slides and struts) against the scalar C
kernel (``kernels.simd(False)``), the Numba kernel and the NumPy path: the same bits of q and
the same statuses on every row — random, inconsistent, far, invalid (each coordinate), beyond
the strokes, on the edge of reach (bisected), at the Rodrigues series' switch, every block
remainder and start offset, on one and two threads."""

from __future__ import annotations

import platform
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.full_pose_forms import FullPoseForms
from tests.native.test_kernels import _edge, _inverse_args, _kernels, _poses

NAMES = ["gough-stewart", "verne"]


def _has_avx2() -> bool:
    cpuinfo = Path("/proc/cpuinfo")
    return platform.machine() in ("x86_64", "AMD64") and cpuinfo.exists() and \
        " avx2" in cpuinfo.read_text()


vectorised = pytest.mark.skipif(_kernels is None or not _has_avx2(),
                                reason="no pkmkit.native.kernels, or a CPU without AVX2")


@pytest.fixture
def simd():
    """The extension with its vectorised path on, switched back on after the test."""
    _kernels.simd(True)
    yield _kernels
    _kernels.simd(True)


def _rotation_rows(m, rng):
    """Rows where the rotation's branches and inputs are odd: rotation vectors of norm 0,
    1e-300, just under and over the series' switch (1e-8), π, beyond 2π; signed zeros;
    coordinates at ±1e9 (valid) and just over (invalid); NaN and ±inf in each of the six
    columns in turn (a lane or column mixed up in the block's transposition shows)."""
    home = np.asarray(m.home_pose, dtype=float)
    rows = []
    for norm in (0.0, 1e-300, 1e-9, np.nextafter(1e-8, 0), 1e-8, 2e-8, 1e-3, 0.3, np.pi, 7.0):
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


@vectorised
def test_the_vectorised_path_is_in_use(simd):
    """On an x86-64 CPU with AVX2 the extension runs four poses per block (a build where the
    path was compiled out, or a broken CPU check, shows here); ``simd(False)`` switches it
    off."""
    assert simd.simd() == 4
    assert simd.simd(False) == 0
    assert simd.simd(True) == 4


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_vectorised_scalar_and_numba_give_the_same_bits(name, simd):
    """On the arguments ``inverse_compiled`` passes (the machine's branches, the opposite
    ones, every rod its own actuator: the consistency test off), rows of every kind: the
    vectorised kernel writes the scalar C kernel's and the Numba kernel's bits and statuses."""
    from pkmkit.machines import full_pose_kernels

    m = pkmkit.machine(name)
    rng = np.random.default_rng(7)
    x = np.concatenate([_poses(m, 3000, seed=4), _rotation_rows(m, rng)])
    forms = FullPoseForms(m.model)
    tol = m._consistency_tol()
    own = _inverse_args(forms, x, forms.rod_branch, tol)
    rods = np.arange(m.model.n_rods)
    own[14:17] = rods[:, None], np.ones_like(rods), np.zeros(m.model.n_rods, dtype=bool)
    for args in (_inverse_args(forms, x, forms.rod_branch, tol),
                 _inverse_args(forms, x, -forms.rod_branch, tol), own):
        vector = _run(simd.inverse_poses, args, x)
        simd.simd(False)
        scalar = _run(simd.inverse_poses, args, x)
        simd.simd(True)
        numba = _run(full_pose_kernels.inverse_poses, args, x)
        _same_bits(vector, scalar)
        _same_bits(vector, numba)
        assert {0, 4} <= set(vector[1].tolist())
        assert (vector[1] == 4).sum() == 3 + 6 * 4  # _poses' three, 4 invalid values × 6 columns
    statuses = _run(simd.inverse_poses, _inverse_args(forms, x, forms.rod_branch, tol), x)[1]
    assert (statuses == 1).sum() >= 50 or name == "gough-stewart"  # struts always close


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_vectorised_against_the_numpy_path(name, simd, monkeypatch):
    """``m.ik(X, full_output=True)`` by the vectorised C kernel and by the NumPy path (the
    independent oracle, other operations): the same statuses and stroke flags, q to 1e-12 (on
    the edge of reach, where rounding decides, the same statuses are not required)."""
    m = pkmkit.machine(name)
    x = _poses(m, 4000, seed=5)
    out = {}
    for compiled in ("1", "0"):
        monkeypatch.setenv("PKMKIT_COMPILED", compiled)
        monkeypatch.setenv("PKMKIT_NATIVE", compiled)
        out[compiled] = m.ik(x, full_output=True, strokes="ignore")
    keep = ~_edge(len(x))
    np.testing.assert_array_equal(out["1"].status[keep], out["0"].status[keep])
    np.testing.assert_allclose(out["1"].q[keep], out["0"].q[keep], rtol=0, atol=1e-12,
                               equal_nan=True)
    assert (out["1"].status == 0).sum() > 1000


@vectorised
@pytest.mark.parametrize("name", NAMES)
def test_every_block_remainder_and_offset(name, simd):
    """Batches of 0 to 15 rows starting at every offset 0 to 7 (the last block partial or the
    scalar tail, unaligned starts): the vectorised kernel's bits are the scalar kernel's."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(8)
    x = np.concatenate([_poses(m, 200, seed=6), _rotation_rows(m, rng)])
    x = x[rng.permutation(len(x))]  # rows of every kind in each window
    forms = FullPoseForms(m.model)
    args = _inverse_args(forms, x, forms.rod_branch, m._consistency_tol())
    for start in range(8):
        for rows in range(16):
            part = x[start * 31: start * 31 + rows]  # views: the buffer starts anywhere
            vector = _run(simd.inverse_poses, args, part)
            simd.simd(False)
            scalar = _run(simd.inverse_poses, args, part)
            simd.simd(True)
            _same_bits(vector, scalar)


@vectorised
@pytest.mark.parametrize("threads", ["1", "2"])
def test_vectorised_on_threads(threads, simd, monkeypatch):
    """``m.ik`` of a batch cut into chunks on one and two threads (odd chunk ends: block
    remainders inside the batch): the same bits with the vectorised path on and off."""
    from pkmkit.numerics import jit

    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    monkeypatch.setenv("PKMKIT_NATIVE", "1")
    monkeypatch.setenv("PKMKIT_THREADS", threads)
    for name in NAMES:
        m = pkmkit.machine(name)
        x = _poses(m, 2 * jit.THREAD_ROWS + 7, seed=9)
        on = m.ik(x, full_output=True, strokes="ignore")
        simd.simd(False)
        off = m.ik(x, full_output=True, strokes="ignore")
        simd.simd(True)
        np.testing.assert_array_equal(on.status, off.status)
        np.testing.assert_array_equal(np.asarray(on.q).view(np.int64),
                                      np.asarray(off.q).view(np.int64))
        assert (on.status == 0).sum() > 1000
