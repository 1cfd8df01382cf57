"""The inverse model of a full-pose machine commanded by its position alone (fewer than six
actuators, the orientation imposed by the rods: the Verne-type module): a mixin of
:class:`~pkmkit.machines.full_pose.FullPoseMachine`."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from pkmkit.exceptions import ConvergenceError, InputError, UnreachablePoseError
from pkmkit.machines.common import (
    MAX_COORDINATE,
    _checked_batch,
    _restore,
    _rows_like,
    _valid_rows,
)
from pkmkit.machines.full_pose_direct import usable
from pkmkit.machines.full_pose_inverse_record import lazy_inverse_record
from pkmkit.machines.position_start import start_table
from pkmkit.machines.results import InverseResult
from pkmkit.machines.slide_columns import SlideColumns, slide_columns
from pkmkit.machines.strokes import judge_rows
from pkmkit.model.rods import SLIDE
from pkmkit.numerics.arrays import restore_shape
from pkmkit.solve.least_squares import SolveResult
from pkmkit.solve.rod_closure import solve_position_inverse
from pkmkit.status import Status

#: Iteration limit of the position inverse (fewer actuators than six) from its first-order
#: guess; rows still short of a solution after it are NOT_CONVERGED.
POSITION_MAX_ITER = 30
#: Earlier limit of the same solve for rows nowhere near a solution: a row whose largest rod
#: residual after ``POSITION_CRAWL[0]`` iterations is above ``POSITION_CRAWL[1]`` × (1 + the
#: longest rod) is NOT_CONVERGED then (the engine's ``crawl``). From the first-order guess the
#: Verne module's reachable positions converge in ≤ 8 iterations (198,189 positions of its
#: workspace study's grid); the rows that ran to POSITION_MAX_ITER were 57 % of the solve's
#: row-iterations there (issue 22 §3).
POSITION_CRAWL = (12, 1e-6)
#: The share of a batch's rows its shared lines along a common slide axis must spare for
#: ``ik`` to solve one row per line (a grid: most rows; a table of rounded random positions:
#: 54 of 10⁶, whose gathers cost more than their solves, issue 22 §5).
LINE_SHARE = 1.0 / 16.0


def _stroke_fields(check) -> dict[str, Any]:
    """``out_of_stroke`` and ``stroke_excess`` of a result from a stroke check (or None)."""
    if check is None:
        return {"out_of_stroke": None, "stroke_excess": None}
    return {"out_of_stroke": check.out_of_stroke, "stroke_excess": check.excess}


class PositionInverse:
    """``ik`` of positions ``(N, 3)`` for a full-pose machine whose rods impose the
    orientation (its ``_ik_position``), and the positions no orientation can serve."""

    def _ik_position(self, arr, q0, branches, full_output, engine_options, strokes="flag"):
        pb, single = _checked_batch(arr, 3, "position")
        engine_options.setdefault("compute_rank", False)
        if q0 is None and "max_iter" not in engine_options:
            # from the first-order guess a reachable position converges in ≤ 11 iterations
            # (10⁵ random positions of the Verne module); the rows still crawling after
            # POSITION_MAX_ITER, or still far from closing after POSITION_CRAWL[0], are beyond
            # reach (a caller's own max_iter keeps its every iteration)
            engine_options["max_iter"] = POSITION_MAX_ITER
            engine_options.setdefault("crawl", (POSITION_CRAWL[0], POSITION_CRAWL[1] * (
                1.0 + float(self.model.rod_length.max()))))
        compiled = q0 is None and self._compiled_positions(engine_options, pb.shape[0])
        # one solve per line along a common slide axis (from the first-order start, which
        # moves with the line): the other rows of the line follow by a shift
        columns = slide_columns(self.model, pb) if q0 is None else None
        if columns is not None and columns.rows.size > (1.0 - LINE_SHARE) * pb.shape[0]:
            columns = None  # a table's few shared lines: gathering every row costs more
        if columns is None:
            q, pose, status, iterations, residual = self._position_rows(
                pb, q0, branches, engine_options, compiled)
        else:
            q, pose, status, iterations, residual = (
                a[columns.of] for a in self._position_rows(pb[columns.rows], None, branches,
                                                           engine_options, compiled))
            q += columns.shift[:, None]
            pose[:, :3] = np.where(np.isnan(pose[:, :1]), np.nan, pb)
        bad = status != Status.OK
        if single and bad[0]:
            if status[0] == Status.INVALID_INPUT:
                raise InputError(f"position {pb[0].tolist()} has a coordinate beyond "
                                 f"{MAX_COORDINATE:g} m")
            if status[0] == Status.WRONG_MODE:
                raise ConvergenceError(
                    "the inverse model converged to another branch or assembly mode than the "
                    "working one; pass q0 closer to the wanted solution")
            raise UnreachablePoseError(-1, "the rods", float(residual[0]), detail=(
                f"the rods cannot close at position {pb[0].tolist()} (least-squares residual "
                f"{float(residual[0]):.6g} m)"))
        check = judge_rows(self, q, status, strokes, single, f"position {pb[0].tolist()}",
                           full_output, stacklevel=4)
        bad = status != Status.OK
        q[bad] = np.nan
        pose[bad] = np.nan
        if not full_output:
            return restore_shape(q, single)
        sigma = self._branches(branches)
        fields = dict(q=q, status=status, branches=sigma,
                      method="numeric", iterations=iterations, residual=residual, pose=pose,
                      **_stroke_fields(check))
        if not single:  # the mode (det A per row) and the shortfalls computed when read
            return lazy_inverse_record(self._forms, self.model.n_rods, pose, finite_only=True,
                                       **fields)
        shortfall = np.full((pb.shape[0], self.model.n_rods), np.nan)
        shortfall[~bad] = self._forms.shortfall(pose[~bad])  # at the orientation found
        out = InverseResult(mode=self._mode_of(pose, q), shortfall=shortfall, **fields)
        return _restore(out, single, ("q", "status", "shortfall", "mode", "iterations",
                                      "residual", "pose", "out_of_stroke", "stroke_excess"))

    def translation_lines(self, points: np.ndarray) -> SlideColumns | None:
        """The lines along the common slide axis through positions ``points (N, 3)`` whose
        rows ``ik`` solves once (:func:`slide_columns`); None for poses ``(N, 6)`` or a
        machine commanded by its whole pose or without a common slide axis."""
        points = np.asarray(points, dtype=float)
        if not self.position_controlled or points.ndim != 2 or points.shape[1] != 3:
            return None
        return slide_columns(self.model, points)

    def _position_rows(self, pb, q0, branches, engine_options, compiled):
        """``(q (N, n), pose (N, 6), status (N,), iterations (N,), residual (N,))`` of positions
        ``pb (N, 3)``: the engine's solve (compiled when ``compiled``; with ``q0`` given, by
        the batch's size), the rows found on another branch or mode WRONG_MODE, the hopeless
        ones UNREACHABLE, the invalid ones INVALID_INPUT, NaN in q and pose wherever the
        status is not OK."""
        n = self.n_actuators
        valid = _valid_rows(pb)
        if compiled:
            result, paired, hopeless = self._compiled_rows(pb, valid, engine_options,
                                                           branches is None)
        else:
            paired = np.zeros(pb.shape[0], dtype=bool)
            hopeless = self._surely_unreachable(pb)
            skip = ~valid | hopeless
            if q0 is None:
                # first order from home: the position rows of J(home) are square (n = 3)
                # (a row that is not finite or beyond MAX_COORDINATE enters as home: LAPACK
                # scales the right-hand sides together, so one inf row would make every guess
                # NaN)
                j_t = self._home_jacobian[:3]
                offset = np.where(valid[:, None], pb - self._home_pose[:3], 0.0)
                dq = np.linalg.lstsq(j_t, offset.T, rcond=None)[0].T
                guess_q = self._home_q + dq
            else:
                guess_q = _rows_like(q0, n, "q0", pb.shape[0])
            guess_pose = self.first_order_pose(guess_q)
            u0 = np.concatenate([guess_q, guess_pose[:, 3:]], axis=1)
            u0[skip] = np.nan
            result = self._solve_positions(pb, u0, engine_options,
                                           compiled=None if q0 is not None else False)
        q = result.u[:, :n].copy()
        pose = np.concatenate([pb, result.u[:, n:]], axis=1)
        status = result.status.copy()
        status[status == Status.INCONSISTENT] = Status.UNREACHABLE
        ok = (status == Status.OK) & ~paired  # the paired solve's q are the rods' own values
        if branches is not None or ok.any():
            # the engine may land on another branch or assembly mode: say so
            sigma = self._branches(branches)
            expected = np.full(pb.shape[0], False)
            with np.errstate(invalid="ignore", over="ignore"):
                q_rod = self._forms.rod_coordinates(pose[ok], sigma)
                back, _ = self._forms.combine(q_rod)
            expected[ok] = np.abs(back - q[ok]).max(axis=1) <= 1e-7
            status[ok & ~expected] = Status.WRONG_MODE
        status[hopeless] = Status.UNREACHABLE
        status[~valid] = Status.INVALID_INPUT
        bad = status != Status.OK
        q[bad] = np.nan
        pose[bad] = np.nan
        return q, pose, status, result.iterations, result.residual

    def _compiled_rows(self, pb: np.ndarray, valid: np.ndarray, engine_options: dict[str, Any],
                       working: bool) -> tuple[SolveResult, np.ndarray, np.ndarray]:
        """The compiled position inverse of ``pb (N, 3)`` from the first-order start, with
        ``valid`` (N,) its finite rows within MAX_COORDINATE: ``(result, paired (N,), hopeless
        (N,))``. On the working branches (``working``) of a machine with two slide rods per
        actuator (:meth:`_paired_geometry`) a first pass solves every valid row by the paired
        Newton solve (``paired``: the rows it answered, OK on the working branches by
        construction); the rows it leaves — and every row otherwise — are checked by
        :meth:`_surely_unreachable` (``hopeless``: not solved) and the others solved by the
        Levenberg–Marquardt solve as before (a row the paired solve answers closes every rod,
        so it is never hopeless: the check is spared there)."""
        geom = self._paired_geometry() if working else None
        paired = np.zeros(pb.shape[0], dtype=bool)
        if geom is None:
            hopeless = self._surely_unreachable(pb)
            return (self._solve_positions(pb, None, engine_options, ~valid | hopeless,
                                          compiled=True), paired, hopeless)
        result = self._solve_positions(pb, None, engine_options, ~valid, compiled=True,
                                       geom=geom)
        paired[:] = result.rank == 1
        rest = np.flatnonzero(valid & ~paired)
        hopeless = np.zeros(pb.shape[0], dtype=bool)
        hopeless[rest] = self._surely_unreachable(pb[rest])
        rest = rest[~hopeless[rest]]
        if rest.size:
            more = self._solve_positions(pb[rest], None, engine_options, compiled=True)
            for name in ("u", "status", "iterations", "residual"):
                getattr(result, name)[rest] = getattr(more, name)
        result.rank[:] = -1
        return result, paired, hopeless

    def _compiled_positions(self, engine_options: dict[str, Any], rows: int) -> bool:
        """Whether the compiled position inverse serves ``rows`` rows with these options
        (three actuators, the engine's own options: :func:`full_pose_direct.usable`; at every
        size when the C twin of :mod:`pkmkit.native` is built, as the direct solve)."""
        plain = {k: v for k, v in engine_options.items() if k != "crawl"}
        return self.n_actuators == 3 and usable(plain, rows, native=True)

    def _solve_positions(self, pb: np.ndarray, u0: np.ndarray | None,
                         engine_options: dict[str, Any],
                         skip: np.ndarray | None = None, *,
                         compiled: bool | None = None,
                         geom: np.ndarray | None = None) -> SolveResult:
        """The engine's position inverse of ``pb (N, 3)`` from ``u0 (N, n + 3)`` (None: the
        first-order start from home, computed in the kernel; ``skip`` rows not solved):
        compiled per row (:mod:`pkmkit.machines.full_pose_position_kernel`, the engine's rules,
        ≈ 10× faster) for three actuators with the engine's own options, else the batched
        NumPy engine (``compiled``: the choice made for the caller's whole batch, None: by
        ``pb``'s size). With ``geom`` (:meth:`_paired_geometry`), compiled from the
        first-order start: the kernel's paired Newton solve alone, ``rank`` 1 on the rows it
        answered (OK), −1 on the others (left INVALID_INPUT, NaN)."""
        if compiled is None:
            compiled = self._compiled_positions(engine_options, pb.shape[0])
        if compiled:
            from pkmkit.machines import full_pose_position_solve as kernel  # C or Numba

            data = self.direct_kernel()
            jt_inv = self.__dict__.get("_position_jt_inv")
            if jt_inv is None:
                jt_inv = np.linalg.inv(self._home_jacobian[:3])
                object.__setattr__(self, "_position_jt_inv", jt_inv)
            crawl = engine_options.get("crawl") or (0, np.inf)
            opts = np.concatenate([data.options(engine_options), [crawl[0], crawl[1]]])
            if geom is None:
                u, status, iterations, residual = kernel.solve(
                    data.geom, pb, u0, opts, skip=skip, home=data.home, jt_inv=jt_inv)
                rank = np.full(pb.shape[0], -1)
            else:
                paired = np.append(opts, 1.0)
                table = self._position_start(kernel, geom, paired, data.home, jt_inv)
                u, status, iterations, residual, answered = kernel.solve(
                    geom, pb, None, paired if table is None else np.append(paired, table),
                    skip=skip, home=data.home, jt_inv=jt_inv, paired=True)
                rank = np.where(answered, 1, -1)
            return SolveResult(u=u, status=status, residual=residual, iterations=iterations,
                               rank=rank)
        with np.errstate(invalid="ignore", over="ignore"):
            return solve_position_inverse(self.model, pb, u0, **engine_options)

    def _paired_geometry(self) -> np.ndarray | None:
        """The direct kernel's geometry with each rod's working branch in column 15 when every
        actuator carries two slide rods (the Verne-type module): the position inverse's kernel
        then solves for the rotation alone, two rods of an actuator giving the same coordinate
        (``solve_paired``); None otherwise, or with ``PKMKIT_POSITION_PAIRED=0`` (the
        Levenberg–Marquardt solve on every row: the bench's baseline)."""
        if os.environ.get("PKMKIT_POSITION_PAIRED", "").strip() == "0":
            return None
        geom = self.__dict__.get("_position_paired_geom", False)
        if geom is False:
            m = self.model
            counts = np.bincount(m.rod_actuator, minlength=m.n_actuators)
            geom = None
            if m.n_actuators == 3 and (m.rod_kind == SLIDE).all() and (counts == 2).all():
                geom = self.direct_kernel().geom.copy()
                geom[:, 15] = self._forms.rod_branch
            object.__setattr__(self, "_position_paired_geom", geom)
        return geom

    def _position_start(self, kernel, geom: np.ndarray, opts: np.ndarray, home: np.ndarray,
                        jt_inv: np.ndarray) -> np.ndarray | None:
        """The paired solve's start table (:mod:`pkmkit.machines.position_start`), built once
        per machine by the paired solve itself from the first-order start (``kernel``, its
        ``geom``, ``opts (10,)``, ``home``, ``jt_inv``); None without a common slide axis or
        with ``PKMKIT_POSITION_TABLE=0`` (the first-order start on every row)."""
        if os.environ.get("PKMKIT_POSITION_TABLE", "").strip() == "0":
            return None
        table = self.__dict__.get("_position_start_table", False)
        if table is False:
            def solve(points):
                u, *_, answered = kernel.solve(geom, points, None, opts, home=home,
                                               jt_inv=jt_inv, paired=True)
                return u[:, 3:], answered

            table = start_table(self.model, np.asarray(self._home_pose[:3], dtype=float), solve)
            object.__setattr__(self, "_position_start_table", table)
        return table

    def _surely_unreachable(self, positions: np.ndarray) -> np.ndarray:
        """``(N,)`` positions no orientation can serve: a slide rod whose platform joint, at most
        ``|b|`` from the platform point whatever the rotation, stays farther than the rod's
        length from its slide's line (``dist(p, line) − |b| > L``). A sufficient test only: it
        spares the iterative solve the hopeless rows of a workspace grid."""
        m = self.model
        slides = np.flatnonzero(m.rod_kind == SLIDE)
        out = np.zeros(positions.shape[0], dtype=bool)
        if slides.size == 0:
            return out
        with np.errstate(invalid="ignore", over="ignore"):  # rows beyond 1e154: invalid
            rel = positions[:, None, :] - m.rod_base[slides][None]
            along = np.einsum("nsk,sk->ns", rel, m.rod_axis[slides])
            perp = rel - along[..., None] * m.rod_axis[slides][None]
            dist = np.linalg.norm(perp, axis=2)
            reach = np.linalg.norm(m.rod_platform[slides], axis=1) + m.rod_length[slides]
            out = (dist > reach[None] * (1 + 1e-9)).any(axis=1)
        return out & _valid_rows(positions)
