"""Tool paths, G-code, time laws and joint trajectories."""

from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.joints import JointTrajectory, Limits, check_limits, joint_trajectory
from pkmkit.motion.paths import Arc, Line, Path, arc_through, chain, circle, helix, line, raster
from pkmkit.motion.timelaw import (
    PROFILES,
    Trajectory,
    constant_speed,
    plan,
    scurve,
    trapezoid,
)

__all__ = [
    "PROFILES",
    "Arc",
    "JointTrajectory",
    "Limits",
    "Line",
    "Path",
    "Trajectory",
    "arc_through",
    "chain",
    "check_limits",
    "circle",
    "constant_speed",
    "helix",
    "joint_trajectory",
    "line",
    "plan",
    "raster",
    "read_gcode",
    "scurve",
    "trapezoid",
]
