"""The machine protocol's first-order defect model: every family linearises its own closure.

``machine.closure_linearisation(q)`` gives ``C_U dU + C_δ dδ = 0`` at actuator coordinates q
and ``machine.tool_sensitivity(q)`` the tool's motion per unit defect through it (the faces
:func:`pkmkit.geometric_errors.model.closure_linearisation` and
:func:`~pkmkit.geometric_errors.model.tool_sensitivity` delegate here, so the error analyses
never test the family):

- rod legs (:class:`TranslationalLinearisation`, :class:`FullPoseLinearisation`): residuals
  ``|p + R b − a(q)| − ℓ`` per rod of the defect level, unknowns the platform pose;
  ``dX = −A⁺ ∂r/∂δ`` (a solve for a translating platform, a pseudo-inverse for a turning one);
- joint chains (:class:`ChainLinearisation`): the legs' closures on the platform
  (:mod:`pkmkit.solve.chains`), unknowns the platform twist and the passive joints;
  ``dU = −C_U⁺ C_δ`` in least squares (a hyperstatic closure's incompatible defect directions
  leave a residual, ``closure_defect``, instead of a motion; notes §3.9, §4.5).

Rotation rows are the tool frame's small rotation vector (rad per SI unit of the defect); a
translating platform's are zero. Defects in SI, displacements in m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError


@dataclass(frozen=True)
class ToolSensitivity:
    """First-order effect of every defect on the tool at N configurations.

    Attributes:
        point: ``(N, 3, d)`` tool point displacement per unit defect (m per SI unit).
        rotation: ``(N, 3, d)`` tool frame rotation vector per unit defect (rad per SI unit).
        pose: ``(N, 6)`` the nominal tool pose (point and rotation vector, or axis for joint
            chains) at which it was taken.
        closure_defect: ``(N, r, d)`` or None — for a hyperstatic closure, the part of each
            defect's closure residual that no motion can absorb (the incompatible part,
            projected on the left null space), in m per unit.
    """

    point: np.ndarray
    rotation: np.ndarray
    pose: np.ndarray
    closure_defect: np.ndarray | None = None

    def stacked(self, rows: str = "point") -> np.ndarray:
        """``(N·r, d)`` rows of the point (``"point"``) or point and rotation (``"pose"``)."""
        if rows == "point":
            return self.point.reshape(-1, self.point.shape[2])
        return np.concatenate([self.point, self.rotation], axis=1).reshape(
            -1, self.point.shape[2])


@dataclass(frozen=True)
class ClosureLinearisation:
    """The closure of a machine linearised at N configurations: ``C_U dU + C_δ dδ = 0``.

    Attributes:
        unknowns: ``(N, r, u)`` ∂(closure residual)/∂(unknowns): the platform pose increments
            (translation, then rotation for full-pose and joint-chain machines) and, for joint
            chains, the passive joints; rows in m (rod residuals, chain translation rows, chain
            rotation rows × the characteristic length).
        defects: ``(N, r, d)`` ∂(closure residual)/∂(defects) (m per SI unit of the defect).
        pose: ``(N, 6)`` the nominal tool pose (see :class:`ToolSensitivity`).
    """

    unknowns: np.ndarray
    defects: np.ndarray
    pose: np.ndarray


def _checked_q(machine, q: Any) -> np.ndarray:
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.ndim != 2 or qb.shape[1] != machine.n_actuators:
        raise InputError(f"q must have {machine.n_actuators} components per row, got "
                         f"{qb.shape[-1]}")
    return qb


def _assembled_poses(machine, q: np.ndarray) -> np.ndarray:
    """The direct model's poses ``(N, dims)`` at q; an InputError naming the first row
    without an assembly."""
    x = np.atleast_2d(machine.fk(q))
    if not np.isfinite(x).all():
        bad = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
        raise InputError(f"configuration {bad}: the direct model has no assembly at q = "
                         f"{q[bad].tolist()}")
    return x


class _RodLinearisation:
    """What both rod-leg families share: the closure and the tool's motion through it."""

    def closure_linearisation(self, q: Any, *, tool_length: Any = None
                              ) -> ClosureLinearisation:
        """The closure linearised at actuator coordinates ``q`` ``(n,)`` or ``(N, n)``
        (module docstring; ``tool_length`` is a joint chain's and is ignored here).

        Raises:
            InputError: mis-shaped q, or configurations where the direct model fails.
        """
        _, unknowns, cols, pose = self._rod_linearisation(_checked_q(self, q))
        return ClosureLinearisation(unknowns, cols, pose)

    def tool_sensitivity(self, q: Any, *, tool_length: Any = None, start: Any = None,
                         **engine_options: Any) -> ToolSensitivity:
        """First-order effect of every defect on the tool at actuator coordinates ``q``
        ``(n,)`` or ``(N, n)`` (module docstring; ``tool_length``, ``start`` and
        ``engine_options`` tune a joint chain's closure and are ignored here: a rod machine's
        direct model is a closed form).

        Raises:
            InputError: mis-shaped q, or configurations where the direct model fails.
            UnsupportedOperationError: a ``start`` (there is no closure to start).
        """
        if start is not None:
            from pkmkit.exceptions import UnsupportedOperationError

            raise UnsupportedOperationError(
                "a direct-model start", self.id, self.family,
                "its direct model is a closed form: there is no closure to start")
        return self._rod_sensitivity(_checked_q(self, q))


class TranslationalLinearisation(_RodLinearisation):
    """The first-order defect model of rod legs on a translating platform."""

    def _rod_linearisation(self, q: np.ndarray):
        """(fk poses, ∂r/∂(platform) with unit rod rows, ∂r/∂δ, tool pose (N, 6))."""
        from pkmkit.model.defect_rule import defect_index
        from pkmkit.solve.rod_closure import defect_columns

        index = defect_index(self)
        x = _assembled_poses(self, q)
        n, dims = q.shape[0], self.dims
        position = np.zeros((n, 3))
        position[:, :dims] = x
        _, cols = defect_columns(self.model, index, position, None, q)
        a = self.jacobian(x, q=q).A  # rows p − c_i (N, n, dims)
        a_unit = a / np.linalg.norm(a, axis=2)[:, :, None]
        return x, a_unit, cols, np.concatenate([position, np.zeros((n, 3))], axis=1)

    def _rod_sensitivity(self, q: np.ndarray) -> ToolSensitivity:
        _, a_unit, cols, pose = self._rod_linearisation(q)
        n, d, dims = q.shape[0], cols.shape[2], self.dims
        motion = -np.linalg.solve(a_unit, cols)  # (N, dims, d)
        point = np.zeros((n, 3, d))
        point[:, :dims] = motion
        return ToolSensitivity(point=point, rotation=np.zeros((n, 3, d)), pose=pose)


class FullPoseLinearisation(_RodLinearisation):
    """The first-order defect model of rod legs on a turning (full-pose) platform."""

    def _rod_linearisation(self, q: np.ndarray):
        """(fk poses, ∂r/∂(platform) with unit rod rows, ∂r/∂δ, tool pose (N, 6))."""
        from pkmkit.machines.full_pose_forms import FullPoseForms
        from pkmkit.model.defect_rule import defect_index
        from pkmkit.solve.rod_closure import defect_columns
        from pkmkit.spatial.rotation import rotvec_to_matrix

        index = defect_index(self)
        x = _assembled_poses(self, q)
        rot = rotvec_to_matrix(x[:, 3:6])
        _, cols = defect_columns(self.model, index, x[:, :3], rot, q)
        a, _ = FullPoseForms(self.model).jacobians(x, q)
        a_unit = a / np.linalg.norm(a[:, :, :3], axis=2)[:, :, None]
        return x, a_unit, cols, x

    def _rod_sensitivity(self, q: np.ndarray) -> ToolSensitivity:
        x, a_unit, cols, _ = self._rod_linearisation(q)
        motion = -np.linalg.pinv(a_unit) @ cols  # (N, 6, d)
        return ToolSensitivity(point=motion[:, :3], rotation=motion[:, 3:], pose=x)


class ChainLinearisation:
    """The first-order defect model of joint chains (possibly hyperstatic)."""

    def closure_linearisation(self, q: Any, *, tool_length: Any = None
                              ) -> ClosureLinearisation:
        """The legs' closures linearised at actuator coordinates ``q`` ``(n,)`` or ``(N, n)``
        with the tool ``tool_length`` (m) along the tool axis (default the machine's).

        Raises:
            InputError: mis-shaped q, or configurations where the legs do not close.
        """
        lin = self._chain_closure(_checked_q(self, q), tool_length)
        return ClosureLinearisation(lin["cu"], lin["cd"], lin["direct"].pose)

    def tool_sensitivity(self, q: Any, *, tool_length: Any = None, start: Any = None,
                         **engine_options: Any) -> ToolSensitivity:
        """First-order effect of every defect on the tool at actuator coordinates ``q``
        ``(n,)`` or ``(N, n)`` (module docstring), with the tool ``tool_length`` (m); the
        closure solved from ``start`` (as :meth:`fk`'s, e.g. the solution of a previous call
        at the same q) with ``engine_options`` (:meth:`fk`'s, e.g. ``compiled=True``).

        Raises:
            InputError: mis-shaped q, or configurations where the legs do not close.
        """
        return self._chain_tool_sensitivity(_checked_q(self, q), tool_length, start=start,
                                            **engine_options)

    def _chain_closure(self, q: np.ndarray, tool_length: Any, columns=None, *,
                       start: Any = None, **engine_options: Any) -> dict:
        """The closure at ``q (N, n)``: ``{"direct", "cu", "cd", "values", "rot", "p_x"}``
        (and ``"tool_twists" (N, 6, d)`` from the compiled kernel with ``compiled=True``)
        (``columns``: a model with the machine's frames whose defect columns to use instead,
        :func:`pkmkit.solve.chains.with_column_twists`; ``start``, ``engine_options``: as
        :meth:`fk`'s)."""
        from pkmkit.solve import chain_rows  # C twins of the compiled kernels, else Numba
        from pkmkit.solve.chains import closure, compiled_closure_available
        from pkmkit.spatial.rotation import rotvec_to_matrix

        model = self.model
        direct = self.fk(q, tool_length=tool_length, full_output=True, start=start,
                         **engine_options)
        if not np.isfinite(direct.pose).all():
            bad = int(np.flatnonzero(~np.isfinite(direct.pose).all(axis=1))[0])
            raise InputError(f"configuration {bad}: the legs do not close at q = "
                             f"{q[bad].tolist()}")
        n = q.shape[0]
        values = np.tile(model.home, (n, 1))
        act = np.flatnonzero(model.actuated)
        passive = np.flatnonzero(~model.actuated & model.loop_variables)
        values[:, act] = q
        values[:, passive] = direct.passive
        p_x = direct.platform[:, :3].T
        source = columns if columns is not None else model
        rot = rotvec_to_matrix(direct.platform[:, 3:]).transpose(1, 2, 0)
        if engine_options.get("compiled") and (chain_rows.linearise_native()
                                               or compiled_closure_available()):
            cu, cd, _, _, tool = chain_rows.linearise(source, values, direct.platform,
                                                      passive)
            return {"direct": direct, "cu": cu, "cd": cd, "values": values, "rot": rot,
                    "p_x": p_x, "tool_twists": tool}
        c = closure(source, rot, p_x, values.T, defects=True)
        cu = np.concatenate([c.platform, c.variables[:, passive]], axis=1).transpose(2, 0, 1)
        cd = c.defects.transpose(2, 0, 1)
        return {"direct": direct, "cu": cu, "cd": cd, "values": values, "rot": rot, "p_x": p_x}

    def _chain_tool_sensitivity(self, q: np.ndarray, tool_length: Any, columns=None, *,
                                start: Any = None, **engine_options: Any) -> ToolSensitivity:
        """:meth:`tool_sensitivity` at ``q (N, n)``, of the defect columns of ``columns``
        (a model of :func:`pkmkit.solve.chains.with_column_twists`) when given."""
        from pkmkit.solve.chains import tool_frame
        from pkmkit.spatial.rotation import skew

        lin = self._chain_closure(q, tool_length, columns, start=start, **engine_options)
        direct, cu, cd = lin["direct"], lin["cu"], lin["cd"]
        rot, p_x, values = lin["rot"], lin["p_x"], lin["values"]
        n = q.shape[0]
        # dU = −C_U⁺ C_δ (N, 6 + n_p, d) and the part of C_δ no motion absorbs, (I − C_U C_U⁺) C_δ
        if "tool_twists" in lin:  # compiled: normal equations, the pseudo-inverse where singular
            from pkmkit.solve.chain_rows import absorb

            du, incompatible, ok = absorb(cu, cd)
        else:
            ok = np.zeros(n, dtype=bool)
            du, incompatible = np.empty((n, cu.shape[2], cd.shape[2])), np.empty_like(cd)
        if not ok.all():
            bad = np.flatnonzero(~ok)
            du[bad] = -np.linalg.pinv(cu[bad], rcond=1e-9) @ cd[bad]
            incompatible[bad] = cd[bad] + cu[bad] @ du[bad]
        tool_twists = lin.get("tool_twists")
        if tool_twists is None:
            tool_twists = tool_frame(columns if columns is not None else self.model, rot, p_x,
                                     values.T, defects=True).defect_twists.transpose(2, 0, 1)
        plat = np.zeros((n, 6, 6))
        plat[:, :3, :3] = np.eye(3)
        plat[:, 3:, 3:] = np.eye(3)
        plat[:, :3, 3:] = skew(p_x.T)
        twist = plat @ du[:, :6, :] + tool_twists
        point = direct.pose[:, :3]
        dp = twist[:, :3] + np.cross(twist[:, 3:].transpose(0, 2, 1), point[:, None, :]
                                     ).transpose(0, 2, 1)
        return ToolSensitivity(point=dp, rotation=twist[:, 3:], pose=direct.pose,
                               closure_defect=incompatible)
