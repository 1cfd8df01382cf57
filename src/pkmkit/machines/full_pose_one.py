"""The inverse model of one full pose in plain Python floats (issue 22 §1).

:class:`OnePoseInverse` runs the rod-by-rod closed forms of
:mod:`pkmkit.machines.full_pose_forms` (slide, strut, crank) for a single pose row
``(x, y, z, rx, ry, rz)`` with the compiled kernel's operations
(:func:`pkmkit.machines.full_pose_kernels.rod_coordinates`: Rodrigues with its series below
1e-8 rad, then each rod), then combines the rods of each actuator as
:meth:`~pkmkit.machines.full_pose_forms.FullPoseForms.combine` does. No array is built: a
few microseconds where a batch call of one row costs a hundred or more. Anything else — not six
plain finite numbers, a rod that cannot close, rods of one actuator that disagree — returns
None, and the machine takes the batch path, which gives the same numbers and the typed errors.

With the C extension, :func:`native_one` packs these constants, the strokes and the direct
model's data once per machine (of up to six rods) into ``pkmkit.native.kernels.pose_one``,
whose ``ik``, ``fk`` and ``jacobian`` check one plain pose or configuration, run the kernel
and judge the strokes in one C call each (``native/pose_one.c``; the same bits as this
class, the batch path's direct solve and the velocity kernel): ``m.ik(x)`` and ``m.fk(q)``
of :class:`~pkmkit.machines.full_pose.FullPoseMachine` take it first, this class only where
the pose is of another type (an integer array) or the extension is absent.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pkmkit.machines.full_pose_direct import DEFAULT_OPTIONS
from pkmkit.machines.full_pose_forms import BOUNDARY_TOL, FullPoseForms
from pkmkit.machines.strokes import stroke_limits
from pkmkit.model.rods import CRANK, STRUT
from pkmkit.numerics import jit

#: Pose coordinates beyond this magnitude are refused by the batch path (invalid input).
MAX_ABS = 1e9


class OnePoseInverse:
    """Per-rod constants of a :class:`FullPoseForms` as Python floats, computed once.

    Args:
        forms: the machine's closed forms.
        consistency_tol: largest disagreement between rods of one actuator (m or rad).
    """

    def __init__(self, forms: FullPoseForms, consistency_tol: float) -> None:
        m = forms.model
        rows = []
        for j in range(m.n_rods):
            rows.append((int(m.rod_kind[j]), *m.rod_platform[j].tolist(),
                         *m.rod_base[j].tolist(), *m.rod_axis[j].tolist(),
                         float(forms.length_sq[j]), float(m.rod_length[j]),
                         *m.rod_pivot[j].tolist(), *forms.crank_e1[j].tolist(),
                         *forms.crank_e2[j].tolist(), float(forms.crank_radius[j]),
                         float(forms.crank_offset[j]), float(forms.rod_branch[j])))
        self.rows = tuple(rows)
        act = m.rod_actuator
        self.simple = m.n_rods == m.n_actuators and bool((act == np.arange(m.n_actuators)).all())
        self.groups = tuple((tuple(int(j) for j in np.flatnonzero(act == k)),
                             bool(m.rod_kind[np.flatnonzero(act == k)[0]] == CRANK))
                            for k in range(m.n_actuators))
        # half of it: rods of one actuator that disagree by more go to the batch path, whose
        # sums round otherwise (at the tolerance's edge the two answered differently)
        self.tol = 0.5 * float(consistency_tol)

    def __call__(self, x: Any) -> list[float] | None:
        """Actuator coordinates of one pose ``x`` (6 plain numbers: list, tuple or 1-D float
        array), or None (module docstring)."""
        if isinstance(x, np.ndarray):
            if x.shape != (6,) or x.dtype.kind not in "fi":
                return None
            x = x.tolist()
        elif not isinstance(x, (list, tuple)) or len(x) != 6:
            return None
        for v in x:
            if type(v) not in (float, int) or not -MAX_ABS <= v <= MAX_ABS:
                return None  # bools, strings, NaN, ±inf, absurd magnitudes: the batch path
        px, py, pz, wx, wy, wz = (float(v) for v in x)
        theta = math.sqrt(wx * wx + wy * wy + wz * wz)
        if theta < 1e-8:
            a = 1.0 - theta * theta / 6.0
            b = 0.5 - theta * theta / 24.0
        else:
            a = math.sin(theta) / theta
            b = (1.0 - math.cos(theta)) / (theta * theta)
        r00, r11, r22 = (1.0 - b * (wy * wy + wz * wz), 1.0 - b * (wx * wx + wz * wz),
                         1.0 - b * (wx * wx + wy * wy))
        r01, r10 = b * wx * wy - a * wz, b * wx * wy + a * wz
        r02, r20 = b * wx * wz + a * wy, b * wx * wz - a * wy
        r12, r21 = b * wy * wz - a * wx, b * wy * wz + a * wx
        rod_q = []
        for (kind, bx, by, bz, cx, cy, cz, ux, uy, uz, length_sq, length, ox, oy, oz,
             e1x, e1y, e1z, e2x, e2y, e2z, radius, offset, sigma) in self.rows:
            qx = px + r00 * bx + r01 * by + r02 * bz
            qy = py + r10 * bx + r11 * by + r12 * bz
            qz = pz + r20 * bx + r21 * by + r22 * bz
            if kind == CRANK:
                vx, vy, vz = qx - ox, qy - oy, qz - oz
                vw = vx * ux + vy * uy + vz * uz - offset
                v1 = vx * e1x + vy * e1y + vz * e1z
                v2 = vx * e2x + vy * e2y + vz * e2z
                perp = math.sqrt(v1 * v1 + v2 * v2)
                g = vw * vw + perp * perp + radius * radius - length_sq
                amplitude = 2.0 * radius * perp
                if amplitude <= 0.0:
                    return None
                cosine = g / amplitude
                if abs(g) - amplitude <= BOUNDARY_TOL * length_sq:
                    cosine = min(1.0, max(-1.0, cosine))
                elif not -1.0 <= cosine <= 1.0:
                    return None
                angle = math.atan2(v2, v1) + sigma * math.acos(cosine)
                rod_q.append((angle + math.pi) % (2.0 * math.pi) - math.pi)
                continue
            wxr, wyr, wzr = qx - cx, qy - cy, qz - cz
            dist_sq = wxr * wxr + wyr * wyr + wzr * wzr
            if kind == STRUT:
                rod_q.append(math.sqrt(dist_sq) - length)
                continue
            s = wxr * ux + wyr * uy + wzr * uz
            radicand = length_sq - dist_sq + s * s
            if radicand < 0.0:
                if radicand <= -BOUNDARY_TOL * length_sq:
                    return None
                radicand = 0.0
            rod_q.append(s + sigma * math.sqrt(radicand))
        if self.simple:
            return rod_q
        out = []
        for rods, angular in self.groups:
            first = rod_q[rods[0]]
            diffs = [0.0]
            for j in rods[1:]:
                d = rod_q[j] - first
                if angular:
                    d = (d + math.pi) % (2.0 * math.pi) - math.pi
                diffs.append(d)
            mean = sum(diffs[1:]) / len(rods)
            if max(abs(d - mean) for d in diffs) > self.tol:
                return None  # the rods disagree: the batch path says which and by how much
            out.append(first + mean)
        return out


def native_one(machine: Any) -> Any | None:
    """The ``pkmkit.native.kernels.PoseOne`` of a full-pose ``machine`` (built once, kept on
    it), or None: no C extension (or ``PKMKIT_NATIVE=0`` / ``PKMKIT_COMPILED=0``), or more than
    six rods."""
    native = jit.native_kernels_now()
    if native is None:
        return None
    one = machine.__dict__.get("_pose_one")
    if one is None:
        one = _pose_one(machine, native) or False
        object.__setattr__(machine, "_pose_one", one)
    return one or None


def _pose_one(machine: Any, native: Any) -> Any | None:
    """``native.pose_one(...)`` of ``machine`` (its arguments: the C file's docstring)."""
    model = machine.model
    if model.n_rods > 6 or not hasattr(native, "pose_one"):
        return None
    inverse = machine.one_pose_inverse()
    groups = np.zeros((len(inverse.groups), 8))
    for k, (rods, angular) in enumerate(inverse.groups):
        groups[k, :2] = len(rods), angular
        groups[k, 2:2 + len(rods)] = rods
    lower, upper = stroke_limits(machine)
    kernel = machine.direct_kernel()
    return native.pose_one(np.array(inverse.rows, dtype=float).tobytes(), groups.tobytes(),
                           inverse.simple, BOUNDARY_TOL, inverse.tol, MAX_ABS,
                           np.ascontiguousarray(lower, dtype=float),  # as within_strokes
                           np.ascontiguousarray(upper, dtype=float),
                           np.ascontiguousarray(kernel.geom), kernel.home, DEFAULT_OPTIONS,
                           float(machine.characteristic_length))
