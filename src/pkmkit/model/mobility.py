"""Mobility by the Grübler–Kutzbach count over a rod-leg model's joint graph.

The joint graph is derived from the rods (no hand-typed counts):

- spatial machine (``dims`` 3 or 6): each slide or crank rod is a body with a spherical joint at
  each end and one internal mobility (spin about its own axis); each slide actuator is a carriage
  body on a prismatic joint, each crank actuator an arm body on a revolute joint; a strut is two
  bodies (cylinder, piston) joined U–P–S;
- planar machine (``dims = 2``): the same with revolute joints and no internal mobility.

    m = d (N − 1 − j) + Σ f_i − m_int        (d = 6 spatial, 3 planar; N counts the base)

The count is blind to the geometry: it undercounts over-constrained mechanisms (parallelograms in
a plane, for instance). :func:`pkmkit.solve.rod_closure.instantaneous_mobility` gives the
rank-based value; their difference is the number of redundant constraints.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from pkmkit.model.rods import CRANK, STRUT, RodModel


@dataclass(frozen=True)
class GrublerCount:
    """Terms of the Grübler–Kutzbach formula.

    Attributes:
        motion_space: 6 (spatial) or 3 (planar).
        bodies: N, bodies including the fixed base.
        joints: j, number of joints.
        joint_freedoms: Σ f_i.
        internal_mobilities: m_int (rod spins).
        joints_by_type: number of joints of each type (``{"P": 3, "S": 12}``).
        mobility: m.
    """

    motion_space: int
    bodies: int
    joints: int
    joint_freedoms: int
    internal_mobilities: int
    joints_by_type: dict[str, int]
    mobility: int

    def as_dict(self) -> dict:
        """Plain-dict form for JSON output."""
        return asdict(self)


_FREEDOMS = {"P": 1, "R": 1, "U": 2, "S": 3}


def grubler_count(model: RodModel) -> GrublerCount:
    """Grübler–Kutzbach mobility of ``model``'s joint graph (see the module docstring)."""
    spatial = model.dims != 2
    end_joint = "S" if spatial else "R"
    joints: dict[str, int] = {}

    def add(kind: str, count: int = 1) -> None:
        joints[kind] = joints.get(kind, 0) + count

    bodies = 2  # fixed base and platform
    internal = 0
    carriages: dict[int, str] = {}
    for rod in range(model.n_rods):
        if model.rod_kind[rod] != STRUT:
            bodies += 1
            add(end_joint, 2)
            internal += 1 if spatial else 0
            carriages[int(model.rod_actuator[rod])] = (
                "R" if model.rod_kind[rod] == CRANK else "P")
        else:
            bodies += 2
            add("U" if spatial else "R")
            add("P")
            add(end_joint)
    bodies += len(carriages)
    for joint in carriages.values():
        add(joint)
    d = 6 if spatial else 3
    n_joints = sum(joints.values())
    freedoms = sum(_FREEDOMS[k] * n for k, n in joints.items())
    mobility = d * (bodies - 1 - n_joints) + freedoms - internal
    return GrublerCount(
        motion_space=d,
        bodies=bodies,
        joints=n_joints,
        joint_freedoms=freedoms,
        internal_mobilities=internal,
        joints_by_type=dict(sorted(joints.items())),
        mobility=mobility,
    )
