"""A workspace grid evaluated by a flood fill from home (issue 22 §3).

A study that keeps only the part of the feasible set connected to home (``Criteria.connected``)
decides nothing with the points outside that part and not next to it. On a machine whose
inverse model is numerical and continues from a neighbouring point's solution
(``machine.inverse_continues``: a joint chain's closure, ~100 µs a point), the grid is
therefore evaluated by breadth-first wavefronts from home's grid point: each wavefront is one
batched evaluation (in chunks of :data:`~pkmkit.analysis.criteria.EVALUATION_CHUNK`) of the
not yet evaluated face neighbours of the points the previous wavefront found feasible, each
started from a feasible neighbour's solution where ``machine.continues_from`` allows it (else
from home; the inverse's own rules — the legs' home modes checked, the re-solve from home, the
head's branch — are those of :mod:`pkmkit.analysis.continuation`). The fill stops when a
wavefront adds no feasible point: the evaluated points are then the connected part (face
neighbours, the connectivity of :func:`~pkmkit.analysis.workspace.compute_workspace`) and its
infeasible rim, and the kept part is the one the whole grid gives.

Seeds: home's grid point when it is feasible; else, as the whole grid's study does
(``_part_next_to``: a home at a stroke end rounds to a grid point just outside), the feasible
point nearest home of the cell around it (one step along each free axis); the cell's other
feasible points join the fill when it reaches them. With no feasible seed — or home outside the
grid — the study keeps the largest part, which needs every point: :func:`flood_grid` returns
None and the caller evaluates the whole grid.
"""

from __future__ import annotations

import itertools
import warnings
from typing import Any

import numpy as np

from pkmkit.analysis.criteria import EVALUATION_CHUNK, Criteria, _evaluate_chunk
from pkmkit.analysis.evaluation import PoseEvaluation
from pkmkit.analysis.grids import Grid
from pkmkit.exceptions import StrokeWarning
from pkmkit.progress import tracked


def floods(machine: Any, criteria: Criteria, scheduler: Any = None) -> bool:
    """Whether :func:`pkmkit.analysis.workspace.compute_workspace` evaluates its grid by a
    flood fill: only the part connected to home is kept, the machine's inverse continues from
    a neighbour's solution (a numerical, per-point costly inverse), the criteria do not ask
    for the whole grid, and no Dask ``scheduler`` is to evaluate it."""
    return (criteria.connected and not criteria.whole_grid and scheduler is None
            and bool(machine.inverse_continues))


def grid_points_at(grid: Grid, flat: np.ndarray) -> np.ndarray:
    """``(len(flat), dims)`` grid points at flat (C-order) indices ``flat``."""
    flat = np.asarray(flat, dtype=np.int64)
    out = np.tile(grid.base, (flat.size, 1))
    for k, axis, index in zip(grid.free, grid.axes, np.unravel_index(flat, grid.shape),
                              strict=True):
        out[:, k] = axis[index]
    return out


class _Store:
    """The flat arrays of a grid's evaluation filled wavefront by wavefront (NaN and False
    where not evaluated)."""

    def __init__(self, size: int) -> None:
        self.size = size
        self.evaluated = np.zeros(size, dtype=bool)
        self.feasible = np.zeros(size, dtype=bool)
        self.arrays: dict[str, np.ndarray] = {}
        self.masks: dict[str, np.ndarray] = {}
        self.points = 0

    def put(self, flat: np.ndarray, ev: PoseEvaluation) -> None:
        for name in ("q", "factors", "condition", "stiffness", "deflection"):
            value = getattr(ev, name)
            if value is None:
                continue
            if name not in self.arrays:
                self.arrays[name] = np.full((self.size, *value.shape[1:]), np.nan)
            self.arrays[name][flat] = value
        for name, mask in ev.masks.items():
            self.masks.setdefault(name, np.zeros(self.size, dtype=bool))[flat] = mask
        self.evaluated[flat] = True
        self.feasible[flat] = ev.feasible
        self.points += len(flat)

    def evaluation(self) -> PoseEvaluation:
        a = self.arrays
        return PoseEvaluation(q=a["q"], factors=a["factors"], condition=a["condition"],
                              masks=self.masks, stiffness=a.get("stiffness"),
                              deflection=a.get("deflection"))


def _evaluate(machine: Any, grid: Grid, criteria: Criteria, flat: np.ndarray,
              start: np.ndarray | None, factors: bool, store: _Store) -> np.ndarray:
    """Evaluate the grid points ``flat`` (each from its row of ``start``, NaN rows and None
    from home) in chunks, into ``store``; returns their inverse solutions ``(len(flat), w)``."""
    solutions = []
    for k in range(0, len(flat), EVALUATION_CHUNK):
        rows = flat[k:k + EVALUATION_CHUNK]
        points = grid_points_at(grid, rows)
        given = None if start is None else start[k:k + EVALUATION_CHUNK]
        if given is not None and not np.isfinite(given).all(axis=1).any():
            given = None
        if given is not None:  # the kind's closed start first (continuation_starts)
            given = machine.continuation_starts(points, given)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", StrokeWarning)
            inv = (machine.ik(points, full_output=True) if given is None else
                   machine.ik(points, full_output=True, start=given))
        store.put(rows, _evaluate_chunk(machine, points, criteria, factors=factors,
                                        inverse=inv))
        solutions.append(np.atleast_2d(inv.solution))
    return np.concatenate(solutions)


def _seeds(machine: Any, grid: Grid, criteria: Criteria, home: np.ndarray, factors: bool,
           store: _Store, known: dict[int, np.ndarray]) -> tuple[np.ndarray, np.ndarray] | None:
    """Flat index and solution of the point the fill starts from (module docstring), or None
    (no feasible seed: the whole grid is needed). The feasible points of the cell evaluated on
    the way are put in ``known`` (flat index: solution): the fill takes them in when it
    reaches them."""
    index = grid.nearest_index(home)
    if index is None:
        return None
    flat = np.array([np.ravel_multi_index(index, grid.shape)])
    solution = _evaluate(machine, grid, criteria, flat, None, factors, store)
    if store.feasible[flat[0]]:
        return flat, solution
    ranges = [range(max(i - 1, 0), min(i + 2, n)) for i, n in zip(index, grid.shape,
                                                                     strict=True)]
    cell = np.array([np.ravel_multi_index(c, grid.shape) for c in itertools.product(*ranges)
                     if c != tuple(index)], dtype=np.int64)
    if not cell.size:
        return None
    solution = _evaluate(machine, grid, criteria, cell, None, factors, store)
    ok = np.flatnonzero(store.feasible[cell])
    if not ok.size:
        return None
    # the feasible point nearest home (the first in C order at a tie), whose part the whole
    # grid's study keeps (workspace._part_next_to): the other parts around home are not filled
    free = list(grid.free)
    gap = np.linalg.norm(grid_points_at(grid, cell[ok])[:, free] - home[free], axis=1)
    nearest = ok[int(np.argmin(gap))]
    known.update({int(cell[k]): solution[k] for k in ok})
    return cell[nearest:nearest + 1], solution[nearest:nearest + 1]


def _frontier(grid: Grid, machine: Any, new: np.ndarray, solution: np.ndarray,
              evaluated: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The not yet evaluated face neighbours of the points ``new`` (flat, sorted) and each one's
    start: the solution of a neighbour in ``new`` it may continue from (``continues_from``),
    preferring the one a step back along the first axis (the whole grid's continuation), else
    NaN (from home)."""
    shape = grid.shape
    strides = np.cumprod((*shape[1:], 1)[::-1])[::-1]
    index = np.unravel_index(new, shape)
    continues = np.asarray(machine.continues_from(solution), dtype=bool)
    targets, sources = [], []
    for axis, n in enumerate(shape):
        for step in (1, -1):  # the neighbour a step forward sees this point a step back
            inside = (index[axis] + step >= 0) & (index[axis] + step < n)
            targets.append(new[inside] + step * strides[axis])
            sources.append(np.flatnonzero(inside))
    target, source = np.concatenate(targets), np.concatenate(sources)
    keep = ~evaluated[target]
    target, source = target[keep], source[keep]
    # per target, the first candidate with a start (in the order above), else the first one
    order = np.lexsort((np.arange(len(target)), ~continues[source], target))
    target, source = target[order], source[order]
    first = np.ones(len(target), dtype=bool)
    first[1:] = target[1:] != target[:-1]
    target, source = target[first], source[first]
    start = np.where(continues[source][:, None], solution[source], np.nan)
    return target, start


def flood_grid(machine: Any, grid: Grid, criteria: Criteria, home: np.ndarray, *,
               factors: bool = True) -> tuple[PoseEvaluation, np.ndarray] | None:
    """The criteria on ``grid`` evaluated by a flood fill from ``home`` (module docstring):
    ``(evaluation, evaluated)`` — the flat evaluation (NaN factors/q and False masks where
    not evaluated) and the ``(grid.size,)`` mask of the points evaluated — or None when no
    seed is feasible (the caller evaluates the whole grid)."""
    store = _Store(grid.size)
    known: dict[int, np.ndarray] = {}
    seeds = _seeds(machine, grid, criteria, np.asarray(home, dtype=float), factors, store,
                   known)
    if seeds is None:
        return None
    new, solution = seeds
    # closed: evaluated, except the feasible points of home's cell the fill has not reached
    # (their part may be the fill's: they join it when reached)
    closed = store.evaluated.copy()
    closed[[k for k in known if k not in set(new.tolist())]] = False
    # a bar over the grid's points counts those evaluated (the fill ends well short of all)
    bar = tracked(range(grid.size), total=grid.size, unit="point",
                  label=f"{machine.id}: flood fill from home, points evaluated")
    counted = getattr(bar, "update", None)  # a bar only when a display is open
    if counted is not None:
        counted(store.points)
    while new.size:
        target, start = _frontier(grid, machine, new, solution, closed)
        closed[target] = True
        taken = store.evaluated[target]
        joined = target[taken]
        target, start = target[~taken], start[~taken]
        found = np.empty((0, solution.shape[1]))
        if target.size:
            found = _evaluate(machine, grid, criteria, target, start, factors, store)
            if counted is not None:
                counted(len(target))
        ok = store.feasible[target]
        new = np.concatenate([target[ok], joined])
        solution = np.concatenate([found[ok], *([known[int(k)]] for k in joined)])
        order = np.argsort(new)
        new, solution = new[order], solution[order]
    if counted is not None:
        bar.close()
    return store.evaluation(), store.evaluated
