"""The C batched singular values (``pkmkit.native.kernels`` ``singular_values``,
``singular_rates``, ``native/svd.c``; issue 22 §5) against their Numba twins
(:mod:`pkmkit.numerics.svd_kernel`, :mod:`pkmkit.numerics.svd_rates_kernel`) **bit for bit**,
and both against LAPACK (``np.linalg.svd``: the independent oracle) to rounding: random
matrices of every shape a study uses and more, rank-deficient and nearly singular ones, tiny
and huge scales, repeated singular values, non-finite rows; the outputs' untouched shape on
empty batches; the arguments the C kernels refuse; the dispatch of
:func:`pkmkit.numerics.linalg.small_singular_values` / ``singular_value_rates``."""

from __future__ import annotations

import numpy as np
import pytest

from pkmkit.numerics import jit, linalg

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "singular_rates"),
                                reason="pkmkit.native.kernels was not built")

SHAPES = [(6, 6), (3, 6), (6, 3), (2, 2), (3, 3), (6, 5), (5, 6), (1, 4), (4, 1), (1, 1),
          (8, 7)]


def _bits(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a).view(np.int64)


def _same_bits(got: np.ndarray, want: np.ndarray, what: str) -> None:
    assert got.shape == want.shape, what
    same = _bits(got) == _bits(want)
    assert same.all(), (what, np.argwhere(~same)[:5], got[~same][:5], want[~same][:5])


def _hard_stack(shape: tuple[int, int], n: int, seed: int) -> np.ndarray:
    """``n`` matrices of ``shape``: random ones at scales 1e-8..1e8, rank-deficient (a zero
    column, a repeated column, a repeated row), nearly singular (a column 1e-14 from another),
    repeated singular values (orthogonal times a scalar), the zero matrix, tiny (1e-160) and
    huge (1e150) scales, and NaN / ±inf entries."""
    rng = np.random.default_rng(seed)
    r, c = shape
    m = rng.standard_normal((n, r, c)) * 10.0 ** rng.uniform(-8, 8, (n, 1, 1))
    kinds = 12
    for k in range(0, n, kinds):
        if c > 1:
            m[k, :, 0] = 0.0
            m[k + 1, :, 1] = m[k + 1, :, 0]
            m[k + 2, :, 1] = m[k + 2, :, 0] + 1e-14 * rng.standard_normal(r)
        if r > 1:
            m[k + 3, 1] = m[k + 3, 0]
        q, _ = np.linalg.qr(rng.standard_normal((max(r, c), max(r, c))))
        m[k + 4] = 3.0 * q[:r, :c]
        m[k + 5] = 0.0
        m[k + 6] *= 1e-160 / np.abs(m[k + 6]).max()
        m[k + 7] *= 1e150 / np.abs(m[k + 7]).max()
        m[k + 8, rng.integers(r), rng.integers(c)] = np.nan
        m[k + 9, rng.integers(r), rng.integers(c)] = np.inf
        m[k + 10, rng.integers(r), rng.integers(c)] = -np.inf
    return m


@pytest.mark.parametrize("shape", SHAPES)
def test_singular_values_bits_of_numba(shape):
    from pkmkit.numerics import svd_kernel

    m = _hard_stack(shape, 1200, seed=sum(shape))
    k = min(shape)
    got, want = np.full((m.shape[0], k), 7.0), np.full((m.shape[0], k), 7.0)
    _kernels.singular_values(m, got)
    svd_kernel.singular_values(m, want)
    _same_bits(got, want, f"singular values {shape}")
    # both against LAPACK, the independent oracle, on the finite rows
    ok = np.isfinite(m).all(axis=(1, 2))
    assert np.isnan(got[~ok]).all() and (~ok).sum() >= 3 * (m.shape[0] // 12)
    with np.errstate(over="ignore", invalid="ignore"):
        lapack = np.linalg.svd(m[ok], compute_uv=False)
    scale = lapack[:, :1]
    # where the squared column norms neither overflow nor underflow (the kernels' domain)
    fine = np.isfinite(lapack).all(axis=1) & (scale[:, 0] < 1e140) & (
        (scale[:, 0] > 1e-140) | (scale[:, 0] == 0.0))
    err = np.abs(got[ok][fine] - lapack[fine]) / np.where(scale[fine] > 0, scale[fine], 1.0)
    assert err.max() <= 1e-13, err.max()


@pytest.mark.parametrize("shape", [s for s in SHAPES if s[0] >= s[1]])
def test_singular_rates_bits_of_numba(shape):
    from pkmkit.numerics import svd_rates_kernel

    rng = np.random.default_rng(100 + sum(shape))
    m = _hard_stack(shape, 1200, seed=50 + sum(shape))
    rates = rng.standard_normal((*m.shape, 3))
    rates[13, 0, 0, 2] = np.nan
    rates[25, -1, -1, 0] = np.inf
    n, c = m.shape[0], shape[1]
    got = (np.full((n, c), 7.0), np.full((n, c, 3), 7.0))
    want = (np.full((n, c), 7.0), np.full((n, c, 3), 7.0))
    _kernels.singular_rates(m, rates, *got)
    svd_rates_kernel.singular_rates(m, rates, *want)
    _same_bits(got[0], want[0], f"sigma {shape}")
    _same_bits(got[1], want[1], f"rates {shape}")
    ok = np.isfinite(m).all(axis=(1, 2)) & np.isfinite(rates).all(axis=(1, 2, 3))
    assert np.isnan(got[0][~ok]).all() and np.isnan(got[1][~ok]).all()
    # against LAPACK's vectors on the well-separated, moderate rows
    u, s, vt = np.linalg.svd(m[ok], full_matrices=False)
    lapack = np.einsum("kai,kabd,kib->kid", u, rates[ok], vt)
    gaps = np.diff(s, axis=1) if c > 1 else np.zeros((s.shape[0], 0))
    scale = s[:, 0]
    sep = (np.abs(gaps) > 1e-3 * scale[:, None]).all(axis=1) & (s[:, -1] > 1e-6 * scale) & (
        scale > 1e-100) & (scale < 1e100)
    assert sep.sum() >= 80  # the plain random matrices (one in 12) at least
    assert (np.abs(got[0][ok][sep] - s[sep]).max(axis=1) <= 1e-13 * scale[sep]).all()
    # σ̇ is defined up to rounding × ‖Ṁ‖ / gap: compare to a scale of the rates
    err = np.abs(got[1][ok][sep] - lapack[sep]).max(axis=(1, 2))
    assert (err <= 1e-8 * np.abs(rates[ok][sep]).max(axis=(1, 2, 3))).all()


def test_zero_singular_value_has_nan_rates():
    m = np.zeros((1, 3, 2))
    m[0, 0, 0] = 2.0
    rates = np.ones((1, 3, 2, 2))
    sigma, out = np.empty((1, 2)), np.empty((1, 2, 2))
    _kernels.singular_rates(m, rates, sigma, out)
    assert sigma.tolist() == [[2.0, 0.0]]
    assert np.isfinite(out[0, 0]).all() and np.isnan(out[0, 1]).all()


def test_empty_batches_and_refused_arguments():
    _kernels.singular_values(np.empty((0, 6, 6)), np.empty((0, 6)))
    _kernels.singular_rates(np.empty((0, 6, 6)), np.empty((0, 6, 6, 3)), np.empty((0, 6)),
                            np.empty((0, 6, 3)))
    m = np.ones((4, 6, 6))
    with pytest.raises(ValueError):
        _kernels.singular_values(m, np.empty((4, 5)))
    with pytest.raises(ValueError):
        _kernels.singular_values(m, np.empty((3, 6)))
    with pytest.raises(TypeError):
        _kernels.singular_values(m.astype(np.float32), np.empty((4, 6)))
    with pytest.raises(TypeError):
        _kernels.singular_values(m[:, :, ::2], np.empty((4, 3)))  # not contiguous
    with pytest.raises(TypeError):
        _kernels.singular_values(m, np.empty((4, 6)).T.copy().T)  # F-ordered output
    with pytest.raises(TypeError):
        _kernels.singular_values(m)
    with pytest.raises(ValueError):  # wide matrices: the caller transposes
        _kernels.singular_rates(np.ones((2, 3, 6)), np.ones((2, 3, 6, 1)), np.empty((2, 6)),
                                np.empty((2, 6, 1)))
    with pytest.raises(ValueError):
        _kernels.singular_rates(m, np.ones((4, 6, 6, 2)), np.empty((4, 6)),
                                np.empty((4, 6, 3)))


def test_dispatch_takes_the_c_twin(monkeypatch):
    """``small_singular_values`` and ``singular_value_rates`` of a large stack run the C
    kernel when the extension is built (Numba not needed), the Numba one with
    ``PKMKIT_NATIVE=0``: the same bits."""
    assert jit.kernel("pkmkit.numerics.svd_kernel", "singular_values") is \
        _kernels.singular_values
    assert jit.kernel("pkmkit.numerics.svd_rates_kernel", "singular_rates") is \
        _kernels.singular_rates
    rng = np.random.default_rng(3)
    m = rng.standard_normal((jit.MIN_ROWS + 5, 6, 6))
    rates = rng.standard_normal((jit.MIN_ROWS + 5, 6, 6, 2))
    calls = []
    real = jit.kernel

    def spy(module, name):
        function = real(module, name)
        calls.append(function)
        return function

    monkeypatch.setattr(jit, "kernel", spy)
    sv = linalg.small_singular_values(m)
    sigma, out = linalg.singular_value_rates(m, rates)
    assert calls == [_kernels.singular_values, _kernels.singular_rates]
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    pytest.importorskip("numba")
    _same_bits(linalg.small_singular_values(m), sv, "dispatch sv")
    numba_sigma, numba_out = linalg.singular_value_rates(m, rates)
    _same_bits(numba_sigma, sigma, "dispatch sigma")
    _same_bits(numba_out, out, "dispatch rates")
    assert calls[2:] and all(f is not _kernels.singular_values for f in calls[2:])


def test_two_threads_give_the_one_thread_bits(monkeypatch):
    """The kernels release the GIL and keep their work arrays per call: a batch spread over
    threads gives the bits of one thread."""
    rng = np.random.default_rng(4)
    m = rng.standard_normal((3 * jit.THREAD_ROWS, 6, 6))
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = linalg.small_singular_values(m)
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    _same_bits(linalg.small_singular_values(m), one, "threads")
