"""Batched linear algebra on stacks of small matrices ``(N, n, n)``."""

from __future__ import annotations

import numpy as np

from pkmkit.numerics import small


def batched_det(m: np.ndarray) -> np.ndarray:
    """Determinants of a stack of square matrices.

    Args:
        m: ``(..., n, n)``.

    Returns:
        ``(...)``. Closed forms for n = 2 and n = 3 (exact expansions, several times faster
        than LU for tiny matrices); LAPACK otherwise.
    """
    n = m.shape[-1]
    if n == 2:
        return m[..., 0, 0] * m[..., 1, 1] - m[..., 0, 1] * m[..., 1, 0]
    if n == 3:
        return (
            m[..., 0, 0] * (m[..., 1, 1] * m[..., 2, 2] - m[..., 1, 2] * m[..., 2, 1])
            - m[..., 0, 1] * (m[..., 1, 0] * m[..., 2, 2] - m[..., 1, 2] * m[..., 2, 0])
            + m[..., 0, 2] * (m[..., 1, 0] * m[..., 2, 1] - m[..., 1, 1] * m[..., 2, 0])
        )
    return np.linalg.det(m)


def singular_values(m: np.ndarray) -> np.ndarray:
    """Singular values, in decreasing order, of a stack of matrices ``(..., r, c)``.

    Square 2×2 and 3×3 stacks use the closed forms of :mod:`pkmkit.numerics.small`; others
    LAPACK. Matrices holding NaN give NaN singular values instead of a LAPACK error.

    Returns:
        ``(..., min(r, c))``.
    """
    if m.shape[-2:] in ((2, 2), (3, 3)):
        flat = m.reshape(-1, *m.shape[-2:])
        sv = small.singular_values(np.ascontiguousarray(flat.transpose(1, 2, 0)))
        return sv.T.reshape(*m.shape[:-2], m.shape[-1])
    out = np.full((*m.shape[:-2], min(m.shape[-2:])), np.nan)
    ok = np.isfinite(m).all(axis=(-2, -1))
    if ok.any():
        out[ok] = np.linalg.svd(m[ok], compute_uv=False)
    return out


def condition_number(sv: np.ndarray) -> np.ndarray:
    """Condition numbers σ_max/σ_min from singular values ``(..., k)`` sorted decreasing.

    Returns ``inf`` where σ_min = 0 and NaN where the singular values are NaN.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = sv[..., 0] / sv[..., -1]
    return np.where(sv[..., -1] == 0.0, np.inf, kappa)


def small_singular_values(m: np.ndarray) -> np.ndarray:
    """Singular values, decreasing, of a stack of small matrices ``(N, r, c)`` (6×6
    Jacobians…): ``(N, min(r, c))``, NaN rows for matrices holding NaN or inf.

    Large stacks (:func:`pkmkit.numerics.jit.use_compiled`) go through the compiled one-sided
    Jacobi kernel of :mod:`pkmkit.numerics.svd_kernel` (≈ 2× faster than LAPACK on 6×6
    matrices, 5× on 3×6, spread over threads), small ones through LAPACK; both agree to
    ~1e-15 of the largest singular value."""
    from pkmkit.numerics import jit

    m = np.asarray(m, dtype=float)
    rows, r, c = m.shape
    out = np.full((rows, min(r, c)), np.nan)
    if rows and jit.use_compiled(rows, native=True):  # the C twin (native/svd.c) when built
        kernel = jit.kernel("pkmkit.numerics.svd_kernel", "singular_values")

        mats = np.ascontiguousarray(m)

        def work(start: int, stop: int) -> None:
            kernel(mats[start:stop], out[start:stop])

        jit.run_chunks(work, rows)
        return out
    ok = np.isfinite(m).all(axis=(1, 2))
    if ok.any():
        out[ok] = np.linalg.svd(m[ok], compute_uv=False)
    return out


def singular_value_rates(m: np.ndarray, rates: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Singular values ``(N, k)``, decreasing, of a stack of small matrices ``m (N, r, c)``
    and their rates ``(N, k, d)`` along ``rates (N, r, c, d)`` (d derivatives of each matrix):
    ``σ̇_i = u_iᵀ Ṁ v_i`` for simple singular values (k = min(r, c)). NaN rows where ``m`` or
    ``rates`` is not finite.

    Large stacks go through the compiled one-sided Jacobi kernel of
    :mod:`pkmkit.numerics.svd_rates_kernel`, small ones through LAPACK's SVD with vectors;
    they agree to rounding (of σ_max), except where singular values are repeated (their
    vectors, hence their rates, are not unique)."""
    from pkmkit.numerics import jit

    m = np.asarray(m, dtype=float)
    rates = np.asarray(rates, dtype=float)
    if m.shape[1] < m.shape[2]:  # wide: the transposes have the same singular values
        m, rates = m.transpose(0, 2, 1), rates.transpose(0, 2, 1, 3)
    rows, c = m.shape[0], m.shape[2]
    sigma = np.full((rows, c), np.nan)
    out = np.full((rows, c, rates.shape[-1]), np.nan)
    if rows and jit.use_compiled(rows, native=True):  # the C twin (native/svd.c) when built
        kernel = jit.kernel("pkmkit.numerics.svd_rates_kernel", "singular_rates")

        mats, derivs = np.ascontiguousarray(m), np.ascontiguousarray(rates)

        def work(start: int, stop: int) -> None:
            kernel(mats[start:stop], derivs[start:stop], sigma[start:stop], out[start:stop])

        jit.run_chunks(work, rows)
        return sigma, out
    ok = np.isfinite(m).all(axis=(1, 2)) & np.isfinite(rates).all(axis=(1, 2, 3))
    if ok.any():
        u, sigma[ok], vt = np.linalg.svd(m[ok], full_matrices=False)
        out[ok] = np.einsum("kai,kabd,kib->kid", u, rates[ok], vt)
    return sigma, out
