"""The direct model of one configuration of a translational rod-leg machine in plain Python
floats (issue 22 §1).

:func:`direct_one` intersects the legs' spheres (circles in the plane) as
:meth:`pkmkit.machines.closed_form.RodClosedForm.direct_all` does for a batch — the same
formulas, in scalars — and returns the platform point of one assembly mode. Whatever the batch
path treats specially returns None, and the machine then takes that path (which gives the same
numbers and the typed errors): not ``n`` plain finite numbers, no real assembly, sphere centres
(nearly) aligned, a negative strut length, or a configuration near a parallel singularity whose
solution the batch path checks leg by leg.

With the C extension, the machine's one-pose ``ik``, ``fk`` and ``jacobian`` are one C call
each (``rod_ik_one``, ``rod_fk_one``, ``rod_jacobian_one`` of ``native/rod_one.c``: the input
read and checked, the solve, the stroke check and the result array in C — the same operations
as here and as :meth:`RodClosedForm.inverse_one`, the same bits); :func:`one_pose_pack` packs the
machine's constants for them once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from pkmkit.machines.closed_form import MAX_ABS, SUSPECT_GRAM, RodClosedForm
from pkmkit.machines.velocity import NEAR_PARALLEL
from pkmkit.machines.velocity_one import native_legs

#: A discriminant within this of the radius² is a double root (as ``direct_all``'s default).
REL_TOL = 1e-12

#: Doubles before the legs in :func:`one_pose_pack` (``PK_HEAD`` of ``native/rod_one.c``).
PACK_HEAD = 14


def _legs(closed: RodClosedForm) -> tuple:
    """Per-leg constants as Python floats (3 coordinates, z = 0 in the plane), once."""
    cached = closed.__dict__.get("_one_direct")
    if cached is None:
        m = closed.model

        def three(v):
            return [*np.asarray(v, dtype=float).tolist(), 0.0][:3]

        legs = []
        for i in range(m.n_legs):
            kind = 2 if closed.crank[i] else 1 if closed.strut[i] else 0
            legs.append((kind, *three(closed.centre0[i]), *three(closed.axis[i]),
                         float(m.leg_length[i]),
                         *three(m.leg_pivot[i] + closed.crank_offset[i] * m.leg_axis[i]
                                - m.leg_platform[i]),
                         *three(closed.crank_radius[i] * closed.crank_e1[i]),
                         *three(closed.crank_radius[i] * closed.crank_e2[i])))
        cached = tuple(legs)
        object.__setattr__(closed, "_one_direct", cached)
    return cached


def direct_one(closed: RodClosedForm, q: Any, sign: int) -> list[float] | None:
    """Platform point ``(dims,)`` of one configuration ``q`` (``n`` plain numbers: list, tuple
    or 1-D float array) in the assembly mode of sign ``sign`` (of det A), or None (module
    docstring)."""
    m = closed.model
    dims = m.dims
    if isinstance(q, np.ndarray):
        if q.ndim != 1 or q.dtype.kind not in "fi":
            return None
        q = q.tolist()
    elif not isinstance(q, (list, tuple)):
        return None
    if len(q) != m.n_legs or m.n_legs != dims:
        return None
    for v in q:
        if type(v) not in (float, int) or not -MAX_ABS <= v <= MAX_ABS:
            return None
    centres = []
    for (kind, cx, cy, cz, ux, uy, uz, length, tx, ty, tz, ax, ay, az, bx, by, bz), v in zip(
            _legs(closed), q, strict=True):
        v = float(v)
        if kind == 0:  # slide
            centres.append((cx + v * ux, cy + v * uy, cz + v * uz, length * length))
        elif kind == 1:  # strut
            if not length + v > 0.0:
                return None
            centres.append((cx, cy, cz, (length + v) * (length + v)))
        else:  # crank
            c, s = math.cos(v), math.sin(v)
            centres.append((tx + c * ax + s * bx, ty + c * ay + s * by, tz + c * az + s * bz,
                            length * length))
    (x1, y1, z1, r1), (x2, y2, z2, r2) = centres[0], centres[1]
    if dims == 3:
        x3, y3, z3, r3 = centres[2]
        e1x, e1y, e1z = x2 - x1, y2 - y1, z2 - z1
        e2x, e2y, e2z = x3 - x1, y3 - y1, z3 - z1
        g11 = e1x * e1x + e1y * e1y + e1z * e1z
        g12 = e1x * e2x + e1y * e2y + e1z * e2z
        g22 = e2x * e2x + e2y * e2y + e2z * e2z
        h2 = 0.5 * (r1 - r2 + g11)
        h3 = 0.5 * (r1 - r3 + g22)
        gram = g11 * g22 - g12 * g12
        size_sq = r1 + g11 + g22
        if not gram >= SUSPECT_GRAM * size_sq * size_sq:
            return None  # (nearly) aligned centres: the batch path checks or refuses
        alpha = (h2 * g22 - h3 * g12) / gram
        beta = (h3 * g11 - h2 * g12) / gram
        wx, wy, wz = alpha * e1x + beta * e2x, alpha * e1y + beta * e2y, alpha * e1z + beta * e2z
        nx, ny, nz = e1y * e2z - e1z * e2y, e1z * e2x - e1x * e2z, e1x * e2y - e1y * e2x
    else:
        ex, ey = x2 - x1, y2 - y1
        gram = ex * ex + ey * ey
        if not gram >= SUSPECT_GRAM * (r1 + gram):
            return None
        alpha = 0.5 * (r1 - r2 + gram) / gram
        wx, wy, wz = alpha * ex, alpha * ey, 0.0
        nx, ny, nz = -ey, ex, 0.0
    t_sq = (r1 - (wx * wx + wy * wy + wz * wz)) / gram
    if abs(t_sq) <= 2.0 * REL_TOL * r1 / gram:
        return None  # a double root, or rounding away from the batch row's test of one
    if not t_sq >= 0.0:
        return None  # no real assembly: the batch path raises NoAssemblyError
    t = math.sqrt(t_sq) if sign > 0 else -math.sqrt(t_sq)
    if dims == 3:
        return [x1 + wx + t * nx, y1 + wy + t * ny, z1 + wz + t * nz]
    return [x1 + wx + t * nx, y1 + wy + t * ny]


def one_pose_pack(closed: RodClosedForm, branches: Sequence[float], lower: Sequence[float],
                  upper: Sequence[float]) -> bytes | None:
    """The constants of the one-pose C entries of ``native/rod_one.c`` (bytes of float64): the
    head (legs ``n``, :data:`~pkmkit.machines.closed_form.MAX_ABS`, ``SUSPECT_GRAM``,
    :data:`REL_TOL`, ``NEAR_PARALLEL``, the strokes' ``lower`` and ``upper`` limits with their
    tolerance), then the inverse legs of ``branches`` (:meth:`RodClosedForm.single_legs_packed`),
    the velocity legs (:func:`~pkmkit.machines.velocity_one.native_legs`) and the direct legs
    (:func:`_legs`). None for a machine with other than 2 or 3 legs, one per coordinate and
    actuator (its one-pose calls stay in Python)."""
    m = closed.model
    n = m.n_legs
    if n not in (2, 3) or m.dims != n or m.n_actuators != n or len(lower) != n:
        return None
    head = np.zeros(PACK_HEAD)
    head[:5] = n, MAX_ABS, SUSPECT_GRAM, REL_TOL, NEAR_PARALLEL
    head[8:8 + n], head[11:11 + n] = lower, upper
    return (head.tobytes() + closed.single_legs_packed(branches) + native_legs(closed)
            + np.array(_legs(closed), dtype=float).tobytes())
