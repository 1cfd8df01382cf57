"""Compiled (Numba) singular values of a stack of small matrices: one-sided Jacobi (Hestenes).

Imported lazily, only for large batches (see :mod:`pkmkit.numerics.jit` and
:func:`pkmkit.numerics.linalg.small_singular_values`); LAPACK (``np.linalg.svd``) is the
reference it is tested against. Per matrix LAPACK pays for a bidiagonalisation built for large
matrices; this loop keeps one matrix in a small buffer and rotates pairs of its columns until
they are orthogonal to working precision (5–6 sweeps for the 6×6 Jacobians of a workspace),
then returns the column norms, decreasing: ≈ 2× faster than LAPACK per 6×6 matrix, 5× per 3×6
(measured under load, `docs/benchmarks.md`). One-sided Jacobi computes every singular value to
high relative accuracy (the small ones included), so it agrees with LAPACK to ~1e-15 of σ_max,
and it is no less accurate near a singularity.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

#: Sweeps over every column pair before giving up (convergence takes 5–8 for 6×6).
MAX_SWEEPS = 60


@njit(**_OPTIONS)
def singular_values(mats, out):  # pragma: no cover
    """Singular values ``out (N, k)``, decreasing, of ``mats (N, r, c)`` (k = min(r, c)); a
    matrix with a non-finite entry gives a row of NaN."""
    n, r, c = mats.shape
    tall = r >= c
    p = r if tall else c  # length of a working column
    k = c if tall else r  # working columns = singular values
    work = np.empty((k, p))
    norms = np.empty(k)
    tol = p * 2.220446049250313e-16
    for m in range(n):
        finite = True
        for i in range(r):
            for j in range(c):
                v = mats[m, i, j]
                if not math.isfinite(v):
                    finite = False
                if tall:
                    work[j, i] = v
                else:
                    work[i, j] = v
        if not finite:
            for i in range(k):
                out[m, i] = np.nan
            continue
        for _ in range(MAX_SWEEPS):
            for i in range(k):  # squared column norms, updated along the sweep
                s = 0.0
                for t in range(p):
                    s += work[i, t] * work[i, t]
                norms[i] = s
            rotated = False
            for i in range(k - 1):
                for j in range(i + 1, k):
                    alpha = norms[i]
                    beta = norms[j]
                    gamma = 0.0
                    for t in range(p):
                        gamma += work[i, t] * work[j, t]
                    if gamma == 0.0 or abs(gamma) <= tol * math.sqrt(alpha) * math.sqrt(beta):
                        continue
                    rotated = True
                    zeta = (beta - alpha) / (2.0 * gamma)
                    tan = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
                    cos = 1.0 / math.sqrt(1.0 + tan * tan)
                    sin = cos * tan
                    for t in range(p):
                        a = work[i, t]
                        b = work[j, t]
                        work[i, t] = cos * a - sin * b
                        work[j, t] = sin * a + cos * b
                    norms[i] = alpha - tan * gamma
                    norms[j] = beta + tan * gamma
            if not rotated:
                break
        for i in range(k):
            s = 0.0
            for t in range(p):
                s += work[i, t] * work[i, t]
            norms[i] = math.sqrt(s)
        for i in range(1, k):  # insertion sort, decreasing
            v = norms[i]
            j = i - 1
            while j >= 0 and norms[j] < v:
                norms[j + 1] = norms[j]
                j -= 1
            norms[j + 1] = v
        for i in range(k):
            out[m, i] = norms[i]
