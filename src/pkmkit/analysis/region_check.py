"""Checking a prescribed square or cube densely: where each criterion fails, by how much (signed
slacks), and feasible intervals along a direction."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.analysis.criteria import (
    STIFFNESS_MASK,
    Criteria,
    evaluate_poses,
    study_length,
)
from pkmkit.analysis.evaluation import PoseEvaluation
from pkmkit.analysis.grids import Grid, make_grid
from pkmkit.analysis.slack import criteria_slack  # noqa: F401  (re-exported: its old home)
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.numerics.arrays import real

#: Smallest side (m) of a checked square or cube (a smaller one is a unit slip).
MIN_SIDE = 1e-9

def _surface_offsets(d: int, per_edge: int) -> np.ndarray:
    """Points of the faces of ``[-1, 1]^d``, ``per_edge`` per edge (duplicates removed)."""
    axis = np.linspace(-1.0, 1.0, per_edge)
    faces = []
    for k in range(d):
        grids = np.meshgrid(*([axis] * (d - 1)), indexing="ij")
        inner = np.stack([g.ravel() for g in grids], axis=-1) if d > 1 else np.zeros((1, 0))
        for side in (-1.0, 1.0):
            face = np.insert(inner, k, side, axis=1)
            faces.append(face)
    return np.unique(np.concatenate(faces), axis=0)


def _full(base: np.ndarray, free: list[int], values: np.ndarray) -> np.ndarray:
    out = np.array(base, dtype=float)
    out[free] = values
    return out


def check_region_samples(free_axes: int) -> int:
    """Lattice points per edge of :func:`check_region` for a square (2 free axes) or a cube."""
    return 41 if free_axes <= 2 else 25


@dataclass(frozen=True)
class RegionCheck:
    """Dense verification of a prescribed square/cube.

    Attributes:
        feasible: every sample satisfies every criterion, with no sign change of det A.
        samples: number of samples checked.
        failures: ``{criterion: number of failing samples}``.
        worst: ``{criterion: description of the worst violation with its pose}``.
        factor_range: (min, max) velocity transmission factor over the reachable samples.
        q_range: ``(q_lo (n,), q_hi (n,))`` actuator coordinates needed over the region.
    """

    feasible: bool
    samples: int
    failures: dict[str, int]
    worst: dict[str, str]
    factor_range: tuple[float, float]
    q_range: tuple[np.ndarray, np.ndarray]


def region_grid(machine: Machine, center: Any, side: float, free: tuple[int, ...] | None = None,
                samples: int | None = None) -> Grid:
    """Grid of ``samples`` points per edge over the square/cube of ``side`` centred at
    ``center``; ``free`` defaults to every pose coordinate."""
    # a machine that takes positions alone (a Verne-type module) may be given a position
    widths = {machine.dims} | ({3} if machine.position_controlled else set())
    expected = " or ".join(str(w) for w in sorted(widths))
    try:
        center = np.asarray(center, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"the centre must be {expected} finite coordinates, got "
                         f"{center!r}") from None
    if center.shape[0] not in widths or not np.isfinite(center).all():
        raise InputError(f"the centre must be {expected} finite coordinates")
    side = real(side, "the side", positive=True, limit=1e6)
    if side < MIN_SIDE:
        raise InputError(f"the side = {side:g} m is below {MIN_SIDE:g} m (1 nm): its samples "
                         "cannot be told apart from the centre; check the units")
    free = tuple(range(len(center))) if free is None else free
    samples = samples or check_region_samples(len(free))
    lower = [center[k] - side / 2 for k in free]
    upper = [center[k] + side / 2 for k in free]
    return make_grid(lower, upper, free=free, base=center,
                     names=machine.pose_names[:len(center)], resolution=samples)


def check_region(machine: Machine, center: Any, side: float, criteria: Criteria | None = None,
                 *, free: tuple[int, ...] | None = None, samples: int | None = None
                 ) -> RegionCheck:
    """Is the axis-aligned square/cube of ``side`` centred at ``center`` usable, and where does
    it fail? Checks ``samples`` points per edge (faces included).

    The Orthoglide prototype's 0.2 m cube under 1/2 ≤ λ ≤ 2 (seed 001), and a larger one:

    >>> import pkmkit
    >>> m = pkmkit.machine("orthoglide")
    >>> c = -0.0267446 * np.ones(3)
    >>> check_region(m, c, 0.199, Criteria(bounds=(0.5, 2.0))).feasible
    True
    >>> check = check_region(m, c, 0.21, Criteria(bounds=(0.5, 2.0)))
    >>> check.feasible, sorted(check.failures)
    (False, ['bounds', 'strokes'])
    """
    criteria = criteria or Criteria()
    grid = region_grid(machine, center, side, free, samples)
    points = grid.points
    ev = evaluate_poses(machine, points, criteria)
    failures: dict[str, int] = {}
    worst: dict[str, str] = {}
    names = machine.actuator_names
    for name in ev.masks:  # MASK_NAMES, and "stiffness" with a stiffness criterion
        bad = ~ev.masks[name]
        if name != "reachable":
            bad &= ev.masks["reachable"]
        if not bad.any():
            continue
        failures[name] = int(bad.sum())
        worst[name] = _worst(name, bad, points, ev, criteria, machine, names)
    reach = ev.masks["reachable"]
    if reach.any():
        lo_q, hi_q = _q_extremes(machine, grid, ev.q, reach)
    else:
        lo_q = hi_q = np.full(len(names), np.nan)
    factor_range = ((float(np.nanmin(ev.factors[reach])), float(np.nanmax(ev.factors[reach])))
                    if reach.any() else (float("nan"), float("nan")))
    return RegionCheck(feasible=not failures, samples=len(points), failures=failures,
                       worst=worst, factor_range=factor_range, q_range=(lo_q, hi_q))


def _bounded_minimum(fun: Callable[[np.ndarray], float], start: np.ndarray,
                     bounds: list[tuple[float, float]], fallback: float) -> float:
    """Local minimum of ``fun`` from ``start`` within ``bounds`` (L-BFGS-B).

    ``fun`` returns NaN where it is undefined (unreachable pose, no assembly): such points are
    given the finite value ``fallback + 1`` (worse than the start, whose value is ``fallback``)
    so that the finite-difference gradients stay finite. Numerical warnings of the optimiser are
    kept from the user. Returns the smallest *defined* value found (at least as good as
    ``fallback``)."""
    from scipy.optimize import minimize

    best = [fallback]

    def value(y: np.ndarray) -> float:
        v = float(fun(y))
        if not np.isfinite(v):
            return fallback + 1.0 + abs(fallback)
        best[0] = min(best[0], v)
        return v

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        minimize(value, start, method="L-BFGS-B", bounds=bounds,
                 options={"maxiter": 100, "ftol": 1e-15, "gtol": 1e-12})
    return best[0]


def _grid_bounds(grid: Grid) -> list[tuple[float, float]]:
    return [(float(lo), float(max(hi, axis[-1]))) for lo, hi, axis in
            zip(grid.lower_bounds, grid.upper_bounds, grid.axes, strict=True)]


def _full_point(grid: Grid, y: np.ndarray) -> np.ndarray:
    full = grid.base.copy()
    full[list(grid.free)] = y
    return full


def _column_extremes(grid: Grid, values: np.ndarray, fun: Callable[[np.ndarray], np.ndarray],
                     columns: list[tuple[int, float]]) -> list[float]:
    """Refined extremes of columns of ``values (M, k)`` sampled at ``grid.points``:
    ``columns`` lists ``(column, sign)``, sign +1 for the minimum, −1 for the maximum; ``fun``
    maps a full point ``(dims,)`` to a row ``(k,)`` (NaN where undefined)."""
    points_free = list(grid.free)
    bounds = _grid_bounds(grid)
    out = []
    for column, sign in columns:
        signed = sign * values[:, column]
        if not np.isfinite(signed).any():
            out.append(float("nan"))
            continue
        start = int(np.nanargmin(signed))
        found = _bounded_minimum(
            lambda y, c=column, s=sign: s * fun(_full_point(grid, y))[c],
            grid.point(np.unravel_index(start, grid.shape))[points_free], bounds,
            float(signed[start]))
        out.append(sign * found)
    return out


def _q_extremes(machine: Machine, grid: Grid, q: np.ndarray, reach: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest value of each actuator coordinate over the region: the sampled
    extremes, refined by bounded local optimisation (they may lie between samples, e.g. inside
    a face)."""
    values = np.where(reach[:, None], q, np.nan)
    n = q.shape[1]
    found = _column_extremes(grid, values, lambda x: machine.ik(x[None])[0],
                             [(k, s) for k in range(n) for s in (1.0, -1.0)])
    return np.array(found[0::2]), np.array(found[1::2])


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def _worst(name: str, bad: np.ndarray, points: np.ndarray, ev: PoseEvaluation,
           criteria: Criteria, machine: Machine, names) -> str:
    idx = np.flatnonzero(bad)
    if name == "reachable":
        k, why = machine.unreachable_reason(points[idx])
        return f"at {_fmt(points[idx[k]])}: {why}"
    if name == "strokes":
        lo, hi = criteria.limits(machine)
        k, why = machine.out_of_stroke_reason(ev.q[idx], lo, hi, names)
        return f"at {_fmt(points[idx[k]])}: {why}"
    if name == "bounds":
        lo, hi = criteria.bounds
        ratio = np.maximum(lo / ev.factors[idx, -1], ev.factors[idx, 0] / hi)
        k = int(np.nanargmax(ratio))
        f = ev.factors[idx[k]]
        which = f"λ_min = {f[-1]:.6g} < {lo:g}" if f[-1] < lo else f"λ_max = {f[0]:.6g} > {hi:g}"
        return f"at {_fmt(points[idx[k]])}: {which}"
    if name == STIFFNESS_MASK:
        return _worst_stiffness(idx, points, ev, criteria)
    if name == "condition":
        k = int(np.nanargmax(ev.condition[idx]))
        return (f"at {_fmt(points[idx[k]])}: condition {ev.condition[idx[k]]:.6g} > "
                f"{criteria.kappa_max:g}")
    k = 0
    return (f"at {_fmt(points[idx[k]])}: other assembly mode or parallel singularity "
            f"({len(idx)} samples)")


def _worst_stiffness(idx: np.ndarray, points: np.ndarray, ev: PoseEvaluation,
                     criteria: Criteria) -> str:
    """Where the stiffness criterion fails worst (relative shortfall), in SI units."""
    parts = []
    with np.errstate(invalid="ignore", divide="ignore"):
        if criteria.min_stiffness is not None:
            parts.append(criteria.min_stiffness / ev.stiffness[idx] - 1.0)
        if criteria.max_deflection is not None:
            parts.append(ev.deflection[idx] / criteria.max_deflection - 1.0)
    shortfall = np.nan_to_num(np.max(parts, axis=0), nan=np.inf)
    k = int(np.argmax(shortfall))
    i = idx[k]
    if not np.isfinite(ev.stiffness[i]):
        return f"at {_fmt(points[i])}: no stiffness (singular configuration)"
    text = f"smallest translational stiffness {ev.stiffness[i]:.6g} N/m"
    if criteria.min_stiffness is not None:
        text += f" (min {criteria.min_stiffness:g})"
    if criteria.max_deflection is not None:
        text += f", deflection {ev.deflection[i]:.6g} m (max {criteria.max_deflection:g})"
    return f"at {_fmt(points[i])}: {text}"


def feasible_interval(machine: Machine, point: Any, direction: Any, criteria: Criteria,
                      *, reach: float | None = None, samples: int = 2001) -> tuple[float, float]:
    """Interval ``(t_lo, t_hi)`` of the line ``point + t·direction`` around t = 0 where every
    criterion holds (``connected`` is implied: the interval contains 0), each end refined by
    bisection to machine precision.

    For the Orthoglide, the ends along the cube diagonal from the isotropic point are the
    reference points Q1 and Q2 of seed 001's sizing method.

    Raises:
        InputError: the criteria fail at ``point`` itself.
    """
    point = np.asarray(point, dtype=float)
    direction = np.asarray(direction, dtype=float)
    reach = reach or 2.0 * study_length(machine)
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max,
                     strokes=criteria.strokes, q_limits=criteria.q_limits, connected=False,
                     tol=criteria.tol, rtol=0.0)  # the ends are located exactly

    def ok(t: np.ndarray) -> np.ndarray:
        return evaluate_poses(machine, point + np.outer(t, direction), loose).feasible

    if not ok(np.zeros(1))[0]:
        raise InputError(f"the criteria fail at {point.tolist()} itself")
    ends = []
    for sign in (-1.0, 1.0):
        t = sign * np.linspace(0.0, reach, samples)
        good = ok(t)
        first_bad = int(np.argmin(good)) if not good.all() else None
        if first_bad is None:
            ends.append(t[-1])
            continue
        inside, outside = t[first_bad - 1], t[first_bad]
        for _ in range(60):
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if ok(np.array([mid]))[0] else (inside, mid)
            if abs(outside - inside) <= 1e-15 * max(1.0, abs(inside)):
                break
        ends.append(inside)
    return float(ends[0]), float(ends[1])
