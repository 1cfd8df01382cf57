"""The Tripteor X7's closed-form starts compiled (issue 22 §1, session 35): the Numba twin of
:func:`pkmkit.machines.tripteor_forms.start_unknowns` (the inverse model's start) and
:func:`~pkmkit.machines.tripteor_forms.direct_unknowns` (the direct model's), statement for
statement with ``native/chain_one_tripteor.c`` (the C call's twin).

The start functions carry this module's name as ``start.compiled``
(:func:`pkmkit.machines.chain_starts.compiled_start` reads it): without the C extension, once
Numba is imported, the batch path (:func:`~pkmkit.machines.chain_starts.closed_starts`,
:func:`~pkmkit.machines.chain_starts.closed_direct_starts`) and the one-pose Numba path
(:mod:`pkmkit.machines.chain_one`) both run :func:`inverse_rows` / :func:`direct_rows` — the
same compiled function on each row, so their answers agree bit for bit — where the NumPy
functions cost ≈ 250 µs per one-row call; with it, the C twin's batch entries
(``native/chain_closed_rows.c``), whose bits are these (tests/machines/test_closed_starts.py).
The NumPy functions stay the reference (agreement to rounding: NumPy's AVX-512
transcendental functions and libm's differ in the last place).

``k``: :func:`pkmkit.machines.tripteor_forms.constants` (25,). The module's constants are
:mod:`~pkmkit.machines.tripteor_forms`'s (read at its import: one set of values).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines import tripteor_forms as _forms

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}
_STEPS = _forms.INVERSE_STEPS
_DIRECT_STEPS = _forms.DIRECT_STEPS
_TOL = _forms.INVERSE_TOL
_STALL = _forms.INVERSE_STALL
_SINGULAR = _forms.INVERSE_SINGULAR
_H = _forms.JACOBIAN_STEP
_REFRESH = _forms.JACOBIAN_REFRESH
_FOUR_BAR = _forms.FOUR_BAR
_THETA0, _PSI0 = _forms.DIRECT_START
_INVERSE, _DIRECT = 0, 1  # the residual of _newton2


@njit(**_OPTIONS)
def _acos(x):
    """NumPy's ``arccos``: NaN beyond [−1, 1]."""
    return math.acos(x) if -1.0 <= x <= 1.0 else math.nan


@njit(**_OPTIONS)
def _explicit(k, px, py, pz):
    """tripteor_forms._explicit: ψ, σ of the platform whose MPS origin is P."""
    ax2, ay2 = -k[3], -0.5 * k[2]
    r = math.sqrt(px * px + pz * pz)
    psi = math.atan2(pz, px) + k[22] * _acos(k[15] / r)
    cp, sp = math.cos(psi), math.sin(psi)
    ea = -sp * (px - ax2) + cp * pz
    eb = -(py - ay2)
    rho = math.sqrt(ea * ea + eb * eb)
    return psi, math.atan2(eb, ea) + k[23] * _acos(-(k[16] - k[13]) / rho)


@njit(**_OPTIONS)
def _frame(psi, sigma, f):
    """R51's columns x51, y51, z51 into ``f (9,)``."""
    cp, sp, cs, ss = math.cos(psi), math.sin(psi), math.cos(sigma), math.sin(sigma)
    f[0], f[1], f[2] = -sp * cs, -ss, cp * cs
    f[3], f[4], f[5] = sp * ss, -cs, -cp * ss
    f[6], f[7], f[8] = cp, 0.0 * cp, sp


@njit(**_OPTIONS)
def _head(k, psi, sigma, ax, ay, az, b, f, xq):
    """tripteor_forms._head: R51's columns into ``f``, x' into ``xq``; returns (a·z_P, |g|)."""
    _frame(psi, sigma, f)
    zp0 = f[0] * k[6] + f[3] * k[9] + f[6] * k[12]
    zp1 = f[1] * k[6] + f[4] * k[9] + f[7] * k[12]
    zp2 = f[2] * k[6] + f[5] * k[9] + f[8] * k[12]
    az_dot = ax * zp0 + ay * zp1 + az * zp2
    gx, gy, gz = ax - az_dot * zp0, ay - az_dot * zp1, az - az_dot * zp2
    gn = math.sqrt(gx * gx + gy * gy + gz * gz)
    scale = -b / gn
    xq[0], xq[1], xq[2] = scale * gx, scale * gy, scale * gz
    return az_dot, gn


@njit(**_OPTIONS)
def _step(k, psi, sigma, data, f, xq):
    """Φ(ψ, σ): the explicit angles of P = W − c1 x'(ψ, σ); ``data`` (w, a, b)."""
    _head(k, psi, sigma, data[3], data[4], data[5], data[6], f, xq)
    c1 = k[0]
    return _explicit(k, data[0] - c1 * xq[0], data[1] - c1 * xq[1], data[2] - c1 * xq[2])


@njit(**_OPTIONS)
def _platform_of(k, theta, psi, q1, q3, f, b1):
    """tripteor_forms._platform_of: σ; R51's columns into ``f``, B1 into ``b1``."""
    big, small = k[2], k[24]
    s1, t1 = q1 * math.cos(theta), q1 * math.sin(theta)
    ds, dt = s1, t1 - big
    rho = math.sqrt(ds * ds + dt * dt)
    ca = (q3 * q3 + rho * rho - small * small) / (2 * q3 * rho)
    alpha = math.atan2(dt, ds) + _FOUR_BAR * _acos(ca)
    s3, t3 = q3 * math.cos(alpha), big + q3 * math.sin(alpha)
    sigma = math.atan2(t1 - t3, s1 - s3)
    _frame(psi, sigma, f)
    cp, sp = math.cos(psi), math.sin(psi)
    b1[0], b1[1], b1[2] = -sp * s1, -t1, cp * s1
    return sigma


@njit(**_OPTIONS)
def _equations(which, k, z0, z1, data, f, xq):
    """The two functions of :func:`_newton2` at ``(z0, z1)``: the inverse's Φ (``data``: w, a,
    b) or the direct model's leg 2 (tripteor_forms._leg2; ``data``: q)."""
    if which == _INVERSE:
        return _step(k, z0, z1, data, f, xq)
    _platform_of(k, z0, z1, data[0], data[2], f, xq)
    d0 = xq[0] + f[0] * k[16] + f[3] * k[17] + f[6] * k[18] + k[3]
    d1 = xq[1] + f[1] * k[16] + f[4] * k[17] + f[7] * k[18] + 0.5 * k[2]
    d2 = xq[2] + f[2] * k[16] + f[5] * k[17] + f[8] * k[18]
    return (d0 * f[0] + d1 * f[1] + d2 * f[2],
            math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - data[1])


@njit(**_OPTIONS)
def _newton2(which, k, z0, z1, steps, data, f, xq):
    """tripteor_forms._newton2 on one row: Newton's steps on ``F(z) − shift z = 0`` (shift 1:
    the inverse's fixed point of Φ; 0: the direct model's equations) from ``(z0, z1)``, the
    Jacobian by differences, chord steps once a step is below the refresh threshold;
    ``(z0, z1, converged)``."""
    shift = 1.0 if which == _INVERSE else 0.0
    f0, f1 = _equations(which, k, z0, z1, data, f, xq)
    i00 = i01 = i10 = i11 = 0.0
    fresh = True
    last = math.inf
    for _ in range(steps):
        r0, r1 = f0 - shift * z0, f1 - shift * z1
        if fresh:
            a0, a1 = _equations(which, k, z0 + _H, z1, data, f, xq)
            c0, c1 = _equations(which, k, z0, z1 + _H, data, f, xq)
            j00, j10 = (a0 - f0) / _H - shift, (a1 - f1) / _H
            j01, j11 = (c0 - f0) / _H, (c1 - f1) / _H - shift
            det = j00 * j11 - j01 * j10
            i00, i01, i10, i11 = j11 / det, -j01 / det, -j10 / det, j00 / det
        d0, d1 = i00 * r0 + i01 * r1, i10 * r0 + i11 * r1
        z0, z1 = z0 - d0, z1 - d1
        change = abs(d0) + abs(d1)
        if change <= _TOL or (change <= _STALL and change >= last):
            return z0, z1, True
        last = change
        fresh = change > _REFRESH
        f0, f1 = _equations(which, k, z0, z1, data, f, xq)
    return z0, z1, False


@njit(**_OPTIONS)
def _rotvec(psi, sigma, u):
    """tripteor_forms._rotvec into ``u[3:6]``."""
    r = math.sqrt(0.5)
    cp, sp = math.cos(0.5 * psi), math.sin(0.5 * psi)
    cs, ss = math.cos(0.5 * sigma), math.sin(0.5 * sigma)
    aw, ax, ay, az = r * cp, r * cp, -r * sp, r * sp
    # times (½, ½, ½, ½)
    bw = aw * 0.5 - ax * 0.5 - ay * 0.5 - az * 0.5
    bx = aw * 0.5 + ax * 0.5 + ay * 0.5 - az * 0.5
    by = aw * 0.5 - ax * 0.5 + ay * 0.5 + az * 0.5
    bz = aw * 0.5 + ax * 0.5 - ay * 0.5 + az * 0.5
    zero = 0.0 * cs
    w = bw * cs - bx * zero - by * zero - bz * ss
    qx = bw * zero + bx * cs + by * ss - bz * zero
    qy = bw * zero - bx * ss + by * cs + bz * zero
    qz = bw * ss + bx * zero - by * zero + bz * cs
    flip = -1.0 if w < 0 else 1.0
    w, qx, qy, qz = w * flip, qx * flip, qy * flip, qz * flip
    norm = math.sqrt(qx * qx + qy * qy + qz * qz)
    scale = 2.0 * math.atan2(norm, w) / norm
    u[3], u[4], u[5] = scale * qx, scale * qy, scale * qz


@njit(**_OPTIONS)
def _legs(k, psi, sigma, f, b1, u):
    """tripteor_forms._legs: the platform and every joint of the legs into ``u[:19]``."""
    b2x = f[0] * k[16] + f[3] * k[17] + f[6] * k[18]
    b2y = f[1] * k[16] + f[4] * k[17] + f[7] * k[18]
    b2z = f[2] * k[16] + f[5] * k[17] + f[8] * k[18]
    b3x = f[0] * k[19] + f[3] * k[20] + f[6] * k[21]
    b3y = f[1] * k[19] + f[4] * k[20] + f[7] * k[21]
    b3z = f[2] * k[19] + f[5] * k[20] + f[8] * k[21]
    u[0], u[1], u[2] = b1[0], b1[1], b1[2]
    _rotvec(psi, sigma, u)
    cp, sp = math.cos(psi), math.sin(psi)
    big, dd = k[2], k[3]
    e1b1 = -sp * b1[0] + cp * b1[2]
    theta1 = math.atan2(-b1[1], e1b1)
    d3x, d3y, d3z = b1[0] + b3x, b1[1] + b3y + big, b1[2] + b3z
    e1b3 = -sp * d3x + cp * d3z
    theta3 = math.atan2(-d3y, e1b3)
    d2x, d2y, d2z = b1[0] + b2x + dd, b1[1] + b2y + 0.5 * big, b1[2] + b2z
    q2 = math.sqrt(d2x * d2x + d2y * d2y + d2z * d2z)
    psi2 = math.atan2(-d2y, d2z)
    theta2 = math.atan2(d2x, math.sqrt(d2y * d2y + d2z * d2z))
    c2, s2, ct2, st2 = math.cos(psi2), math.sin(psi2), math.cos(theta2), math.sin(theta2)
    mx = ct2 * f[0] + s2 * st2 * f[1] - c2 * st2 * f[2]
    my = c2 * f[1] + s2 * f[2]
    eta2 = math.atan2(-mx, my)
    phi2 = math.atan2(d2x * f[6] + d2y * f[7] + d2z * f[8], d2x * f[3] + d2y * f[4] + d2z * f[5])
    half = 0.5 * np.pi
    u[6], u[7], u[8], u[9] = psi, theta1, math.hypot(e1b1, b1[1]), sigma - theta1 + half
    u[10], u[11], u[12], u[13], u[14] = psi2, theta2, eta2, q2, phi2
    u[15], u[16], u[17], u[18] = psi, theta3, math.hypot(e1b3, d3y), sigma - theta3 + half


@njit(**_OPTIONS)
def _finite(u) -> bool:
    for v in u:
        if not math.isfinite(v):
            return False
    return True


@njit(**_OPTIONS)
def inverse_row(k, tool, target, branch, u) -> bool:
    """The inverse model's closed start of one ``target (6,)`` (unit axis) at tool length
    ``tool`` on ``branch`` (±1; 0: the branch nearest home, tripteor_forms._nearest_branch)
    into ``u (21,)``: True, or False where it declines (``u`` then undefined)."""
    ax, ay, az = target[3], target[4], target[5]
    reach = k[1] + tool
    wx, wy, wz = target[0] - reach * ax, target[1] - reach * ay, target[2] - reach * az
    f = np.empty(9)
    xq = np.empty(3)
    psi, sigma = _explicit(k, wx, wy, wz)  # c1 = 0
    if branch == 0.0:
        _frame(psi, sigma, f)
        along = -(ax * (f[0] * k[4] + f[3] * k[7] + f[6] * k[10])
                  + ay * (f[1] * k[4] + f[4] * k[7] + f[7] * k[10])
                  + az * (f[2] * k[4] + f[5] * k[7] + f[8] * k[10]))
        branch = 1.0 if along >= 0 else -1.0
    data = np.empty(7)
    data[0], data[1], data[2], data[3], data[4], data[5], data[6] = wx, wy, wz, ax, ay, az, \
        branch
    psi, sigma, done = _newton2(_INVERSE, k, psi, sigma, _STEPS, data, f, xq)
    az_dot, gn = _head(k, psi, sigma, ax, ay, az, branch, f, xq)
    c1 = k[0]
    b1 = np.empty(3)
    for i in range(3):
        b1[i] = (data[i] - c1 * xq[i]) - (f[i] * k[13] + f[3 + i] * k[14] + f[6 + i] * k[15])
    _legs(k, psi, sigma, f, b1, u)
    xp0 = f[0] * k[4] + f[3] * k[7] + f[6] * k[10]
    xp1 = f[1] * k[4] + f[4] * k[7] + f[7] * k[10]
    xp2 = f[2] * k[4] + f[5] * k[7] + f[8] * k[10]
    yp0 = f[0] * k[5] + f[3] * k[8] + f[6] * k[11]
    yp1 = f[1] * k[5] + f[4] * k[8] + f[7] * k[11]
    yp2 = f[2] * k[5] + f[5] * k[8] + f[8] * k[11]
    u[19] = math.atan2(xq[0] * yp0 + xq[1] * yp1 + xq[2] * yp2,
                       xq[0] * xp0 + xq[1] * xp1 + xq[2] * xp2)
    u[20] = branch * math.atan2(gn, -az_dot)
    return done and gn >= _SINGULAR and _finite(u)


@njit(**_OPTIONS)
def direct_row(k, q, u) -> bool:
    """The direct model's closed start at actuators ``q (5,)`` into ``u (21,)``: True, or
    False where it declines."""
    f = np.empty(9)
    b1 = np.empty(3)
    theta, psi, done = _newton2(_DIRECT, k, _THETA0, _PSI0, _DIRECT_STEPS, q, f, b1)
    sigma = _platform_of(k, theta, psi, q[0], q[2], f, b1)
    _legs(k, psi, sigma, f, b1, u)
    u[19], u[20] = q[3], q[4]
    return done and _finite(u)


@njit(**_OPTIONS)
def inverse_rows(k, targets, tools, branches, out) -> None:
    """:func:`inverse_row` on every row into ``out (N, 21)``, NaN rows where it declines."""
    for i in range(targets.shape[0]):
        if not inverse_row(k, tools[i], targets[i], branches[i], out[i]):
            out[i, :] = np.nan


@njit(**_OPTIONS)
def direct_rows(k, q, out) -> None:
    """:func:`direct_row` on every row into ``out (N, 21)``, NaN rows where it declines."""
    for i in range(q.shape[0]):
        if not direct_row(k, q[i], out[i]):
            out[i, :] = np.nan
