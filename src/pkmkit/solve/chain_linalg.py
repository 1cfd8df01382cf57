"""Compiled (Numba) linear algebra of joint-chain closure Jacobians at many configurations:
``dU = −C_U⁺ C_δ`` by the normal equations (:func:`absorb`, the identification's defect
columns) and ``dU = −C_U⁺ C_q`` with the rank and the singularity measure of C_U
(:func:`closure_rates`, the velocity model of a workspace grid). Imported lazily, as
:mod:`pkmkit.solve.chain_kernel` (which re-exports them); LAPACK's pseudo-inverse is the
reference they are tested against (tests/solve/test_chain_kernel.py,
tests/solve/test_chain_inverse_kernel.py)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.numerics.svd_rates_kernel import jacobi_sweeps

# the entry points of _absorb_rows and _closure_rates_rows (Numba-free: their C twins may
# run), re-exported
from pkmkit.solve.chain_rows import absorb, closure_rates  # noqa: F401

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}


#: A closure Jacobian C_U whose Cholesky pivots of C_Uᵀ C_U fall below this fraction of its
#: largest diagonal entry is treated as rank-deficient (left to the pseudo-inverse); the C
#: twin (native/chain_linearise.c) has the same constant.
RANK_PIVOT = 1e-10


@njit(**_OPTIONS)
def _absorb_rows(cu, cd, du, rest, ok):  # pragma: no cover
    n, r, u = cu.shape
    d = cd.shape[2]
    h = np.empty((u, u))
    low = np.empty((u, u))
    g = np.empty((u, d))
    for k in range(n):
        c_u, c_d, x = cu[k], cd[k], du[k]
        h[:, :] = 0.0
        g[:, :] = 0.0
        for i in range(r):  # H = C_Uᵀ C_U, G = −C_Uᵀ C_δ (rows of C_U streamed once)
            for a in range(u):
                v = c_u[i, a]
                for c in range(a + 1):
                    h[a, c] += v * c_u[i, c]
                for col in range(d):
                    g[a, col] -= v * c_d[i, col]
        biggest = 0.0
        for a in range(u):
            biggest = max(biggest, h[a, a])
        good = biggest > 0.0
        for j in range(u):
            s = h[j, j]
            for p in range(j):
                s -= low[j, p] * low[j, p]
            if not s > RANK_PIVOT * biggest:
                good = False
                break
            low[j, j] = math.sqrt(s)
            for i in range(j + 1, u):
                t = h[i, j]
                for p in range(j):
                    t -= low[i, p] * low[j, p]
                low[i, j] = t / low[j, j]
        ok[k] = good
        if not good:
            x[:, :] = math.nan
            rest[k] = math.nan
            continue
        for i in range(u):  # L Y = G
            for p in range(i):
                f = low[i, p]
                for col in range(d):
                    g[i, col] -= f * g[p, col]
            f = 1.0 / low[i, i]
            for col in range(d):
                g[i, col] *= f
        for i in range(u - 1, -1, -1):  # Lᵀ X = Y
            for p in range(i + 1, u):
                f = low[p, i]
                for col in range(d):
                    g[i, col] -= f * x[p, col]
            f = 1.0 / low[i, i]
            for col in range(d):
                x[i, col] = g[i, col] * f
        for i in range(r):  # C_δ + C_U dU
            for col in range(d):
                rest[k, i, col] = c_d[i, col]
            for a in range(u):
                v = c_u[i, a]
                for col in range(d):
                    rest[k, i, col] += v * x[a, col]



@njit(**_OPTIONS)
def _householder(a, b):  # pragma: no cover
    """Householder QR of ``a (r, c)`` in place (R on and above the diagonal, the reflectors
    below, their leading entries lost), the reflections applied to ``b (r, k)``; False where a
    column is zero (no R)."""
    r, c = a.shape
    k = b.shape[1]
    for j in range(c):
        norm = 0.0
        for i in range(j, r):
            norm += a[i, j] * a[i, j]
        norm = math.sqrt(norm)
        if norm == 0.0:
            return False
        alpha = -norm if a[j, j] >= 0 else norm
        v0 = a[j, j] - alpha
        # v = (v0, a[j+1:, j]); H = I − 2 v vᵀ / vᵀv
        vtv = v0 * v0
        for i in range(j + 1, r):
            vtv += a[i, j] * a[i, j]
        a[j, j] = v0
        for col in range(j + 1, c):
            s = 0.0
            for i in range(j, r):
                s += a[i, j] * a[i, col]
            s *= 2.0 / vtv
            for i in range(j, r):
                a[i, col] -= s * a[i, j]
        for col in range(k):
            s = 0.0
            for i in range(j, r):
                s += a[i, j] * b[i, col]
            s *= 2.0 / vtv
            for i in range(j, r):
                b[i, col] -= s * a[i, j]
        a[j, j] = alpha
    return True


@njit(**_OPTIONS)
def _qr_rates(a, b, rinv, du_m, threshold):  # pragma: no cover
    """Householder QR of ``a (r, c)`` (overwritten: R above the diagonal) applied to ``b
    (r, k)``; when ``1 / (‖R‖_F ‖R⁻¹‖_F) > threshold`` writes ``du_m = −R⁻¹ (Qᵀ b)[:c]`` and
    returns that bound, else returns −1."""
    c = a.shape[1]
    k = b.shape[1]
    if not _householder(a, b):
        return -1.0
    frob, frob_inv = 0.0, 0.0
    for i in range(c):
        for j in range(i, c):
            frob += a[i, j] * a[i, j]
    for j in range(c):  # columns of R⁻¹ (upper triangular) by back substitution
        for i in range(c - 1, -1, -1):
            t = 1.0 if i == j else 0.0
            if i > j:
                rinv[i, j] = 0.0
                continue
            for p in range(i + 1, j + 1):
                t -= a[i, p] * rinv[p, j]
            rinv[i, j] = t / a[i, i]
            frob_inv += rinv[i, j] * rinv[i, j]
    bound = 1.0 / math.sqrt(frob * frob_inv)
    if not bound > threshold:
        return -1.0
    for i in range(c):
        for col in range(k):
            s = 0.0
            for p in range(i, c):
                s += rinv[i, p] * b[p, col]
            du_m[i, col] = -s
    return bound


@njit(**_OPTIONS)
def _closure_rates_rows(cu, cq, rcond, tol, expected, du, rank, ratio):  # pragma: no cover
    n, r, c = cu.shape
    k = cq.shape[2]
    a, b, rinv = np.empty((r, c)), np.empty((r, k)), np.empty((c, c))
    work = np.empty((c, r))  # columns of C_U V
    vmat = np.empty((c, c))  # columns of V
    norms = np.empty(c)
    sv = np.empty(c)
    threshold = max(tol, rcond)
    for m in range(n):
        finite = True
        for i in range(r):
            for j in range(c):
                finite = finite and math.isfinite(cu[m, i, j])
            for j in range(k):
                finite = finite and math.isfinite(cq[m, i, j])
        if not finite:
            du[m] = math.nan
            ratio[m] = math.nan
            rank[m] = 0
            continue
        if expected == c:
            a[:, :] = cu[m]
            b[:, :] = cq[m]
            bound = _qr_rates(a, b, rinv, du[m], threshold)
            if bound > 0.0:
                rank[m] = c
                ratio[m] = bound
                continue
        _jacobi_rates(cu[m], cq[m], rcond, work, vmat, norms, sv, du[m])
        count = 0
        for i in range(c):
            if sv[i] > rcond * sv[0]:
                count += 1
        rank[m] = count
        ratio[m] = sv[expected - 1] / sv[0]


@njit(**_OPTIONS)
def _jacobi_rates(cu_m, cq_m, rcond, work, vmat, norms, sv, du_m):  # pragma: no cover
    """One row of :func:`closure_rates` by one-sided Jacobi: singular values ``sv``
    (decreasing) and ``du_m = −C_U⁺ C_q``."""
    r, c = cu_m.shape
    k = cq_m.shape[1]
    tol = r * 2.220446049250313e-16
    for i in range(r):
        for j in range(c):
            work[j, i] = cu_m[i, j]
    for i in range(c):
        for j in range(c):
            vmat[i, j] = 1.0 if i == j else 0.0
    jacobi_sweeps(work, vmat.T, norms, tol)  # V held by columns
    biggest = 0.0
    for i in range(c):
        s = 0.0
        for t in range(r):
            s += work[i, t] * work[i, t]
        norms[i] = math.sqrt(s)
        biggest = max(biggest, norms[i])
        sv[i] = norms[i]
    for i in range(1, c):  # decreasing
        v = sv[i]
        j = i - 1
        while j >= 0 and sv[j] < v:
            sv[j + 1] = sv[j]
            j -= 1
        sv[j + 1] = v
    # dU = −V Σ⁻² (C_U V)ᵀ C_q over the singular values above the cutoff
    du_m[:, :] = 0.0
    cutoff = rcond * biggest
    for a in range(c):
        s_a = norms[a]
        if not s_a > cutoff:
            continue
        f = -1.0 / (s_a * s_a)
        for col in range(k):
            g = 0.0
            for t in range(r):
                g += work[a, t] * cq_m[t, col]
            g *= f
            for i in range(c):
                du_m[i, col] += vmat[i, a] * g
