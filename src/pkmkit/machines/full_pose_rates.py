"""Velocity models of full-pose machines beyond J: J̇ along a twist and the helpers it shares with
the Jacobian (batched, SI units)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from pkmkit.exceptions import (
    InputError,
)
from pkmkit.machines.results import (
    JacobianRates,
)
from pkmkit.model.rods import STRUT

if TYPE_CHECKING:
    from pkmkit.machines.full_pose import FullPoseJacobians


class FullPoseRates:
    """Mixin of :class:`~pkmkit.machines.full_pose.FullPoseMachine`: J̇ and its helpers."""

    def jacobian_dot(self, x: Any, xd: Any, *, q: Any = None) -> JacobianRates:
        """Time derivatives of the velocity model along a motion through poses ``x``.

        Args:
            x: ``(6,)`` / ``(N, 6)`` poses (positions ``(3,)`` / ``(N, 3)`` for a machine with
                fewer than six actuators: the orientation its rods impose is found).
            xd: the platform twists ``(6,)`` / ``(N, 6)`` = (v in m/s, ω in rad/s, both in the
                base frame, v of the platform reference point); for a machine with fewer than
                six actuators, also the velocities of the position ``(3,)`` / ``(N, 3)`` (its
                twist then follows from its rods).
            q: actuator coordinates at ``x`` (default: the inverse model).

        Returns:
            :class:`~pkmkit.machines.results.JacobianRates`: ``qd (N, n)`` the actuator rates,
            ``A_dot (N, m, 6)``, ``B_dot (N, m, n)`` and ``J_dot (N, 6, n)`` with
            ``J̇ = A⁻¹(Ḃ − ȦJ)`` (least squares ``A⁺`` beyond six rods), so that the platform's
            acceleration twist is ``J q̈ + J̇ q̇``.

        Raises:
            InputError: mis-shaped or non-finite input, a twist a position-controlled machine
                cannot follow (its rods do not allow it: the rates disagree by more than 1e-9
                relative).
        """
        jac = self.jacobian(x, q=q) if q is not None else self.jacobian(x)
        single = np.ndim(jac.condition) == 0
        poses = np.atleast_2d(self._poses_of(x, jac))
        j = np.atleast_3d(jac.J) if not single else jac.J[None]
        a = jac.A[None] if single else jac.A
        b = jac.B[None] if single else jac.B
        qb = np.atleast_2d(jac.q)
        size = poses.shape[0]
        try:
            xdb = np.asarray(xd, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"xd must be an array of numbers: {exc}") from None
        xdb = xdb[None] if xdb.ndim == 1 else xdb
        widths = (6, 3) if self.position_controlled else (6,)
        if xdb.ndim != 2 or xdb.shape[1] not in widths or xdb.shape[0] != size:
            raise InputError(f"xd must have shape ({size}, {' or '.join(map(str, widths))}) to "
                             f"match x, got {np.shape(xd)}")
        if not np.isfinite(xdb).all():
            raise InputError("xd must be finite")
        if (np.abs(xdb) > 1e9).any():
            raise InputError("xd has a component beyond 1e9 (m/s or rad/s): check the units")
        with np.errstate(invalid="ignore"):
            if xdb.shape[1] == 3:
                qd = np.full((size, self.n_actuators), np.nan)
                ok = np.isfinite(j).all(axis=(1, 2))
                qd[ok] = np.linalg.solve(j[ok, :3], xdb[ok][:, :, None])[:, :, 0]
                twist = np.einsum("kij,kj->ki", j, qd)
            else:
                twist = xdb
                qd = np.einsum("kij,kj->ki", np.linalg.pinv(b) @ a, twist)
                if self.position_controlled:
                    back = np.einsum("kij,kj->ki", j, qd)
                    off = np.abs(back - twist).max(axis=1) > 1e-9 * (
                        1 + np.abs(twist).max(axis=1))
                    if (off & np.isfinite(back).all(axis=1)).any():
                        k = int(np.flatnonzero(off)[0])
                        raise InputError(f"twist row {k} is not one the rods of {self.id!r} "
                                         "allow; give the velocity of the position (3 values)")
        a_dot, b_dot = self._forms.jacobian_rates(poses, qb, twist, qd)
        rhs = b_dot - np.einsum("kij,kjl->kil", a_dot, j)
        j_dot = np.full((size, 6, self.n_actuators), np.nan)
        ok = np.isfinite(a).all(axis=(1, 2)) & np.isfinite(rhs).all(axis=(1, 2))
        if ok.any():
            j_dot[ok] = solve_j(a[ok], rhs[ok])
        rates = JacobianRates(qd=qd, A_dot=a_dot, B_dot=b_dot, J_dot=j_dot)
        if single:
            return JacobianRates(**{k: v[0] for k, v in rates.__dict__.items()})
        return rates

    def _poses_of(self, x: Any, jac: FullPoseJacobians) -> np.ndarray:
        """The full poses a velocity model was taken at (positions completed by the inverse
        model for a position-controlled machine)."""
        arr = np.asarray(x, dtype=float)
        if self.position_controlled and arr.shape[-1] == 3:
            return np.asarray(self.ik(arr, full_output=True).pose)
        return arr

    def _fitting_q(self, xb: np.ndarray, qb: np.ndarray, single: bool) -> np.ndarray:
        """``qb`` with NaN rows where it does not close every rod at ``xb`` within 1e-9 m
        relative (as rod machines check q given with poses); a single misfit raises
        :class:`~pkmkit.exceptions.InputError` naming the rod."""
        with np.errstate(invalid="ignore", over="ignore"):
            error = self._forms.closure_errors(xb, qb)
        bad = ~(error <= 1e-9 * (1.0 + float(self.model.rod_length.max()))).all(axis=1)
        bad &= np.isfinite(qb).all(axis=1) & np.isfinite(xb).all(axis=1)
        if not bad.any():
            return qb
        if single:
            rod = int(np.nanargmax(np.where(np.isfinite(error[0]), error[0], np.inf)))
            raise InputError(f"q = {qb[0].tolist()} does not fit pose {xb[0].tolist()}: "
                             f"{self._rod_name(rod)} misses its length by {error[0, rod]:.6g} m")
        qb = qb.copy()
        qb[bad] = np.nan
        return qb


def solve_j(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """J = A⁻¹B ``(N, 6, n)`` of ``a (N, m, 6)``, ``b (N, m, n)`` (six rods), or the
    least-squares A⁺B (more rods); ``b`` may carry more trailing axes' worth of columns."""
    if a.shape[1] == 6:
        return np.linalg.solve(a, b)
    return np.linalg.pinv(a) @ b


def base_joint_speeds(model: Any, q: np.ndarray) -> np.ndarray:
    """``|∂a_j/∂q|`` ``(N, m)`` of a rod ``model`` at actuator rows ``q (N, n)`` (1 for
    struts, whose base joints do not move)."""
    from pkmkit.solve.rod_closure import actuator_rates

    rates = actuator_rates(model, np.nan_to_num(q).T)  # (3, m, N)
    speed = np.linalg.norm(rates, axis=0).T
    speed[:, model.rod_kind == STRUT] = 1.0
    return speed


def rod_b_pinv(b: np.ndarray) -> np.ndarray:
    """``B⁺ (N, n, m)`` of a rod machine's ``B (N, m, n)``, whose row j has one entry, in
    the column of rod j's actuator: the columns have disjoint supports, so BᵀB is diagonal,
    the singular values of B are its column norms and ``B⁺ = (BᵀB)⁺Bᵀ`` — entry (a, j) is
    ``B[j, a] / |B[:, a]|²``, 0 for a column below ``np.linalg.pinv``'s cutoff (1e-15 of the
    largest column norm: an actuator whose rods are all at a serial singularity). The same
    matrix as ``np.linalg.pinv(b)`` to rounding, without an SVD per row."""
    squares = np.einsum("kja,kja->ka", b, b)
    norms = np.sqrt(squares)
    large = norms > 1e-15 * norms.max(axis=1, keepdims=True)
    inverse = np.divide(1.0, squares, where=large, out=np.zeros_like(squares))
    return (b * inverse[:, None, :]).transpose(0, 2, 1)
