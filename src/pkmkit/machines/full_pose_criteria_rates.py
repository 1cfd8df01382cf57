"""Derivatives of what a workspace's criteria read, along position axes, for full-pose rod
machines (issue 22 §3): the analytic gradients of the inscribed-box refinement's slacks
(:func:`pkmkit.analysis.slack.slack_and_gradient`) in place of a finite-difference lattice
per axis.

Moving the platform position along axis e_k (the orientation held for a six-actuator machine;
for a position-controlled one, the orientation its rods impose follows):

- the platform twist t and the actuator rates q̇: ``t = (e_k, 0)``, ``q̇ = B⁺A t`` (six or more
  actuators); ``q̇ = (J_p)⁻¹ e_k`` with J_p the linear rows of J, ``t = J q̇`` (three actuators
  setting the orientation);
- ``Ȧ``, ``Ḃ`` along (t, q̇) (:meth:`~pkmkit.machines.full_pose_forms.FullPoseForms.
  jacobian_rates`), ``J̇ = A⁻¹(Ḃ − ȦJ)``;
- a singular value σ_i of a matrix M with singular vectors (u_i, v_i) moves at
  ``σ̇_i = u_iᵀ Ṁ v_i`` (simple singular values): for the parallel measure σ_min/σ_max of A with
  unit rows (moments over L) and for the transmission factors, the singular values of the
  homogenised J;
- a rod's shortfall (distance from its platform joint P_j to the reach of its base joint) moves
  with ``Ṗ_j = v + ω × R b_j``.

Each is checked against central differences of the machine's own ``ik``/``jacobian``
(tests/machines/test_full_pose_criteria_rates.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.machines.full_pose_rates import rod_b_pinv, solve_j
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.numerics.linalg import singular_value_rates


@dataclass(frozen=True)
class CriteriaRates:
    """Derivatives along ``d`` position axes at N poses (NaN where the quantity or its
    derivative does not exist: unreachable rows, a parallel singularity, degenerate singular
    values).

    Attributes:
        q: ``(N, n, d)`` actuator rates ∂q/∂x_k (m/m, rad/m).
        shortfall: ``(N, m, d)`` ∂(rod shortfall)/∂x_k (0 for struts, always reached).
        parallel_measure: ``(N, d)`` ∂(σ_min/σ_max of A with unit rows)/∂x_k (1/m).
        singular_values: ``(N, n, d)`` ∂(singular values of the homogenised J)/∂x_k, in their
            decreasing order, or None when not asked.
    """

    q: np.ndarray
    shortfall: np.ndarray
    parallel_measure: np.ndarray
    singular_values: np.ndarray | None = None


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products along the last axis (3) of two arrays of the same shape."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


class FullPoseCriteriaRates:
    """Mixin of :class:`~pkmkit.machines.full_pose.FullPoseMachine`: :meth:`criteria_rates`."""

    def criteria_rates(self, points: np.ndarray, inverse: Any, jacobians: Any,
                       axes: tuple[int, ...], *, factors: bool = False) -> CriteriaRates | None:
        """Derivatives of the criteria's quantities along position ``axes`` at ``points``.

        Args:
            points: ``(N, 6)`` poses or, for a position-controlled machine, ``(N, 3)``
                positions (as given to ``ik``).
            inverse: ``ik(points, full_output=True)``.
            jacobians: the velocity model at the inverse model's poses and q.
            axes: the pose coordinates that move (position axes 0–2).
            factors: also the rates of the transmission factors.

        Returns:
            :class:`CriteriaRates`, or None when an axis is not a position axis (a rotation
            vector's component: no analytic rates, difference instead).
        """
        axes = tuple(int(k) for k in axes)
        if not axes or any(k not in (0, 1, 2) for k in axes):
            return None
        points = np.asarray(points, dtype=float)
        poses = np.asarray(inverse.pose) if (getattr(inverse, "pose", None) is not None
                                            and points.shape[1] == 3) else points
        q = np.asarray(jacobians.q)
        a, b = jacobians.A, jacobians.B  # J (a solve per row) read only where needed
        size, d = poses.shape[0], len(axes)
        unit = np.zeros((3, d))
        unit[list(axes), np.arange(d)] = 1.0
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            if points.shape[1] == 3 and self.position_controlled:
                j = jacobians.J
                q_rate = np.full((size, self.n_actuators, d), np.nan)
                ok = np.isfinite(j).all(axis=(1, 2))
                if ok.any():
                    q_rate[ok] = np.linalg.solve(j[ok, :3], np.broadcast_to(
                        unit, (int(ok.sum()), 3, d)))
                twist = np.einsum("kin,knd->kid", j, q_rate)
            else:
                twist = np.zeros((size, 6, d))
                twist[:, :3] = unit
                q_rate = (rod_b_pinv(b) @ a)[:, :, list(axes)]
            a_dot = self._a_rates(poses, q, a, twist, q_rate)
            parallel = self._parallel_rate(a, a_dot)
            shortfall = self._shortfall_rates(poses, twist)
            sv_rate = None
            if factors:
                b_dot = np.empty((*b.shape, d))
                for i in range(d):
                    b_dot[..., i] = self._forms.jacobian_rates(
                        poses, q, twist[:, :, i], q_rate[:, :, i])[1]
                sv_rate = self._factor_rates(a, a_dot, b_dot, jacobians.J)
        return CriteriaRates(q=q_rate, shortfall=shortfall, parallel_measure=parallel,
                             singular_values=sv_rate)

    def _a_rates(self, poses: np.ndarray, q: np.ndarray, a: np.ndarray, twist: np.ndarray,
                 q_rate: np.ndarray) -> np.ndarray:
        """``Ȧ (N, m, 6, d)`` along each twist ``(N, 6, d)`` with actuator rates
        ``(N, n, d)``: rows ``(ḋ, ṙ × d + r × ḋ)`` with ``r = R b``, ``ṙ = ω × r``,
        ``ḋ = v + ṙ − ∂a/∂q q̇`` (as :meth:`FullPoseForms.jacobian_rates`)."""
        from pkmkit.solve.rod_closure import actuator_rates

        model = self.model
        rod = self._forms.platform_points(poses) - poses[:, None, :3]  # r = R b (N, m, 3)
        vec = a[:, :, :3]  # d
        moving = actuator_rates(model, np.nan_to_num(q).T).transpose(2, 1, 0)  # ∂a/∂q
        moving = np.where(np.isfinite(q).all(axis=1)[:, None, None], moving, np.nan)
        out = np.empty((*a.shape, twist.shape[-1]))
        for i in range(twist.shape[-1]):
            v, w = twist[:, None, :3, i], twist[:, None, 3:, i]
            rod_dot = _cross(np.broadcast_to(w, rod.shape), rod)
            vec_dot = v + rod_dot - moving * q_rate[:, model.rod_actuator, i][:, :, None]
            out[:, :, :3, i] = vec_dot
            out[:, :, 3:, i] = _cross(rod_dot, vec) + _cross(rod, vec_dot)
        return out

    def _parallel_rate(self, a: np.ndarray, a_dot: np.ndarray) -> np.ndarray:
        """``(N, d)`` rate of σ_min/σ_max of A with unit rows (moments over L)."""
        length = float(self.characteristic_length)
        dist = np.linalg.norm(a[:, :, :3], axis=2)[:, :, None]  # (N, m, 1)
        along = np.einsum("kja,kjad->kjd", a[:, :, :3], a_dot[:, :, :3])  # d·ḋ
        unit = a / dist
        unit_dot = a_dot / dist[..., None] - a[..., None] * (along / dist**3)[:, :, None, :]
        unit[:, :, 3:] /= length
        unit_dot[:, :, 3:] /= length
        sigma, rates = singular_value_rates(unit, unit_dot)
        largest, smallest = sigma[:, :1], sigma[:, 5:6]
        return (rates[:, 5] * largest - smallest * rates[:, 0]) / largest**2

    def _factor_rates(self, a: np.ndarray, a_dot: np.ndarray, b_dot: np.ndarray,
                      j: np.ndarray) -> np.ndarray:
        """``(N, n, d)`` rates of the singular values of the homogenised J."""
        length = float(self.characteristic_length)
        rhs = b_dot - np.einsum("kjad,kan->kjnd", a_dot, j)
        j_dot = np.full((*j.shape, rhs.shape[-1]), np.nan)
        ok = np.isfinite(j).all(axis=(1, 2)) & np.isfinite(rhs).all(axis=(1, 2, 3))
        if ok.any():
            for i in range(rhs.shape[-1]):
                j_dot[ok, :, :, i] = solve_j(a[ok], rhs[ok, :, :, i])
        scale = np.array([1.0, 1.0, 1.0, length, length, length])
        return singular_value_rates(j * scale[None, :, None], j_dot * scale[None, :, None, None])[1]

    def _shortfall_rates(self, poses: np.ndarray, twist: np.ndarray) -> np.ndarray:
        """``(N, m, d)`` rates of each rod's shortfall (:meth:`FullPoseForms.shortfall`)."""
        m, forms = self.model, self._forms
        out = np.zeros((poses.shape[0], m.n_rods, twist.shape[-1]))
        if not np.isin(m.rod_kind, (SLIDE, CRANK)).any():
            return out  # struts reach everywhere
        points = forms.platform_points(poses)  # (N, m, 3)
        offsets = points - poses[:, None, :3]
        # Ṗ_j = v + ω × R b_j  (N, m, 3, d)
        speed = twist[:, None, :3, :] + np.cross(
            np.moveaxis(twist[:, 3:, :], 1, 2)[:, None, :, :], offsets[:, :, None, :]
        ).transpose(0, 1, 3, 2)
        for jj in range(m.n_rods):
            kind, p_dot = m.rod_kind[jj], speed[:, jj]
            if kind == SLIDE:
                w = points[:, jj] - m.rod_base[jj]
                across = w - (w @ m.rod_axis[jj])[:, None] * m.rod_axis[jj]
                perp = np.linalg.norm(across, axis=1)
                out[:, jj] = np.einsum("ka,kad->kd", across, p_dot) / perp[:, None]
            elif kind == CRANK:
                v = points[:, jj] - m.rod_pivot[jj]
                v_w = v @ m.rod_axis[jj] - forms.crank_offset[jj]
                v1, v2 = v @ forms.crank_e1[jj], v @ forms.crank_e2[jj]
                perp = np.hypot(v1, v2)
                r = forms.crank_radius[jj]
                w_dot = np.einsum("a,kad->kd", m.rod_axis[jj], p_dot)
                perp_dot = (v1[:, None] * np.einsum("a,kad->kd", forms.crank_e1[jj], p_dot)
                            + v2[:, None] * np.einsum("a,kad->kd", forms.crank_e2[jj], p_dot)
                            ) / perp[:, None]
                nearest, farthest = np.hypot(v_w, perp - r), np.hypot(v_w, perp + r)
                near_dot = (v_w[:, None] * w_dot + (perp - r)[:, None] * perp_dot) / nearest[
                    :, None]
                far_dot = (v_w[:, None] * w_dot + (perp + r)[:, None] * perp_dot) / farthest[
                    :, None]
                length = m.rod_length[jj]
                out[:, jj] = np.where((nearest - length >= length - farthest)[:, None],
                                      near_dot, -far_dot)
        return out
