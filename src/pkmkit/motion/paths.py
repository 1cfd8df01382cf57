"""Tool paths: straight lines, circular arcs and helices, chained into a :class:`Path`.

Every segment is parameterised by its arc length s ∈ [0, length] with analytic first and second
derivatives x'(s), x''(s), so velocities and accelerations along a trajectory are exact (no finite
differences). Coordinates are 3-D (metres); a planar machine uses x and y.

Builders: :func:`line`, :func:`arc`, :func:`circle`, :func:`helix`, :func:`raster` (facing a
rectangle in one-way or zig-zag passes). G-code is read by :mod:`pkmkit.motion.gcode`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.arrays import real

#: Largest coordinate or length of a path, m (beyond: a unit mistake, and squares overflow).
MAX_PATH_LENGTH = 1e6
#: Smallest arc radius, m (below, curvatures and their powers overflow).
MIN_RADIUS = 1e-9
#: Shortest move of a generated path (facing passes, step-overs, retracts), m.
MIN_MOVE = 1e-9

#: Most segments a path may hold: each is a Python object (about :data:`SEGMENT_BYTES`), and
#: a longer path would exhaust memory before it is even sampled.
MAX_SEGMENTS = 2_000_000
#: Approximate memory of one segment (object, arrays), bytes.
SEGMENT_BYTES = 1000


def _vec3(value, what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be 2 or 3 finite coordinates, got {value!r}") from None
    if arr.size == 2:
        arr = np.append(arr, 0.0)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise InputError(f"{what} must be 2 or 3 finite coordinates, got {value!r}")
    if np.abs(arr).max() > MAX_PATH_LENGTH:
        raise InputError(f"{what} {arr.tolist()} lies beyond {MAX_PATH_LENGTH:g} m; check the "
                         "units")
    return arr


@dataclass(frozen=True)
class Line:
    """Straight segment from ``start`` to ``end`` (``(3,)`` m); ``rapid`` marks positioning moves
    (G0), ``feed`` a programmed feed rate (m/s, None for the default)."""

    start: np.ndarray
    end: np.ndarray
    rapid: bool = False
    feed: float | None = None

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    def evaluate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, x', x'' at arc lengths ``s (k,)``, each ``(k, 3)``."""
        t = (self.end - self.start) / self.length
        x = self.start + np.outer(s, t)
        return x, np.tile(t, (len(s), 1)), np.zeros((len(s), 3))

    @property
    def curvature(self) -> float:
        return 0.0

    @property
    def torsion(self) -> float:
        return 0.0

    def tangent(self, end: bool) -> np.ndarray:
        return (self.end - self.start) / self.length


@dataclass(frozen=True)
class Arc:
    """Circular arc or helix: centre ``center``, radius, in the plane spanned by ``e1``, ``e2``
    (unit, orthogonal; ``normal = e1 × e2``), from angle ``phi0`` through ``sweep`` (signed, rad,
    positive counter-clockwise about ``normal``), advancing ``rise`` (m) along ``normal``.
    ``feed``: programmed feed rate (m/s), None for the default."""

    center: np.ndarray
    radius: float
    e1: np.ndarray
    e2: np.ndarray
    phi0: float
    sweep: float
    rise: float = 0.0
    rapid: bool = False
    feed: float | None = None

    def __post_init__(self) -> None:
        if not MIN_RADIUS <= self.radius <= MAX_PATH_LENGTH:
            raise InputError(f"an arc radius of {self.radius:g} m is outside [{MIN_RADIUS:g}, "
                             f"{MAX_PATH_LENGTH:g}] m; check the units")

    @property
    def normal(self) -> np.ndarray:
        return np.cross(self.e1, self.e2)

    @property
    def length(self) -> float:
        return float(math.hypot(self.radius * self.sweep, self.rise))

    @property
    def curvature(self) -> float:
        """Curvature of the (helical) arc, 1/m."""
        dphi = self.sweep / self.length
        return self.radius * dphi**2

    @property
    def torsion(self) -> float:
        """|Torsion| of the helix (0 for a plane arc), 1/m."""
        return abs(self.rise * self.sweep) / self.length**2

    def evaluate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        dphi = self.sweep / self.length
        phi = self.phi0 + dphi * s
        c, sn = np.cos(phi)[:, None], np.sin(phi)[:, None]
        radial = c * self.e1 + sn * self.e2
        tangential = -sn * self.e1 + c * self.e2
        axial = (self.rise / self.length) * self.normal
        x = self.center + self.radius * radial + np.outer(s * self.rise / self.length,
                                                          self.normal)
        dx = self.radius * dphi * tangential + axial
        ddx = -self.radius * dphi**2 * radial
        return x, dx, ddx

    def tangent(self, end: bool) -> np.ndarray:
        s = np.array([self.length if end else 0.0])
        return self.evaluate(s)[1][0]

    @property
    def start(self) -> np.ndarray:
        return self.evaluate(np.zeros(1))[0][0]

    @property
    def end(self) -> np.ndarray:
        return self.evaluate(np.array([self.length]))[0][0]


Segment = Line | Arc


@dataclass(frozen=True)
class Path:
    """A chain of segments; ``source`` lines (e.g. G-code line numbers) and ``blocks`` (the
    text of those lines, without comments) per segment, when the path was read from a
    program."""

    segments: tuple[Segment, ...]
    source: tuple[int, ...] = field(default=())
    blocks: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.segments:
            raise InputError("the path has no segment")

    @property
    def length(self) -> float:
        """Total length (rapid moves included), m."""
        return float(sum(seg.length for seg in self.segments))

    @property
    def cutting_length(self) -> float:
        """Length of the feed (non-rapid) moves, m."""
        return float(sum(seg.length for seg in self.segments if not seg.rapid))

    def sample(self, spacing: float) -> np.ndarray:
        """Points every ``spacing`` m (and every segment end), ``(k, 3)``."""
        pts = []
        for seg in self.segments:
            n = max(2, math.ceil(seg.length / spacing) + 1)
            pts.append(seg.evaluate(np.linspace(0.0, seg.length, n))[0])
        return np.concatenate(pts)


def _basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = normal / np.linalg.norm(normal)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, n)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def line(start, end, *, rapid: bool = False) -> Path:
    """A straight path."""
    a, b = _vec3(start, "line start"), _vec3(end, "line end")
    if np.linalg.norm(b - a) == 0:
        raise InputError("a line needs distinct start and end points")
    return Path((Line(a, b, rapid),))


#: Arcs whose start and end radii differ by at most this fraction of the radius, or by
#: :data:`ARC_ABS_TOL` (m), are accepted (rounded CAM output); their centre is then moved onto the
#: chord's perpendicular bisector so the arc ends exactly at the programmed point.
ARC_REL_TOL = 1e-3
ARC_ABS_TOL = 5e-6


def arc_through(start, end, center, normal, *, clockwise: bool, full_turns: int = 0,
                rapid: bool = False, tol: float = ARC_REL_TOL, abs_tol: float = ARC_ABS_TOL,
                feed: float | None = None, units: tuple[str, float] = ("m", 1.0)) -> Arc:
    """Arc from ``start`` to ``end`` about ``center`` in the plane of ``normal`` (any motion
    along ``normal`` becomes a helical rise), as G-code G2 (clockwise) / G3 describe it.

    Args:
        tol, abs_tol: accepted difference between the start and end radii, relative and
            absolute (m): the larger applies.
        units: (name, metres per unit) for error messages.

    Raises:
        InputError: radii at start and end differing by more than the tolerance, zero radius.
    """
    start, end, center = (_vec3(v, w) for v, w in ((start, "arc start"), (end, "arc end"),
                                                   (center, "arc centre")))
    n = _vec3(normal, "arc normal")
    n = n / np.linalg.norm(n)
    rise = float(np.dot(end - start, n))

    def in_plane(v: np.ndarray) -> np.ndarray:
        return v - np.dot(v, n) * n

    rs_p, re_p = in_plane(start - center), in_plane(end - center)
    r0, r1 = np.linalg.norm(rs_p), np.linalg.norm(re_p)
    if r0 == 0:
        raise InputError("the arc has zero radius (start point on the centre)")
    if abs(r0 - r1) > max(tol * r0, abs_tol):
        name, scale = units
        raise InputError(f"inconsistent arc: radius {r0 / scale:.9g} {name} at the start but "
                         f"{r1 / scale:.9g} {name} at the end")
    chord = re_p - rs_p
    if np.linalg.norm(chord) > 0 and r0 != r1:
        # move the centre onto the chord's perpendicular bisector: both radii become equal
        u = chord / np.linalg.norm(chord)
        center = center + np.dot(rs_p + 0.5 * chord, u) * u
        rs_p, re_p = in_plane(start - center), in_plane(end - center)
        r0 = np.linalg.norm(rs_p)
    e1 = rs_p / r0
    e2 = np.cross(n, e1)
    angle = math.atan2(float(np.dot(re_p, e2)), float(np.dot(re_p, e1)))
    if clockwise:
        sweep = angle - 2 * math.pi if angle > 1e-12 else angle
        if abs(angle) <= 1e-12:
            sweep = -2 * math.pi
        sweep -= 2 * math.pi * full_turns
    else:
        sweep = angle + 2 * math.pi if angle < -1e-12 else angle
        if abs(angle) <= 1e-12:
            sweep = 2 * math.pi
        sweep += 2 * math.pi * full_turns
    center_in_plane = center + np.dot(start - center, n) * n
    return Arc(center_in_plane, float(r0), e1, e2, 0.0, float(sweep), rise, rapid, feed)


def circle(center, radius: float, *, normal=(0, 0, 1), start_angle: float = 0.0,
           clockwise: bool = False) -> Path:
    """A full circle (one turn), starting at ``start_angle`` (rad) from the plane's first axis
    (the x axis for a horizontal circle)."""
    return helix(center, radius, pitch=0.0, turns=1.0, normal=normal, start_angle=start_angle,
                 clockwise=clockwise)


def helix(center, radius: float, *, pitch: float, turns: float, normal=(0, 0, 1),
          start_angle: float = 0.0, clockwise: bool = False) -> Path:
    """A helix of ``turns`` turns advancing ``pitch`` m per turn along ``normal`` (pitch may be
    negative: descending)."""
    c = _vec3(center, "centre")
    radius = real(radius, "the radius", positive=True, limit=MAX_PATH_LENGTH)
    turns = real(turns, "the number of turns", positive=True, limit=1e6)
    pitch = real(pitch, "the pitch", limit=MAX_PATH_LENGTH)
    start_angle = real(start_angle, "the start angle", limit=1e6)
    n = _vec3(normal, "normal")
    if not np.linalg.norm(n) > 0:
        raise InputError("the normal must be a non-zero vector")
    if np.allclose(n, [0, 0, 1]):
        e1, e2 = np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    else:
        e1, e2 = _basis(n)
    sweep = 2 * math.pi * turns * (-1.0 if clockwise else 1.0)
    return Path((Arc(c, float(radius), e1, e2, float(start_angle), sweep,
                     float(pitch * turns)),))


def raster(corner, width: float, height: float, passes: int, *, strategy: str = "zigzag",
           clearance: float = 0.01) -> Path:
    """Facing a rectangle in ``passes`` parallel passes along x.

    Args:
        corner: ``(x, y, z)`` of the rectangle's lower corner at cutting height.
        width, height: extents along x and y (m); passes are spread evenly over y.
        passes: number of passes (≥ 1).
        strategy: ``"zigzag"`` (alternate directions, step over at feed) or ``"one-way"``
            (every pass along +x; retract by ``clearance``, rapid back above the next pass,
            plunge).
        clearance: retract height for one-way passes, m.
    """
    c = _vec3(corner, "corner")
    width = real(width, "the rectangle's width", positive=True, limit=MAX_PATH_LENGTH)
    height = real(height, "the rectangle's height", nonnegative=True, limit=MAX_PATH_LENGTH)
    passes = real(passes, "passes", positive=True)  # bounded by MAX_SEGMENTS below
    clearance = real(clearance, "the clearance", positive=True, limit=MAX_PATH_LENGTH)
    if int(passes) != passes:
        raise InputError(f"passes must be a positive integer, got {passes}")
    passes = int(passes)
    if height == 0 and passes > 1:
        raise InputError("a rectangle of height 0 is faced in one pass, not several")
    if strategy not in ("zigzag", "one-way"):
        raise InputError(f"unknown strategy {strategy!r}; use zigzag or one-way")
    if not clearance > 0:
        raise InputError(f"the clearance must be > 0, got {clearance}")
    count = float(passes) * (4 if strategy == "one-way" else 2) - 1  # a float: never huge ints
    if count > MAX_SEGMENTS:
        raise InputError(f"{passes:.10g} passes make {count:.3g} path segments (about "
                         f"{count * SEGMENT_BYTES / 2**30:.3g} GiB), above the limit of "
                         f"{MAX_SEGMENTS:.3g}; face in fewer passes")
    ys = [c[1]] if passes == 1 else list(np.linspace(c[1], c[1] + height, passes))
    up = np.array([0.0, 0.0, clearance])
    segs: list[Segment] = []
    for k, y in enumerate(ys):
        a = np.array([c[0], y, c[2]])
        b = np.array([c[0] + width, y, c[2]])
        if strategy == "zigzag":
            start, end = (a, b) if k % 2 == 0 else (b, a)
            if segs:
                segs.append(Line(segs[-1].end, start))
            segs.append(Line(start, end))
        else:
            if segs:
                previous = segs[-1].end
                segs += [Line(previous, previous + up, rapid=True),
                         Line(previous + up, a + up, rapid=True),
                         Line(a + up, a)]
            segs.append(Line(a, b))
    shortest = min(seg.length for seg in segs)
    if not shortest >= MIN_MOVE:  # a pass, step-over or retract of (nearly) zero length
        raise InputError(f"a facing move of {shortest:.3g} m (pass, step-over or clearance) is "
                         f"shorter than {MIN_MOVE:g} m: check the sizes and their units")
    return Path(tuple(segs))


def chain(paths: Sequence[Path]) -> Path:
    """Concatenate paths (each must start where the previous one ends, within 1 µm)."""
    segs: list[Segment] = []
    for p in paths:
        if segs and np.linalg.norm(p.segments[0].start - segs[-1].end) > 1e-6:
            raise InputError("chained paths must be continuous")
        segs.extend(p.segments)
    return Path(tuple(segs))
