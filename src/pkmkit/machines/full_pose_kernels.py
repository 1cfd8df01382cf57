"""Compiled (Numba) kernel of the full-pose rod machines' closed-form inverse model.

Imported lazily, only for large batches (see :mod:`pkmkit.numerics.jit`); the NumPy code of
:meth:`pkmkit.machines.full_pose_forms.FullPoseForms.rod_coordinates` is the reference it is
tested against. One fused loop per pose: the rotation matrix from the rotation vector
(Rodrigues), then every rod's closed form — slide, strut or crank — with no temporaries, no
BLAS, single-threaded (it holds beside other work and inside Dask workers).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}


@njit(**_OPTIONS)
def rod_coordinates(x, kind, base, platform, axis, pivot, e1, e2, length_sq, length,
                    crank_radius, crank_offset, sigma, boundary_tol, out):  # pragma: no cover
    """Actuator coordinate implied by every rod ``out (m, N)`` for pose rows ``x (N, 6)``.

    ``kind (m,)`` 0 slide, 1 strut, 2 crank; ``base``, ``platform``, ``axis``, ``pivot``,
    ``e1``, ``e2`` ``(m, 3)``; ``length_sq``, ``length``, ``crank_radius``, ``crank_offset``,
    ``sigma`` ``(m,)``; ``boundary_tol`` as in :mod:`pkmkit.machines.full_pose_forms`."""
    for k in range(x.shape[0]):
        _pose_rods(x, k, kind, base, platform, axis, pivot, e1, e2, length_sq, length,
                   crank_radius, crank_offset, sigma, boundary_tol, out, k)


@njit(inline="always", **_OPTIONS)
def rotation_entries(wx, wy, wz):  # pragma: no cover
    """The nine entries ``r00, r01, …, r22`` of the rotation of rotation vector (wx, wy, wz)
    (Rodrigues; the series R = I + [w] + [w]²/2 below 1e-8 rad)."""
    theta = math.sqrt(wx * wx + wy * wy + wz * wz)
    if theta < 1e-8:
        a = 1.0 - theta * theta / 6.0
        b = 0.5 - theta * theta / 24.0
    else:
        a = math.sin(theta) / theta
        b = (1.0 - math.cos(theta)) / (theta * theta)
    r00 = 1.0 - b * (wy * wy + wz * wz)
    r11 = 1.0 - b * (wx * wx + wz * wz)
    r22 = 1.0 - b * (wx * wx + wy * wy)
    r01 = b * wx * wy - a * wz
    r10 = b * wx * wy + a * wz
    r02 = b * wx * wz + a * wy
    r20 = b * wx * wz - a * wy
    r12 = b * wy * wz - a * wx
    r21 = b * wy * wz + a * wx
    return r00, r01, r02, r10, r11, r12, r20, r21, r22


@njit(inline="always", **_OPTIONS)
def _pose_rods(x, k, kind, base, platform, axis, pivot, e1, e2, length_sq, length,
               crank_radius, crank_offset, sigma, boundary_tol, out, col):  # pragma: no cover
    """Every rod's actuator coordinate of pose row ``x[k]`` into ``out[:, col]``."""
    m = kind.shape[0]
    two_pi = 2.0 * math.pi
    px, py, pz = x[k, 0], x[k, 1], x[k, 2]
    wx, wy, wz = x[k, 3], x[k, 4], x[k, 5]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(wx, wy, wz)
    for j in range(m):
        bx, by, bz = platform[j, 0], platform[j, 1], platform[j, 2]
        qx = px + r00 * bx + r01 * by + r02 * bz
        qy = py + r10 * bx + r11 * by + r12 * bz
        qz = pz + r20 * bx + r21 * by + r22 * bz
        if kind[j] == 2:  # crank
            vx, vy, vz = qx - pivot[j, 0], qy - pivot[j, 1], qz - pivot[j, 2]
            vw = vx * axis[j, 0] + vy * axis[j, 1] + vz * axis[j, 2] - crank_offset[j]
            v1 = vx * e1[j, 0] + vy * e1[j, 1] + vz * e1[j, 2]
            v2 = vx * e2[j, 0] + vy * e2[j, 1] + vz * e2[j, 2]
            perp = math.sqrt(v1 * v1 + v2 * v2)
            r = crank_radius[j]
            g = vw * vw + perp * perp + r * r - length_sq[j]
            amplitude = 2.0 * r * perp
            cosine = g / amplitude if amplitude > 0.0 else math.nan
            if abs(g) - amplitude <= boundary_tol * length_sq[j]:
                cosine = min(1.0, max(-1.0, cosine))
            if cosine > 1.0 or cosine < -1.0 or cosine != cosine:
                out[j, col] = math.nan
            else:
                angle = math.atan2(v2, v1) + sigma[j] * math.acos(cosine)
                out[j, col] = (angle + math.pi) % two_pi - math.pi
            continue
        wxr, wyr, wzr = qx - base[j, 0], qy - base[j, 1], qz - base[j, 2]
        dist_sq = wxr * wxr + wyr * wyr + wzr * wzr
        if kind[j] == 1:  # strut
            out[j, col] = math.sqrt(dist_sq) - length[j]
            continue
        s = wxr * axis[j, 0] + wyr * axis[j, 1] + wzr * axis[j, 2]
        radicand = length_sq[j] - dist_sq + s * s
        if radicand < 0.0:
            if radicand > -boundary_tol * length_sq[j]:
                radicand = 0.0
            else:
                out[j, col] = math.nan
                continue
        out[j, col] = s + sigma[j] * math.sqrt(radicand)


@njit(**_OPTIONS)
def inverse_poses(x, kind, base, platform, axis, pivot, e1, e2, length_sq, length,
                  crank_radius, crank_offset, sigma, boundary_tol, groups, counts, angular,
                  consistency_tol, q, status):  # pragma: no cover
    """The whole inverse model of pose rows ``x (N, 6)`` in one pass: actuator coordinates
    ``q (N, n)`` and ``status (N,)`` (0 OK, 1 unreachable — a rod that cannot close or rods of
    one actuator that disagree by more than ``consistency_tol`` —, 4 invalid input: a value
    not finite or beyond 1e9); q is NaN on every row that is not OK.

    Rod arguments as :func:`rod_coordinates`; ``groups (n, g)`` the rods of each actuator
    (first ``counts[k]`` entries), ``angular (n,)`` whether its rods' values are angles
    (differences wrapped to (−π, π]) — as
    :meth:`pkmkit.machines.full_pose_forms.FullPoseForms.combine`."""
    size = x.shape[0]
    m = kind.shape[0]
    n = counts.shape[0]
    rod_q = np.empty((m, 1))
    for k in range(size):
        valid = True
        for i in range(6):
            if not abs(x[k, i]) <= 1e9:
                valid = False
        if not valid:
            status[k] = 4
            for a in range(n):
                q[k, a] = math.nan
            continue
        _pose_rods(x, k, kind, base, platform, axis, pivot, e1, e2, length_sq, length,
                   crank_radius, crank_offset, sigma, boundary_tol, rod_q, 0)
        ok = True
        for j in range(m):
            if not rod_q[j, 0] == rod_q[j, 0]:
                ok = False
        spread = 0.0
        if ok:
            for a in range(n):
                first = rod_q[groups[a, 0], 0]
                total = 0.0
                for c in range(1, counts[a]):
                    d = rod_q[groups[a, c], 0] - first
                    if angular[a]:
                        d = ((d + math.pi) % (2.0 * math.pi)) - math.pi
                    total += d
                mean = total / counts[a]
                spread = max(spread, abs(mean))
                for c in range(1, counts[a]):
                    d = rod_q[groups[a, c], 0] - first
                    if angular[a]:
                        d = ((d + math.pi) % (2.0 * math.pi)) - math.pi
                    spread = max(spread, abs(d - mean))
                q[k, a] = first + mean
            ok = spread <= consistency_tol
        if ok:
            status[k] = 0
        else:
            status[k] = 1
            for a in range(n):
                q[k, a] = math.nan
