"""A whole machining move: time law, actuator motion, inverse dynamics and limit checks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.inverse import ForceResult, inverse_dynamics
from pkmkit.dynamics.masses import MassProperties
from pkmkit.dynamics.wrench import WrenchSeries
from pkmkit.machines.machine import Machine
from pkmkit.motion.joints import JointTrajectory, Limits, check_limits, joint_trajectory
from pkmkit.motion.paths import Path
from pkmkit.motion.timelaw import plan


@dataclass(frozen=True)
class PathResult:
    """Everything about one move along a path."""

    motion: JointTrajectory
    forces: ForceResult
    masses: MassProperties
    limits: dict[str, Any]

    def summary(self) -> dict[str, Any]:
        """Duration, length, actuator ranges and peaks, forces, powers and limit violations
        (SI units)."""
        m = self.motion
        f = self.forces
        violations = [{"limit": kind, **entry["first"]} for kind, entry in self.limits.items()
                      if entry["exceeded"]]
        return {
            "duration": m.trajectory.duration, "length": m.trajectory.length,
            "cutting_length": m.trajectory.path.cutting_length, "samples": len(m.t),
            "q_min": m.q.min(axis=0), "q_max": m.q.max(axis=0), "stroke": m.stroke,
            "qd_max": np.abs(m.qd).max(axis=0), "qd_range": [m.qd.min(axis=0), m.qd.max(axis=0)],
            "qdd_max": np.abs(m.qdd).max(axis=0),
            "force_max": np.abs(f.force).max(axis=0),
            "force_range": [f.force.min(axis=0), f.force.max(axis=0)],
            "power_max": np.abs(f.power).max(axis=0),
            "leg_axial_max": np.abs(np.nan_to_num(f.leg_axial, nan=np.inf)).max(axis=0),
            "tool_speed_max": float(np.linalg.norm(m.xd, axis=1).max()),
            "tool_accel_max": float(np.linalg.norm(m.xdd, axis=1).max()),
            "violations": violations,
        }


def simulate_path(machine: Machine, path: Path, *, feed: float, accel: float,
                  jerk: float | None = None, profile: str = "scurve",
                  rapid_feed: float | None = None, period: float = 0.01,
                  masses: MassProperties | None = None, wrench: Any = None,
                  limits: Limits | None = None) -> PathResult:
    """Plan the move, follow it with the machine and compute the actuator forces.

    Args:
        machine: the machine.
        path: the tool path (machine coordinates, m).
        feed, accel, jerk, profile, rapid_feed, period: see :func:`pkmkit.motion.plan`.
        masses: mass properties (default: :func:`pkmkit.dynamics.defaults.default_masses`).
        wrench: external force on the tool, ``(3,)`` / ``(6,)``, one row per sample, or a
            :class:`~pkmkit.dynamics.wrench.WrenchSeries` (forces against time, interpolated).
        limits: actuator limits to check (strokes always).

    Raises:
        InputError: bad limits, a path the machine cannot follow (with the first failing
            sample), bad masses or wrench.
    """
    trajectory = plan(path, feed=feed, accel=accel, jerk=jerk, profile=profile,
                      rapid_feed=rapid_feed, period=period)
    motion = joint_trajectory(machine, trajectory)
    masses = masses or default_masses(machine)
    if isinstance(wrench, WrenchSeries):
        wrench = wrench.at(motion.t)
    forces = inverse_dynamics(machine, masses, motion.x, motion.xd, motion.xdd, motion.q,
                              motion.qd, motion.qdd, wrench=wrench)
    report = check_limits(machine, motion, limits or Limits(), forces.force)
    return PathResult(motion=motion, forces=forces, masses=masses, limits=report)
