"""Time laws along a path: constant feed with acceleration and jerk limits.

The path is cut into *blocks* at every corner (tangent discontinuity, however small: a polyline
stops at each vertex), wherever the feed or the move type (rapid / feed) changes and — for the
jerk-limited profile — wherever the curvature vector jumps (a line meeting an arc, another radius
or plane, an S-bend: the normal acceleration would jump, an unbounded jerk); the tool stops at
block ends (exact stop), which is what makes the limits hold through corners. Zero-length
segments are dropped. Each block runs a
rest-to-rest profile of its arc length:

- ``"trapezoid"``: acceleration-limited (piecewise-constant acceleration);
- ``"scurve"``: jerk-limited seven-phase profile (piecewise-constant jerk), with the cases where
  the acceleration or the speed limit is not reached.

On curved blocks the tool also accelerates towards the centre (v²κ) and that acceleration turns:
the jerk is (ȧ_t − v³κ²) T + 3 v a_t κ N + v³κτ B on a helix of curvature κ and torsion τ. The
block's speed and tangential limits are reduced so that the *total* acceleration ≤ A and jerk ≤ J:
tangential acceleration ≤ (√3/2)A with normal ≤ A/2, and |ȧ_t|, v³κ², 3 v a_t κ, v³κτ ≤ J/3 each
(|jerk| ≤ (√6/3) J).

Sampling at a fixed period gives positions, velocities and accelerations from the analytic path
derivatives: ẋ = x'(s) ṡ, ẍ = x''(s) ṡ² + x'(s) s̈.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.motion.paths import Path
from pkmkit.numerics.arrays import real

PROFILES = ("trapezoid", "scurve")


@dataclass(frozen=True)
class Profile:
    """Rest-to-rest motion over a distance: phases of constant jerk.

    Attributes:
        distance: m.
        durations: ``(k,)`` phase durations, s.
        accel0: ``(k,)`` acceleration at each phase start, m/s².
        jerk: ``(k,)`` jerk in each phase, m/s³.
        peak_speed: m/s.
    """

    distance: float
    durations: np.ndarray
    accel0: np.ndarray
    jerk: np.ndarray
    peak_speed: float

    @property
    def duration(self) -> float:
        return float(self.durations.sum())

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """s, ṡ, s̈ at times ``t`` (clipped to [0, duration])."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        starts = np.concatenate([[0.0], np.cumsum(self.durations)[:-1]])
        s0 = np.zeros(len(self.durations))
        v0 = np.zeros(len(self.durations))
        for k in range(1, len(self.durations)):
            d, a, j = self.durations[k - 1], self.accel0[k - 1], self.jerk[k - 1]
            v0[k] = v0[k - 1] + a * d + j * d**2 / 2
            s0[k] = s0[k - 1] + v0[k - 1] * d + a * d**2 / 2 + j * d**3 / 6
        phase = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(starts) - 1)
        tau = t - starts[phase]
        a, j = self.accel0[phase], self.jerk[phase]
        s = s0[phase] + v0[phase] * tau + a * tau**2 / 2 + j * tau**3 / 6
        v = v0[phase] + a * tau + j * tau**2 / 2
        acc = a + j * tau
        return np.minimum(s, self.distance), v, acc


def trapezoid(distance: float, speed: float, accel: float) -> Profile:
    """Acceleration-limited rest-to-rest profile."""
    t_acc = speed / accel
    if speed * t_acc >= distance:  # triangular
        t_acc = math.sqrt(distance / accel)
        speed = accel * t_acc
        cruise = 0.0
    else:
        cruise = (distance - speed * t_acc) / speed
    durations = np.array([t_acc, cruise, t_acc])
    return Profile(distance, durations, np.array([accel, 0.0, -accel]), np.zeros(3), speed)


def scurve(distance: float, speed: float, accel: float, jerk: float) -> Profile:
    """Jerk-limited (seven-phase) rest-to-rest profile."""

    def accel_phase(v: float) -> tuple[float, float, float]:
        """(jerk time, constant-acceleration time, peak acceleration) to reach speed v."""
        if v * jerk >= accel**2:
            return accel / jerk, v / accel - accel / jerk, accel
        a = math.sqrt(v * jerk)
        return a / jerk, 0.0, a

    def accel_distance(v: float) -> float:
        tj, ta, _ = accel_phase(v)
        return v * (2 * tj + ta) / 2  # symmetric: average speed v/2

    v = speed
    if 2 * accel_distance(v) > distance:  # the speed limit is not reached: bisect the peak
        lo, hi = 0.0, v
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if 2 * accel_distance(mid) <= distance else (lo, mid)
        v = lo
    tj, ta, a = accel_phase(v)
    cruise = max(distance - 2 * accel_distance(v), 0.0) / v if v > 0 else 0.0
    durations = np.array([tj, ta, tj, cruise, tj, ta, tj])
    accel0 = np.array([0.0, a, a, 0.0, 0.0, -a, -a])
    jerks = np.array([jerk, 0.0, -jerk, 0.0, -jerk, 0.0, jerk])
    return Profile(distance, durations, accel0, jerks, v)


@dataclass(frozen=True)
class Block:
    """Tangent-continuous run of segments with one feed, traversed rest to rest."""

    segments: tuple[int, ...]
    lengths: np.ndarray
    profile: Profile
    rapid: bool
    speed_limit: float


@dataclass(frozen=True)
class Trajectory:
    """A path sampled in time.

    Attributes:
        t: ``(N,)`` s.
        x, xd, xdd: ``(N, 3)`` position (m), velocity (m/s), acceleration (m/s²).
        segment: ``(N,)`` index of the path segment of each sample.
        rapid: ``(N,)`` sample on a rapid move.
        blocks: the motion blocks.
        path: the path.
        period: sampling period, s.
    """

    t: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    xdd: np.ndarray
    segment: np.ndarray
    rapid: np.ndarray
    blocks: tuple[Block, ...]
    path: Path
    period: float

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def length(self) -> float:
        return self.path.length

    def at(self, t: np.ndarray) -> Trajectory:
        """The same motion evaluated at the times ``t`` ``(M,)`` s (clipped to [0, duration]),
        whatever the sampling period: positions, velocities and accelerations of the continuous
        time law."""
        t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, self.duration)
        if self.blocks:
            return _evaluate_blocks(self.path, self.blocks, t, self.period)
        return _constant_speed_at(self.path, self.length / self.duration, t, self.period)

    def breakpoints(self) -> np.ndarray:
        """Sorted times (s, from 0 to the duration) where the motion may be non-smooth: block
        ends, the time law's phase changes (a jump of the acceleration or of the jerk) and the
        joints between segments (a jump of the curvature). Between two consecutive breakpoints
        every quantity of the motion is an analytic function of time."""
        if not self.blocks:
            lengths = np.array([seg.length for seg in self.path.segments])
            times = np.concatenate([[0.0], np.cumsum(lengths)]) * (self.duration / lengths.sum())
            return np.unique(np.clip(times, 0.0, self.duration))
        times = [np.zeros(1)]
        start = 0.0
        for block in self.blocks:
            prof = block.profile
            times.append(start + np.cumsum(prof.durations))
            joints = np.cumsum(block.lengths)[:-1]
            if joints.size:
                times.append(start + _times_at_distances(prof, joints))
            start += prof.duration
        return np.unique(np.clip(np.concatenate(times), 0.0, self.duration))


def _times_at_distances(profile: Profile, distances: np.ndarray) -> np.ndarray:
    """Times at which a rest-to-rest profile has covered ``distances`` (bisection: s(t) is
    non-decreasing)."""
    lo = np.zeros(len(distances))
    hi = np.full(len(distances), profile.duration)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = profile.evaluate(mid)[0] < distances
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return 0.5 * (lo + hi)


def _corner(a, b, tol: float) -> bool:
    ta, tb = a.tangent(end=True), b.tangent(end=False)
    cos = float(np.dot(ta, tb) / (np.linalg.norm(ta) * np.linalg.norm(tb)))
    return cos < math.cos(tol)


def _curvature_jump(a, b) -> bool:
    """The curvature vector x'' differs across the joint (line ↔ arc, another radius, plane or
    turning direction — an S-bend): the normal acceleration would jump, an unbounded jerk."""
    ka = a.evaluate(np.array([a.length]))[2][0]
    kb = b.evaluate(np.array([0.0]))[2][0]
    scale = max(np.linalg.norm(ka), np.linalg.norm(kb))
    return bool(np.linalg.norm(ka - kb) > 1e-9 * scale) if scale > 0 else False


#: Segments shorter than this (m) are dropped by the planner: they carry no motion.
MIN_SEGMENT = 1e-12


def _limit(value, name: str, largest: float) -> float:
    """A limit > 0 (SI), at least 1e-9 and at most ``largest`` (else a unit mistake)."""
    value = real(value, name, positive=True, limit=largest)
    if value < 1e-9:
        raise InputError(f"{name} = {value:g} is below 1e-9 (SI units); check the units")
    return value


#: Default S-curve jerk per unit of acceleration (1/s) when no jerk is given: the acceleration
#: builds up in 0.1 s — the ratio of seed 000's examples (1000 mm/s², 10000 mm/s³) and a
#: common CNC jerk time.
DEFAULT_JERK_PER_ACCEL = 10.0


def plan(path: Path, *, feed: float, accel: float, jerk: float | None = None,
         profile: str = "scurve", rapid_feed: float | None = None, period: float = 0.01,
         corner_tol: float = 1e-6, max_samples: int = 5_000_000) -> Trajectory:
    """Time law along ``path`` and its samples every ``period`` seconds.

    The tool stops exactly at every corner: a polyline approximating a curve stops at each
    vertex (send arcs, G2/G3, to move through curves at feed); corner blending is not done.

    Args:
        path: the path.
        feed: default feed rate (m/s) for feed moves without a programmed one.
        accel: acceleration limit A (m/s²), on the total Cartesian acceleration.
        jerk: jerk limit J (m/s³) of ``"scurve"`` (default :data:`DEFAULT_JERK_PER_ACCEL` ×
            accel); ignored by ``"trapezoid"``.
        profile: ``"scurve"`` or ``"trapezoid"``.
        rapid_feed: speed of rapid moves (default: 5 × feed).
        period: sampling period (s).
        corner_tol: tangent angle (rad) above which a joint between segments is a corner (the
            default only absorbs rounding: the velocity jump v·angle it lets through is
            negligible).
        max_samples: refuse plans that would need more samples.

    Raises:
        InputError: non-positive limits or period, a path of zero length, too
            many samples, a time law that is not finite.

    Example: seed 000's Ø300 mm circle at 120 mm/s, A = 1 m/s², J = 10 m/s³.

    >>> from pkmkit.motion import circle, plan
    >>> traj = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=0.01)
    >>> round(traj.duration, 4), traj.x.shape
    (8.2335, (825, 3))
    >>> speed = traj.at([4.0]).xd[0]  # the velocity at any time, between samples too
    >>> round(float(np.linalg.norm(speed)), 9)
    0.12
    """
    # beyond these limits a value is a unit mistake (and its powers overflow)
    feed = _limit(feed, "feed", 1e4)
    accel = _limit(accel, "accel", 1e7)
    period = _limit(period, "period", 1e4)
    if profile not in PROFILES:
        raise InputError(f"unknown profile {profile!r}; use {' or '.join(PROFILES)}")
    if profile == "scurve" and jerk is None:
        jerk = DEFAULT_JERK_PER_ACCEL * accel
    if profile == "scurve":
        jerk = _limit(jerk, "the S-curve's jerk limit", 1e11)
    if profile == "trapezoid":
        jerk = None
    rapid_feed = _limit(5.0 * feed if rapid_feed is None else rapid_feed, "rapid feed", 1e4)
    segs = path.segments
    moving = [k for k in range(len(segs)) if segs[k].length > MIN_SEGMENT]
    if not moving:
        raise InputError("the path has zero length")

    def speed_of(k: int) -> float:
        seg = segs[k]
        return rapid_feed if seg.rapid else (seg.feed or feed)

    blocks = [_block(segs, group, speed_of(group[0]), accel, jerk, profile)
              for group in _groups(segs, moving, speed_of, corner_tol, jerk)]
    total = sum(b.profile.duration for b in blocks)
    if total / period + 1 > max_samples:
        raise InputError(f"{total:.6g} s at a {period:g} s period needs more than "
                         f"{max_samples} samples; increase the period")
    return _sample(path, tuple(blocks), period)


def _groups(segs, moving: list[int], speed_of, corner_tol: float,
            jerk: float | None) -> list[list[int]]:
    """Consecutive moving segments joined into blocks without a stop: same motion type and
    speed, no corner, and (S-curve) no curvature jump."""
    groups: list[list[int]] = [[moving[0]]]
    for k in moving[1:]:
        prev = segs[groups[-1][-1]]
        if (segs[k].rapid != prev.rapid or speed_of(k) != speed_of(groups[-1][-1])
                or _corner(prev, segs[k], corner_tol)
                or (jerk is not None and _curvature_jump(prev, segs[k]))):
            groups.append([k])
        else:
            groups[-1].append(k)
    return groups


def _block_speed(v: float, accel: float, a_t: float, jerk: float | None, kappa: float,
                 tau: float) -> float:
    """The block's speed ``v`` (m/s) lowered so that the centripetal acceleration and, for an
    S-curve, the jerk of a helix of curvature ``kappa`` and torsion ``tau`` (1/m) stay within
    the limits."""
    if kappa > 0:
        v = min(v, math.sqrt(accel / 2 / kappa))
        if jerk is not None:
            # jerk on a helix: (ȧ_t − v³κ²) T + 3 v a_t κ N + v³ κ τ B; each of
            # |ȧ_t|, v³κ², 3 v a_t κ and v³κτ ≤ J/3 keeps |jerk| ≤ √(6)/3 J < J
            v = min(v, (jerk / 3 / kappa**2) ** (1 / 3), jerk / 9 / (a_t * kappa))
            if tau > 0:
                v = min(v, (jerk / 3 / (kappa * tau)) ** (1 / 3))
    return v


def _block(segs, group: list[int], v: float, accel: float, jerk: float | None,
           profile: str) -> Block:
    """The time law of one block of segments ``group`` at programmed speed ``v`` (m/s)."""
    lengths = np.array([segs[k].length for k in group])
    kappa = max(segs[k].curvature for k in group)
    tau = max(segs[k].torsion for k in group)
    if kappa > 1e9 or tau > 1e9:
        raise InputError(f"segment {group[0] + 1} curves with a radius below 1 nm; check "
                         "the units")
    a_t = accel * (math.sqrt(3) / 2 if kappa > 0 else 1.0)
    j_t = None if jerk is None else jerk / (3.0 if kappa > 0 else 1.0)
    v = _block_speed(v, accel, a_t, jerk, kappa, tau)
    try:
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            prof = (trapezoid(float(lengths.sum()), v, a_t) if profile == "trapezoid"
                    else scurve(float(lengths.sum()), v, a_t, j_t))
    except (OverflowError, ZeroDivisionError, FloatingPointError):
        prof = None
    if prof is None or not (np.isfinite(prof.durations).all() and prof.duration > 0
                            and np.isfinite(prof.peak_speed)):
        raise InputError(
            f"the time law of a {float(lengths.sum()):.6g} m block is not finite with feed "
            f"{v:g} m/s, acceleration {a_t:g} m/s² and jerk "
            f"{'-' if j_t is None else f'{j_t:g}'} m/s³: the limits are too far apart")
    return Block(tuple(group), lengths, prof, segs[group[0]].rapid, v)

def _sample(path: Path, blocks: tuple[Block, ...], period: float) -> Trajectory:
    starts = np.concatenate([[0.0], np.cumsum([b.profile.duration for b in blocks])])
    n = math.floor(starts[-1] / period + 1e-9) + 1
    t = np.arange(n) * period
    if t[-1] < starts[-1] - 1e-12:
        t = np.append(t, starts[-1])
    return _evaluate_blocks(path, blocks, t, period)


def _evaluate_blocks(path: Path, blocks: tuple[Block, ...], t: np.ndarray,
                     period: float) -> Trajectory:
    """The planned motion at times ``t`` (s, within [0, duration])."""
    starts = np.concatenate([[0.0], np.cumsum([b.profile.duration for b in blocks])])
    x = np.empty((len(t), 3))
    xd = np.empty_like(x)
    xdd = np.empty_like(x)
    segment = np.empty(len(t), dtype=int)
    rapid = np.empty(len(t), dtype=bool)
    which = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(blocks) - 1)
    for b, block in enumerate(blocks):
        rows = np.flatnonzero(which == b)
        if rows.size == 0:
            continue
        s, sd, sdd = block.profile.evaluate(t[rows] - starts[b])
        bounds = np.concatenate([[0.0], np.cumsum(block.lengths)])
        local = np.clip(np.searchsorted(bounds, s, side="right") - 1, 0, len(block.lengths) - 1)
        for j, k in enumerate(block.segments):
            sel = local == j
            if not sel.any():
                continue
            seg = path.segments[k]
            p, dp, ddp = seg.evaluate(np.clip(s[sel] - bounds[j], 0.0, seg.length))
            r = rows[sel]
            x[r] = p
            xd[r] = dp * sd[sel, None]
            xdd[r] = ddp * sd[sel, None] ** 2 + dp * sdd[sel, None]
            segment[r] = k
        rapid[rows] = block.rapid
    return Trajectory(t=t, x=x, xd=xd, xdd=xdd, segment=segment, rapid=rapid, blocks=blocks,
                      path=path, period=period)


def constant_speed(path: Path, *, speed: float, period: float) -> Trajectory:
    """The path at a constant speed from the first sample to the last — no start or stop ramp,
    as in a textbook (or the seeds' MATLAB) trajectory ``x = x0 + v t``: ẍ is only the
    centripetal part on arcs. The velocity jumps from and to rest at the ends, so use it to
    reproduce such studies, not to drive a machine (see :func:`plan`).

    Raises:
        InputError: non-positive speed or period, a path of zero length.
    """
    for name, value in (("speed", speed), ("period", period)):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"{name} must be > 0, got {value}")
    lengths = np.array([seg.length for seg in path.segments])
    if lengths.sum() <= MIN_SEGMENT:
        raise InputError("the path has zero length")
    duration = float(lengths.sum()) / speed
    n = math.floor(duration / period + 1e-9) + 1
    t = np.arange(n) * period
    if t[-1] < duration - 1e-12:
        t = np.append(t, duration)
    return _constant_speed_at(path, speed, t, period)


def _constant_speed_at(path: Path, speed: float, t: np.ndarray, period: float) -> Trajectory:
    lengths = np.array([seg.length for seg in path.segments])
    s = np.minimum(speed * t, lengths.sum())
    bounds = np.concatenate([[0.0], np.cumsum(lengths)])
    which = np.clip(np.searchsorted(bounds, s, side="right") - 1, 0, len(lengths) - 1)
    x, xd, xdd = (np.empty((len(t), 3)) for _ in range(3))
    for k, seg in enumerate(path.segments):
        rows = np.flatnonzero(which == k)
        if rows.size == 0 or seg.length <= MIN_SEGMENT:
            continue
        p, dp, ddp = seg.evaluate(np.clip(s[rows] - bounds[k], 0.0, seg.length))
        x[rows], xd[rows], xdd[rows] = p, dp * speed, ddp * speed**2
    return Trajectory(t=t, x=x, xd=xd, xdd=xdd, segment=which,
                      rapid=np.array([path.segments[k].rapid for k in which]), blocks=(),
                      path=path, period=period)
