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
from pkmkit.machines.protocol import require_translational
from pkmkit.motion.timelaw import Trajectory
from pkmkit.numerics import small


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
                     tol: float = SINGULARITY_TOL) -> JointTrajectory:
    """Actuator positions, speeds and accelerations along ``trajectory``.

    Batched over the samples in the batch-last layout of the closed forms: A and the diagonal
    of B once, then q̇ = B⁻¹A ẋ, Ȧ (rows ẋ − q̇_i u_i), Ḃ and q̈.

    Raises:
        InputError: the path leaves the workspace (the first failing sample: time, pose, the leg
            and by how much), enters the other assembly mode or comes within ``tol`` of a
            singularity (|cos| between a leg and its slide, or |det| of the unit leg
            directions) — the machine cannot follow it.

    >>> import pkmkit
    >>> from pkmkit.motion import circle, joint_trajectory, plan
    >>> m = pkmkit.machine("linear-delta-table-iv1")
    >>> traj = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=0.01)
    >>> jt = joint_trajectory(m, traj)
    >>> [round(1000 * v, 3) for v in jt.stroke.tolist()]  # mm, over the samples only
    [190.844, 190.844, 190.844]
    """
    require_translational(machine, "a joint trajectory along a tool path")
    dims = machine.dims
    if dims == 2 and np.abs(trajectory.x[:, 2]).max() > 1e-12:
        raise InputError("a planar machine needs a path in the plane z = 0")
    x = np.ascontiguousarray(trajectory.x[:, :dims])
    xd = np.ascontiguousarray(trajectory.xd[:, :dims])
    xdd = np.ascontiguousarray(trajectory.xdd[:, :dims])
    closed = machine.closed_form
    q = closed.inverse(x, machine.model.leg_branch)
    unreachable = ~np.isfinite(q).all(axis=1)
    a, b = closed.jacobians_t(x, q)  # (n, dims, N), (n, N); NaN where unreachable
    lengths = np.sqrt(np.einsum("ikn,ikn->in", a, a))
    det = small.det(a)
    with np.errstate(invalid="ignore", divide="ignore"):
        det_unit = det / np.prod(lengths, axis=0)
        serial = np.min(np.abs(b) / lengths, axis=0)
    wrong = ~unreachable & ((np.sign(det) != machine.working_mode) | (np.abs(det_unit) < tol)
                            | (serial < tol))
    failing = np.flatnonzero(unreachable | wrong)
    if failing.size:
        k = int(failing[0])
        if unreachable[k]:
            short = closed.shortfall(x[k:k + 1])[0]
            leg = int(np.nanargmax(short))
            what = (f"leaves the workspace ({machine.model.leg_names[leg]} too short by "
                    f"{short[leg]:.6g} m)")
        elif serial[k] < tol:
            what = "meets a serial singularity (a leg perpendicular to its slide)"
        elif abs(det_unit[k]) < tol:
            what = "meets a parallel singularity"
        else:
            mode = machine.mode_label(int(np.sign(det[k])))
            what = (f"starts in the other assembly mode ({mode!r})" if k == 0 else
                    f"crosses a parallel singularity into the other assembly mode ({mode!r})")
        raise InputError(f"the path {what}: first at t = {trajectory.t[k]:.6g} s, pose "
                         f"{np.round(x[k], 9).tolist()} m{_stroke_note(machine, trajectory, q, k)}")
    xd_t, xdd_t = xd.T, xdd.T
    qd = np.einsum("ikn,kn->in", a, xd_t) / b
    # ∂c/∂q (n, dims, N): slide axis, crank-tip velocity per radian, zero for struts
    rates = closed.carriage_rates(q).transpose(1, 2, 0)
    a_dot = xd_t[None] - qd[:, None, :] * rates
    b_dot = np.einsum("ikn,ikn->in", a_dot, rates) + closed.strut[:, None] * qd
    for i in np.flatnonzero(closed.crank):  # the crank tip's velocity turns with the arm
        radial = np.cross(machine.model.leg_axis[i][:, None], rates[i], axis=0)
        b_dot[i] += np.einsum("kn,kn->n", a[i], radial) * qd[i]
    qdd = (np.einsum("ikn,kn->in", a, xdd_t) + np.einsum("ikn,kn->in", a_dot, xd_t)
           - b_dot * qd) / b
    return JointTrajectory(t=trajectory.t, x=x, xd=xd, xdd=xdd, q=q, qd=qd.T, qdd=qdd.T,
                           trajectory=trajectory)


def _stroke_note(machine: Machine, trajectory: Trajectory, q: np.ndarray, k: int) -> str:
    """Mention a stroke limit already exceeded before sample ``k`` (empty string if none)."""
    model = machine.model
    outside = (q[:k] < model.q_min) | (q[:k] > model.q_max)
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
        lo, hi = machine.model.q_min, machine.model.q_max
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
