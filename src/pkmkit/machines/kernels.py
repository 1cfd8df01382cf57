"""Compiled (Numba) kernels of the closed-form models of translational rod-leg machines.

Imported lazily, only for large batches (see :mod:`pkmkit.numerics.jit`); the NumPy code of
:mod:`pkmkit.machines.closed_form` and :mod:`pkmkit.machines.velocity` is the reference they
are tested against. Each kernel is one fused loop over poses that keeps its intermediates in
registers: no temporaries, no BLAS (the tiny per-pose products are written out), one pass over
memory, single-threaded — so it holds when another process keeps the other cores busy, and
inside Dask workers.

Layouts: poses ``x (N, dims)`` C-ordered; actuator coordinates and other per-leg outputs with
the batch axis last, ``(n, N)``. Only square machines (n = dims = 2 or 3) have velocity kernels.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from pkmkit.machines.cos_third import COEFFICIENTS

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}
#: Poses per block of the inverse model: the block's coordinates stay in L1/L2 between legs.
_BLOCK = 2048


@njit(**_OPTIONS)
def inverse(x, basis, offset, length, slide, branch, boundary_tol, out):  # pragma: no cover
    """Closed-form inverse model (see :meth:`RodClosedForm.inverse`) into ``out (n, N)``.

    ``basis (n, dims, dims)``: rows u_i (slide axis) then two unit vectors across it;
    ``offset (n, dims)``: ``basis_i @ (a0_i − b_i)``; ``length (n,)`` rod lengths;
    ``slide (n,)`` bool; ``branch (n,)`` ±1.0; ``boundary_tol`` as
    :data:`~pkmkit.machines.closed_form.BOUNDARY_TOL`. Returns the number of non-finite outputs
    (unreachable poses or non-finite input).
    """
    size, dims = x.shape
    n = basis.shape[0]
    c0 = np.empty(_BLOCK)
    c1 = np.empty(_BLOCK)
    c2 = np.zeros(_BLOCK)
    bad = 0
    for start in range(0, size, _BLOCK):
        m = min(size - start, _BLOCK)
        for k in range(m):  # de-interleave the block (structure of arrays)
            c0[k] = x[start + k, 0]
            c1[k] = x[start + k, 1]
            if dims == 3:
                c2[k] = x[start + k, 2]
        for i in range(n):
            u0, u1 = basis[i, 0, 0], basis[i, 0, 1]
            v0, v1 = basis[i, 1, 0], basis[i, 1, 1]
            u2 = v2 = w0 = w1 = w2 = o2 = 0.0
            if dims == 3:
                u2, v2 = basis[i, 0, 2], basis[i, 1, 2]
                w0, w1, w2 = basis[i, 2, 0], basis[i, 2, 1], basis[i, 2, 2]
                o2 = offset[i, 2]
            o0, o1 = offset[i, 0], offset[i, 1]
            row = out[i, start:start + m]
            if slide[i] and dims == 2:  # planar: one coordinate across the slide
                length_sq = length[i] * length[i]
                limit = -boundary_tol * length_sq
                sign = branch[i]
                for k in range(m):
                    s = u0 * c0[k] + u1 * c1[k] - o0
                    p = v0 * c0[k] + v1 * c1[k] - o1
                    radicand = length_sq - p * p
                    radicand = 0.0 if (radicand < 0.0 and radicand > limit) else radicand
                    value = s + sign * np.sqrt(radicand)
                    row[k] = value
                    bad += 0 if value - value == 0.0 else 1
            elif slide[i]:
                length_sq = length[i] * length[i]
                limit = -boundary_tol * length_sq
                sign = branch[i]
                for k in range(m):
                    s = u0 * c0[k] + u1 * c1[k] + u2 * c2[k] - o0
                    p = v0 * c0[k] + v1 * c1[k] + v2 * c2[k] - o1
                    r = w0 * c0[k] + w1 * c1[k] + w2 * c2[k] - o2
                    radicand = length_sq - (p * p + r * r)
                    radicand = 0.0 if (radicand < 0.0 and radicand > limit) else radicand
                    value = s + sign * np.sqrt(radicand)
                    row[k] = value
                    bad += 0 if value - value == 0.0 else 1
            else:
                rod = length[i]
                for k in range(m):
                    s = u0 * c0[k] + u1 * c1[k] + u2 * c2[k] - o0
                    p = v0 * c0[k] + v1 * c1[k] + v2 * c2[k] - o1
                    r = w0 * c0[k] + w1 * c1[k] + w2 * c2[k] - o2
                    value = np.sqrt((p * p + r * r) + s * s) - rod  # the reference's order
                    row[k] = value
                    bad += 0 if value - value == 0.0 else 1
    return bad


@njit(**_OPTIONS)
def reach_and_det(x, q, basis, offset, centre, axis, length, slide, short_out,
                  det_out):  # pragma: no cover
    """The other outputs of the inverse model of a square machine of slides and struts
    (n = dims = 2 or 3), from its result ``q (n, N)``: ``short_out (n, N)`` as
    :meth:`RodClosedForm.shortfall` (−inf for struts) and ``det_out (N,)`` det A, A rows
    ``p − (centre_i + q_i axis_i)`` (slides; ``centre_i`` for struts), expanded as
    :func:`~pkmkit.numerics.linalg.batched_det` — the same operations in the same order as the
    NumPy reference, so the same bits. ``basis``, ``offset``, ``length``, ``slide`` as for
    :func:`inverse`; ``centre``, ``axis (n, dims)``. Blocks of poses in a structure-of-arrays
    layout, as :func:`inverse`, so that the loops vectorise."""
    size, dims = x.shape
    n = basis.shape[0]
    c = np.zeros((3, _BLOCK))
    a = np.zeros((3, 3, _BLOCK))
    for start in range(0, size, _BLOCK):
        m = min(size - start, _BLOCK)
        for d in range(dims):
            for k in range(m):
                c[d, k] = x[start + k, d]
        for i in range(n):
            v0, v1, v2 = basis[i, 1, 0], basis[i, 1, 1], 0.0
            w0 = w1 = w2 = o2 = 0.0
            if dims == 3:
                v2 = basis[i, 1, 2]
                w0, w1, w2 = basis[i, 2, 0], basis[i, 2, 1], basis[i, 2, 2]
                o2 = offset[i, 2]
            o1 = offset[i, 1]
            rod = length[i]
            short = short_out[i, start:start + m]
            if not slide[i]:
                for k in range(m):
                    short[k] = -np.inf
            elif dims == 2:
                for k in range(m):
                    p = v0 * c[0, k] + v1 * c[1, k] - o1
                    short[k] = np.sqrt(p * p) - rod
            else:
                for k in range(m):
                    p = v0 * c[0, k] + v1 * c[1, k] + v2 * c[2, k] - o1
                    r = w0 * c[0, k] + w1 * c[1, k] + w2 * c[2, k] - o2
                    short[k] = np.sqrt(p * p + r * r) - rod
            qi = q[i, start:start + m]
            for d in range(dims):
                centre_d, axis_d = centre[i, d], axis[i, d]
                row = a[i, d]
                if slide[i]:
                    for k in range(m):
                        row[k] = c[d, k] - (centre_d + qi[k] * axis_d)
                else:
                    for k in range(m):
                        row[k] = c[d, k] - (centre_d + 0.0 * axis_d)
        det = det_out[start:start + m]
        if dims == 2:
            for k in range(m):
                det[k] = a[0, 0, k] * a[1, 1, k] - a[0, 1, k] * a[1, 0, k]
        else:
            for k in range(m):
                det[k] = (a[0, 0, k] * (a[1, 1, k] * a[2, 2, k] - a[1, 2, k] * a[2, 1, k])
                          - a[0, 1, k] * (a[1, 0, k] * a[2, 2, k] - a[1, 2, k] * a[2, 0, k])
                          + a[0, 2, k] * (a[1, 0, k] * a[2, 1, k] - a[1, 1, k] * a[2, 0, k]))


@njit(inline="always")
def _leg_row(x0, x1, x2, q, c0, c1, c2, u0, u1, u2, slide, rod):  # pragma: no cover
    """Row ``p − c_i(q)`` of A and entry i of diag B (``jacobians_t``), from scalars (the
    axis is zero for struts, so ``c_i(q) = c_i`` there)."""
    a0 = x0 - (c0 + q * u0)
    a1 = x1 - (c1 + q * u1)
    a2 = x2 - (c2 + q * u2)
    # slide is 1.0 or 0.0: branch-free, exact (a finite term times 0 adds nothing)
    b = slide * (a0 * u0 + a1 * u1 + a2 * u2) + (1.0 - slide) * (rod + q)
    return a0, a1, a2, b


@njit
def _legs(centre, axis, slide, rod):  # pragma: no cover
    """Per-leg constants as a flat float tuple source: ``(n, 8)`` rows
    ``c0 c1 c2 u0 u1 u2 slide rod`` (z = 0 for planar machines)."""
    n, dims = centre.shape
    out = np.zeros((n, 8))
    for i in range(n):
        for d in range(dims):
            out[i, d] = centre[i, d]
            out[i, 3 + d] = axis[i, d]
        out[i, 6] = 1.0 if slide[i] else 0.0
        out[i, 7] = rod[i]
    return out


_COS_THIRD = COEFFICIENTS  # shared with the C twin (native/rod_velocity.c)


@njit(inline="always")
def _cos_third(h):  # pragma: no cover
    """cos(arccos(h) / 3) for h in [−1, 1] without library calls (so the loop vectorises): with
    h = 2s² − 1, it is cos(2 arccos(s) / 3), a smooth function of s on [0, 1] — a polynomial
    gives it to 2e-12, then two Newton steps on the triple-angle identity 4c³ − 3c = h (c is
    its largest root, in [1/2, 1]) make it exact to rounding."""
    s = np.sqrt(0.5 * (1.0 + h))
    c = 0.0
    for k in range(_COS_THIRD.size - 1, -1, -1):
        c = c * s + _COS_THIRD[k]
    for _ in range(2):
        slope = 12.0 * c * c - 3.0
        step = ((4.0 * c * c - 3.0) * c - h) / slope
        c = c - step if slope > 1e-300 else c
    return c


#: Poses per block of the velocity kernels: the block's intermediates stay in L1.
_VBLOCK = 256


@njit(**_OPTIONS)
def velocity3(x, q, centre, axis, slide, rod, bound_limit, det_out, sv_out, cond_out,
              serial_out, hard_out):  # pragma: no cover
    """Velocity summary of a square spatial machine (n = dims = 3), per pose: det A, singular
    values of J = A⁻¹B (decreasing), σ_max/σ_min, the serial measure, and a flag for the rows
    this kernel leaves to the NumPy reference.

    ``x (N, 3)``, ``q (3, N)``; ``centre (3, 3)`` rod centres at q = 0; ``axis (3, 3)``;
    ``slide (3,)`` bool; ``rod (3,)`` lengths. A row is *hard* (``hard_out`` True, other
    outputs undefined) when the lower bound |det Â|/(1.5√3) of the parallel measure σ_min/σ_max
    of A with unit rows Â is below ``bound_limit`` (near a parallel singularity, or within the
    classification tolerance), when two singular values nearly coincide (the closed forms lose
    √eps there), or when a finite input overflows. Rows with a non-finite input get NaN outputs.
    Singular values as in :func:`pkmkit.numerics.small.singular_values`.

    Each block of poses runs in three loops — the algebra (vectorised by the compiler), the
    arccos/cos of the largest eigenvalue of JᵀJ (library calls), then the singular values
    (vectorised) — with the intermediates in small block buffers.
    """
    size = x.shape[0]
    nan = np.nan
    inv_bound = 1.0 / (1.5 * np.sqrt(3.0))
    g = _legs(centre, axis, slide, rod)
    p00, p01, p02, p03, p04, p05, p06, p07 = g[0, 0], g[0, 1], g[0, 2], g[0, 3], g[0, 4], \
        g[0, 5], g[0, 6], g[0, 7]
    p10, p11, p12, p13, p14, p15, p16, p17 = g[1, 0], g[1, 1], g[1, 2], g[1, 3], g[1, 4], \
        g[1, 5], g[1, 6], g[1, 7]
    p20, p21, p22, p23, p24, p25, p26, p27 = g[2, 0], g[2, 1], g[2, 2], g[2, 3], g[2, 4], \
        g[2, 5], g[2, 6], g[2, 7]
    mean_b = np.empty(_VBLOCK)
    spread_b = np.empty(_VBLOCK)
    half_b = np.empty(_VBLOCK)
    cos_b = np.empty(_VBLOCK)
    detj_b = np.empty(_VBLOCK)
    e2_b = np.empty(_VBLOCK)
    bound_b = np.empty(_VBLOCK)
    check_b = np.empty(_VBLOCK)
    det_b = np.empty(_VBLOCK)
    serial_b = np.empty(_VBLOCK)
    xb0 = np.empty(_VBLOCK)
    xb1 = np.empty(_VBLOCK)
    xb2 = np.empty(_VBLOCK)
    for start in range(0, size, _VBLOCK):
        m = min(size - start, _VBLOCK)
        for t in range(m):  # de-interleave (1-D buffers let the compiler vectorise)
            xb0[t] = x[start + t, 0]
            xb1[t] = x[start + t, 1]
            xb2[t] = x[start + t, 2]
        q0 = q[0, start:start + m]
        q1 = q[1, start:start + m]
        q2 = q[2, start:start + m]
        for t in range(m):
            x0, x1, x2 = xb0[t], xb1[t], xb2[t]
            a00, a01, a02, b0 = _leg_row(x0, x1, x2, q0[t], p00, p01, p02, p03, p04, p05,
                                         p06, p07)
            a10, a11, a12, b1 = _leg_row(x0, x1, x2, q1[t], p10, p11, p12, p13, p14, p15,
                                         p16, p17)
            a20, a21, a22, b2 = _leg_row(x0, x1, x2, q2[t], p20, p21, p22, p23, p24, p25,
                                         p26, p27)
            check_b[t] = (a00 + a01 + a02 + a10 + a11 + a12 + a20 + a21 + a22
                          + b0 + b1 + b2)
            # cofactors C[i, j] of A and det A
            c00 = a11 * a22 - a12 * a21
            c01 = a12 * a20 - a10 * a22
            c02 = a10 * a21 - a11 * a20
            c10 = a21 * a02 - a22 * a01
            c11 = a22 * a00 - a20 * a02
            c12 = a20 * a01 - a21 * a00
            c20 = a01 * a12 - a02 * a11
            c21 = a02 * a10 - a00 * a12
            c22 = a00 * a11 - a01 * a10
            det = a00 * c00 + a01 * c01 + a02 * c02
            det_b[t] = det
            l0 = np.sqrt(a00 * a00 + a01 * a01 + a02 * a02)
            l1 = np.sqrt(a10 * a10 + a11 * a11 + a12 * a12)
            l2 = np.sqrt(a20 * a20 + a21 * a21 + a22 * a22)
            serial_b[t] = min(min(abs(b0) / l0, abs(b1) / l1), abs(b2) / l2)
            bound_b[t] = abs(det) / (l0 * l1 * l2) * inv_bound
            # J[r, c] = C[c, r] b_c / det A
            s0, s1, s2 = b0 / det, b1 / det, b2 / det
            j00, j01, j02 = c00 * s0, c10 * s1, c20 * s2
            j10, j11, j12 = c01 * s0, c11 * s1, c21 * s2
            j20, j21, j22 = c02 * s0, c12 * s1, c22 * s2
            # G = JᵀJ, its mean eigenvalue and spread
            g00 = j00 * j00 + j10 * j10 + j20 * j20
            g11 = j01 * j01 + j11 * j11 + j21 * j21
            g22 = j02 * j02 + j12 * j12 + j22 * j22
            g01 = j00 * j01 + j10 * j11 + j20 * j21
            g02 = j00 * j02 + j10 * j12 + j20 * j22
            g12 = j01 * j02 + j11 * j12 + j21 * j22
            mean = (g00 + g11 + g22) / 3.0
            off = g01 * g01 + g02 * g02 + g12 * g12
            d0, d1, d2 = g00 - mean, g11 - mean, g22 - mean
            spread = np.sqrt((d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off) / 6.0)
            scale = 1.0 / spread if spread > 0.0 else 0.0
            h00, h11, h22 = d0 * scale, d1 * scale, d2 * scale
            h01, h02, h12 = g01 * scale, g02 * scale, g12 * scale
            half = 0.5 * (h00 * (h11 * h22 - h12 * h12) - h01 * (h01 * h22 - h12 * h02)
                          + h02 * (h01 * h12 - h11 * h02))
            half_b[t] = min(max(half, -1.0), 1.0)
            mean_b[t] = mean
            spread_b[t] = spread
            # invariants of J: |det J| and the sum of its squared 2×2 minors
            m00 = j11 * j22 - j12 * j21
            m01 = j12 * j20 - j10 * j22
            m02 = j10 * j21 - j11 * j20
            m10 = j21 * j02 - j22 * j01
            m11 = j22 * j00 - j20 * j02
            m12 = j20 * j01 - j21 * j00
            m20 = j01 * j12 - j02 * j11
            m21 = j02 * j10 - j00 * j12
            m22 = j00 * j11 - j01 * j10
            detj_b[t] = abs(j00 * m00 + j01 * m01 + j02 * m02)
            e2_b[t] = (m00 * m00 + m01 * m01 + m02 * m02 + m10 * m10 + m11 * m11 + m12 * m12
                       + m20 * m20 + m21 * m21 + m22 * m22)
        for t in range(m):  # cos(arccos(h)/3), vectorised (see _cos_third)
            h = half_b[t]
            h = h if h - h == 0.0 else 0.0
            cos_b[t] = _cos_third(h)
        det_o = det_out[start:start + m]
        serial_o = serial_out[start:start + m]
        cond_o = cond_out[start:start + m]
        hard_o = hard_out[start:start + m]
        sv0 = sv_out[0, start:start + m]
        sv1 = sv_out[1, start:start + m]
        sv2 = sv_out[2, start:start + m]
        for t in range(m):
            mean, spread = mean_b[t], spread_b[t]
            lam1 = mean + 2.0 * spread * cos_b[t]
            sig1 = np.sqrt(max(lam1, 0.0))
            pair = detj_b[t] / sig1 if sig1 > 0.0 else 0.0
            rest = (e2_b[t] - pair * pair) / lam1 if lam1 > 0.0 else 0.0
            sig2 = 0.5 * (np.sqrt(max(rest + 2.0 * pair, 0.0))
                          + np.sqrt(max(rest - 2.0 * pair, 0.0)))
            sig3 = pair / sig2 if sig2 > 0.0 else 0.0
            sig2 = min(sig2, sig1)
            sig3 = min(sig3, sig2)
            # |half det| → 1: two singular values nearly coincide (LAPACK in the reference)
            coincide = (spread > 0.0) & ((abs(half_b[t]) > 1.0 - 1e-6)
                                         | (rest - 2.0 * pair < 1e-6 * rest))
            total = sig1 + sig2 + sig3
            check = check_b[t]
            finite_in = check - check == 0.0
            hard = finite_in & (~(bound_b[t] >= bound_limit) | coincide | ~(total - total == 0.0))
            hard_o[t] = hard
            sv0[t] = sig1 if finite_in else nan
            sv1[t] = sig2 if finite_in else nan
            sv2[t] = sig3 if finite_in else nan
            cond = sig1 / sig3 if sig3 != 0.0 else np.inf
            cond_o[t] = cond if finite_in else nan
            det_o[t] = det_b[t] if finite_in else nan
            serial_o[t] = serial_b[t] if finite_in else nan


@njit(**_OPTIONS)
def velocity2(x, q, centre, axis, slide, rod, bound_limit, det_out, sv_out, cond_out,
              serial_out, hard_out):  # pragma: no cover
    """:func:`velocity3` for planar machines (n = dims = 2); the parallel-measure bound is
    |det Â|/2."""
    size = x.shape[0]
    nan = np.nan
    g = _legs(centre, axis, slide, rod)
    p00, p01, p03, p04, p06, p07 = g[0, 0], g[0, 1], g[0, 3], g[0, 4], g[0, 6], g[0, 7]
    p10, p11, p13, p14, p16, p17 = g[1, 0], g[1, 1], g[1, 3], g[1, 4], g[1, 6], g[1, 7]
    for k in range(size):
        x0, x1 = x[k, 0], x[k, 1]
        a00, a01, _, b0 = _leg_row(x0, x1, 0.0, q[0, k], p00, p01, 0.0, p03, p04, 0.0, p06, p07)
        a10, a11, _, b1 = _leg_row(x0, x1, 0.0, q[1, k], p10, p11, 0.0, p13, p14, 0.0, p16, p17)
        check = a00 + a01 + a10 + a11 + b0 + b1
        hard_out[k] = False
        if check - check != 0.0:
            det_out[k] = nan
            sv_out[0, k] = sv_out[1, k] = nan
            cond_out[k] = nan
            serial_out[k] = nan
            continue
        det = a00 * a11 - a01 * a10
        det_out[k] = det
        l0 = np.sqrt(a00 * a00 + a01 * a01)
        l1 = np.sqrt(a10 * a10 + a11 * a11)
        serial_out[k] = min(abs(b0) / l0, abs(b1) / l1)
        bound = abs(det) / (l0 * l1) * 0.5
        if not bound >= bound_limit:
            hard_out[k] = True
            continue
        # J[r, c] = C[c, r] b_c / det with C = [[a11, −a10], [−a01, a00]]
        s0, s1 = b0 / det, b1 / det
        ja, jb = a11 * s0, -a01 * s1
        jc, jd = -a10 * s0, a00 * s1
        sig1 = 0.5 * (np.hypot(ja + jd, jc - jb) + np.hypot(ja - jd, jb + jc))
        sig2 = abs(ja * jd - jb * jc) / sig1 if sig1 > 0.0 else 0.0
        total = sig1 + sig2
        if total - total != 0.0:
            hard_out[k] = True
            continue
        sv_out[0, k] = sig1
        sv_out[1, k] = sig2
        cond_out[k] = sig1 / sig2 if sig2 != 0.0 else np.inf
