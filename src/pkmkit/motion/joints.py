"""Joint trajectories of any machine along a sampled tool trajectory, and limit checks.

q from the inverse model; q̇ and q̈ from the analytic velocity model — q̇ = B⁻¹A ẋ and, differentiating
A ẋ = B q̇, q̈ = B⁻¹(A ẍ + Ȧ ẋ − Ḃ q̇) — never from finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.machine import SINGULARITY_TOL, Machine
from pkmkit.machines.strokes import stroke_limits
from pkmkit.motion.timelaw import Trajectory


@dataclass(frozen=True)
class JointTrajectory:
    """Actuator motion along a trajectory (N samples, n actuators).

    Attributes:
        t: ``(N,)`` s.
        x, xd, xdd: ``(N, dims)`` tool position, velocity, acceleration.
        q, qd, qdd: ``(N, n)`` actuator positions (m), speeds (m/s), accelerations (m/s²).
        trajectory: the tool trajectory.
    """

    t: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    xdd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    trajectory: Trajectory

    @property
    def stroke(self) -> np.ndarray:
        """``(n,)`` range of each actuator coordinate, m."""
        return self.q.max(axis=0) - self.q.min(axis=0)


def joint_trajectory(machine: Machine, trajectory: Trajectory, *,
                     tol: float = SINGULARITY_TOL, orientation: Any = None) -> JointTrajectory:
    """Actuator positions, speeds and accelerations along ``trajectory``.

    Any machine through its protocol method ``joint_motion``
    (:mod:`pkmkit.machines.joint_motion`): a translating platform batched in the closed forms'
    layout; a full-pose platform at the held rotation vector ``orientation`` (rad, default its
    home orientation; a machine with fewer than six actuators at the orientation its rods
    impose). ``x``, ``xd``, ``xdd`` of the result are the path's (the platform point's).

    Raises:
        InputError: the path leaves the workspace (the first failing sample: time, pose, the leg
            and by how much), enters the other assembly mode or comes within ``tol`` of a
            singularity (|cos| between a leg and its slide, or |det| of the unit leg
            directions) — the machine cannot follow it.
        UnsupportedOperationError: a joint-chain machine (its velocity model has no time
            derivative yet), naming why.

    >>> import pkmkit
    >>> from pkmkit.motion import circle, joint_trajectory, plan
    >>> m = pkmkit.machine("linear-delta-table-iv1")
    >>> traj = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=0.01)
    >>> jt = joint_trajectory(m, traj)
    >>> [round(1000 * v, 3) for v in jt.stroke.tolist()]  # mm, over the samples only
    [190.844, 190.844, 190.844]
    """
    dims = min(machine.dims, 3)
    if dims == 2 and np.abs(trajectory.x[:, 2]).max() > 1e-12:
        raise InputError("a planar machine needs a path in the plane z = 0")
    x = np.ascontiguousarray(trajectory.x[:, :dims])
    xd = np.ascontiguousarray(trajectory.xd[:, :dims])
    xdd = np.ascontiguousarray(trajectory.xdd[:, :dims])
    motion = machine.joint_motion(x, xd, xdd, tol=tol, orientation=orientation)
    if motion.failed is not None:
        k = motion.failed
        raise InputError(f"the path {motion.reason}: first at t = {trajectory.t[k]:.6g} s, pose "
                         f"{np.round(x[k], 9).tolist()} m"
                         f"{_stroke_note(machine, trajectory, motion.q_partial, k)}")
    return JointTrajectory(t=trajectory.t, x=x, xd=xd, xdd=xdd, q=motion.q, qd=motion.qd,
                           qdd=motion.qdd, trajectory=trajectory)


def _stroke_note(machine: Machine, trajectory: Trajectory, q: np.ndarray, k: int) -> str:
    """Mention a stroke limit already exceeded before sample ``k`` (empty string if none)."""
    q_min, q_max = stroke_limits(machine)
    outside = (q[:k] < q_min) | (q[:k] > q_max)
    if not outside.any():
        return ""
    first = int(np.flatnonzero(outside.any(axis=1))[0])
    actuator = int(np.flatnonzero(outside[first])[0])
    return (f"; the stroke of {machine.actuator_names[actuator]} is already exceeded from "
            f"t = {trajectory.t[first]:.6g} s")


@dataclass(frozen=True)
class Limits:
    """Actuator limits; each is a scalar (all actuators) or ``(n,)``, None when not checked.

    Attributes:
        speed: m/s. accel: m/s². force: N (absolute value).
        strokes: check the machine's ``q_min``/``q_max``.
    """

    speed: Any = None
    accel: Any = None
    force: Any = None
    strokes: bool = True


def check_limits(machine: Machine, motion: JointTrajectory, limits: Limits,
                 forces: np.ndarray | None = None) -> dict[str, Any]:
    """Compare the motion (and the actuator forces) with the limits.

    Returns:
        ``{kind: {"max": (n,), "limit": (n,), "exceeded": bool, "first": {...} | None}}`` for
        each checked kind (``position``, ``speed``, ``accel``, ``force``); ``first`` says when,
        where, which actuator and by how much the limit is first exceeded.
    """
    n = machine.n_actuators
    report: dict[str, Any] = {}

    def add(kind: str, values: np.ndarray, lower: np.ndarray, upper: np.ndarray,
            peak: np.ndarray) -> None:
        excess = np.maximum(lower[None] - values, values - upper[None])
        over = excess > 1e-12
        entry = {"max": peak, "limit": upper if kind != "position" else np.stack([lower, upper]),
                 "exceeded": bool(over.any()), "first": None}
        if over.any():
            k = int(np.flatnonzero(over.any(axis=1))[0])
            a = int(np.argmax(excess[k]))
            entry["first"] = {"t": float(motion.t[k]), "actuator": machine.actuator_names[a],
                              "value": float(values[k, a]), "excess": float(excess[k, a]),
                              "pose": motion.x[k]}
        report[kind] = entry

    if limits.strokes:
        lo, hi = stroke_limits(machine)
        add("position", motion.q, lo, hi, motion.q.max(axis=0))
    for kind, values, limit in (("speed", motion.qd, limits.speed),
                                ("accel", motion.qdd, limits.accel),
                                ("force", forces, limits.force)):
        if limit is None or values is None:
            continue
        lim = np.broadcast_to(np.asarray(limit, dtype=float), (n,))
        if not (np.isfinite(lim).all() and (lim > 0).all()):
            raise InputError(f"{kind} limits must be > 0, got {limit}")
        add(kind, values, -lim, lim, np.abs(values).max(axis=0))
    return report
