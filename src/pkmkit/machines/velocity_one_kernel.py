"""Compiled (Numba) velocity model of one pose of a spatial translational rod machine (issue 22
§1): the operations of :meth:`pkmkit.machines.velocity_one.OnePoseVelocity._compute3` in one
call, used by :mod:`pkmkit.machines.velocity_one` only once Numba is imported in the process
(a one-shot process never pays its import for one pose).

Legs ``legs (3, 21)``: kind (0), carriage centre at q = 0 (1:4), axis (4:7), rod length (7),
crank-circle centre (8:11), arm directions e1 (11:14), e2 (14:17), arm length (17), platform
joint (18:21). Output ``out (30,)``: A row-major (0:9), diag B (9:12), J row-major (12:21),
singular values of J (21:24), condition, det A, det B, parallel measure, serial measure, flags
(24:30). Returns 0, or 1 for whatever the plain-Python path treats specially (not finite,
nearly equal singular values, near a parallel singularity): the caller then takes that path.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines.velocity import NEAR_PARALLEL

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}


@njit(inline="always", **_OPTIONS)
def _sv3(m00, m01, m02, m10, m11, m12, m20, m21, m22, out, at):  # pragma: no cover
    """Closed-form singular values into ``out[at:at + 3]``; False where the closed forms hand
    the matrix to LAPACK (see :func:`pkmkit.machines.velocity_one.singular_values`)."""
    g00 = m00 * m00 + m10 * m10 + m20 * m20
    g11 = m01 * m01 + m11 * m11 + m21 * m21
    g22 = m02 * m02 + m12 * m12 + m22 * m22
    g01 = m00 * m01 + m10 * m11 + m20 * m21
    g02 = m00 * m02 + m10 * m12 + m20 * m22
    g12 = m01 * m02 + m11 * m12 + m21 * m22
    mean = (g00 + g11 + g22) / 3.0
    spread = math.sqrt(((g00 - mean) ** 2 + (g11 - mean) ** 2 + (g22 - mean) ** 2
                        + 2.0 * (g01 * g01 + g02 * g02 + g12 * g12)) / 6.0)
    scale = 1.0 / spread if spread > 0 else 0.0
    s00, s11, s22 = (g00 - mean) * scale, (g11 - mean) * scale, (g22 - mean) * scale
    s01, s02, s12 = g01 * scale, g02 * scale, g12 * scale
    sym_det = (s00 * (s11 * s22 - s12 * s12) - s01 * (s01 * s22 - s12 * s02)
               + s02 * (s01 * s12 - s11 * s02))
    half_det = min(max(0.5 * sym_det, -1.0), 1.0)
    lam1 = mean + 2.0 * spread * math.cos(math.acos(half_det) / 3.0)
    s1 = math.sqrt(lam1) if lam1 > 0 else 0.0
    c00, c01, c02 = m11 * m22 - m12 * m21, m12 * m20 - m10 * m22, m10 * m21 - m11 * m20
    c10, c11, c12 = m21 * m02 - m22 * m01, m22 * m00 - m20 * m02, m20 * m01 - m21 * m00
    c20, c21, c22 = m01 * m12 - m02 * m11, m02 * m10 - m00 * m12, m00 * m11 - m01 * m10
    d = abs(m00 * c00 + m01 * c01 + m02 * c02)
    e2 = (c00 * c00 + c01 * c01 + c02 * c02 + c10 * c10 + c11 * c11 + c12 * c12
          + c20 * c20 + c21 * c21 + c22 * c22)
    pair = d / s1 if s1 > 0 else 0.0
    rest = (e2 - pair * pair) / lam1 if lam1 > 0 else 0.0
    if spread > 0 and (abs(half_det) > 1.0 - 1e-6 or rest - 2 * pair < 1e-6 * rest):
        return False
    s2 = 0.5 * (math.sqrt(max(rest + 2 * pair, 0.0)) + math.sqrt(max(rest - 2 * pair, 0.0)))
    s3 = pair / s2 if s2 > 0 else 0.0
    if s2 > s1:
        s2 = s1
    out[at] = s1
    out[at + 1] = s2
    out[at + 2] = s3 if s3 < s2 else s2
    return True


@njit(**_OPTIONS)
def velocity_one3(x, q, legs, tol, out):  # pragma: no cover
    """The velocity model of pose ``x (3,)`` at ``q (3,)`` into ``out`` (module docstring);
    flags 1 (serial) and 2 (parallel) as :class:`~pkmkit.machines.results.Singularity`."""
    for i in range(3):
        kind = legs[i, 0]
        qi = q[i]
        bi = 0.0
        if kind == 0.0:  # slide
            for k in range(3):
                ak = x[k] - (legs[i, 1 + k] + qi * legs[i, 4 + k])
                out[3 * i + k] = ak
                if legs[i, 4 + k] != 0.0:
                    bi += ak * legs[i, 4 + k]
        elif kind == 2.0:  # crank
            cos, sin = math.cos(qi), math.sin(qi)
            radius = legs[i, 17]
            for k in range(3):
                f1, f2 = legs[i, 11 + k], legs[i, 14 + k]
                ak = x[k] - ((legs[i, 8 + k] + radius * (cos * f1 + sin * f2)) - legs[i, 18 + k])
                out[3 * i + k] = ak
                bi += ak * (radius * (cos * f2 - sin * f1))
        else:  # strut
            for k in range(3):
                out[3 * i + k] = x[k] - legs[i, 1 + k]
            bi = legs[i, 7] + qi
        out[9 + i] = bi
    for k in range(12):
        if not math.isfinite(out[k]):
            return 1
    a00, a01, a02, a10, a11, a12, a20, a21, a22 = out[0], out[1], out[2], out[3], out[4], \
        out[5], out[6], out[7], out[8]
    b0, b1, b2 = out[9], out[10], out[11]
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    c10, c11, c12 = a21 * a02 - a22 * a01, a22 * a00 - a20 * a02, a20 * a01 - a21 * a00
    c20, c21, c22 = a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10
    det_a = a00 * c00 + a01 * c01 + a02 * c02
    l0 = math.sqrt(a00 * a00 + a01 * a01 + a02 * a02)
    l1 = math.sqrt(a10 * a10 + a11 * a11 + a12 * a12)
    l2 = math.sqrt(a20 * a20 + a21 * a21 + a22 * a22)
    if not (l0 > 0 and l1 > 0 and l2 > 0):
        return 1
    unit = np.empty(3)
    if not _sv3(a00 / l0, a01 / l0, a02 / l0, a10 / l1, a11 / l1, a12 / l1, a20 / l2,
                a21 / l2, a22 / l2, unit, 0):
        return 1
    parallel = unit[2] / unit[0]
    serial = min(abs(b0) / l0, abs(b1) / l1, abs(b2) / l2)
    flags = 1 if serial < tol else 0
    if parallel < tol or det_a == 0.0:
        flags |= 2
        for k in range(12, 25):
            out[k] = np.nan
    else:
        inv_det = 1.0 / det_a
        if not math.isfinite(inv_det):
            return 1
        s0, s1, s2 = b0 * inv_det, b1 * inv_det, b2 * inv_det
        j = (c00 * s0, c10 * s1, c20 * s2, c01 * s0, c11 * s1, c21 * s2, c02 * s0, c12 * s1,
             c22 * s2)
        for k in range(9):
            if not math.isfinite(j[k]):
                return 1
            out[12 + k] = j[k]
        if parallel < NEAR_PARALLEL and parallel < serial:
            return 1
        if not _sv3(j[0], j[1], j[2], j[3], j[4], j[5], j[6], j[7], j[8], out, 21):
            return 1
        out[24] = math.inf if out[23] == 0.0 else out[21] / out[23]
    out[25] = det_a
    out[26] = b0 * b1 * b2
    out[27] = parallel
    out[28] = serial
    out[29] = flags
    return 0
