"""Velocity model of joint-chain machines: the closure Jacobians, J at configurations, and the
degree of hyperstatism from their ranks."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import (
    InputError,
    SingularConfigurationError,
    UnsupportedOperationError,
)
from pkmkit.machines.chain_one import ChainOnePose
from pkmkit.machines.chain_one import jacobian as one_pose_jacobian
from pkmkit.machines.chain_one_velocity import at_call
from pkmkit.machines.chain_velocity_record import (
    RANK_RCOND,
    SINGULAR_TOL,
    ChainJacobians,
)
from pkmkit.machines.chunks import chunked
from pkmkit.machines.common import _checked_batch
from pkmkit.model.chains import FIXED
from pkmkit.numerics.arrays import as_batch
from pkmkit.numerics.linalg import small_singular_values
from pkmkit.solve.chains import (
    closure,
    tool_frame,
)
from pkmkit.spatial.rotation import rotvec_to_matrix
from pkmkit.status import Status


@dataclass(frozen=True)
class HyperstatismCount:
    """Mobility and degree of hyperstatism of the parallel part (legs closed on the platform).

    Attributes:
        bodies: bodies of the parallel part, base and platform included.
        joints: one-DOF joints (each shared joint once); joints_by_type ``{"R": …, "P": …}``.
        loops: independent loops ν = joints − bodies + 1.
        mobility: m, from the rank of the closure Jacobian at home (degrees of freedom).
        hyperstatism: h = 6ν − Σ f + m (Fayet/Grübler).
        grubler_mobility: 6(bodies − 1 − joints) + Σ f, the count blind to geometry.
        rank_hyperstatism: closure equations − rank at home (the redundant equations).
    """

    bodies: int
    joints: int
    joints_by_type: dict[str, int]
    loops: int
    mobility: int
    hyperstatism: int
    grubler_mobility: int
    rank_hyperstatism: int


class ChainVelocity(ChainOnePose):
    """Mixin of :class:`~pkmkit.machines.joint_chain.JointChainMachine`: its velocity model
    (and, from :class:`~pkmkit.machines.chain_one.ChainOnePose`, the one-pose paths)."""

    # ---------------------------------------------------------------- velocity
    def jacobian(self, x: Any = None, *, q: Any = None, branches: Any = None,
                 tol: float = SINGULAR_TOL, start: Any = None) -> ChainJacobians:
        """Velocity model at tool poses ``x`` or at actuator coordinates ``q`` (the closure
        linearised: ``dU = −C_U⁺ C_q dq`` for the platform and passive joints U, then the
        head), with the argument conventions of every machine.

        Args:
            x: ``(6,)`` or ``(N, 6)`` tool points and axes; their actuator coordinates come from
                the inverse model unless ``q`` is given. The former call ``jacobian(q)`` (one
                positional array of actuator values) still works, with a DeprecationWarning.
            q: ``(n,)`` or ``(N, n)`` actuator coordinates (then ``x`` may be omitted).
            branches: must be None (a joint chain has no leg branches; reach other solutions
                with ``ik(x, q0=...)`` and pass ``q``).
            tol: threshold on σ_min/σ_max of the closure's Jacobian below which a row is a
                singular closure.
            start: warm start of the closure at ``q``, as :meth:`fk`'s (e.g. an inverse
                result's ``closure_start``: the direct model then converges at once, on the
                assembly the inverse found); default home.

        Rows without assembly or at a singular closure are NaN with their status.

        Raises:
            InputError: neither x nor q, a ``branches`` value, mis-shaped input.
            ConvergenceError: a single x the inverse model cannot reach.
            ClosureMissError: a single q whose legs do not close.
            SingularConfigurationError: a single q at a singular closure.
        """
        if q is None and branches is None and start is None and x is not None:
            # one plain pose: one C call (machines/chain_one_velocity.py), before the batch
            # wrapper; False: the other one-pose paths (machines/chain_one.py), None: the batch
            fast = at_call(self, x, tol)
            if fast is False:
                fast = one_pose_jacobian(self, x, tol)
            if fast is not None:
                return fast
        return self._jacobian_rows(x, q=q, branches=branches, tol=tol, start=start)

    @chunked  # a batch of more than ``chunk_rows`` rows chunk by chunk (issue 22 §6)
    def _jacobian_rows(self, x: Any = None, *, q: Any = None, branches: Any = None,
                       tol: float = SINGULAR_TOL, start: Any = None) -> ChainJacobians:
        """:meth:`jacobian` by the batch path (one pose too, where the one-pose paths do not
        answer)."""
        if branches is not None:
            raise InputError("a joint-chain machine has no leg branches: reach another "
                             "solution with ik(x, q0=...) and pass its q")
        if not (isinstance(tol, int | float | np.floating) and np.isfinite(tol) and tol > 0):
            raise InputError(f"tol must be a positive number, got {tol!r}")
        given = None
        if q is None:
            if x is None:
                raise InputError("jacobian needs the poses x or the actuator coordinates q")
            if self._is_actuator_array(x):
                warnings.warn("jacobian(q) of a joint-chain machine: pass the actuator values "
                              "as jacobian(q=q) (a positional argument is a pose, as for every "
                              "machine)", DeprecationWarning, stacklevel=4)
                q = x
            else:
                xb, single = _checked_batch(x, 6, "pose")
                q = self.ik(xb[0] if single else xb, strokes="ignore")
        elif x is not None:
            given = x
        return self._velocity(q, float(tol), given, start)

    def in_working_mode(self, jacobians: ChainJacobians, tol: float) -> np.ndarray:
        """``(N,)`` bool: the closure of each configuration of ``jacobians`` is regular (status
        OK: not singular within the ``tol`` its Jacobian was computed with) and keeps its home
        rank — no parallel singularity (the protocol's question; rod machines also check the
        sign of det A)."""
        return ((np.asarray(jacobians.status) == Status.OK)
                & (np.asarray(jacobians.closure_rank) == jacobians.expected_rank))

    def _is_actuator_array(self, x: Any) -> bool:
        """The former positional form: one array as wide as the actuator vector (when that is
        six wide, as wide as a pose, the former meaning is kept)."""
        shape = np.shape(x)
        return len(shape) in (1, 2) and shape[-1] == self.n_actuators

    def _refuse_misfit(self, x: Any, qb: np.ndarray, pose: np.ndarray, status: np.ndarray,
                       single: bool) -> None:
        """q must put the tool at the poses x given with it (tool point within 1e-9 m relative,
        axis within 1e-9): a single misfit raises, batched misfits get status INVALID_INPUT."""
        xb, _ = _checked_batch(x, 6, "pose") if single else as_batch(x, 6, "pose")
        if xb.shape[0] != qb.shape[0]:
            raise InputError(f"x has {xb.shape[0]} rows but q has {qb.shape[0]}")
        with np.errstate(invalid="ignore", divide="ignore"):
            axis = xb[:, 3:] / np.linalg.norm(xb[:, 3:], axis=1, keepdims=True)
            miss = np.maximum(np.abs(pose[:, :3] - xb[:, :3]).max(axis=1)
                              / (1.0 + np.abs(xb[:, :3]).max(axis=1)),
                              np.abs(pose[:, 3:] - axis).max(axis=1))
        off = miss > 1e-9
        if single and off[0]:
            raise InputError(f"q = {qb[0].tolist()} does not fit pose {xb[0].tolist()}: its tool "
                             f"point and axis miss it by {miss[0]:.3g}")
        status[off] = Status.INVALID_INPUT

    def jacobian_dot(self, x: Any, xd: Any, *, q: Any = None) -> None:
        """Refused: the time derivative of a joint-chain machine's velocity model is not
        computed (its closure's second derivatives are not implemented).

        Raises:
            UnsupportedOperationError: always.
        """
        raise UnsupportedOperationError(
            "jacobian_dot", self.id, self.family,
            "the time derivative of a joint-chain closure's velocity model (its second "
            "derivatives) is not implemented; difference jacobian(q=...) along the motion")

    def joint_motion(self, x: Any, xd: Any, xdd: Any, **options: Any) -> None:
        """Refused: actuator accelerations need :meth:`jacobian_dot`, not computed for a
        joint-chain machine.

        Raises:
            UnsupportedOperationError: always.
        """
        raise UnsupportedOperationError(
            "a joint trajectory along a tool path", self.id, self.family,
            "actuator accelerations need the time derivative of the closure's velocity model, "
            "which is not implemented for joint chains; follow the path pose by pose with ik")

    def fk_all(self, q: Any, **options: Any) -> None:
        """Refused: the assembly modes of a joint-chain machine are not enumerated.

        Raises:
            UnsupportedOperationError: always.
        """
        raise UnsupportedOperationError(
            "fk_all", self.id, self.family,
            "the assembly modes of a (hyperstatic) joint-chain closure are not enumerated; "
            "fk(q, start=...) reaches the mode nearest a start")

    def _velocity(self, q: Any, tol: float, x: Any = None, start: Any = None
                  ) -> ChainJacobians:
        """The velocity model at actuator coordinates ``q`` (see :meth:`jacobian`)."""
        qb, single = _checked_batch(q, self.n_actuators, "q")
        direct = self.fk(qb, start=start, full_output=True, strokes="ignore",
                         check_singular=False)
        n = qb.shape[0]
        values = self.full_values(np.nan_to_num(qb))
        values[:, self._passive] = np.nan_to_num(direct.passive)  # failed rows: NaN at the end
        rot = rotvec_to_matrix(np.nan_to_num(direct.platform[:, 3:])).transpose(1, 2, 0)
        p_x = np.nan_to_num(direct.platform[:, :3]).T
        length = self.model.characteristic_length
        loop_act = [i for i in self._actuated if self.model.loop_variables[i]]
        head_act = [i for i in self._actuated if not self.model.loop_variables[i]]
        cu, cq = self._closure_columns(values, direct.platform, loop_act, rot, p_x)
        closed = np.isfinite(direct.passive).all(axis=1)  # rows with an assembly
        du = np.full((n, cu.shape[2], len(loop_act)), np.nan)
        rank = np.zeros(n, dtype=int)
        expected = self.expected_rank()
        ratio = np.full(n, np.nan)
        if closed.any():
            du[closed], rank[closed], ratio[closed] = _closure_rates(
                cu[closed], cq[closed], tol, expected, single)
        tool = tool_frame(self.model, rot, p_x, values.T, twists=True)
        # platform increments → tool twist, then loop actuators through them
        plat = np.zeros((n, 6, 6))
        plat[:, :3, :3] = np.eye(3)
        plat[:, 3:, 3:] = np.eye(3)
        from pkmkit.spatial.rotation import skew

        plat[:, :3, 3:] = skew(p_x.T)
        twist_q = np.zeros((n, 6, self.n_actuators))
        order = {v: k for k, v in enumerate(self._actuated)}
        loop_twist = plat @ du[:, :6, :]
        for j, v in enumerate(loop_act):
            twist_q[:, :, order[v]] = loop_twist[:, :, j]
        for v in head_act:
            twist_q[:, :, order[v]] = tool.variable_twists[:, v].T
        # tool point velocity: v + ω × p_point
        point = direct.pose[:, :3]
        jac = twist_q.copy()
        jac[:, :3] += np.cross(twist_q[:, 3:].transpose(0, 2, 1), point[:, None, :]
                               ).transpose(0, 2, 1)
        scale = np.array([1, 1, 1, length, length, length], dtype=float)
        j_h = jac * scale[None, :, None]
        sv = small_singular_values(j_h)  # NaN rows where j_h is not finite
        with np.errstate(divide="ignore", invalid="ignore"):
            condition = sv[:, 0] / sv[:, -1]
        passive_rates = np.zeros((n, len(self._passive), self.n_actuators))
        for j, v in enumerate(loop_act):
            passive_rates[:, :, order[v]] = du[:, 6:, j]
        status = direct.status.copy()
        if x is not None:
            self._refuse_misfit(x, qb, direct.pose, status, single)
        status[((status == Status.OK) | (status == Status.INCONSISTENT)) & closed
               & (ratio < tol)] = Status.SINGULAR
        bad = (status != Status.OK) & (status != Status.INCONSISTENT)
        for arr in (jac, j_h, sv, condition, passive_rates):
            arr[bad] = np.nan
        if single and status[0] == Status.NO_ASSEMBLY:
            self.fk(qb[0], strokes="ignore")  # raises the ClosureMissError naming the leg
        if single and status[0] == Status.SINGULAR:
            raise SingularConfigurationError(
                f"q = {qb[0].tolist()}: singular closure (σ_min/σ_max of its Jacobian "
                f"{ratio[0]:.2g} < {tol:g}): the velocity model does not exist there")
        out = ChainJacobians(J=jac, J_homogeneous=j_h, singular_values=sv, condition=condition,
                             passive_rates=passive_rates, closure_rank=rank,
                             expected_rank=expected, q=qb, status=status)
        if single:
            return ChainJacobians(**{k: (v[0] if isinstance(v, np.ndarray) else v)
                                     for k, v in out.__dict__.items()})
        return out

    def _closure_columns(self, values: np.ndarray, platform: np.ndarray, loop_act: list,
                         rot: np.ndarray, p_x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(C_U (N, 6L, 6 + n_p), C_q (N, 6L, n_loop))``: the closure's Jacobian at
        ``values (N, n_var)`` and ``platform (N, 6)`` (``rot (3, 3, N)``, ``p_x (3, N)`` its
        rotation and position) for the platform and passive joints, and for the legs'
        actuators — compiled (:func:`pkmkit.solve.chain_rows.closure_jacobian`: C or Numba)
        in a batch the compiled solvers take, else :func:`pkmkit.solve.chains.closure`."""
        from pkmkit.solve.chain_rows import closure_jacobian

        n_u = 6 + len(self._passive)
        if len(values) > 1 and _compiled_velocity(len(values)):

            full = closure_jacobian(self.model, values, np.nan_to_num(platform),
                                    np.concatenate([self._passive, loop_act]).astype(int))
            return full[:, :, :n_u], full[:, :, n_u:]
        c = closure(self.model, rot, p_x, values.T)
        cu = np.concatenate([c.platform, c.variables[:, self._passive]], axis=1)
        return cu.transpose(2, 0, 1), c.variables[:, loop_act].transpose(2, 0, 1)

    def expected_rank(self) -> int:
        """The rank of the closure's Jacobian in the platform and passive joints at home (its
        singular values above ``RANK_RCOND`` × the largest): ``6 + n_p`` where the closure is
        regular there."""
        values = self._home["values"][:, None]
        rot = rotvec_to_matrix(self._home["platform"][3:]).transpose(1, 2, 0)
        c = closure(self.model, rot, self._home["platform"][:3, None], values)
        cu = np.concatenate([c.platform, c.variables[:, self._passive]], axis=1)[:, :, 0]
        sv = np.linalg.svd(cu, compute_uv=False)
        return int((sv > RANK_RCOND * sv[0]).sum())

    # ---------------------------------------------------------------- structure
    def hyperstatism(self) -> HyperstatismCount:
        """Bodies, joints, loops, mobility and degree of hyperstatism of the parallel part."""
        model = self.model
        loop_elements = {e for leg in model.legs for e in leg}
        joints = sorted(e for e in loop_elements if model.elements[e].type != FIXED)
        by_type = {"R": 0, "P": 0}
        for e in joints:
            by_type[model.elements[e].type] += 1
        last_joints = set()
        for leg in model.legs:
            movers = [e for e in leg if model.elements[e].type != FIXED]
            last_joints.add(movers[-1])
        bodies = 2 + len(joints) - len(last_joints)
        loops = len(joints) - bodies + 1
        freedoms = len(joints)
        values = self._home["values"][:, None]
        rot = rotvec_to_matrix(self._home["platform"][3:]).transpose(1, 2, 0)
        c = closure(model, rot, self._home["platform"][:3, None], values)
        loop_vars = np.flatnonzero(model.loop_variables)
        full = np.concatenate([c.platform, c.variables[:, loop_vars]], axis=1)[:, :, 0]
        sv = np.linalg.svd(full, compute_uv=False)
        rank = int((sv > RANK_RCOND * sv[0]).sum())
        mobility = full.shape[1] - rank
        return HyperstatismCount(
            bodies=bodies, joints=len(joints), joints_by_type=by_type, loops=loops,
            mobility=mobility, hyperstatism=6 * loops - freedoms + mobility,
            grubler_mobility=6 * (bodies - 1 - len(joints)) + freedoms,
            rank_hyperstatism=full.shape[0] - rank)


def _closure_rates(cu: np.ndarray, cq: np.ndarray, tol: float, expected: int, single: bool
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(−C_U⁺ C_q (N, c, k), rank of C_U (N,), σ_expected / σ_max (N,))`` of closure
    Jacobians ``cu (N, r, c)`` and ``cq (N, r, k)`` (pseudo-inverse and rank cutoff
    :data:`RANK_RCOND`). A batch the compiled solvers take, with a tall C_U, goes through
    :func:`pkmkit.solve.chain_rows.closure_rates` (a QR where the closure is certainly
    regular — ``ratio`` is then a lower bound above ``tol`` — else a one-sided Jacobi SVD;
    equal to LAPACK's pseudo-inverse to rounding; C or Numba); a single row (whose error
    message quotes the ratio) and the rest through LAPACK."""
    if not single and cu.shape[1] >= cu.shape[2] and _compiled_velocity(len(cu)):
        from pkmkit.solve.chain_rows import closure_rates

        return closure_rates(cu, cq, RANK_RCOND, tol, expected)
    pinv, sv = _pinv_and_singular_values(cu, RANK_RCOND)
    return (-pinv @ cq, (sv > RANK_RCOND * sv[:, :1]).sum(axis=1),
            sv[:, expected - 1] / sv[:, 0])


def _compiled_velocity(rows: int) -> bool:
    """Whether a batch of ``rows`` closure Jacobians goes through the compiled kernels: their
    C twins (:mod:`pkmkit.native`, no Numba import) at every size when built, else Numba
    where the compiled solvers run (:func:`pkmkit.numerics.jit.use_compiled_solver`)."""
    from pkmkit.numerics.jit import use_compiled_solver
    from pkmkit.solve.chain_rows import velocity_native
    from pkmkit.solve.chains import compiled_closure_available

    if velocity_native():
        return use_compiled_solver(rows, native=True)
    return use_compiled_solver(rows) and compiled_closure_available()


def _pinv_and_singular_values(a: np.ndarray, rcond: float) -> tuple[np.ndarray, np.ndarray]:
    """``np.linalg.pinv(a, rcond=rcond)`` of a stack ``a (N, r, c)`` (the same arithmetic, so
    the same bits) and the singular values ``(N, min(r, c))`` of its one SVD, which the rank
    and the singularity measure of a closure need too (a second SVD of the same matrices
    cost as much)."""
    u, s, vt = np.linalg.svd(a, full_matrices=False)
    cutoff = rcond * np.amax(s, axis=-1, keepdims=True)
    large = s > cutoff
    inverse = np.divide(1, s, where=large, out=s.copy())
    inverse[~large] = 0
    pinv = np.matmul(np.swapaxes(vt, -1, -2), np.multiply(inverse[..., None],
                                                        np.swapaxes(u, -1, -2)))
    return pinv, s
