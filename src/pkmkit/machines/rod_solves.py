"""The row solves behind :meth:`Machine.ik <pkmkit.machines.machine.Machine.ik>` and
:meth:`Machine.fk <pkmkit.machines.machine.Machine.fk>` of rod-leg machines: the closed forms
and the numeric engine over every rod, each giving per-row values and statuses that the
methods then judge (strokes, single-pose errors) and package.

Conventions: SI (m, rad); ``xb (N, dims)`` poses, ``qb (N, n)`` actuator coordinates; rows
that fail are NaN with their :class:`~pkmkit.status.Status`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import ConvergenceError, InputError
from pkmkit.machines.common import TURNED_TOL, _rows_like, _valid_rows
from pkmkit.numerics.linalg import batched_det
from pkmkit.solve.rod_closure import solve_direct, solve_inverse
from pkmkit.status import Status


class RodSolveRows:
    """Per-row inverse and direct solves of a rod-leg machine (mixed into ``Machine``)."""

    def _inverse_rows(self, xb: np.ndarray, br: np.ndarray, method: str, q0: Any,
                      engine_options: dict, out: np.ndarray | None = None
                      ) -> tuple[np.ndarray, np.ndarray, Any, Any]:
        """``(q (N, n), status (N,), iterations, residual)`` of ``method`` on branches
        ``br``; iterations and residual are None for the closed form, whose compiled kernel
        writes q into a caller's ``out`` (``ik(X, out=Q)``)."""
        if method == "closed":
            return (*self._inverse_closed_rows(xb, br, out), None, None)
        if method == "numeric":
            return self._inverse_numeric_rows(xb, br, q0, engine_options)
        raise InputError(f"unknown method {method!r}; use 'closed' or 'numeric'")

    def _inverse_closed_rows(self, xb: np.ndarray, br: np.ndarray,
                             out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The closed-form inverse: unreachable rows and non-finite input flagged, poses
        beyond MAX_COORDINATE refused (a vertical slide follows any height)."""
        return self._closed_rows(xb, *self._closed.inverse_counted(xb, br, out))

    def _inverse_closed_full(self, xb: np.ndarray, br: np.ndarray, out: np.ndarray | None = None
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(q, status, shortfall (N, n), mode (N,))`` of the closed form in one pass
        (:meth:`RodClosedForm.inverse_full`; the machine's closed form must ``fuse``): the
        mode is the sign of det A on rows with a finite q, else 0."""
        q, n_bad, shortfall, det_a = self._closed.inverse_full(xb, br, out)
        q, status = self._closed_rows(xb, q, n_bad)
        # the rows not OK are exactly those whose q is not finite (NaN now): mode 0
        mode = np.where(status == Status.OK, np.sign(det_a), 0.0).astype(int)
        return q, status, shortfall, mode

    def _closed_rows(self, xb: np.ndarray, q: np.ndarray,
                     n_bad: int) -> tuple[np.ndarray, np.ndarray]:
        """Statuses of the closed form's ``q`` (``n_bad`` non-finite coordinates); failed and
        refused rows set to NaN."""
        status = np.zeros(xb.shape[0], dtype=int)
        if n_bad:  # rows with NaN (unreachable) or non-finite input
            bad = np.flatnonzero(~np.isfinite(q).all(axis=1))
            status[bad] = np.where(_valid_rows(xb[bad]), Status.UNREACHABLE,
                                   Status.INVALID_INPUT)
            q[bad] = np.nan
        huge = ~_valid_rows(xb)  # finite q of a pose beyond MAX_COORDINATE: refused as the
        if huge.any():           # single call does
            status[huge] = Status.INVALID_INPUT
            q[huge] = np.nan
        return q, status

    def _inverse_numeric_rows(self, xb: np.ndarray, br: np.ndarray, q0: Any,
                              engine_options: dict) -> tuple[np.ndarray, np.ndarray, Any, Any]:
        """Least squares over every rod from ``q0`` (default: the branch guess); rows that
        reached other branches are WRONG_MODE."""
        if q0 is None:
            guess = self._branch_guess_q(xb, br)
        else:
            guess = _rows_like(q0, self.n_actuators, "q0", xb.shape[0])
        guess[~_valid_rows(xb)] = np.nan  # the engine skips (and flags) these rows
        engine_options.setdefault("compute_rank", False)
        result = solve_inverse(self.model, xb, guess, **engine_options)
        q, status = result.u, result.status.copy()
        status[status == Status.INCONSISTENT] = Status.UNREACHABLE
        ok = status == Status.OK
        wrong = ok.copy()
        wrong[ok] = (self._closed.branch_signs(xb[ok], q[ok]) != br).any(axis=1)
        status[wrong] = Status.WRONG_MODE
        q = np.where((status == Status.OK)[:, None], q, np.nan)
        status[~_valid_rows(xb)] = Status.INVALID_INPUT
        return q, status, result.iterations, result.residual

    def _direct_rows(self, qb: np.ndarray, sign: int, method: str, x0: Any, dof: str,
                     single: bool, engine_options: dict) -> tuple:
        """``(pose (N, dims), status (N,), rotation, iterations, residual)`` of ``method`` in
        the mode of det A sign ``sign``; the last three are None for the closed form."""
        if method == "closed":
            return (*self._direct_closed_rows(qb, sign), None, None, None)
        if method == "numeric":
            return self._direct_numeric_rows(qb, sign, x0, dof, single, engine_options)
        raise InputError(f"unknown method {method!r}; use 'closed' or 'numeric'")

    def _direct_closed_rows(self, qb: np.ndarray, sign: int) -> tuple[np.ndarray, np.ndarray]:
        """The sphere intersection in the requested mode; rows without a real solution are
        NO_ASSEMBLY, aligned centres SINGULAR."""
        poses, degenerate = self._closed.direct_all(qb)
        pose = poses[:, 0 if sign < 0 else 1]
        # a NaN row sum flags rows without a real solution (or with non-finite input)
        with np.errstate(invalid="ignore", over="ignore"):
            row_sum = sum(pose[:, d] for d in range(self.dims))
        status = np.where(np.isfinite(row_sum), Status.OK, Status.NO_ASSEMBLY)
        status[degenerate] = Status.SINGULAR
        return pose, status

    def _direct_numeric_rows(self, qb: np.ndarray, sign: int, x0: Any, dof: str, single: bool,
                             engine_options: dict) -> tuple:
        """Least squares over every rod from ``x0`` (default: the mode's guess); with
        ``dof="full"`` the platform rotation is solved too and a turned platform is
        WRONG_MODE (a single one raises :class:`ConvergenceError`)."""
        if dof not in ("translation", "full"):
            raise InputError(f"dof must be 'translation' or 'full', got {dof!r}")
        if x0 is None:
            guess = self._mode_guess_pose(qb, sign)
        else:
            guess = _rows_like(x0, self.dims, "x0", qb.shape[0])
        guess[~_valid_rows(qb)] = np.nan  # the engine skips (and flags) these rows
        if dof == "full":
            extra = 3 if self.dims == 3 else 1
            guess = np.concatenate([guess, np.zeros((qb.shape[0], extra))], axis=1)
        engine_options.setdefault("compute_rank", False)
        with np.errstate(invalid="ignore", over="ignore"):
            result = solve_direct(self.model, qb, np.array(guess), dof=dof, **engine_options)
        pose = result.u[:, : self.dims].copy()
        status = result.status.copy()
        status[status == Status.INCONSISTENT] = Status.NO_ASSEMBLY
        rotation = None
        if dof == "full":
            rotation = self._turned_rows(result.u, status, single)
        ok = status == Status.OK
        a, _ = self._closed.jacobians(pose[ok], qb[ok])
        wrong = ok.copy()
        wrong[ok] = np.sign(batched_det(a)) != sign
        status[wrong] = Status.WRONG_MODE
        return pose, status, rotation, result.iterations, result.residual

    def _turned_rows(self, u: np.ndarray, status: np.ndarray, single: bool) -> np.ndarray:
        """The platform rotation ``(N, 3)`` of a ``dof="full"`` solve; rows where the rods
        closed with the platform turned (not a mode of this translating platform: the engine
        went there from a poor start) become WRONG_MODE in ``status``."""
        rotation = np.zeros((u.shape[0], 3))
        if self.dims == 3:
            rotation[:] = u[:, 3:6]
        else:
            rotation[:, 2] = u[:, 2]
        with np.errstate(invalid="ignore"):
            turned = np.linalg.norm(rotation, axis=1) > TURNED_TOL
        status[turned & (status == Status.OK)] = Status.WRONG_MODE
        if single and turned[0] and status[0] == Status.WRONG_MODE:
            raise ConvergenceError(
                f"the numeric direct model (dof='full') closed the rods with the platform "
                f"turned by {np.linalg.norm(rotation[0]):.3g} rad: not an assembly mode of "
                "this translating platform; pass x0 closer to the wanted solution")
        return rotation
