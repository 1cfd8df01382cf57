"""A whole machining move: time law, actuator motion, inverse dynamics and limit checks.

The figures of a move (strokes, extreme speeds, accelerations, forces and powers) and its limit
verdicts hold for the continuous motion, not only at the output samples: they come from
:func:`pkmkit.motion.extrema.continuous_extrema` (to 10⁻⁴ of each quantity's range), so the
sampling period only sets the output.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.inverse import ForceResult, inverse_dynamics
from pkmkit.dynamics.masses import MassProperties
from pkmkit.dynamics.wrench import WrenchSeries
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.motion.extrema import DEFAULT_RTOL, Extrema, continuous_extrema
from pkmkit.motion.joints import JointTrajectory, Limits, joint_trajectory
from pkmkit.motion.limits import LimitViolation, limit_bounds, path_limit_violations
from pkmkit.motion.paths import Path
from pkmkit.motion.timelaw import Trajectory, plan

QUANTITY_NAMES = {"q": "actuator position", "qd": "actuator speed",
                  "qdd": "actuator acceleration", "force": "actuator force",
                  "power": "actuator power", "leg_axial": "leg axial force",
                  "tool_speed": "tool speed", "tool_accel": "tool acceleration"}


@dataclass(frozen=True)
class PathResult:
    """Everything about one move along a path.

    Attributes:
        motion: actuator motion at the output samples.
        forces: actuator forces at the output samples.
        masses: the mass properties used.
        limits: limit checks over continuous time, per kind (see
            :func:`check_limits_continuous`).
        extrema: extrema over continuous time of ``q``, ``qd``, ``qdd``, ``force``, ``power``,
            ``leg_axial``, ``tool_speed`` and ``tool_accel``.
        violations: every limit exceeded, per kind and actuator, with all its excursions
            (:class:`~pkmkit.motion.limits.LimitViolation`).
    """

    motion: JointTrajectory
    forces: ForceResult
    masses: MassProperties
    limits: dict[str, Any]
    extrema: Extrema
    violations: tuple[LimitViolation, ...] = ()

    def summary(self) -> dict[str, Any]:
        """Duration, length, actuator ranges and peaks, forces, powers and limit violations
        (SI units), over continuous time."""
        m = self.motion
        e = self.extrema
        violations = [v.as_dict(m.trajectory, m.x.shape[1]) for v in self.violations]
        return {
            "duration": m.trajectory.duration, "length": m.trajectory.length,
            "cutting_length": m.trajectory.path.cutting_length, "samples": len(m.t),
            "q_min": e.low["q"], "q_max": e.high["q"], "stroke": e.range("q"),
            "qd_max": e.abs_max("qd"), "qd_range": [e.low["qd"], e.high["qd"]],
            "qdd_max": e.abs_max("qdd"),
            "force_max": e.abs_max("force"),
            "force_range": [e.low["force"], e.high["force"]],
            "power_max": e.abs_max("power"),
            "leg_axial_max": e.abs_max("leg_axial"),
            "tool_speed_max": float(e.high["tool_speed"][0]),
            "tool_accel_max": float(e.high["tool_accel"][0]),
            "violations": violations,
            "between_samples": {"rtol": e.rtol, "converged": e.converged, "levels": e.levels,
                                "evaluations": e.evaluations},
        }


def motion_quantities(machine: Machine, trajectory: Trajectory, masses: MassProperties,
                      wrench: Any = None):
    """``evaluate(t)``: the actuator motion, forces and tool speed at any times ``t`` (s) of the
    continuous motion, as ``{name: (M, k)}`` (names as in :attr:`PathResult.extrema`).

    ``wrench``: constant, a :class:`WrenchSeries`, or one row per output sample of
    ``trajectory`` (then interpolated linearly in time between samples).
    """
    if wrench is not None and not isinstance(wrench, WrenchSeries):
        w = np.asarray(wrench, dtype=float)
        if w.ndim == 2 and w.shape[0] == len(trajectory.t) and w.shape[0] > 1:
            wrench = WrenchSeries(trajectory.t, w[:, :3]) if np.all(np.diff(trajectory.t) > 0) \
                else w
    def evaluate(t: np.ndarray) -> dict[str, np.ndarray]:
        traj = trajectory.at(t)
        motion = joint_trajectory(machine, traj)
        w = wrench.at(motion.t) if isinstance(wrench, WrenchSeries) else wrench
        forces = inverse_dynamics(machine, masses, motion.x, motion.xd, motion.xdd, motion.q,
                                  motion.qd, motion.qdd, wrench=w)
        return {"q": motion.q, "qd": motion.qd, "qdd": motion.qdd, "force": forces.force,
                "power": forces.power, "leg_axial": forces.leg_axial,
                "tool_speed": np.linalg.norm(traj.xd, axis=1)[:, None],
                "tool_accel": np.linalg.norm(traj.xdd, axis=1)[:, None]}

    return evaluate


def check_limits_continuous(machine: Machine, trajectory: Trajectory, extrema: Extrema,
                            limits: Limits) -> tuple[dict[str, Any], list[LimitViolation]]:
    """Compare the motion with the actuator limits over continuous time.

    Returns:
        ``(report, violations)``: ``violations`` lists every (kind, actuator) exceeded with all
        its excursions (:func:`pkmkit.motion.limits.path_limit_violations`); ``report`` sums
        it up per kind: ``{kind: {"max": (n,), "limit": (n,), "exceeded": bool, "first": {...}
        | None}}`` for each checked kind (``position``, ``speed``, ``accel``, ``force``), where
        ``first`` is the earliest excursion of any actuator (``t``, ``actuator``, and its
        peak: ``t_peak``, ``value``, ``excess``, ``pose``).
    """
    violations = path_limit_violations(machine, trajectory, extrema, limits)
    report: dict[str, Any] = {}
    for kind, name, lo, hi in limit_bounds(machine, limits):
        mine = [v for v in violations if v.kind == kind]
        first = None
        if mine:
            v = min(mine, key=lambda v: v.excursions[0].span.start)
            span = v.excursions[0].span
            pose = trajectory.at(np.array([span.t_peak])).x[0, :machine.dims]
            first = {"t": span.start, "t_peak": span.t_peak, "actuator": v.joint,
                     "value": span.value, "excess": span.excess, "pose": pose}
        peak = extrema.high[name] if kind == "stroke" else extrema.abs_max(name)
        report["position" if kind == "stroke" else kind] = {
            "max": peak, "limit": np.stack([lo, hi]) if kind == "stroke" else hi,
            "exceeded": bool(mine), "first": first}
    return report, violations


def simulate_path(machine: Machine, path: Path, *, feed: float, accel: float,
                  jerk: float | None = None, profile: str = "scurve",
                  rapid_feed: float | None = None, period: float = 0.01,
                  masses: MassProperties | None = None, wrench: Any = None,
                  limits: Limits | None = None, rtol: float = DEFAULT_RTOL) -> PathResult:
    """Plan the move, follow it with the machine and compute the actuator forces.

    Args:
        machine: the machine.
        path: the tool path (machine coordinates, m).
        feed, accel, jerk, profile, rapid_feed, period: see :func:`pkmkit.motion.plan`;
            ``period`` only sets the output samples: the figures and limit checks hold for the
            continuous motion.
        masses: mass properties (default: :func:`pkmkit.dynamics.defaults.default_masses`).
        wrench: external force on the tool, ``(3,)`` / ``(6,)``, one row per sample, or a
            :class:`~pkmkit.dynamics.wrench.WrenchSeries` (forces against time, interpolated).
        limits: actuator limits to check (strokes always).
        rtol: tolerance of the extrema, relative to each quantity's range.

    Raises:
        InputError: bad limits, a path the machine cannot follow (with the first failing
            sample, between output samples too), bad masses or wrench.

    Seed 000's circle sampled every second still gives its stroke and peak speeds:

    >>> import pkmkit
    >>> from pkmkit.dynamics.trajectory import simulate_path
    >>> from pkmkit.motion import circle
    >>> m = pkmkit.machine("linear-delta-table-iv1")
    >>> r = simulate_path(m, circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0,
    ...                   period=1.0)
    >>> s = r.summary()
    >>> s["samples"], [round(1000 * float(v), 2) for v in s["stroke"]]
    (10, [190.84, 190.84, 190.84])
    >>> [round(1000 * float(v), 2) for v in s["qd_max"]]  # mm/s
    [76.34, 76.34, 76.34]
    """
    trajectory = plan(path, feed=feed, accel=accel, jerk=jerk, profile=profile,
                      rapid_feed=rapid_feed, period=period)
    motion = joint_trajectory(machine, trajectory)
    masses = masses or default_masses(machine)
    sampled_wrench = wrench.at(motion.t) if isinstance(wrench, WrenchSeries) else wrench
    forces = inverse_dynamics(machine, masses, motion.x, motion.xd, motion.xdd, motion.q,
                              motion.qd, motion.qdd, wrench=sampled_wrench)
    evaluate = motion_quantities(machine, trajectory, masses, wrench)
    breakpoints = trajectory.breakpoints()
    if isinstance(wrench, WrenchSeries):
        inside = wrench.t[(wrench.t > 0) & (wrench.t < trajectory.duration)]
        breakpoints = np.union1d(breakpoints, inside)
    extrema = continuous_extrema(evaluate, breakpoints, rtol=rtol)
    for name in ("q", "qd", "qdd", "force", "power", "leg_axial", "tool_speed", "tool_accel"):
        if not (np.isfinite(extrema.low[name]).all() and np.isfinite(extrema.high[name]).all()):
            raise InputError(
                f"the {QUANTITY_NAMES[name]} along the path is not finite (a value overflows): "
                "check the feed, acceleration and jerk limits, the masses and the wrench")
    report, violations = check_limits_continuous(machine, trajectory, extrema,
                                                 limits or Limits())
    return PathResult(motion=motion, forces=forces, masses=masses, limits=report,
                      extrema=extrema, violations=tuple(violations))
