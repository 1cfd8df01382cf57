"""Sizing of the linear Delta with vertical slides for a prescribed cube (issue 4 §4, seed 000).

Only two lengths enter the kinematics: d = R − r (horizontal offset of a slide from the nacelle
joint it drives) and the arm length L; the nacelle radius r only adds to R (it is set by the
spindle the nacelle carries, an input here). A vertical translation of the cube moves the three
carriages together, so it changes the slider positions but not the transmission factors.

**A bound every design obeys.** A pure vertical motion ż needs q̇ = ż (1, 1, 1), so the gain
|ẋ| / |q̇| is 1/√3 in that direction and 1/√3 lies between λ_min and λ_max at *every* pose of
*every* vertical-slide Delta. Bounds that exclude 1/√3 ≈ 0.577 are refused at once.

**Objectives** (the cube must satisfy λ_min ≥ lo and λ_max ≤ hi at every pose):

- ``"size"`` (default) — the shortest arms L (with the best d) for which the cube is feasible.
  It is the analogue of the Orthoglide rule: below that L no d keeps the whole cube within the
  bounds; at it both bounds are usually reached somewhere in the cube. For each trial L the
  most favourable d minimises the largest relative excess of a bound over the cube (bounded
  Brent search); L is the root of that best excess (Brent's method, bracketed by an infeasible
  and a feasible length, to 1e-6 relative).
- ``"compactness"`` — the largest Lw / stroke with L ≤ ``max_leg`` (required: the compactness
  keeps growing slowly with the size of the machine, so without a size limit the optimum is an
  infinitely large machine). For a fixed d the compactness grows with L, so the answer uses
  L = ``max_leg`` (the tests check it against a (d, L) grid); there the feasible d-interval is
  scanned and its best point refined by bisection toward the infeasible neighbour.

The search evaluates the cube on a coarse grid (``search_samples`` per edge). The answer is then
verified by brute force on a dense grid (``samples`` per edge, with the refined actuator
extremes of :func:`pkmkit.analysis.check_region`); if the dense grid finds a factor beyond a
bound that the coarse grid missed, the search is repeated with the bounds tightened by that
difference, until the dense check passes.

The strokes are the actuator ranges over the cube (slider positions ``q_min``, ``q_max``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.analysis.workspace import Criteria, RegionCheck, check_region
from pkmkit.design.checks import VERIFY_RTOL, degenerate_note, relaxed, require_side
from pkmkit.design.metrics import Region, evaluate_metrics
from pkmkit.exceptions import InputError, ParameterError
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import machine as builtin_machine
from pkmkit.model.parameters import MAX_LENGTH
from pkmkit.numerics.arrays import real_pair

#: The transmission factor of a pure vertical motion, for every vertical-slide Delta.
VERTICAL_FACTOR = 1.0 / math.sqrt(3.0)
OBJECTIVES = ("size", "compactness")


@dataclass(frozen=True)
class LinearDeltaSizing:
    """Result of :func:`size_linear_delta` (lengths in m).

    Attributes:
        cube_side: prescribed side Lw.
        center: ``(3,)`` centre of the cube.
        bounds: (λ_min, λ_max) bounds.
        objective: ``"size"`` or ``"compactness"``.
        R, r, L: slide-circle radius, nacelle radius, arm length.
        d: R − r.
        q_min, q_max: ``(3,)`` slider positions at the ends of the strokes.
        stroke: largest slider stroke.
        compactness: Lw / stroke.
        index_range: (min, max) transmission factor over the cube (dense check).
        gci: mean 1/κ over the cube (search grid).
        check: brute-force verification of the cube.
        machine: the sized machine (strokes set to ``q_min``, ``q_max``).
        notes: remarks on the specification (a degenerate one).
    """

    cube_side: float
    center: np.ndarray
    bounds: tuple[float, float]
    objective: str
    R: float
    r: float
    L: float
    d: float
    q_min: np.ndarray
    q_max: np.ndarray
    stroke: float
    compactness: float
    index_range: tuple[float, float]
    gci: float
    check: RegionCheck
    machine: Machine
    notes: tuple[str, ...] = ()


def _candidate(base: Machine, d: float, r: float, length: float) -> Machine:
    """The candidate (d, L) with slider stops ±3 L, which hold its home pose at every scale
    (the stops are not searched: the criteria ignore them, and the result gets the cube's
    strokes). The base's stops [0.7, 2] m put the home of arms of 750 m "beyond its stroke
    by 374 times its size", refused as a unit slip, so cubes above ~200 m could not be sized.
    """
    return base.with_params(R=d + r, r=r, L=length, q_min=(-3.0 * length,) * 3,
                            q_max=(3.0 * length,) * 3)


class _Search:
    """Margins and metrics of candidate (d, L) designs on the coarse grid."""

    def __init__(self, base: Machine, region: Region, r: float, bounds: tuple[float, float],
                 samples: int):
        self.base, self.region, self.r, self.samples = base, region, r, samples
        self.bounds = bounds
        self.criteria = Criteria(bounds=bounds, strokes=False)

    def machine(self, d: float, length: float) -> Machine | None:
        try:
            return _candidate(self.base, d, self.r, length)
        except ParameterError:
            return None

    def metrics(self, d: float, length: float, names: tuple[str, ...]) -> dict[str, Any] | None:
        m = self.machine(d, length)
        if m is None:
            return None
        return evaluate_metrics(m, self.region, self.criteria, names, self.samples)

    def margin(self, d: float, length: float) -> float:
        """Largest relative excess of a bound over the cube (< 0: strictly inside the bounds);
        1 + the unreachable fraction where part of the cube is out of reach; 10 for no machine."""
        v = self.metrics(d, length, ("violation", "lambda_min", "lambda_max"))
        if v is None or not np.isfinite(v["lambda_min"]):
            return 10.0
        lo, hi = self.bounds
        excess = max(lo / v["lambda_min"] - 1.0, v["lambda_max"] / hi - 1.0)
        if v["violation"] > max(excess, 0.0):  # some poses unreachable or in the other mode
            return 1.0 + v["violation"]
        return excess

    def best_d(self, length: float) -> tuple[float, float]:
        """(d, margin) minimising the margin for arms of ``length``."""
        from scipy.optimize import minimize_scalar  # at first use, not at `--help`

        res = minimize_scalar(lambda d: self.margin(d, length), bounds=(1e-3 * length, length),
                              method="bounded", options={"xatol": 1e-7 * length})
        return float(res.x), float(res.fun)

    def smallest(self, lower: float, max_leg: float | None, guess: float | None = None
                 ) -> tuple[float, float]:
        """(d, L) with the shortest arms keeping the margin ≤ 0, to 1e-6 relative in L.
        ``lower`` is an infeasible arm length; ``guess`` a likely answer (narrows the
        bracket)."""
        cap = MAX_LENGTH if max_leg is None else max_leg
        if cap <= lower:
            raise InputError(f"arms of {cap:g} m cannot reach every corner of the cube (they "
                             f"must be longer than {lower:.6g} m)")
        bad, good = lower, min(2.0 * lower, cap)
        if guess is not None and guess < cap:
            if self.best_d(0.99 * guess)[1] > 0:
                bad, good = 0.99 * guess, min(1.01 * guess, cap)
        while self.best_d(good)[1] > 0:
            if good >= cap:
                limit = "any admissible length" if max_leg is None else (
                    f"the admissible {max_leg:g} m")
                raise InputError(f"no linear Delta with arms up to {limit} keeps every "
                                 f"transmission factor of the cube within {list(self.bounds)}")
            bad, good = good, min(2.0 * good, cap)
        from scipy.optimize import brentq  # at first use, not at `--help`

        # the best margin decreases through 0 as L grows: its root, to 1e-6 relative
        root = brentq(lambda length: self.best_d(length)[1], bad, good, xtol=1e-7 * bad,
                      rtol=1e-6)
        for length in (root, root * (1 + 1e-6), root * (1 + 1e-5), good):
            d, margin = self.best_d(length)
            if margin <= 0:
                return d, length
        raise AssertionError("unreachable: the bracket's upper end is feasible")

    def most_compact(self, length: float) -> tuple[float, float]:
        """(d, L = length) maximising the compactness with the margin ≤ 0."""
        d0, m0 = self.best_d(length)
        if m0 > 0:
            raise InputError(f"no linear Delta with arms of {length:g} m keeps every "
                             f"transmission factor of the cube within {list(self.bounds)}; "
                             "allow longer arms")
        ds = np.unique(np.append(np.geomspace(1e-3 * length, length, 33)[:-1], d0))
        ok = np.array([self.margin(d, length) <= 0 for d in ds])
        comp = np.array([self.metrics(d, length, ("compactness",))["compactness"] if good
                         else -np.inf for d, good in zip(ds, ok, strict=True)])
        k = int(np.argmax(comp))
        best_d, best_c = ds[k], comp[k]
        for j in (k - 1, k + 1):  # refine toward an infeasible neighbour (the boundary)
            if 0 <= j < len(ds) and not ok[j]:
                inside, outside = ds[k], ds[j]
                while abs(outside - inside) > 1e-9 * length:
                    mid = 0.5 * (inside + outside)
                    inside, outside = ((mid, outside) if self.margin(mid, length) <= 0
                                       else (inside, mid))
                c = self.metrics(inside, length, ("compactness",))["compactness"]
                if c > best_c:
                    best_d, best_c = inside, c
        return float(best_d), length


def _factor_bounds(bounds: Any) -> tuple[float, float]:
    """The transmission-factor bounds ``(lo, hi)``, which must contain 1/√3."""
    lo, hi = real_pair(bounds, "the transmission-factor bounds")
    Criteria(bounds=(lo, hi))  # validates 0 < lo < hi
    if not lo <= VERTICAL_FACTOR <= hi:
        raise InputError(
            f"bounds [{lo:g}, {hi:g}] exclude 1/√3 = {VERTICAL_FACTOR:.6f}, the transmission "
            "factor of a pure vertical motion (q̇ = ż (1, 1, 1)) at every pose of every "
            "vertical-slide linear Delta: no design can satisfy them")
    return lo, hi


def _check_objective(objective: str, max_leg: float | None) -> None:
    """A known objective; ``max_leg`` within (0, MAX_LENGTH] m, required by compactness."""
    if objective not in OBJECTIVES:
        raise InputError(f"unknown objective {objective!r}; use {' or '.join(OBJECTIVES)}")
    if max_leg is not None and not (np.isfinite(max_leg) and 0 < max_leg <= MAX_LENGTH):
        raise InputError(f"the largest admissible arm length must be in (0, {MAX_LENGTH:g}] m, "
                         f"got {max_leg}")
    if objective == "compactness" and max_leg is None:
        raise InputError("objective 'compactness' needs a largest arm length (max_leg): the "
                         "compactness keeps growing slowly with the size of the machine, so "
                         "without a limit the optimum is an infinitely large machine")


def _verified_design(base, region, center: np.ndarray, r: float,
                     bounds: tuple[float, float], criteria,
                     lower: float, objective: str, max_leg: float | None, samples: int,
                     search_samples: int) -> tuple:
    """``(d, L, sized machine, check)``: the search on a coarse grid, verified on a dense one;
    where the dense grid finds a factor beyond a bound between the search samples, the
    search bounds are tightened and the search repeated (at most 6 times)."""
    lo, hi = bounds
    cube_side = region.side
    search_bounds = (lo, hi)
    guess = None
    for _ in range(6):
        search = _Search(base, region, r, search_bounds, search_samples)
        if objective == "size":
            d, length = search.smallest(lower, max_leg, guess)
            guess = length
        else:
            d, length = search.most_compact(max_leg)
        sized = _candidate(base, d, r, length)
        check = check_region(sized, center, cube_side, relaxed(criteria), samples=samples)
        if check.feasible:
            return d, length, sized, check
        if set(check.failures) - {"bounds"}:
            raise InputError(f"the sized cube fails the brute-force check: {check.worst}")
        # the dense grid found a factor beyond a bound between the search samples: tighten
        coarse = search.metrics(d, length, ("lambda_min", "lambda_max"))
        f_lo, f_hi = check.factor_range
        s_lo, s_hi = search_bounds
        if f_lo < lo * (1.0 - VERIFY_RTOL):
            s_lo *= coarse["lambda_min"] / f_lo * (1.0 + 1e-4)
        if f_hi > hi * (1.0 + VERIFY_RTOL):
            s_hi *= coarse["lambda_max"] / f_hi / (1.0 + 1e-4)
        search_bounds = (s_lo, s_hi)
    raise InputError(f"the sized cube fails the brute-force check: {check.worst}")


def size_linear_delta(cube_side: float, bounds: tuple[float, float], *,
                      center: Any = None, r: float | None = None, objective: str = "size",
                      max_leg: float | None = None, samples: int = 25,
                      search_samples: int = 7) -> LinearDeltaSizing:
    """Size a vertical-slide linear Delta (slides at 0°, 120°, 240°) for a prescribed cube
    (see the module docstring).

    Args:
        cube_side: prescribed cube side Lw, m.
        bounds: (lo, hi) bounds on every velocity transmission factor; lo ≤ 1/√3 ≤ hi.
        center: ``(3,)`` centre of the cube, m (default (0, 0, Lw/2): the cube stands on the
            plane z = 0 under the centre of the slides, as in seed 000's Table III.2).
        r: nacelle radius, m (default 0.3 Lw, the seed's 0.15 m for its 0.5 m cube).
        objective: ``"size"`` (shortest arms) or ``"compactness"`` (largest Lw / stroke with
            L ≤ ``max_leg``).
        max_leg: largest admissible arm length, m (required for ``"compactness"``).
        samples: points per edge of the brute-force verification.
        search_samples: points per edge of the cube during the search.

    Raises:
        InputError: bad side, centre, r or bounds, bounds excluding 1/√3, an unknown objective,
            a missing or too short ``max_leg``, or no design passing the verification.
    """
    cube_side = require_side(cube_side, "cube side")
    lo, hi = _factor_bounds(bounds)
    _check_objective(objective, max_leg)
    center = (np.array([0.0, 0.0, 0.5 * cube_side]) if center is None
              else np.asarray(center, dtype=float).reshape(-1))
    if center.shape != (3,) or not np.isfinite(center).all():
        raise InputError(f"the cube centre must be 3 finite coordinates, got {center.tolist()}")
    r = 0.3 * cube_side if r is None else r
    if not (np.isfinite(r) and 0 < r <= MAX_LENGTH):
        raise InputError(f"the nacelle radius r must be > 0, got {r}")
    base = builtin_machine("linear-delta")
    region = Region(cube_side, tuple(center))
    # every column must reach the farthest corner: L > the square's half-diagonal (+ offset)
    lower = math.hypot(*(abs(center[:2]) + 0.5 * cube_side))
    criteria = Criteria(bounds=(lo, hi), strokes=False)
    d, length, sized, check = _verified_design(base, region, center, r, (lo, hi), criteria,
                                               lower, objective, max_leg, samples,
                                               search_samples)
    notes: list[str] = []
    note = degenerate_note(length, cube_side, (lo, hi))
    if note:
        notes.append(note)
    q_min, q_max = check.q_range
    stroke = float((q_max - q_min).max())
    gci = evaluate_metrics(sized, region, criteria, ("gci",), search_samples)["gci"]
    sized = sized.with_params(q_min=tuple(q_min), q_max=tuple(q_max))
    return LinearDeltaSizing(
        cube_side=cube_side, center=center, bounds=(float(lo), float(hi)), objective=objective,
        R=float(d + r), r=float(r), L=float(length), d=float(d), q_min=q_min, q_max=q_max,
        stroke=stroke, compactness=cube_side / stroke, index_range=check.factor_range,
        gci=float(gci), check=check, machine=sized, notes=tuple(notes))
