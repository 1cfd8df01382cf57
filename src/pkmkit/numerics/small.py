"""Closed forms for stacks of 2×2 and 3×3 matrices, batch axis last.

Arrays are ``(n, n, N)``: entry ``m[i, j]`` is a contiguous ``(N,)`` array, so each formula below
is a few dozen long vectorised operations — an order of magnitude faster than LAPACK called on a
million tiny matrices.

Singular values use the eigenvalues of ``G = MᵀM`` only for the largest one (Smith's trigonometric
method, with the spread of G measured as a sum of squares so that isotropic matrices give exact
results), then recover the others from invariants computed directly from M — ``|det M|`` and the
sum of squared 2×2 minors ``e2 = Σσ_i²σ_j²`` (Cauchy–Binet) — so the smallest singular value keeps
its relative accuracy when it alone is small (``σ_min = |det M| / (σ1 σ2)``). The trigonometric
formula loses accuracy (≈ √eps) when the two largest singular values nearly coincide
(``det(B)/2 → −1``); those few matrices are handed to LAPACK.
"""

from __future__ import annotations

import numpy as np


def det(m: np.ndarray, cof: np.ndarray | None = None) -> np.ndarray:
    """Determinants ``(N,)`` of ``m (n, n, N)``, n = 2 or 3 (``cof``: its cofactors, if known)."""
    if m.shape[0] == 2:
        return m[0, 0] * m[1, 1] - m[0, 1] * m[1, 0]
    c = cofactors(m) if cof is None else cof
    return m[0, 0] * c[0, 0] + m[0, 1] * c[0, 1] + m[0, 2] * c[0, 2]


def gram(m: np.ndarray) -> np.ndarray:
    """``MᵀM (n, n, N)`` of ``m (n, n, N)``, each entry summed in index order: the same bits
    for every batch size and layout (``np.einsum`` sums a contiguous batch of one with SIMD
    partial sums, which round differently), so a row of any batch is the one-pose value of
    :mod:`pkmkit.machines.velocity_one`."""
    n = m.shape[0]
    g = np.empty((n, n, m.shape[2]))
    for i in range(n):
        for j in range(i, n):
            np.multiply(m[0, i], m[0, j], out=g[i, j])
            for k in range(1, n):
                g[i, j] += m[k, i] * m[k, j]
            if j > i:
                g[j, i] = g[i, j]
    return g


def row_norms(m: np.ndarray) -> np.ndarray:
    """``|m_i| (n, N)`` of the rows of ``m (n, d, N)``, squares summed in index order (the same
    bits for every batch size, see :func:`gram`)."""
    sq = m[:, 0] * m[:, 0]
    for k in range(1, m.shape[1]):
        sq += m[:, k] * m[:, k]
    return np.sqrt(sq)


def _symmetric_det3(s: np.ndarray) -> np.ndarray:
    return (s[0, 0] * (s[1, 1] * s[2, 2] - s[1, 2] ** 2)
            - s[0, 1] * (s[0, 1] * s[2, 2] - s[1, 2] * s[0, 2])
            + s[0, 2] * (s[0, 1] * s[1, 2] - s[1, 1] * s[0, 2]))


def cofactors(m: np.ndarray) -> np.ndarray:
    """Cofactor matrices ``C (n, n, N)`` (``adj M = Cᵀ``), n = 2 or 3."""
    if m.shape[0] == 2:
        return np.stack([np.stack([m[1, 1], -m[1, 0]]), np.stack([-m[0, 1], m[0, 0]])])
    out = np.empty_like(m)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            out[i, j] = m[i1, j1] * m[i2, j2] - m[i1, j2] * m[i2, j1]
    return out


def singular_values(m: np.ndarray, cof: np.ndarray | None = None) -> np.ndarray:
    """Singular values ``(n, N)``, decreasing, of ``m (n, n, N)`` for n = 2 or 3.

    ``cof``: the cofactors of m, if already known. NaN entries give NaN singular values.
    """
    if m.shape[0] == 2:
        a, b, c, d = m[0, 0], m[0, 1], m[1, 0], m[1, 1]
        s1 = 0.5 * (np.hypot(a + d, c - b) + np.hypot(a - d, b + c))
        with np.errstate(invalid="ignore", divide="ignore"):
            s2 = np.where(s1 > 0, np.abs(a * d - b * c) / s1, 0.0)
        out = np.stack([s1, s2])
        # NaN (or inf) entries: NaN singular values, never a silent 0 (np.where above maps a
        # NaN s1 to the "zero matrix" branch)
        out[:, ~np.isfinite(m).all(axis=(0, 1))] = np.nan
        return out
    if m.shape[0] != 3:
        raise ValueError(f"closed-form singular values need 2x2 or 3x3 matrices, got {m.shape}")
    g = gram(m)  # MᵀM
    mean = (g[0, 0] + g[1, 1] + g[2, 2]) / 3.0
    off = g[0, 1] ** 2 + g[0, 2] ** 2 + g[1, 2] ** 2
    spread_sq = ((g[0, 0] - mean) ** 2 + (g[1, 1] - mean) ** 2 + (g[2, 2] - mean) ** 2
                 + 2.0 * off) / 6.0
    spread = np.sqrt(spread_sq)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(spread > 0, 1.0 / spread, 0.0)
        shifted = (g - mean * np.eye(3)[:, :, None]) * scale
        half_det = np.clip(0.5 * _symmetric_det3(shifted), -1.0, 1.0)
        phi = np.arccos(half_det) / 3.0
        lam1 = mean + 2.0 * spread * np.cos(phi)
        s1 = np.sqrt(np.maximum(lam1, 0.0))
        c = cofactors(m) if cof is None else cof
        d = np.abs(det(m, c))
        e2 = c[0, 0] * c[0, 0]  # Σ C_ij², summed in order (see gram)
        for i, j in ((0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0), (2, 1), (2, 2)):
            e2 += c[i, j] * c[i, j]
        pair = np.where(s1 > 0, d / s1, 0.0)  # σ2 σ3
        rest = np.where(lam1 > 0, (e2 - pair**2) / lam1, 0.0)  # σ2² + σ3²
        s2 = 0.5 * (np.sqrt(np.maximum(rest + 2 * pair, 0.0))
                    + np.sqrt(np.maximum(rest - 2 * pair, 0.0)))
        s3 = np.where(s2 > 0, pair / s2, 0.0)
    s2 = np.minimum(s2, s1)
    out = np.stack([s1, s2, np.minimum(s3, s2)])
    finite = np.isfinite(m).all(axis=(0, 1))
    out[:, ~finite] = np.nan
    # nearly equal singular values make the closed forms lose about √eps: LAPACK for those
    # (rare) matrices — the two largest (φ → π/3) or the two smallest (φ → 0, or σ2 − σ3
    # obtained as a small difference)
    with np.errstate(invalid="ignore"):
        close = finite & (spread > 0) & ((np.abs(half_det) > 1.0 - 1e-6)
                                         | (rest - 2 * pair < 1e-6 * rest))
    close = np.flatnonzero(close)
    if close.size:
        out[:, close] = np.linalg.svd(m[:, :, close].transpose(2, 0, 1), compute_uv=False).T
    return out
