"""Compiled (Numba) velocity model of one full pose of a rod machine (issue 22 §1).

:func:`velocity_one` computes, for one pose row and its actuator coordinates, every field of
:meth:`pkmkit.machines.full_pose.FullPoseMachine._jacobians` (the NumPy reference it is tested
against) in one call: ``A (m, 6)`` rows ``(d_jᵀ, (R b_j × d_j)ᵀ)``, ``B (m, n)``, the
singularity measures (σ_min/σ_max of A with unit rows and moments over L; the smallest |cos|
between a rod and its base joint's motion), ``J = A⁻¹B`` (LAPACK; ``A⁺B`` beyond six rods),
``J⁻¹ = B⁺A``, det A, det B, and the singular values of the homogenised J and of its linear and
angular rows (one-sided Jacobi, :mod:`pkmkit.numerics.svd_kernel`). Rods are given as in
:mod:`pkmkit.machines.full_pose_direct_kernel` (``geom (m, 16)``).

:func:`velocity_matrices` computes the same minus the singular values of J (what J, A, B, J⁻¹,
the determinants and the flags need; the parallel measure only where its lower bound cannot
settle the flags): the same operations, so the same bits for the fields both give.

Output ``out`` (flat): A (6m), B (mn), J (6n), J⁻¹ (6n), σ(J_h) (min(6, n)), σ(J[:3])
(min(3, n)), σ(J[3:]) (min(3, n)), then condition, det A, det B, parallel, serial, flags —
:func:`layout` gives the offsets. Returns 0, or 1 when the row is not finite (the caller then
takes the batch path).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import lru_cache
from types import MappingProxyType

import numpy as np
from numba import njit

from pkmkit.machines.full_pose_direct_kernel import _rods
from pkmkit.machines.full_pose_kernels import rotation_entries
from pkmkit.numerics.svd_kernel import singular_values

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}


@lru_cache(maxsize=64)
def layout(m: int, n: int) -> Mapping[str, tuple[int, int]]:
    """``name -> (start, stop)`` of each field in the output vector of :func:`velocity_one`."""
    sizes = [("A", 6 * m), ("B", m * n), ("J", 6 * n), ("J_inv", 6 * n), ("sv", min(6, n)),
             ("sv_t", min(3, n)), ("sv_r", min(3, n)), ("condition", 1), ("det_A", 1),
             ("det_B", 1), ("parallel", 1), ("serial", 1), ("flags", 1)]
    out, start = {}, 0
    for name, size in sizes:
        out[name] = (start, start + size)
        start += size
    return MappingProxyType(out)  # cached: every caller reads the same mapping


@njit(**_OPTIONS)
def _values(mat, out, at):  # pragma: no cover
    """Singular values of ``mat (r, c)`` into ``out[at:at + min(r, c)]`` (NaN if not finite)."""
    k = min(mat.shape[0], mat.shape[1])
    sv = np.empty((1, k))
    singular_values(mat.reshape((1, mat.shape[0], mat.shape[1])), sv)
    for i in range(k):
        out[at + i] = sv[0, i]


@njit(**_OPTIONS)
def _fill(x, q, geom, n, length_l, tol, out, exact):  # pragma: no cover
    """A, B, J, J⁻¹, det A, det B, the serial measure and the flags of pose ``x (6,)`` at
    ``q (n,)`` into ``out`` (module docstring); the parallel measure too when ``exact`` or
    when its lower bound cannot tell it from ``tol`` (NaN otherwise). Returns 0, or 1 for a
    row that is not finite."""
    m = geom.shape[0]
    base = np.empty((m, 3))
    length = np.empty(m)
    _rods(q, geom, base, length)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(x[3], x[4], x[5])
    a = np.zeros((m, 6))
    b = np.zeros((m, n))
    unit = np.empty((m, 6))
    serial = np.inf
    for j in range(m):
        bx, by, bz = geom[j, 3], geom[j, 4], geom[j, 5]
        sx = r00 * bx + r01 * by + r02 * bz
        sy = r10 * bx + r11 * by + r12 * bz
        sz = r20 * bx + r21 * by + r22 * bz
        dx, dy, dz = x[0] + sx - base[j, 0], x[1] + sy - base[j, 1], x[2] + sz - base[j, 2]
        a[j, 0], a[j, 1], a[j, 2] = dx, dy, dz
        a[j, 3], a[j, 4], a[j, 5] = sy * dz - sz * dy, sz * dx - sx * dz, sx * dy - sy * dx
        kind = geom[j, 13]
        k = int(geom[j, 14])
        if kind == 0.0:  # slide: the axis
            vx, vy, vz = geom[j, 6], geom[j, 7], geom[j, 8]
        elif kind == 2.0:  # crank: w × (a_j − P)
            wx, wy, wz = geom[j, 6], geom[j, 7], geom[j, 8]
            px, py, pz = base[j, 0] - geom[j, 9], base[j, 1] - geom[j, 10], base[j, 2] - geom[
                j, 11]
            vx, vy, vz = wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px
        else:
            vx, vy, vz = 0.0, 0.0, 0.0
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        for i in range(6):
            unit[j, i] = a[j, i] / dist if i < 3 else a[j, i] / dist / length_l
        if kind == 1.0:  # strut: its base joint does not move, the measure is 1
            b[j, k] = length[j]
            serial = min(serial, 1.0)
        else:
            b[j, k] = dx * vx + dy * vy + dz * vz
            cos = abs(b[j, k]) / (dist * math.sqrt(vx * vx + vy * vy + vz * vz))
            serial = min(serial, cos)
    for j in range(m):
        for i in range(6):
            if not math.isfinite(a[j, i]) or not math.isfinite(unit[j, i]):
                return 1
        for i in range(n):
            if not math.isfinite(b[j, i]):
                return 1
    if not math.isfinite(serial):
        return 1
    spot = layout_offsets(m, n)
    parallel = np.nan
    if exact or m != 6 or not _surely_above(unit, tol):
        sv_a = np.empty(6)
        _values(unit, sv_a, 0)
        parallel = sv_a[5] / sv_a[0]
    if abs(serial - tol) <= 1e-9 * tol or abs(parallel - tol) <= 1e-9 * tol:
        return 1  # a measure at tol: its flag the batch path's (velocity_one.FLAG_BAND)
    flags = (1 if serial < tol else 0) | (2 if parallel < tol else 0)
    det_a = np.linalg.det(a) if m == 6 else np.nan
    if flags & 2:  # no J at a parallel singularity (A may be exactly singular there)
        j_mat = np.full((6, n), np.nan)
    elif m == 6:
        j_mat = np.linalg.solve(a, b)
    else:
        j_mat = np.linalg.pinv(a) @ b
    at = spot[0]
    for j in range(m):
        for i in range(6):
            out[at + 6 * j + i] = a[j, i]
    at = spot[1]
    for j in range(m):
        for i in range(n):
            out[at + n * j + i] = b[j, i]
    at = spot[2]
    for r in range(6):
        for c in range(n):
            out[at + n * r + c] = j_mat[r, c]
    # J⁻¹ = B⁺A: entry (c, j) of B⁺ is B[j, c] / |B[:, c]|² (0 below 1e-15 of the largest norm)
    squares = np.zeros(n)
    for c in range(n):
        for j in range(m):
            squares[c] += b[j, c] * b[j, c]
    largest = 0.0
    for c in range(n):
        largest = max(largest, math.sqrt(squares[c]))
    at = spot[3]
    for c in range(n):
        keep = math.sqrt(squares[c]) > 1e-15 * largest
        for i in range(6):
            s = 0.0
            if keep:
                for j in range(m):
                    s += b[j, c] / squares[c] * a[j, i]
            out[at + 6 * c + i] = np.nan if flags & 2 else s
    out[spot[8]] = det_a
    out[spot[9]] = np.linalg.det(b) if m == n else np.nan
    out[spot[10]] = parallel
    out[spot[11]] = serial
    out[spot[12]] = flags
    return 0


@njit(**_OPTIONS)
def _surely_above(unit, tol):  # pragma: no cover
    """Whether σ_min/σ_max of the square ``unit (6, 6)`` is ≥ ``tol`` (with margin), from its
    lower bound |det U| / (‖U‖²_F / 3)³ (AM–GM on σ1², σ1², σ2², …, σ5²); the factor 2 and the
    1e-12 absorb the rounding of the determinant and of the singular values."""
    frobenius = 0.0
    for j in range(6):
        for i in range(6):
            frobenius += unit[j, i] * unit[j, i]
    det_u = np.linalg.det(unit)
    return abs(det_u) > (4.0 * tol + 2e-12) * (frobenius / 3.0) ** 3


@njit(**_OPTIONS)
def velocity_matrices(x, q, geom, n, length_l, tol, out):  # pragma: no cover
    """:func:`velocity_one` without the singular values of J (and without the parallel
    measure where its bound settles the flags: NaN there): what J, A, B, J⁻¹, the
    determinants and the flags need. Returns 0, or 1 for a row that is not finite."""
    return _fill(x, q, geom, n, length_l, tol, out, False)


@njit(**_OPTIONS)
def velocity_one(x, q, geom, n, length_l, tol, out):  # pragma: no cover
    """The velocity model of pose ``x (6,)`` at actuator coordinates ``q (n,)`` into ``out``
    (module docstring); returns 0, or 1 for a row that is not finite."""
    if _fill(x, q, geom, n, length_l, tol, out, True):
        return 1
    spot = layout_offsets(geom.shape[0], n)
    j_mat = np.empty((6, n))
    for r in range(6):
        for c in range(n):
            j_mat[r, c] = out[spot[2] + n * r + c]
    j_h = j_mat.copy()
    for r in range(3, 6):
        for c in range(n):
            j_h[r, c] *= length_l
    _values(j_h, out, spot[4])
    _values(np.ascontiguousarray(j_mat[:3]), out, spot[5])
    _values(np.ascontiguousarray(j_mat[3:]), out, spot[6])
    out[spot[7]] = out[spot[4]] / out[spot[4] + min(6, n) - 1]
    return 0


@njit(**_OPTIONS)
def layout_offsets(m, n):  # pragma: no cover
    """The start of each field of :func:`layout`, in its order."""
    sizes = (6 * m, m * n, 6 * n, 6 * n, min(6, n), min(3, n), min(3, n), 1, 1, 1, 1, 1, 1)
    out = np.empty(13, dtype=np.int64)
    start = 0
    for i in range(13):
        out[i] = start
        start += sizes[i]
    return out
