"""Extrema of a motion's quantities over continuous time, not only at its output samples.

A sampled trajectory says nothing about what happens between its samples: with a coarse period
the peak speed of a circle falls between two samples, and a stroke can even read 0. Here the
quantities (actuator positions, speeds, accelerations, forces, powers, ...) are functions of
time that can be evaluated anywhere (:meth:`pkmkit.motion.Trajectory.at`), and their extrema are
found to a stated relative tolerance whatever the output period:

1. the time axis is cut at the motion's *breakpoints* (block ends, time-law phase changes,
   joints between segments: :meth:`~pkmkit.motion.Trajectory.breakpoints`); between two of
   them every quantity is analytic, so a jump or a kink can only sit on a cut;
2. each piece is sampled on a grid (at least 8 points a piece, spacing ≤ duration/512), its ends
   taken just inside the piece (the one-sided limits of a quantity that jumps there);
3. every local extremum of the grid that could be the global one (its value plus twice its
   rise over its neighbours reaches the grid's extreme — a bound on what a smooth peak between
   two grid points can add) is refined by a golden-section search between its neighbours;
4. the grid is refined (spacing halved) until two successive levels agree to the tolerance
   (default 10⁻⁴ of each quantity's range), so a peak narrower than the grid is not missed.

Limit checks use the same machinery: :func:`first_excursion` finds when a quantity first
exceeds a limit, and by how much at the peak of that excursion, between samples too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

#: Relative tolerance of the extrema (of each quantity's range over the motion).
DEFAULT_RTOL = 1e-4
#: Minimum grid points over the whole motion, and per piece between breakpoints.
MIN_POINTS = 512
MIN_PER_PIECE = 8
#: Grid levels tried before giving up on convergence.
MAX_LEVELS = 7
#: Golden-section iterations (each shrinks the bracket by 0.618: 0.618²⁸ ≈ 1.4e-6).
GOLDEN_ITERATIONS = 28
#: Points evaluated per call (memory bound of one evaluation).
EVAL_CHUNK = 65536

_GOLD = (math.sqrt(5.0) - 1.0) / 2.0

#: ``evaluate(t (M,)) -> {name: (M, k) array}``: every quantity at the times t.
Evaluate = Callable[[np.ndarray], dict[str, np.ndarray]]


@dataclass
class Extrema:
    """Extrema over continuous time of each quantity's columns.

    Attributes:
        low, high: ``{name: (k,)}`` smallest and largest values.
        t_low, t_high: ``{name: (k,)}`` when they are reached, s.
        rtol: tolerance the values are converged to (relative to each column's range).
        levels: grid levels used; ``converged`` False if the last two still disagreed.
        evaluations: points evaluated in all.
    """

    low: dict[str, np.ndarray]
    high: dict[str, np.ndarray]
    t_low: dict[str, np.ndarray]
    t_high: dict[str, np.ndarray]
    rtol: float
    levels: int
    converged: bool
    evaluations: int
    grid: _Grid = field(repr=False)
    evaluate: Evaluate = field(repr=False)

    def abs_max(self, name: str) -> np.ndarray:
        """``(k,)`` largest absolute value of each column."""
        return np.maximum(np.abs(self.low[name]), np.abs(self.high[name]))

    def range(self, name: str) -> np.ndarray:
        """``(k,)`` high − low."""
        return self.high[name] - self.low[name]


@dataclass
class _Grid:
    t: np.ndarray  # (M,)
    piece: np.ndarray  # (M,) index of the piece between breakpoints
    values: dict[str, np.ndarray]  # name -> (M, k)


def continuous_extrema(evaluate: Evaluate, breakpoints: np.ndarray, *,
                       rtol: float = DEFAULT_RTOL) -> Extrema:
    """Extrema over ``[breakpoints[0], breakpoints[-1]]`` of every quantity ``evaluate``
    returns (see the module docstring).

    Args:
        evaluate: the quantities at given times.
        breakpoints: sorted times where a quantity may jump or kink (first and last: the ends).
        rtol: relative tolerance (of each column's range; of its magnitude if constant).

    >>> import numpy as np
    >>> e = continuous_extrema(lambda t: {"s": np.sin(3 * t)[:, None]}, np.array([0.0, 2.0]))
    >>> round(float(e.high["s"][0]), 9), round(float(e.t_high["s"][0]), 4)  # π/6
    (1.0, 0.5236)
    """
    knots = np.unique(np.asarray(breakpoints, dtype=float))
    if knots.size < 2:
        knots = np.array([knots[0], knots[0]]) if knots.size else np.zeros(2)
    evaluations = 0
    previous = None
    result = None
    for level in range(MAX_LEVELS):
        grid = _make_grid(knots, level, evaluate)
        evaluations += len(grid.t)
        result, count = _refine_all(grid, evaluate)
        evaluations += count
        if previous is not None and _agree(previous, result, rtol):
            return _finish(result, grid, evaluate, rtol, level + 1, True, evaluations)
        previous = result
    return _finish(result, grid, evaluate, rtol, MAX_LEVELS, False, evaluations)


def _finish(result, grid, evaluate, rtol, levels, converged, evaluations) -> Extrema:
    low, t_low, high, t_high = result
    return Extrema(low=low, high=high, t_low=t_low, t_high=t_high, rtol=rtol, levels=levels,
                   converged=converged, evaluations=evaluations, grid=grid, evaluate=evaluate)


def _evaluate_chunked(evaluate: Evaluate, t: np.ndarray) -> dict[str, np.ndarray]:
    parts = [evaluate(t[i:i + EVAL_CHUNK]) for i in range(0, len(t), EVAL_CHUNK)]
    return {name: np.concatenate([p[name] for p in parts]).reshape(len(t), -1)
            for name in parts[0]}


def _make_grid(knots: np.ndarray, level: int, evaluate: Evaluate) -> _Grid:
    total = knots[-1] - knots[0]
    lengths = np.diff(knots)
    spacing = total / (MIN_POINTS * 2**level) if total > 0 else 1.0
    counts = np.maximum(MIN_PER_PIECE * 2**level,
                        np.ceil(lengths / spacing).astype(np.int64))
    piece = np.repeat(np.arange(len(lengths)), counts + 1)
    # position of each point within its piece, 0..count
    first = np.concatenate([[0], np.cumsum(counts + 1)[:-1]])
    k = np.arange(len(piece)) - first[piece]
    frac = k / counts[piece]
    # the ends just inside the piece: one-sided limits where a quantity jumps at a breakpoint
    inset = 1e-12
    frac = np.where(k == 0, inset, np.where(k == counts[piece], 1.0 - inset, frac))
    t = knots[piece] + frac * lengths[piece]
    return _Grid(t=t, piece=piece, values=_evaluate_chunked(evaluate, t))


def _candidates(v: np.ndarray, piece: np.ndarray, target: float) -> np.ndarray:
    """Interior grid indices of local maxima of ``v`` whose peak between the neighbours could
    reach ``target`` (the peak of a smooth function sampled at spacing h rises at most about
    its rise over a neighbour above the sample: twice that is the margin)."""
    if len(v) < 3:
        return np.zeros(0, dtype=np.int64)
    mid = v[1:-1]
    left, right = v[:-2], v[2:]
    same = (piece[1:-1] == piece[:-2]) & (piece[1:-1] == piece[2:])
    with np.errstate(invalid="ignore"):
        peak = same & (mid >= left) & (mid >= right)
        rise = np.maximum(mid - left, mid - right)
        hopeful = peak & (mid + 2.0 * rise >= target)
    return np.flatnonzero(hopeful) + 1


def _golden_max(evaluate: Evaluate, lo: np.ndarray, hi: np.ndarray,
                pick: Callable[[dict[str, np.ndarray], np.ndarray], np.ndarray]
                ) -> tuple[np.ndarray, np.ndarray, int]:
    """Vectorised golden-section maximisation of one column per bracket.

    ``pick(values, rows)`` extracts, from the evaluation at one point per bracket, the value of
    each bracket's own column. Returns the best value and time seen per bracket and the number
    of points evaluated.
    """
    a, b = lo.copy(), hi.copy()
    x1 = b - _GOLD * (b - a)
    x2 = a + _GOLD * (b - a)
    f1 = pick(_evaluate_chunked(evaluate, x1), np.arange(len(a)))
    f2 = pick(_evaluate_chunked(evaluate, x2), np.arange(len(a)))
    best = np.where(f1 >= f2, f1, f2)
    t_best = np.where(f1 >= f2, x1, x2)
    count = 2 * len(a)
    for _ in range(GOLDEN_ITERATIONS):
        left = f1 >= f2  # the maximum lies in [a, x2]; else in [x1, b]
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
        new_x = np.where(left, b - _GOLD * (b - a), a + _GOLD * (b - a))
        new_f = pick(_evaluate_chunked(evaluate, new_x), np.arange(len(a)))
        count += len(a)
        x1, x2 = np.where(left, new_x, x2), np.where(left, x1, new_x)
        f1, f2 = np.where(left, new_f, f2), np.where(left, f1, new_f)
        better = new_f > best
        best = np.where(better, new_f, best)
        t_best = np.where(better, new_x, t_best)
    return best, t_best, count


def _refine_all(grid: _Grid, evaluate: Evaluate):
    """Refined extrema of every column of every quantity."""
    names = list(grid.values)
    jobs = []  # (name, column, sign, grid index)
    for name in names:
        values = grid.values[name]
        for c in range(values.shape[1]):
            for sign in (1.0, -1.0):
                v = sign * values[:, c]
                finite = v[np.isfinite(v)]
                if finite.size == 0:
                    continue
                for i in _candidates(v, grid.piece, float(finite.max())):
                    jobs.append((name, c, sign, int(i)))
    refined: dict[tuple[str, int, float], tuple[float, float]] = {}
    count = 0
    if jobs:
        idx = np.array([j[3] for j in jobs])
        signs = np.array([j[2] for j in jobs])
        name_of = [j[0] for j in jobs]
        cols = np.array([j[1] for j in jobs])

        def pick(values: dict[str, np.ndarray], rows: np.ndarray) -> np.ndarray:
            out = np.empty(len(rows))
            for name in names:
                sel = np.array([n == name for n in name_of])
                if sel.any():
                    out[sel] = values[name][rows[sel], cols[sel]]
            return signs * out

        best, t_best, count = _golden_max(evaluate, grid.t[idx - 1], grid.t[idx + 1], pick)
        for (name, c, sign, _), value, t in zip(jobs, best, t_best, strict=True):
            key = (name, c, sign)
            if np.isfinite(value) and (key not in refined or value > refined[key][0]):
                refined[key] = (float(value), float(t))
    low, t_low, high, t_high = {}, {}, {}, {}
    for name in names:
        values = grid.values[name]
        k = values.shape[1]
        low[name], t_low[name] = np.full(k, np.nan), np.full(k, np.nan)
        high[name], t_high[name] = np.full(k, np.nan), np.full(k, np.nan)
        for c in range(k):
            for sign, ext, t_ext in ((1.0, high, t_high), (-1.0, low, t_low)):
                v = sign * values[:, c]
                if not np.isfinite(v).any():
                    continue
                i = int(np.nanargmax(v))
                best, t_best = float(v[i]), float(grid.t[i])
                if (name, c, sign) in refined and refined[(name, c, sign)][0] > best:
                    best, t_best = refined[(name, c, sign)]
                ext[name][c], t_ext[name][c] = sign * best, t_best
    return (low, t_low, high, t_high), count


def _agree(a, b, rtol: float) -> bool:
    low_a, _, high_a, _ = a
    low_b, _, high_b, _ = b
    for name in low_a:
        span = np.maximum(high_b[name] - low_b[name], 0.0)
        size = np.maximum(np.abs(high_b[name]), np.abs(low_b[name]))
        scale = np.where(span > 0, span, size)
        tol = rtol * np.where(scale > 0, scale, 1.0) * 0.1
        for x, y in ((low_a[name], low_b[name]), (high_a[name], high_b[name])):
            both = np.isfinite(x) & np.isfinite(y)
            if (np.isfinite(x) != np.isfinite(y)).any() or (np.abs(x - y)[both] > tol[both]).any():
                return False
    return True


@dataclass(frozen=True)
class Excursion:
    """When a quantity first leaves its limits.

    Attributes:
        t: s, when the limit is first exceeded (to the tolerance of a bisection).
        t_peak: s, when that excursion peaks.
        value: the quantity at the peak.
        excess: by how much it exceeds the limit there (> 0).
    """

    t: float
    t_peak: float
    value: float
    excess: float


def first_excursion(extrema: Extrema, name: str, column: int, lower: float,
                    upper: float) -> Excursion | None:
    """The first time column ``column`` of ``name`` leaves ``[lower, upper]``, over continuous
    time, or None if it never does (its extrema stay within, up to 10⁻¹² of the limit)."""
    found = []
    for sign, limit in ((1.0, upper), (-1.0, lower)):
        if not np.isfinite(limit):
            continue
        extreme = extrema.high[name][column] if sign > 0 else extrema.low[name][column]
        if not sign * (extreme - limit) > 1e-12 * max(abs(limit), 1.0):
            continue
        hit = _first_above(extrema, name, column, sign, sign * limit)
        if hit is not None:
            found.append(hit)
    if not found:
        return None
    return min(found, key=lambda e: e.t)


def _first_above(extrema: Extrema, name: str, column: int, sign: float,
                 level: float) -> Excursion | None:
    grid, evaluate = extrema.grid, extrema.evaluate
    v = sign * grid.values[name][:, column]

    def value_at(t: float) -> float:
        return float(sign * _evaluate_chunked(evaluate, np.array([t]))[name][0, column])

    with np.errstate(invalid="ignore"):
        above = np.flatnonzero(v > level)
    events = [(float(grid.t[k]), float(v[k])) for k in above[:1]]
    peaks = _candidates(v, grid.piece, level)
    refined: list[tuple[float, float]] = []
    if peaks.size:

        def pick(values: dict[str, np.ndarray], rows: np.ndarray) -> np.ndarray:
            return sign * values[name][rows, column]

        best, t_best, _ = _golden_max(evaluate, grid.t[peaks - 1], grid.t[peaks + 1], pick)
        refined = [(float(t), float(f)) for t, f in zip(t_best, best, strict=True) if f > level]
        events += refined[:1] if refined else []
    if not events:
        return None
    t_event = min(t for t, _ in events)
    # the crossing: between the last grid point before the event (at or below the level) and
    # the event, when both lie in the same piece; else the excursion starts at a breakpoint
    after = int(np.searchsorted(grid.t, t_event, side="left"))
    before = after - 1
    if before >= 0 and after < len(v) and grid.piece[before] == grid.piece[after] \
            and v[before] <= level:
        lo_t, hi_t = float(grid.t[before]), t_event
        for _ in range(60):
            mid = 0.5 * (lo_t + hi_t)
            lo_t, hi_t = (lo_t, mid) if value_at(mid) > level else (mid, hi_t)
        t_cross = hi_t
    else:
        t_cross = t_event
    # the peak of this excursion: grid points and refined peaks until it falls back below
    end = after
    while end < len(v) and v[end] > level:
        end += 1
    t_end = float(grid.t[end]) if end < len(v) else math.inf
    window = [(float(v[k]), float(grid.t[k])) for k in range(after, min(end, len(v)))]
    window += [(f, t) for t, f in refined if t_cross <= t <= t_end]
    window += [(f, t) for t, f in events if t == t_event]
    value, t_peak = max(window)
    return Excursion(t=float(t_cross), t_peak=t_peak, value=sign * value, excess=value - level)


@dataclass(frozen=True)
class Span:
    """One excursion of a quantity beyond a limit.

    Attributes:
        start, end: s, when it leaves and comes back within the limit (bisected between the
            grid points; a breakpoint where the quantity jumps; the motion's end if it never
            comes back).
        t_peak: s, when the excess is largest.
        value: the quantity there.
        excess: the largest excess (> 0), in the quantity's unit.
    """

    start: float
    end: float
    t_peak: float
    value: float
    excess: float


def all_excursions(extrema: Extrema, name: str, column: int, lower: float,
                   upper: float) -> list[Span]:
    """Every excursion of column ``column`` of ``name`` beyond ``[lower, upper]`` over
    continuous time, in time order (see the module docstring): the runs of the refined grid
    where the excess ``max(lower − v, v − upper)`` is positive, and peaks narrower than the
    grid, each with its span and its worst excess (golden-section refined)."""
    grid, evaluate = extrema.grid, extrema.evaluate
    values = grid.values[name][:, column]
    high, low = extrema.high[name][column], extrema.low[name][column]
    floor = 1e-12 * max(abs(lower) if np.isfinite(lower) else 0.0,
                        abs(upper) if np.isfinite(upper) else 0.0, 1.0)
    if not (high - upper > floor or lower - low > floor):
        return []

    def excess_of(v: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return np.maximum(lower - v, v - upper)

    def excess_at(t: np.ndarray) -> np.ndarray:
        return excess_of(_evaluate_chunked(evaluate, t)[name][:, column])

    e = excess_of(values)
    over = e > floor
    # narrow peaks between grid points: refined local maxima of the excess that cross
    peaks = _candidates(e, grid.piece, floor)
    if peaks.size:
        best, t_best, _ = _golden_max(evaluate, grid.t[peaks - 1], grid.t[peaks + 1],
                                      lambda vals, rows: excess_of(vals[name][rows, column]))
    else:
        best, t_best = np.zeros(0), np.zeros(0)
    narrow = [(float(t), float(b), int(k)) for t, b, k in zip(t_best, best, peaks, strict=True)
              if b > floor]
    for _, _, k in narrow:  # a peak between grid points joins (or makes) a run
        over[k] = True
    runs = _runs(over)
    if not runs:
        return []
    # crossings, bisected in batch where the neighbour lies in the same piece
    m = len(e)
    starts = np.array([a for a, _ in runs])
    ends = np.array([b for _, b in runs])
    lo_in = (starts > 0) & (grid.piece[np.maximum(starts - 1, 0)] == grid.piece[starts])
    hi_in = (ends < m - 1) & (grid.piece[np.minimum(ends + 1, m - 1)] == grid.piece[ends])
    # a run's first (last) point over the limit: its grid point, or the refined peak of a
    # narrow excursion whose grid point stays below
    peak_at = {k: t for t, _, k in narrow}
    first_over = np.array([grid.t[a] if e[a] > floor else peak_at[a] for a in starts])
    last_over = np.array([grid.t[b] if e[b] > floor else peak_at[b] for b in ends])
    t_start = _bisect(excess_at, grid.t[np.maximum(starts - 1, 0)], first_over, lo_in,
                      floor, rising=True)
    t_end = _bisect(excess_at, last_over, grid.t[np.minimum(ends + 1, m - 1)], hi_in,
                    floor, rising=False)
    t_end = np.where(ends == m - 1, grid.t[-1], t_end)
    out = []
    for r, (a, b) in enumerate(runs):
        k = a + int(np.argmax(e[a:b + 1]))
        peak, t_peak = float(e[k]), float(grid.t[k])
        for t, f, j in narrow:
            if a <= j <= b and f > peak:
                peak, t_peak = f, t
        value = float(_evaluate_chunked(evaluate, np.array([t_peak]))[name][0, column])
        out.append(Span(start=float(t_start[r]), end=float(t_end[r]), t_peak=t_peak,
                        value=value, excess=peak))
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[(first, last)]`` index ranges of the True runs of ``mask``."""
    if not mask.any():
        return []
    padded = np.concatenate([[False], mask, [False]]).astype(np.int8)
    edges = np.diff(padded)
    return list(zip(np.flatnonzero(edges == 1).tolist(),
                    (np.flatnonzero(edges == -1) - 1).tolist(), strict=True))


def _bisect(excess_at: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray,
            active: np.ndarray, floor: float, *, rising: bool) -> np.ndarray:
    """Times where the excess crosses ``floor`` between ``lo`` and ``hi`` (batched bisection);
    where not ``active``, ``hi`` for a rising crossing (the run starts at its first grid point)
    and ``lo`` for a falling one."""
    lo, hi = lo.astype(float).copy(), hi.astype(float).copy()
    fixed = np.where(active, np.nan, hi if rising else lo)
    if active.any():
        a, b = lo[active], hi[active]
        for _ in range(50):
            mid = 0.5 * (a + b)
            inside = excess_at(mid) > floor
            # rising: over at mid → the crossing is before; falling: over at mid → after
            if rising:
                b, a = np.where(inside, mid, b), np.where(inside, a, mid)
            else:
                a, b = np.where(inside, mid, a), np.where(inside, b, mid)
        fixed[active] = b if rising else a
    return fixed
