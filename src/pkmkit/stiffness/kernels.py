"""Compiled (Numba) kernels of the rod-leg and joint-chain elastostatics, one fused loop per
configuration (no temporaries, no BLAS, single-threaded: :func:`pkmkit.numerics.jit.run_chunks`
spreads a batch over threads).

Imported lazily, only for large batches (:mod:`pkmkit.stiffness.compiled`); the NumPy code of
:mod:`pkmkit.stiffness.rod_legs` and :mod:`pkmkit.stiffness.joint_chains` is the reference they
are tested against (``tests/stiffness/test_compiled.py``, 1e-12 relative).

Rod legs with one rod (or one equivalent leg) per actuator, each its own row of the velocity
model in unit rows ``A_u ẋ = B_u q̇`` with a diagonal ``B_u`` (b_j/ℓ_j): the compliance of
:mod:`pkmkit.stiffness.rod_legs` is ``C = A_u⁻¹ D A_u⁻ᵀ`` and the stiffness ``K = A_uᵀ D⁻¹ A_u``
with ``D_j = (b_j/ℓ_j)² c_q,j + ℓ_j c_r,j`` (drive in series with the rod's axial spring
ℓ/(EA), ``c_r`` per unit length).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines.full_pose_kernels import rotation_entries

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

#: Status codes written by the kernels (as :class:`pkmkit.status.Status`).
OK, SINGULAR = 0, 3


@njit(inline="always", **_OPTIONS)
def _largest_symmetric_eigenvalue(a00, a01, a02, a11, a12, a22, d):  # pragma: no cover
    """Largest eigenvalue of a symmetric 2×2 (d = 2, upper entries a00, a01, a11) or 3×3
    matrix: the closed form of the 2×2; for the 3×3 the trigonometric solution of the
    characteristic cubic (Smith 1961), λ = m + 2 p cos(φ/3) with m the mean of the diagonal —
    accurate to a few ε of the largest eigenvalue (its error is ε times the matrix norm, which
    for a positive matrix is that eigenvalue) except near a double root, where acos loses half
    the digits: there the Jacobi method (:func:`_jacobi_largest`)."""
    if d == 2:
        mean = 0.5 * (a00 + a11)
        half = 0.5 * (a00 - a11)
        return mean + math.sqrt(half * half + a01 * a01)
    off = a01 * a01 + a02 * a02 + a12 * a12
    m = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - m, a11 - m, a22 - m
    p = math.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0)
    if p == 0.0:
        return m
    det = (b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02)
           + a02 * (a01 * a12 - b11 * a02))
    r = det / (2.0 * p * p * p)
    if abs(r) > 1.0 - 1e-3:  # a double root: acos would lose half the digits
        return _jacobi_largest(a00, a01, a02, a11, a12, a22)
    return m + 2.0 * p * math.cos(math.acos(r) / 3.0)


@njit(**_OPTIONS)
def _jacobi_largest(a00, a01, a02, a11, a12, a22):  # pragma: no cover
    """Largest eigenvalue of a symmetric 3×3 matrix by the cyclic Jacobi method (accurate to
    rounding whatever the multiplicities; converges quadratically)."""
    a = np.empty((3, 3))
    a[0, 0], a[0, 1], a[0, 2] = a00, a01, a02
    a[1, 0], a[1, 1], a[1, 2] = a01, a11, a12
    a[2, 0], a[2, 1], a[2, 2] = a02, a12, a22
    for _ in range(64):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        diag = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-36 * diag:
            break
        _rotate(a, 0, 1, 2)
        _rotate(a, 0, 2, 1)
        _rotate(a, 1, 2, 0)
    return max(a[0, 0], a[1, 1], a[2, 2])


@njit(inline="always", **_OPTIONS)
def _rotate(a, p, r, o):  # pragma: no cover
    """One Jacobi rotation zeroing ``a[p, r]`` of a symmetric 3×3 (o the third index)."""
    apq = a[p, r]
    if apq == 0.0:
        return
    theta = (a[r, r] - a[p, p]) / (2.0 * apq)
    t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
    if theta < 0.0:
        t = -t
    c = 1.0 / math.sqrt(t * t + 1.0)
    s = t * c
    a[p, p] -= t * apq
    a[r, r] += t * apq
    a[p, r] = 0.0
    a[r, p] = 0.0
    aop, aor = a[o, p], a[o, r]
    a[o, p] = c * aop - s * aor
    a[p, o] = a[o, p]
    a[o, r] = s * aop + c * aor
    a[r, o] = a[o, r]


@njit(**_OPTIONS)
def _invert(a, out, work, d):  # pragma: no cover
    """``out = a⁻¹`` for a ``d × d`` matrix (Gauss–Jordan with partial pivoting); False when a
    pivot is zero or not finite (singular)."""
    for i in range(d):
        for j in range(d):
            work[i, j] = a[i, j]
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(d):
        pivot = col
        best = abs(work[col, col])
        for r in range(col + 1, d):
            if abs(work[r, col]) > best:
                best = abs(work[r, col])
                pivot = r
        if not (best > 0.0) or not math.isfinite(best):
            return False
        if pivot != col:
            for j in range(d):
                work[col, j], work[pivot, j] = work[pivot, j], work[col, j]
                out[col, j], out[pivot, j] = out[pivot, j], out[col, j]
        inv = 1.0 / work[col, col]
        for j in range(d):
            work[col, j] *= inv
            out[col, j] *= inv
        for r in range(d):
            if r != col:
                f = work[r, col]
                if f != 0.0:
                    for j in range(d):
                        work[r, j] -= f * work[col, j]
                        out[r, j] -= f * out[col, j]
    return True


@njit(**_OPTIONS)
def _invert_small(a, out, d):  # pragma: no cover
    """``out = a⁻¹`` for d = 2 or 3 by the adjugate over the determinant (the formula of
    :func:`pkmkit.numerics.small.cofactors`); False when the determinant is zero or not
    finite."""
    if d == 2:
        det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
        if not (abs(det) > 0.0) or not math.isfinite(det):
            return False
        out[0, 0] = a[1, 1] / det
        out[0, 1] = -a[0, 1] / det
        out[1, 0] = -a[1, 0] / det
        out[1, 1] = a[0, 0] / det
        return True
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    if not (abs(det) > 0.0) or not math.isfinite(det):
        return False
    c10 = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    c11 = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    c12 = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    c20 = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    c21 = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    c22 = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    out[0, 0], out[0, 1], out[0, 2] = c00 / det, c10 / det, c20 / det
    out[1, 0], out[1, 1], out[1, 2] = c01 / det, c11 / det, c21 / det
    out[2, 0], out[2, 1], out[2, 2] = c02 / det, c12 / det, c22 / det
    return True


@njit(**_OPTIONS)
def _fill_nan(out, k):  # pragma: no cover
    for i in range(out.shape[1]):
        for j in range(out.shape[2]):
            out[k, i, j] = math.nan


@njit(**_OPTIONS)
def translational(x, q, centre0, axis, strut, leg_length, c_q, c_r, singular_limit,
                  compliance, smallest, status):  # pragma: no cover
    """Compliance ``(N, d, d)`` (m/N) and smallest translational stiffness ``(N,)`` (N/m) of a
    translating rod-leg machine (slides and struts, one leg per actuator, d legs).

    ``x (N, d)`` poses, ``q (N, d)`` actuator coordinates (NaN: no configuration);
    ``centre0 (d, d)`` a leg's carriage centre minus its platform point at q = 0, ``axis
    (d, d)`` slide axes, ``strut (d,)`` bool, ``leg_length (d,)``, ``c_q (d,)`` drive
    compliances, ``c_r (d,)`` the equivalent leg's axial compliance per metre (0: rigid);
    ``singular_limit``: the Frobenius condition of ``A_u`` beyond which a pose is singular.
    ``status (N,)``: in, 0 where q is a configuration; out, 3 where singular (NaN rows)."""
    n, d = x.shape
    a = np.empty((3, 3))
    inv = np.empty((3, 3))
    cc = np.zeros((3, 3))
    dd = np.empty(3)
    for k in range(n):
        if status[k] != OK:
            _fill_nan(compliance, k)
            smallest[k] = math.nan
            continue
        norm_a = 0.0
        for i in range(d):
            ss = 0.0
            along = 0.0
            for c in range(d):
                v = x[k, c] - centre0[i, c]
                if not strut[i]:
                    v -= q[k, i] * axis[i, c]
                a[i, c] = v
                ss += v * v
                along += v * axis[i, c]
            ell = math.sqrt(ss)
            b = leg_length[i] + q[k, i] if strut[i] else along
            for c in range(d):
                a[i, c] /= ell
                norm_a += a[i, c] * a[i, c]
            bu = b / ell
            dd[i] = bu * bu * c_q[i] + ell * c_r[i]
        regular = _invert_small(a, inv, d)
        norm_inv = 0.0
        if regular:
            for i in range(d):
                for j in range(d):
                    norm_inv += inv[i, j] * inv[i, j]
            condition = math.sqrt(norm_a * norm_inv)
            regular = math.isfinite(condition) and condition <= singular_limit
        if not regular:
            status[k] = SINGULAR
            _fill_nan(compliance, k)
            smallest[k] = math.nan
            continue
        for i in range(d):
            for j in range(i, d):
                s = 0.0
                for m in range(d):
                    s += inv[i, m] * dd[m] * inv[j, m]
                compliance[k, i, j] = s
                compliance[k, j, i] = s
                cc[i, j] = s
                cc[j, i] = s
        top = _largest_symmetric_eigenvalue(cc[0, 0], cc[0, 1], cc[0, 2], cc[1, 1], cc[1, 2],
                                            cc[2, 2], d)
        smallest[k] = math.inf if top <= 0.0 else 1.0 / top


@njit(**_OPTIONS)
def six_rods(x, q, base, platform, axis, strut, length, actuator, c_q, c_r, char_length,
             singular_limit, compliance, stiffness, status):  # pragma: no cover
    """Compliance and stiffness ``(N, 6, 6)`` at the platform reference point of a full-pose
    machine with six rods (slides or struts), one per actuator.

    ``x (N, 6)`` poses (position, rotation vector), ``q (N, 6)`` actuator coordinates;
    ``base``, ``platform``, ``axis`` ``(6, 3)`` rod ends and slide axes at q = 0, ``strut
    (6,)``, ``length (6,)``, ``actuator (6,)`` each rod's actuator, ``c_q (6,)`` drive
    compliances by actuator, ``c_r (6,)`` rod axial compliance per metre (0: rigid),
    ``char_length`` (m) scaling the moment columns for the singularity test (Frobenius
    condition above ``singular_limit``); ``status`` as in :func:`translational`. A
    ``compliance`` with no rows (``(0, 6, 6)``) is not computed (the stiffness alone)."""
    n = x.shape[0]
    with_c = compliance.shape[0] == n
    a = np.empty((6, 6))
    inv = np.empty((6, 6))
    work = np.empty((6, 6))
    dd = np.empty(6)
    for k in range(n):
        if status[k] != OK:
            if with_c:
                _fill_nan(compliance, k)
            _fill_nan(stiffness, k)
            continue
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(x[k, 3], x[k, 4],
                                                                      x[k, 5])
        norm_s = 0.0
        for j in range(6):
            bx, by, bz = platform[j, 0], platform[j, 1], platform[j, 2]
            rx = r00 * bx + r01 * by + r02 * bz
            ry = r10 * bx + r11 * by + r12 * bz
            rz = r20 * bx + r21 * by + r22 * bz
            qa = q[k, actuator[j]]
            slide = 0.0 if strut[j] else qa
            dx = x[k, 0] + rx - base[j, 0] - slide * axis[j, 0]
            dy = x[k, 1] + ry - base[j, 1] - slide * axis[j, 1]
            dz = x[k, 2] + rz - base[j, 2] - slide * axis[j, 2]
            ell = math.sqrt(dx * dx + dy * dy + dz * dz)
            b = length[j] + qa if strut[j] else dx * axis[j, 0] + dy * axis[j, 1] + dz * axis[j, 2]
            ux, uy, uz = dx / ell, dy / ell, dz / ell
            a[j, 0], a[j, 1], a[j, 2] = ux, uy, uz
            a[j, 3] = ry * uz - rz * uy
            a[j, 4] = rz * ux - rx * uz
            a[j, 5] = rx * uy - ry * ux
            bu = b / ell
            dd[j] = bu * bu * c_q[actuator[j]] + ell * c_r[j]
            for c in range(3):
                norm_s += a[j, c] * a[j, c]
                norm_s += (a[j, c + 3] / char_length) ** 2
        regular = _invert(a, inv, work, 6)
        if regular:
            norm_inv = 0.0
            for i in range(6):
                scale = char_length if i >= 3 else 1.0
                for j in range(6):
                    norm_inv += (inv[i, j] * scale) ** 2
            condition = math.sqrt(norm_s * norm_inv)
            regular = math.isfinite(condition) and condition <= singular_limit
        if not regular:
            status[k] = SINGULAR
            if with_c:
                _fill_nan(compliance, k)
            _fill_nan(stiffness, k)
            continue
        for m in range(6):
            dd[m] = 1.0 / dd[m] if not with_c else dd[m]
        for i in range(6):
            for j in range(i, 6):
                t = 0.0
                if with_c:
                    s = 0.0
                    for m in range(6):
                        s += inv[i, m] * dd[m] * inv[j, m]
                        t += a[m, i] * a[m, j] / dd[m]
                    compliance[k, i, j] = s
                    compliance[k, j, i] = s
                else:
                    for m in range(6):
                        t += a[m, i] * a[m, j] * dd[m]
                stiffness[k, i, j] = t
                stiffness[k, j, i] = t


@njit(**_OPTIONS)
def chain_reduced(g, t, free, springs, c_s, rank_tol, compliance, done):  # pragma: no cover
    """Tool-point compliance ``(k, 6, 6)`` of joint-chain configurations whose free unknowns
    (platform and passive joints, columns ``free``) are fixed by the closure once the springs
    (columns ``springs``, compliances ``c_s``, diagonal: drives and no link springs) are: then
    every spring deflection s is admissible, the free unknowns follow as ``y = −G_f⁺ G_s s``
    and ``C = J diag(c_s) Jᵀ`` with ``J = T_s − T_f G_f⁺ G_s`` — the null-space formula of
    :mod:`pkmkit.stiffness.joint_chains` in the basis ``N = [−G_f⁺ G_s; I]``.

    ``g (k, r, nz)``, ``t (k, 6, nz)``; ``done (k,)`` in: rows to try; out: True where the
    row was solved here — Householder QR of ``G_f`` with ``σ_min(G_f) ≥ 1/‖R⁻¹‖_F`` above
    ``10 rank_tol ‖G‖_F`` and the residual ``‖G_s − G_f X‖_F`` below ``rank_tol/10 ‖G‖_F``,
    so that G's rank is ``len(free)`` at the relative tolerance ``rank_tol`` of the SVD path;
    with spring compliances within 1e9 of each other and ``‖X‖_F² ≤ 1e3`` (X = G_f⁺ G_s), so
    that no eigenvalue of the reduced stiffness falls below 1e-13 of the largest (the SVD
    path's mechanism test). ``r`` up to 100 rows.
    Other rows are left to the SVD path."""
    k_rows, r, _ = g.shape
    nf = free.shape[0]
    ns = springs.shape[0]
    qr = np.empty((r, nf))
    rhs = np.empty((r, ns))
    beta = np.empty(nf)
    xs = np.empty((nf, ns))
    rinv = np.empty((nf, nf))
    jac = np.empty((6, ns))
    spread = c_s.max() / c_s.min()
    for k in range(k_rows):
        if not done[k]:
            continue
        done[k] = False
        norm_g = 0.0
        for i in range(r):
            for j in range(nf):
                qr[i, j] = g[k, i, free[j]]
                norm_g += qr[i, j] * qr[i, j]
            for j in range(ns):
                rhs[i, j] = g[k, i, springs[j]]
                norm_g += rhs[i, j] * rhs[i, j]
        norm_g = math.sqrt(norm_g)
        if not math.isfinite(norm_g) or norm_g == 0.0 or r < nf:
            continue
        # Householder QR of G_f, Qᵀ applied to G_s on the way
        for j in range(nf):
            s = 0.0
            for i in range(j, r):
                s += qr[i, j] * qr[i, j]
            alpha = math.sqrt(s)
            if qr[j, j] > 0.0:
                alpha = -alpha
            v0 = qr[j, j] - alpha
            vnorm = s - qr[j, j] * qr[j, j] + v0 * v0
            qr[j, j] = v0
            beta[j] = 0.0 if vnorm == 0.0 else 2.0 / vnorm
            for c in range(j + 1, nf):
                dot = 0.0
                for i in range(j, r):
                    dot += qr[i, j] * qr[i, c]
                dot *= beta[j]
                for i in range(j, r):
                    qr[i, c] -= dot * qr[i, j]
            for c in range(ns):
                dot = 0.0
                for i in range(j, r):
                    dot += qr[i, j] * rhs[i, c]
                dot *= beta[j]
                for i in range(j, r):
                    rhs[i, c] -= dot * qr[i, j]
            qr[j, j] = alpha  # R's diagonal; the reflector's head is no longer needed
        # R = upper triangle of qr (strictly upper part untouched by later reflectors)
        ok = True
        for j in range(nf):
            if not (abs(qr[j, j]) > 0.0):
                ok = False
        if not ok:
            continue
        # R⁻¹ (upper triangular) and its Frobenius norm
        norm_rinv = 0.0
        for c in range(nf):
            for i in range(nf - 1, -1, -1):
                s = 1.0 if i == c else 0.0
                for m in range(i + 1, nf):
                    s -= qr[i, m] * rinv[m, c]
                rinv[i, c] = s / qr[i, i]
                norm_rinv += rinv[i, c] * rinv[i, c]
        if not (1.0 / math.sqrt(norm_rinv) > 10.0 * rank_tol * norm_g):
            continue
        # X = R⁻¹ (Qᵀ G_s)[:nf]; residual ‖(Qᵀ G_s)[nf:]‖_F
        resid = 0.0
        for i in range(nf, r):
            for c in range(ns):
                resid += rhs[i, c] * rhs[i, c]
        if not (math.sqrt(resid) < 0.1 * rank_tol * norm_g):
            continue
        if not spread <= 1e9:
            continue
        norm_x = 0.0
        for i in range(nf):
            for c in range(ns):
                s = 0.0
                for m in range(i, nf):
                    s += rinv[i, m] * rhs[m, c]
                xs[i, c] = s
                norm_x += s * s
        if not norm_x <= 1e3:  # the SVD path's mechanism test could see a soft mode
            continue
        for a in range(6):
            for c in range(ns):
                s = t[k, a, springs[c]]
                for m in range(nf):
                    s -= t[k, a, free[m]] * xs[m, c]
                jac[a, c] = s
        for a in range(6):
            for b in range(a, 6):
                s = 0.0
                for c in range(ns):
                    s += jac[a, c] * c_s[c] * jac[b, c]
                compliance[k, a, b] = s
                compliance[k, b, a] = s
        done[k] = True
