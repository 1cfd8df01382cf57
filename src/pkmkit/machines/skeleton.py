"""A machine's skeleton: the polylines a drawing or a 3-D view shows, for every family.

``skeleton(machine, q)`` answers the same question for every machine — where are its guides,
legs, platform, head and tool at actuator coordinates ``q`` — so that a figure or an export
draws any machine without asking which family it is:

- rod-leg machines (translational and full-pose): one guide per leg (the slide around its
  carriage, a crank arm from its pivot, nothing for a strut), every rod from its base joint to
  its platform joint, the platform's joints as a closed polygon, the tool point;
- joint chains: every leg as the polyline through its joint frames, the head, the tool segment.

Points are in metres in the base frame; planar machines get z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pkmkit.exceptions import NoAssemblyError

#: What a line of the skeleton is (drawn in its own style by a view).
KINDS = ("guide", "leg", "platform", "head", "tool")


@dataclass(frozen=True)
class SkeletonLine:
    """One polyline: ``points (k, 3)`` in m, its ``kind`` (one of :data:`KINDS`), the leg it
    belongs to (``-1`` for none) and a name for a legend."""

    name: str
    kind: str
    points: np.ndarray
    leg: int = -1


@dataclass(frozen=True)
class Skeleton:
    """The machine at one configuration: its lines, joint points ``(m, 3)``, the tool point
    ``(3,)`` (m) and the actuator coordinates ``q (n,)`` it was built for (SI)."""

    lines: list[SkeletonLine]
    joints: np.ndarray
    tool: np.ndarray
    q: np.ndarray
    pose: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper corners ``(3,)`` of every point of the skeleton (m)."""
        points = np.concatenate([line.points for line in self.lines] + [self.tool[None]])
        return points.min(axis=0), points.max(axis=0)


def skeleton(machine, q=None) -> Skeleton:
    """The skeleton of ``machine`` at actuator coordinates ``q (n,)`` (SI; default home),
    in its working assembly mode.

    Raises:
        NoAssemblyError: the direct model has no solution at ``q`` (and the errors of the
            machine's ``fk`` for a ``q`` it refuses).
    """
    q = machine.home_q if q is None else np.asarray(q, dtype=float).reshape(-1)
    if machine.family == "chain":
        return _chain_skeleton(machine, q)
    return _rod_skeleton(machine, q)


def _three_d(points: np.ndarray) -> np.ndarray:
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if points.shape[1] == 3:
        return points
    return np.column_stack([points, np.zeros((len(points), 3 - points.shape[1]))])


def _rod_skeleton(machine, q: np.ndarray) -> Skeleton:
    from pkmkit.model.rods import CRANK, SLIDE
    from pkmkit.solve.rod_closure import rod_base_points
    from pkmkit.spatial.rotation import rotvec_to_matrix

    pose = np.asarray(machine.fk(q, strokes="ignore"), dtype=float).reshape(-1)
    if not np.isfinite(pose).all():
        raise NoAssemblyError(f"{machine.id}: no assembly at q = {np.round(q, 6).tolist()} (SI)")
    model = machine.model
    padded = model.pad(pose[None])[0]
    base = rod_base_points(model, q[:, None])[:, :, 0].T
    rotation = rotvec_to_matrix(pose[3:6])[0] if model.full_pose else np.eye(3)
    platform = padded[:3] + model.rod_platform @ rotation.T
    lines = []
    span = 0.6 * float(model.leg_length.max())
    for i in range(model.n_legs):
        rods = np.flatnonzero(model.rod_leg == i)
        carriage = base[rods].mean(axis=0)
        kind = int(model.leg_kind[i])
        if kind == SLIDE:
            guide = np.stack([carriage - span * model.leg_axis[i],
                              carriage + span * model.leg_axis[i]])
            lines.append(SkeletonLine(f"{model.leg_names[i]} slide", "guide", guide, i))
        elif kind == CRANK:
            guide = np.stack([model.leg_pivot[i], carriage])
            lines.append(SkeletonLine(f"{model.leg_names[i]} crank", "guide", guide, i))
        for j in rods:
            lines.append(SkeletonLine(model.leg_names[i], "leg",
                                      np.stack([base[j], platform[j]]), i))
    lines.append(SkeletonLine("platform", "platform", _closed_polygon(platform, rotation)))
    tool = padded[:3]
    return Skeleton(lines=[SkeletonLine(line.name, line.kind, _three_d(line.points), line.leg)
                           for line in lines],
                    joints=_three_d(np.concatenate([base, platform])), tool=_three_d(tool)[0],
                    q=q, pose=pose)


def _closed_polygon(points: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """The distinct ``points`` ordered by angle around their centre in the platform's plane,
    the first repeated at the end (one point: itself)."""
    unique = np.unique(np.round(points, 12), axis=0)
    if len(unique) < 2:
        return unique
    centre = unique.mean(axis=0)
    local = (unique - centre) @ rotation
    order = np.argsort(np.arctan2(local[:, 1], local[:, 0]))
    ring = unique[order]
    return np.concatenate([ring, ring[:1]])


def _chain_points(model, chain, values: np.ndarray, start=None) -> np.ndarray:
    from pkmkit.solve.chains import chain_pose

    points = [np.zeros(3) if start is None else start[1][:, 0]]
    for k in range(1, len(chain) + 1):
        end = chain_pose(model, chain[:k], values[:, None], start=start)
        points.append(end.p[:, 0])
    return np.array(points)


def _chain_skeleton(machine, q: np.ndarray) -> Skeleton:
    from pkmkit.model.chains import FIXED
    from pkmkit.spatial.rotation import rotvec_to_matrix

    res = machine.fk(q, full_output=True, strokes="ignore")
    if not np.isfinite(np.asarray(res.pose, dtype=float)).all():
        raise NoAssemblyError(f"{machine.id}: no assembly at q = {np.round(q, 6).tolist()} (SI)")
    model = machine.model
    values = model.home.copy()
    values[np.flatnonzero(model.actuated)] = q
    values[np.flatnonzero(~model.actuated & model.loop_variables)] = res.passive
    lines, joints = [], []
    for i, (name, leg) in enumerate(zip(model.leg_names, model.legs, strict=True)):
        points = _chain_points(model, leg, values)
        moving = [0] + [k + 1 for k, e in enumerate(leg) if model.elements[e].type != FIXED]
        lines.append(SkeletonLine(name, "leg", points, i))
        joints.append(points[moving])
    if model.head:
        rotation = rotvec_to_matrix(np.asarray(res.platform[3:], dtype=float))[0]
        start = (rotation[:, :, None], np.asarray(res.platform[:3], dtype=float)[:, None])
        lines.append(SkeletonLine("head", "head",
                                  _chain_points(model, model.head, values, start=start)))
    tip = np.asarray(res.pose[:3], dtype=float)
    lines.append(SkeletonLine("tool", "tool",
                              np.stack([np.asarray(res.tool_frame[:3], dtype=float), tip])))
    return Skeleton(lines=lines, joints=np.concatenate(joints), tool=tip, q=q,
                    pose=np.asarray(res.pose, dtype=float))
