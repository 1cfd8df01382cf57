"""Workspace criteria (reachability, strokes, transmission-factor bounds, conditioning, assembly
mode, stiffness) and their evaluation at poses or on a grid, in chunks, for any machine family.

The stiffness criterion (``min_stiffness`` on the smallest translational stiffness, N/m, and
``max_deflection`` on the deflection under ``wrench``, m; :mod:`pkmkit.stiffness.indices`) adds
the mask ``"stiffness"`` only when one of them is given."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.analysis.continuation import inverse_of_chunk
from pkmkit.analysis.evaluation import PoseEvaluation
from pkmkit.analysis.grids import Grid
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import SINGULARITY_TOL, Machine
from pkmkit.machines.strokes import signed_excess, stroke_limits
from pkmkit.numerics.arrays import real, real_pair
from pkmkit.parallel import map_chunks
from pkmkit.progress import tracked
from pkmkit.status import Status
from pkmkit.stiffness.indices import stiffness_figures

MASK_NAMES = ("reachable", "strokes", "bounds", "condition", "mode")
#: The mask of the stiffness criterion (present only when :attr:`Criteria.stiffness_bounded`).
STIFFNESS_MASK = "stiffness"


#: Relative tolerance of the transmission-factor bounds (rounding at a bound is not a failure).
FACTOR_RTOL = 1e-9


@dataclass(frozen=True)
class Criteria:
    """What makes a pose (or an actuator vector) usable.

    Attributes:
        bounds: ``(lo, hi)`` bounds on every velocity transmission factor, or None.
        kappa_max: largest admissible condition number, or None.
        strokes: enforce the actuator strokes.
        q_limits: ``(q_lo (n,), q_hi (n,))`` replacing the machine's strokes, or None.
        connected: keep only the part connected to the home pose (no parallel singularity
            crossed).
        tol: singularity threshold.
        rtol: relative tolerance of the bounds (rounding at a bound is not a failure).
        min_stiffness: smallest admissible translational stiffness (N/m), or None.
        max_deflection: largest admissible deflection of the reference point under
            ``wrench`` (m), or None.
        wrench: ``(d,)`` load at the reference point (N, N·m) for ``max_deflection`` (and the
            deflection figures), or None.
        stiffness_data: the elastic data (:class:`~pkmkit.stiffness.data.StiffnessData`;
            None: the machine's own).
        continuation: solve a grid's inverse model slab by slab from the neighbouring slab's
            solution where the machine's inverse continues (joint chains:
            :mod:`pkmkit.analysis.continuation`; about half the iterations). The head's
            branch is stated and a row whose continued closure leaves the legs' home assembly
            modes is solved again from home (:mod:`pkmkit.machines.warm_starts`), so the
            grids give the start from home's answer wherever it is in home's modes
            (tests/analysis/test_continuation_modes.py); False: every point from home.
        whole_grid: evaluate every point of a grid. By default, when only the part connected
            to home is kept (``connected``) and the machine's inverse is numerical and
            continues from a neighbour's solution (``machine.inverse_continues``: joint
            chains), a grid is evaluated by a flood fill from home
            (:mod:`pkmkit.analysis.flood`): the same kept part, the points outside it and
            not next to it left unevaluated (:attr:`WorkspaceMap.evaluated
            <pkmkit.analysis.workspace.WorkspaceMap>`); True: every criterion's map over
            the whole grid.
    """

    bounds: tuple[float, float] | None = None
    kappa_max: float | None = None
    strokes: bool = True
    q_limits: tuple[np.ndarray, np.ndarray] | None = None
    connected: bool = True
    tol: float = SINGULARITY_TOL
    rtol: float = FACTOR_RTOL
    min_stiffness: float | None = None
    max_deflection: float | None = None
    wrench: tuple[float, ...] | None = None
    stiffness_data: Any = None
    continuation: bool = True
    whole_grid: bool = False

    def __post_init__(self) -> None:
        for name in ("min_stiffness", "max_deflection"):
            value = getattr(self, name)
            if value is not None and not real(value, name) > 0:
                raise InputError(f"{name} must be a finite number > 0 (SI), got {value}")
        if self.max_deflection is not None and self.wrench is None:
            raise InputError("max_deflection needs the wrench that causes the deflection")
        if self.wrench is not None:
            w = np.asarray(self.wrench, dtype=float).reshape(-1)
            if w.size not in (2, 3, 6) or not np.isfinite(w).all():
                raise InputError(f"the wrench must be 2, 3 or 6 finite numbers (N, N·m), got "
                                 f"{self.wrench!r}")
            object.__setattr__(self, "wrench", tuple(float(v) for v in w))
        if self.bounds is not None:
            lo, hi = real_pair(self.bounds, "the transmission-factor bounds")
            if not 0 < lo < hi:
                raise InputError(
                    f"transmission-factor bounds must satisfy 0 < lo < hi, got {self.bounds}"
                )
        if self.kappa_max is not None and not real(self.kappa_max, "kappa_max") >= 1:
            raise InputError(f"kappa_max must be >= 1, got {self.kappa_max}")

    def within_bounds(self, factors: np.ndarray) -> np.ndarray:
        """Rows of transmission factors ``(M, n)`` (largest first) within the bounds, up to a
        relative ``rtol`` (a design sized to touch a bound must pass): ``(M,)``."""
        lo, hi = self.bounds
        with np.errstate(invalid="ignore"):
            return ((factors[:, -1] >= lo * (1 - self.rtol))
                    & (factors[:, 0] <= hi * (1 + self.rtol)))

    @property
    def stiffness_bounded(self) -> bool:
        """A stiffness criterion is asked (``min_stiffness`` or ``max_deflection``)."""
        return self.min_stiffness is not None or self.max_deflection is not None

    def stiffness_ok(self, smallest: np.ndarray, deflection: np.ndarray | None) -> np.ndarray:
        """``(M,)`` the stiffness criterion holds (NaN figures fail), the bounds up to the
        relative ``rtol``."""
        ok = np.ones(len(smallest), dtype=bool)
        with np.errstate(invalid="ignore"):
            if self.min_stiffness is not None:
                ok &= smallest >= self.min_stiffness * (1 - self.rtol)
            if self.max_deflection is not None:
                ok &= deflection <= self.max_deflection * (1 + self.rtol)
        return ok

    def limits(self, machine: Machine) -> tuple[np.ndarray, np.ndarray]:
        """Actuator limits in force (±inf when strokes are not enforced)."""
        if self.q_limits is not None:
            return (np.asarray(self.q_limits[0], float), np.asarray(self.q_limits[1], float))
        if not self.strokes:
            n = machine.n_actuators
            return np.full(n, -np.inf), np.full(n, np.inf)
        return stroke_limits(machine)


#: Poses evaluated at once by :func:`evaluate_poses` / :func:`evaluate_grid` (bounds the
#: temporaries of the inverse and velocity models to a few tens of MB).
EVALUATION_CHUNK = 1 << 16


def evaluate_poses(machine: Machine, points: np.ndarray, criteria: Criteria, *,
                   factors: bool = True) -> PoseEvaluation:
    """Evaluate the criteria (without connectivity) at poses ``points (M, dims)``, in chunks of
    :data:`EVALUATION_CHUNK` poses. ``factors=False``: the masks alone — the transmission
    factors and condition numbers are NaN unless a criterion reads them (no singular values
    of J are computed for the assembly mode, strokes and reach)."""
    points = np.asarray(points, dtype=float)
    if len(points) <= EVALUATION_CHUNK:
        return _evaluate_chunk(machine, points, criteria, factors=factors)
    starts = range(0, len(points), EVALUATION_CHUNK)
    label = f"{machine.id}: {len(points):,} poses"
    return _concatenate([_evaluate_chunk(machine, points[k:k + EVALUATION_CHUNK], criteria,
                                         factors=factors)
                         for k in tracked(starts, total=len(starts), label=label)])


def evaluate_grid(machine: Machine, grid: Grid, criteria: Criteria, *,
                  scheduler: Any = None, factors: bool = True) -> PoseEvaluation:
    """:func:`evaluate_poses` over every point of ``grid`` (flat, C order), generating the
    points chunk by chunk — in this process, or with ``scheduler`` (a Dask address, ``"local:N"``
    or a client, see :mod:`pkmkit.parallel`) in tasks of :data:`TASK_CHUNKS` chunks, each
    generating and evaluating its own points; the results are identical. ``factors``: as for
    :func:`evaluate_poses`."""
    if scheduler is None:
        return _evaluate_range(0, grid.size, machine, grid, criteria, factors)
    parts = map_chunks(_evaluate_range, grid.size, chunk=TASK_CHUNKS * EVALUATION_CHUNK,
                       scheduler=scheduler, args=(machine, grid, criteria, factors),
                       label=f"{machine.id}: {grid.size:,} poses")
    return parts[0] if len(parts) == 1 else _concatenate(parts)


#: Evaluation chunks per Dask task of :func:`evaluate_grid` (a task then takes ~0.1 s).
TASK_CHUNKS = 4


def _evaluate_range(start: int, stop: int, machine: Machine, grid: Grid,
                    criteria: Criteria, factors: bool = True) -> PoseEvaluation:
    """Grid points ``start:stop`` evaluated in chunks of :data:`EVALUATION_CHUNK` (a progress
    bar counts them)."""
    starts = range(start, stop, EVALUATION_CHUNK)
    # chunk boundaries at multiples of EVALUATION_CHUNK whatever the range, so that a grid
    # evaluated here and in Dask tasks (ranges of TASK_CHUNKS chunks) is cut the same way and
    # gives the same bits
    slab = grid.size // grid.shape[0] if criteria.continuation and grid.shape else None
    parts = [_evaluate_chunk(machine, grid.points_between(k, min(k + EVALUATION_CHUNK, stop)),
                             criteria, slab, factors=factors)
             for k in tracked(starts, total=len(starts),
                              label=f"{machine.id}: {stop - start:,} poses")]
    return parts[0] if len(parts) == 1 else _concatenate(parts)


def _concatenate(parts: list[PoseEvaluation]) -> PoseEvaluation:
    def joined(name: str) -> np.ndarray | None:
        values = [getattr(p, name) for p in parts]
        return None if values[0] is None else np.concatenate(values)

    return PoseEvaluation(
        q=np.concatenate([p.q for p in parts]),
        factors=np.concatenate([p.factors for p in parts]),
        condition=np.concatenate([p.condition for p in parts]),
        masks={k: np.concatenate([p.masks[k] for p in parts]) for k in parts[0].masks},
        stiffness=joined("stiffness"), deflection=joined("deflection"))


def _evaluate_chunk(machine: Machine, points: np.ndarray, criteria: Criteria,
                    slab: int | None = None, *, factors: bool = True,
                    inverse: Any = None) -> PoseEvaluation:
    """The criteria at ``points`` (``slab``: points per slab of the grid they come from, for
    the inverse model's continuation, :mod:`pkmkit.analysis.continuation`; ``inverse``: the
    inverse model's ``full_output`` record at ``points`` when the caller solved it, e.g. from
    neighbours' solutions, :mod:`pkmkit.analysis.flood`)."""
    ev = _evaluate_kinematics(machine, points, criteria, slab, factors=factors,
                              inverse=inverse)
    if not (criteria.stiffness_bounded or criteria.wrench is not None):
        return ev
    return _with_stiffness(machine, points, ev, criteria)


def _with_stiffness(machine: Machine, points: np.ndarray, ev: PoseEvaluation,
                    criteria: Criteria) -> PoseEvaluation:
    """``ev`` with the stiffness figures at its reachable poses (one batched evaluation:
    :func:`pkmkit.stiffness.indices.stiffness_figures`) and, with a stiffness criterion, the
    ``"stiffness"`` mask."""
    reach = ev.masks["reachable"]
    smallest = np.full(len(points), np.nan)
    deflection = None if criteria.wrench is None else np.full(len(points), np.nan)
    if reach.any():
        fig = stiffness_figures(machine, points[reach], q=ev.q[reach],
                                data=criteria.stiffness_data, wrench=criteria.wrench)
        smallest[reach] = fig.smallest
        if deflection is not None:
            deflection[reach] = fig.deflection
    masks = dict(ev.masks)
    if criteria.stiffness_bounded:
        masks[STIFFNESS_MASK] = reach & criteria.stiffness_ok(smallest, deflection)
    return PoseEvaluation(q=ev.q, factors=ev.factors, condition=ev.condition, masks=masks,
                          stiffness=smallest, deflection=deflection)


def _evaluate_kinematics(machine: Machine, points: np.ndarray, criteria: Criteria,
                         slab: int | None = None, *, factors: bool = True,
                         inverse: Any = None) -> PoseEvaluation:
    """The criteria at poses ``points (M, dims)`` through the machine protocol: ``ik``
    (reachable; joints beyond their strokes — a joint chain's passive joints too), ``jacobian``
    (transmission factors, conditioning) and ``in_working_mode`` (the assembly mode, away from
    parallel singularities)."""
    inv = inverse_of_chunk(machine, points, slab) if inverse is None else inverse
    q = np.atleast_2d(inv.q)
    reachable = np.atleast_1d(inv.status == Status.OK)
    lines = machine.translation_lines(points)
    if lines is None:
        jac = machine.jacobian(solved_poses(points, inv), q=q, tol=criteria.tol,
                               **closure_start(inv))
        mode = reachable & machine.in_working_mode(jac, criteria.tol)
    else:  # one velocity model per line along the slides (the same along it)
        rows = lines.rows
        solved = machine.jacobian(solved_poses(points, inv)[rows], q=q[rows], tol=criteria.tol)
        mode = reachable & machine.in_working_mode(solved, criteria.tol)[lines.of]
        jac = lines.spread(solved)
    read = factors or criteria.bounds is not None or criteria.kappa_max is not None
    # a full-pose velocity model computes J's singular values only when read
    sv = jac.singular_values if read else np.full(q.shape, np.nan)
    kappa = jac.condition if read else np.full(len(q), np.nan)
    with np.errstate(invalid="ignore"):
        if criteria.strokes and criteria.q_limits is None and inv.out_of_stroke is not None:
            strokes = reachable & ~np.asarray(inv.out_of_stroke, dtype=bool)
        else:
            lo_q, hi_q = criteria.limits(machine)
            strokes = reachable & ~(signed_excess(q, lo_q, hi_q) != 0).any(axis=1)
        if criteria.bounds is None:
            bounds = reachable.copy()
        else:
            bounds = reachable & criteria.within_bounds(sv)
        condition = reachable.copy() if criteria.kappa_max is None else (
            reachable & (kappa <= criteria.kappa_max))
    masks = {"reachable": reachable, "strokes": strokes, "bounds": bounds,
             "condition": condition, "mode": mode}
    return PoseEvaluation(q=q, factors=sv, condition=kappa, masks=masks)


def solved_poses(points: np.ndarray, inv: Any) -> np.ndarray:
    """The poses to take a velocity model at after the inverse model ``inv`` of ``points``:
    the complete poses it found where ``points`` are positions of a machine whose rods set its
    orientation (a Verne-type module: the velocity model would otherwise solve the inverse
    model again), else ``points``."""
    pose = getattr(inv, "pose", None)
    if pose is not None and np.ndim(pose) == 2 and np.shape(pose)[1] != np.shape(points)[-1]:
        return np.asarray(pose)
    return points


def closure_start(inv: Any) -> dict[str, np.ndarray]:
    """``{"start": …}`` for the velocity model after the inverse model ``inv`` when ``inv``
    found a closure the velocity model can start from (a joint chain's platform and passive
    joints: its direct model then converges at once instead of from home), else ``{}``."""
    start = getattr(inv, "closure_start", None)
    return {} if start is None else {"start": start}


def study_length(machine: Machine) -> float:
    """A length (m) that sizes the machine: its longest leg or rod, else (struts whose length
    is the actuator, a hexapod's) its longest finite stroke end, else 1 m. It scales the
    length slacks of :func:`criteria_slack` and the search of :func:`feasible_interval`."""
    leg = float(np.max(machine.model.leg_length, initial=0.0))
    if leg > 0:
        return leg
    q_max = np.asarray(machine.model.q_max, dtype=float)
    quantities = machine.actuator_quantities
    ends = [abs(v) for v, kind in zip(q_max, quantities, strict=False)
            if kind == "length" and np.isfinite(v)]
    return max(ends, default=0.0) or 1.0
