"""Machines built for the stiffness tests."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from pkmkit.machines.full_pose import FullPoseMachine
from pkmkit.model.rods import LegSpec, build_rod_model


def diagonal_up() -> np.ndarray:
    """The rotation taking the cube diagonal (1, 1, 1)/√3 to z."""
    rot, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [np.ones(3) / np.sqrt(3.0)])
    return rot.as_matrix()


def cubic_hexapod(a: float = 0.5, *, motion: np.ndarray | None = None,
                  scale: float = 1.0) -> FullPoseMachine:
    """A cubic Gough–Stewart platform: struts along six edges of a cube of side ``a`` whose
    diagonal is vertical, centre at the platform origin (home pose 0). Lower ends (vertices
    with one coordinate 1) on the base, upper ends (two 1s) on the platform. ``motion``
    ``(4, 4)`` moves the whole machine (base and home pose); ``scale`` multiplies every length.
    """
    up = diagonal_up()
    cube = {v: (np.array(v, dtype=float) - 0.5) * a for v in np.ndindex(2, 2, 2)}
    hexagon = [(1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 1, 1), (0, 0, 1), (1, 0, 1)]
    legs = []
    t = np.eye(4) if motion is None else motion
    for i in range(6):
        v, w = hexagon[i], hexagon[(i + 1) % 6]
        lower, upper = (v, w) if sum(v) == 1 else (w, v)
        base = t[:3, :3] @ (up @ cube[lower]) + t[:3, 3]
        platform = up @ cube[upper]  # in the platform frame
        legs.append(LegSpec(name=f"leg {i + 1}", actuator=i, kind="strut",
                            base=base * scale, platform=platform * scale, length=0.0))
    home = np.zeros(6)
    home[:3] = t[:3, 3] * scale
    home[3:] = Rotation.from_matrix(t[:3, :3]).as_rotvec()
    model = build_rod_model(legs, dims=6, actuator_names=tuple(f"q{i + 1}" for i in range(6)),
                            home_pose=home)
    return FullPoseMachine(id="cubic", name="cubic hexapod", kind=None, params={}, model=model)
