"""Actuator motion (q, q̇, q̈) along sampled tool motions — the kernels behind every machine's
``joint_motion`` protocol method, from the analytic velocity model, never from finite
differences.

- rod legs with a translating platform (:func:`rod_joint_motion`): q̇ = B⁻¹A ẋ and,
  differentiating A ẋ = B q̇, q̈ = B⁻¹(A ẍ + Ȧ ẋ − Ḃ q̇), batched in the closed forms' batch-last
  layout;
- rod legs with a full-pose platform (:func:`full_pose_joint_motion`): the platform keeps a held
  orientation (twist (ẋ, 0)) — or, for a machine with fewer than six actuators, the orientation
  its rods impose — and q̈ = B⁺(A a + Ȧ t − Ḃ q̇) (a, t the acceleration and velocity twists), or
  q̈ = J_p⁻¹(ẍ − (J̇ q̇)_p) from the position rows p of J for a position-controlled machine.

Each returns a :class:`JointMotion` whose ``failed`` names the first sample the machine cannot
follow (out of reach, a singularity, the other assembly mode) and why; the caller says when.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.numerics import small
from pkmkit.status import Status


@dataclass(frozen=True)
class JointMotion:
    """Actuator motion at N samples (n actuators).

    Attributes:
        q, qd, qdd: ``(N, n)`` actuator positions, rates and accelerations (m or rad, per s,
            per s²); None when ``failed`` is set.
        failed: index of the first sample the machine cannot follow, else None.
        reason: why, completing "the path …" (e.g. ``"meets a parallel singularity"``).
        q_partial: ``(N, n)`` the inverse model's actuator positions (NaN where out of reach),
            also when ``failed`` is set (for stroke notes).
    """

    q: np.ndarray | None
    qd: np.ndarray | None
    qdd: np.ndarray | None
    failed: int | None = None
    reason: str = ""
    q_partial: np.ndarray | None = None


def rod_joint_motion(machine, x: np.ndarray, xd: np.ndarray, xdd: np.ndarray,
                     tol: float) -> JointMotion:
    """q, q̇, q̈ of a translational rod-leg machine at poses ``x``, velocities ``xd`` and
    accelerations ``xdd`` ``(N, dims)`` (m, m/s, m/s²); rows within ``tol`` of a singularity
    (|cos| between a leg and its slide, or |det| of the unit leg directions) fail."""
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
        return JointMotion(None, None, None, failed=k, reason=what, q_partial=q)
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
    return JointMotion(q, qd.T, qdd.T, q_partial=q)


def full_pose_joint_motion(machine, x: np.ndarray, xd: np.ndarray, xdd: np.ndarray,
                           tol: float, orientation: np.ndarray | None) -> JointMotion:
    """q, q̇, q̈ of a full-pose rod-leg machine whose platform point follows positions ``x``
    with velocities ``xd`` and accelerations ``xdd`` ``(N, 3)`` at the held rotation vector
    ``orientation (3,)`` (rad; default the home orientation), or — position-controlled — at the
    orientation its rods impose (``orientation`` must then be None)."""
    n_samples = x.shape[0]
    if machine.position_controlled:
        poses, twist = x, xd
    else:
        held = machine.home_pose[3:] if orientation is None else orientation
        poses = np.concatenate([x, np.broadcast_to(held, (n_samples, 3))], axis=1)
        twist = np.concatenate([xd, np.zeros((n_samples, 3))], axis=1)
    inv = machine.ik(poses, full_output=True, strokes="ignore")
    q = np.asarray(inv.q)
    unreachable = inv.status != Status.OK
    jac = machine.jacobian(poses, q=None if machine.position_controlled else q, tol=tol)
    singular = ~unreachable & (np.asarray(jac.singularity) != 0)
    mode = np.asarray(jac.mode)
    other = ~unreachable & (mode != 0) & (mode != machine.working_mode)
    failing = np.flatnonzero(unreachable | singular | other)
    if failing.size:
        k = int(failing[0])
        if unreachable[k]:
            what = f"leaves the workspace ({Status(int(inv.status[k])).label})"
        elif singular[k]:
            what = f"meets a {jac.status[k]} singularity"
        else:
            what = ("starts in the other assembly mode" if k == 0 else
                    "crosses a parallel singularity into the other assembly mode")
        return JointMotion(None, None, None, failed=k, reason=what, q_partial=q)
    rates = machine.jacobian_dot(poses, twist, q=None if machine.position_controlled else q)
    qd = rates.qd
    if machine.position_controlled:
        rhs = xdd - np.einsum("kij,kj->ki", rates.J_dot, qd)[:, :3]
        qdd = np.linalg.solve(jac.J[:, :3], rhs[:, :, None])[:, :, 0]
    else:
        accel = np.concatenate([xdd, np.zeros((n_samples, 3))], axis=1)
        rhs = (np.einsum("kij,kj->ki", jac.A, accel) + np.einsum("kij,kj->ki", rates.A_dot, twist)
               - np.einsum("kij,kj->ki", rates.B_dot, qd))
        qdd = np.einsum("kij,kj->ki", np.linalg.pinv(jac.B), rhs)
    return JointMotion(q, qd, qdd, q_partial=q)
