"""The TriMule 600's closed-form starts compiled (issue 22 §1, session 35): the Numba twin of
:func:`pkmkit.machines.trimule_forms.start_unknowns` (the inverse model's start) and
:func:`~pkmkit.machines.trimule_forms.direct_unknowns` (the direct model's), statement for
statement with ``native/chain_one_trimule.c`` (``pk_one_trimule_start``, ``_direct``: the C twin).

As :mod:`pkmkit.machines.tripteor_start_kernel`: the start functions carry this module's name as
``start.compiled``; without the C extension, once Numba is imported, the batch path and the
one-pose Numba path both run :func:`inverse_rows` / :func:`direct_rows` (with it, the C twin's
batch entries, ``native/chain_closed_rows.c`` and ``chain_one_trimule.c``: the same bits).
``k``: ``trimule_forms.native_constants(params)[1:]``
(c1, c2, spindle, L, l, H, h).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines import trimule_forms as _forms

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}
_SWEEPS = _forms.INVERSE_SWEEPS
_TOL = _forms.INVERSE_TOL
_SINGULAR = _forms.INVERSE_SINGULAR
_BISECTIONS = _forms.DIRECT_BISECTIONS


@njit(**_OPTIONS)
def _clip_unit(x):
    return -1.0 if x < -1.0 else (1.0 if x > 1.0 else x)


@njit(**_OPTIONS)
def _joints(k, length, psi, theta, dx, dy, dz, u) -> None:
    """``native/chain_one.c`` ``closed_joints`` (trimule_forms._platform_rotvec,
    _parallel_joints): the platform and the parallel part's joints into ``u[:25]``."""
    big, small, hb, hs = k[3], k[4], k[5], k[6]
    ct, st, cp, sp = math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    u[0], u[1], u[2] = length * dx, length * dy, length * dz
    ch, sh = math.cos(-0.5 * psi), math.sin(-0.5 * psi)
    cq, sq = math.cos(-0.5 * theta), math.sin(-0.5 * theta)
    w, qx, qy, qz = -sh * sq, ch * sq, -sh * cq, ch * cq
    flip = -1.0 if w < 0 else 1.0
    w, qx, qy, qz = w * flip, qx * flip, qy * flip, qz * flip
    norm = math.sqrt(qx * qx + qy * qy + qz * qz)
    scale = 2.0 * math.atan2(norm, w) / norm
    u[3], u[4], u[5] = scale * qx, scale * qy, scale * qz
    e1x, e1y = big - small * ct + 2 * length * st, small * st + 2 * length * ct
    e3x, e3y = -big + small * ct + 2 * length * st, -small * st + 2 * length * ct
    lx = -length * st
    ly = length * ct * sp - hs * cp + hb
    lz = length * ct * cp + hs * sp
    q2 = math.sqrt(lx * lx + ly * ly + lz * lz)
    ratio = -lx / q2
    theta2 = math.asin(ratio) if -1.0 <= ratio <= 1.0 else math.nan
    psi2 = math.atan2(ly, lz)
    ca, sa = math.cos(theta2), math.sin(theta2)
    cb, sb = math.cos(psi2 - psi), math.sin(psi2 - psi)
    cc, sc = ct, -st
    g00 = ca * cc - sa * cb * sc
    g10 = sb * sc
    g20 = -sa * cc - ca * cb * sc
    g21 = ca * sb
    g22 = -sa * sc + ca * cb * cc
    theta1, theta3 = math.atan2(e1x, e1y), math.atan2(e3x, e3y)
    u[6], u[7], u[8], u[9], u[10] = psi, theta1, 0.5 * math.hypot(e1x, e1y), 0.0, 0.0
    u[11], u[12], u[13], u[14] = theta - theta1, psi2, theta2, q2
    u[15], u[16], u[17] = math.atan2(g10, g00), math.asin(_clip_unit(g20)), math.atan2(g21, g22)
    u[18], u[19], u[20], u[21] = theta3, 0.5 * math.hypot(e3x, e3y), 0.0, 0.0
    u[22], u[23], u[24] = theta3 - theta, theta, length


@njit(**_OPTIONS)
def _finite(u) -> bool:
    for v in u:
        if not math.isfinite(v):
            return False
    return True


@njit(**_OPTIONS)
def inverse_row(k, tool, target, branch, u) -> bool:
    """The inverse model's closed start of one ``target (6,)`` (unit axis) at tool length
    ``tool`` on ``branch`` (±1; 0: the branch nearest home, trimule_forms.start_unknowns) into
    ``u (27,)``: True, or False where it declines (``u`` then undefined)."""
    c1, c2, reach = k[0], k[1], k[2] + tool
    ax, ay, az = target[3], target[4], target[5]
    wx, wy, wz = target[0] - reach * ax, target[1] - reach * ay, target[2] - reach * az
    vx, vy, vz = wx, wy, wz
    if branch == 0.0:
        r = math.sqrt(wx * wx + wy * wy + wz * wz)
        dx, dy, dz = wx / r, wy / r, wz / r
        ct = math.sqrt(dy * dy + dz * dz)
        along = -ct * ax + dx * (dy * ay + dz * az) / ct
        branch = 1.0 if along >= 0 else -1.0
    done = False
    for _ in range(_SWEEPS):
        r = math.sqrt(vx * vx + vy * vy + vz * vz)
        dx, dy, dz = vx / r, vy / r, vz / r
        ad = ax * dx + ay * dy + az * dz
        gx, gy, gz = ax - ad * dx, ay - ad * dy, az - ad * dz
        scale = c2 * branch / math.sqrt(gx * gx + gy * gy + gz * gz)
        nx, ny, nz = wx - scale * gx, wy - scale * gy, wz - scale * gz
        change = abs(nx - vx) + abs(ny - vy) + abs(nz - vz)
        vx, vy, vz = nx, ny, nz
        if change <= _TOL:
            done = True
            break
    r = math.sqrt(vx * vx + vy * vy + vz * vz)
    dx, dy, dz = vx / r, vy / r, vz / r
    ad = ax * dx + ay * dy + az * dz
    gx, gy, gz = ax - ad * dx, ay - ad * dy, az - ad * dz
    gn = math.sqrt(gx * gx + gy * gy + gz * gz)
    if not (done and gn >= _SINGULAR):
        return False
    length = r - c1
    theta = math.asin(-dx) if -1.0 <= -dx <= 1.0 else math.nan
    psi = math.atan2(dy, dz)
    ct, st, cp, sp = math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    _joints(k, length, psi, theta, dx, dy, dz, u)
    u[25] = math.atan2(branch * (-cp * ay + sp * az),
                       branch * (-ct * ax - st * sp * ay - st * cp * az))
    u[26] = branch * math.atan2(gn, ad)
    return _finite(u)


@njit(**_OPTIONS)
def _leg_h(a, b, k, t):
    v = a + b * math.cos(t)
    return math.sqrt(v if v > 0.0 else 0.0) * math.sin(t) - k


@njit(**_OPTIONS)
def direct_row(k, q, u) -> bool:
    """The direct model's closed start at actuators ``q (5,)`` into ``u (27,)``: True, or
    False where it declines (no assembly in the working mode)."""
    big, small, hb, hs = k[3], k[4], k[5], k[6]
    q1, q2, q3 = q[0], q[1], q[2]
    if not (q1 > 0.0 and q2 > 0.0 and q3 > 0.0 and math.isfinite(q1) and math.isfinite(q2)
            and math.isfinite(q3)):
        return False
    kk = (q1 * q1 - q3 * q3) / big
    a = 2 * (q1 * q1 + q3 * q3) - big * big - small * small
    b = 2 * big * small
    c_star = (-a + math.sqrt(a * a + 3 * b * b)) / (3 * b)
    limit = math.acos(_clip_unit(c_star))
    lo, hi = -limit, limit
    if not (a - b > 0 and _leg_h(a, b, kk, lo) <= 0 and _leg_h(a, b, kk, hi) >= 0):
        return False
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        if _leg_h(a, b, kk, mid) > 0:
            hi = mid
        else:
            lo = mid
    theta = 0.5 * (lo + hi)
    for _ in range(2):  # Newton: h' = (3B c² + 2A c − B) / (2u)
        w = math.sqrt(a + b * math.cos(theta))
        c = math.cos(theta)
        theta = theta - _leg_h(a, b, kk, theta) * 2 * w / (3 * b * c * c + 2 * a * c - b)
    length = 0.5 * math.sqrt(a + b * math.cos(theta))
    ca = 2 * hb * length * math.cos(theta)
    cb = -2 * hb * hs
    d = q2 * q2 - length * length - hs * hs - hb * hb
    radius = math.hypot(ca, cb)
    if not abs(d) <= radius:
        return False
    psi = math.atan2(ca, cb) - math.acos(_clip_unit(d / radius))
    psi = (psi + np.pi) % (2 * np.pi) - np.pi
    ct, st, cp, sp = math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi)
    _joints(k, length, psi, theta, -st, ct * sp, ct * cp, u)
    u[0], u[1], u[2] = -length * st, length * ct * sp, length * ct * cp
    u[25], u[26] = q[3], q[4]
    return _finite(u)


@njit(**_OPTIONS)
def inverse_rows(k, targets, tools, branches, out) -> None:
    """:func:`inverse_row` on every row into ``out (N, 27)``, NaN rows where it declines."""
    for i in range(targets.shape[0]):
        if not inverse_row(k, tools[i], targets[i], branches[i], out[i]):
            out[i, :] = np.nan


@njit(**_OPTIONS)
def direct_rows(k, q, out) -> None:
    """:func:`direct_row` on every row into ``out (N, 27)``, NaN rows where it declines."""
    for i in range(q.shape[0]):
        if not direct_row(k, q[i], out[i]):
            out[i, :] = np.nan
