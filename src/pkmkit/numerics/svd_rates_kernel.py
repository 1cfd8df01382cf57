"""Compiled (Numba) singular values of a stack of small tall matrices with their rates along
given derivatives of the matrices (issue 22 §3: analytic gradients of a workspace's slacks).

For a simple singular value σ_i of M with singular vectors (u_i, v_i), ``σ̇_i = u_iᵀ Ṁ v_i``.
One-sided Jacobi (Hestenes, as :mod:`pkmkit.numerics.svd_kernel`) rotates the columns of M
until they are orthogonal, accumulating the rotations in V: then ``M V = U Σ``, so the rotated
column ``w_i = σ_i u_i`` and ``σ̇_i = w_iᵀ (Ṁ v_i) / σ_i`` — no separate U, no LAPACK, one
matrix at a time in small buffers. LAPACK's SVD with vectors is the reference it is tested
against (tests/numerics/test_svd_rates_kernel.py); imported lazily, only for large batches
(:func:`pkmkit.numerics.linalg.singular_value_rates`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

#: Sweeps over every column pair before giving up (convergence takes 5–8 for 6×6).
MAX_SWEEPS = 60


@njit(**_OPTIONS)
def jacobi_sweeps(work, vmat, norms, tol):  # pragma: no cover
    """One-sided Jacobi on the columns ``work (c, r)`` (rows = columns of M) until they are
    orthogonal, each rotation applied to ``vmat (c, c)`` (rows = columns of V) too (a caller
    holding V by columns passes its transpose)."""
    c, r = work.shape
    for _ in range(MAX_SWEEPS):
        for i in range(c):
            s = 0.0
            for t in range(r):
                s += work[i, t] * work[i, t]
            norms[i] = s
        rotated = False
        for i in range(c - 1):
            for j in range(i + 1, c):
                alpha = norms[i]
                beta = norms[j]
                gamma = 0.0
                for t in range(r):
                    gamma += work[i, t] * work[j, t]
                if gamma == 0.0 or abs(gamma) <= tol * math.sqrt(alpha) * math.sqrt(beta):
                    continue
                rotated = True
                zeta = (beta - alpha) / (2.0 * gamma)
                tan = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                cos = 1.0 / math.sqrt(1.0 + tan * tan)
                sin = cos * tan
                for t in range(r):
                    a = work[i, t]
                    b = work[j, t]
                    work[i, t] = cos * a - sin * b
                    work[j, t] = sin * a + cos * b
                for t in range(c):
                    a = vmat[i, t]
                    b = vmat[j, t]
                    vmat[i, t] = cos * a - sin * b
                    vmat[j, t] = sin * a + cos * b
                norms[i] = alpha - tan * gamma
                norms[j] = beta + tan * gamma
        if not rotated:
            break


@njit(**_OPTIONS)
def _load(mat, rates, work):  # pragma: no cover
    """``work (c, r)`` ← the columns of ``mat (r, c)``; False when ``mat`` or its ``rates
    (r, c, d)`` hold a non-finite entry."""
    finite = True
    for i in range(mat.shape[0]):
        for j in range(mat.shape[1]):
            if not math.isfinite(mat[i, j]):
                finite = False
            work[j, i] = mat[i, j]
            for e in range(rates.shape[2]):
                if not math.isfinite(rates[i, j, e]):
                    finite = False
    return finite


@njit(**_OPTIONS)
def _quadratic(w, dm, v):  # pragma: no cover
    """``wᵀ Ṁ v`` for ``w (r,)``, ``dm (r, c)``, ``v (c,)``."""
    acc = 0.0
    for t in range(w.shape[0]):
        mv = 0.0
        for s in range(v.shape[0]):
            mv += dm[t, s] * v[s]
        acc += w[t] * mv
    return acc


@njit(**_OPTIONS)
def singular_rates(mats, rates, sigma, out):  # pragma: no cover
    """Singular values ``sigma (N, c)``, decreasing, of tall ``mats (N, r, c)`` (r ≥ c) and
    their rates ``out (N, c, d)`` along ``rates (N, r, c, d)``; a matrix or derivative with a
    non-finite entry gives NaN rows, a zero singular value NaN rates."""
    n, r, c = mats.shape
    d = rates.shape[3]
    work = np.empty((c, r))  # work[i] = column i of M V
    vmat = np.empty((c, c))  # vmat[i] = column i of V
    norms = np.empty(c)
    order = np.empty(c, dtype=np.int64)
    tol = r * 2.220446049250313e-16
    for m in range(n):
        if not _load(mats[m], rates[m], work):
            for i in range(c):
                sigma[m, i] = np.nan
                for e in range(d):
                    out[m, i, e] = np.nan
            continue
        for i in range(c):
            for j in range(c):
                vmat[i, j] = 1.0 if i == j else 0.0
        jacobi_sweeps(work, vmat, norms, tol)
        for i in range(c):
            s = 0.0
            for t in range(r):
                s += work[i, t] * work[i, t]
            norms[i] = s
            order[i] = i
        for i in range(1, c):  # insertion sort of the indices, decreasing σ
            k = order[i]
            j = i - 1
            while j >= 0 and norms[order[j]] < norms[k]:
                order[j + 1] = order[j]
                j -= 1
            order[j + 1] = k
        for slot in range(c):
            i = order[slot]
            sigma[m, slot] = math.sqrt(norms[i])
            for e in range(d):  # σ̇ = w_i·(Ṁ v_i)/σ_i
                out[m, slot, e] = (_quadratic(work[i], rates[m, :, :, e], vmat[i])
                                   / sigma[m, slot] if norms[i] > 0.0 else np.nan)
