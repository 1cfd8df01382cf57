"""Every real assembly mode of a full-pose machine at given actuator values (the six-rod homotopy,
certified complete), labelled by the sign of det A."""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import (
    InputError,
)
from pkmkit.machines.common import (
    _checked_batch,
    _valid_rows,
)
from pkmkit.machines.modes import ModeNaming
from pkmkit.machines.results import (
    PoseSolutions,
    Singularity,
)
from pkmkit.model.rods import STRUT
from pkmkit.status import Status


class FullPoseModes:
    """Mixin of :class:`~pkmkit.machines.full_pose.FullPoseMachine`: its assembly modes."""

    def in_working_mode(self, jacobians, tol: float) -> np.ndarray:
        """``(N,)`` bool: the configurations of a velocity model lie in the working assembly
        mode (sign of det A) at least ``tol`` from a parallel singularity — read from its
        parallel-singularity flag when it was classified at ``tol`` (the flag is the
        parallel measure below its tolerance; a batch computes that measure only where its
        lower bound does not clear it), else from ``parallel_measure``."""
        if float(jacobians.tolerance) != float(tol):
            return ModeNaming.in_working_mode(self, jacobians, tol)
        with np.errstate(invalid="ignore"):
            clear = (np.asarray(jacobians.singularity) & int(Singularity.PARALLEL)) == 0
            return (np.sign(jacobians.det_A) == self.working_mode) & clear

    def fk_all(self, q: Any, *, tol: float = 1e-10) -> PoseSolutions:
        """Every real assembly mode of actuator coordinates ``q`` (a six-rod machine): the
        all-solutions solver of :mod:`pkmkit.solve.six_rod_direct` (a certified parameter
        homotopy over the 40 complex solutions of a general 6-6 platform), with the base joints
        placed by the actuators (slides move them, cranks turn them).

        Args:
            q: ``(n,)`` or ``(N, n)`` actuator coordinates.
            tol: rod-length tolerance of the refined solutions (m, relative to the size).

        Returns:
            :class:`~pkmkit.machines.results.PoseSolutions` (single q: leading axis dropped).

        Raises:
            InputError: mis-shaped q, or a machine that does not have exactly six rods.
        """
        from pkmkit.solve.rod_closure import rod_base_points
        from pkmkit.solve.six_rod_direct import six_rod_direct_all

        if self.model.n_rods != 6:
            raise InputError(
                f"every assembly mode is computed for six-rod platforms; {self.id!r} has "
                f"{self.model.n_rods} rods (use fk with a guess for the others)")
        qb, single = _checked_batch(q, self.n_actuators, "q")
        finite = _valid_rows(qb)
        base = rod_base_points(self.model, np.nan_to_num(qb).T).transpose(2, 1, 0)
        lengths = self.model.rod_length[None] + np.where(
            self.model.rod_kind[None] == STRUT, np.nan_to_num(qb)[:, self.model.rod_actuator],
            0.0)
        base[~finite] = np.nan
        solutions = six_rod_direct_all(base, self.model.rod_platform, lengths, tol=tol)
        poses = np.atleast_3d(solutions.poses).reshape(qb.shape[0], -1, 6)
        count = np.atleast_1d(solutions.count)
        # the working mode: the solution the engine reaches from home's first-order guess
        working = np.full(qb.shape[0], -1)
        engine = self.fk(qb, full_output=True) if finite.any() else None
        if engine is not None:
            gap = np.linalg.norm(poses[:, :, :3] - engine.pose[:, None, :3], axis=2)
            with np.errstate(invalid="ignore"):
                near = np.nanargmin(np.where(np.isnan(gap), np.inf, gap), axis=1)
                close = np.take_along_axis(gap, near[:, None], 1)[:, 0] <= 1e-6 * (
                    1.0 + float(self.model.rod_length.max()))
            working[close] = near[close]
        sign = np.zeros(poses.shape[:2], dtype=int)
        valid = ~np.isnan(poses[..., 0])
        if valid.any():
            rows, cols = np.nonzero(valid)
            a, _ = self._forms.jacobians(poses[rows, cols], qb[rows])
            sign[rows, cols] = np.sign(np.linalg.det(a)).astype(int)
        status = np.atleast_1d(solutions.status).copy()
        status[~finite] = Status.INVALID_INPUT
        out = PoseSolutions(
            poses=poses, count=count, working=working, mode_sign=sign,
            residual=np.atleast_2d(solutions.residual).reshape(qb.shape[0], -1),
            condition=np.atleast_2d(solutions.condition).reshape(qb.shape[0], -1),
            multiplicity=np.atleast_2d(solutions.multiplicity).reshape(qb.shape[0], -1),
            n_finite=np.atleast_1d(solutions.n_finite), status=status)
        if single:
            return PoseSolutions(**{k: v[0] for k, v in out.__dict__.items()})
        return out
