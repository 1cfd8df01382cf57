"""Seed 003's test part: its cutters, its placement on the table, and its straight passes.

- **Cutters** (seed 003 §4.1): contours with a Ø20 mm end mill, slots with a Ø16 mm ball-end
  mill, both driven along *the same* programmed path by their tool centre — the centre of the end
  mill's flat end, the centre of the ball. In a section across a pass the end mill leaves a
  vertical wall ``R_e`` from the centre (on the material side) and a floor at the centre's
  height; the ball leaves a slot whose bottom ``Q`` is ``R_b`` below the centre.
- **Placement** ``(Δx, Δy, Δz, φ)``: the part frame R_m in the machine frame R_0, z_m parallel to
  z_0 (seed 003 §4.2): ``p_0 = Rz(φ) p_m + Δ``.
- **Passes**: the straight feed moves (G1) of a program that run along the machine's x or y axis
  (horizontal direction within 1 µrad of the axis; a slope in z is allowed) and are at least
  10 mm long horizontally (seed 003: contouring over 10 mm at least). Each is named by its
  G-code file line, which is how a CMM file refers to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.motion.paths import Line, Path

#: Seed 003's cutters (m): Ø20 mm end mill (contours), Ø16 mm ball-end mill (slots).
SEED_END_MILL_RADIUS, SEED_BALL_RADIUS = 0.010, 0.008
#: Shortest pass the seed measures (horizontal length, m).
MIN_PASS = 0.010
#: Largest angle (rad) between a pass's horizontal direction and the x or y axis.
AXIS_TOL = 1e-6


@dataclass(frozen=True)
class Cutters:
    """Cutter radii (m): ``end_mill`` (contour walls), ``ball`` (slot bottoms)."""

    end_mill: float = SEED_END_MILL_RADIUS
    ball: float = SEED_BALL_RADIUS

    def __post_init__(self) -> None:
        for name in ("end_mill", "ball"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"the {name.replace('_', ' ')} radius must be > 0, got {v!r}")

    def reduced(self, probe_radius: float) -> Cutters:
        """The radii of the surfaces a probe tip's *centre* touches (each cutter radius minus
        the tip radius): tip centres lie on the machined surfaces offset by the tip radius."""
        if not (np.isfinite(probe_radius) and 0 <= probe_radius < min(self.end_mill, self.ball)):
            raise InputError(f"the probe tip radius must be ≥ 0 and smaller than both cutter "
                             f"radii ({min(self.end_mill, self.ball) * 1e3:g} mm), got "
                             f"{probe_radius * 1e3:g} mm")
        return Cutters(self.end_mill - probe_radius, self.ball - probe_radius)


@dataclass(frozen=True)
class Placement:
    """The part frame in the machine frame: ``p_0 = Rz(phi) p_m + (dx, dy, dz)`` (m, rad)."""

    dx: float = 0.0
    dy: float = 0.0
    dz: float = 0.0
    phi: float = 0.0

    @property
    def vector(self) -> np.ndarray:
        """``(4,)`` ``(Δx, Δy, Δz, φ)`` — the order of the identification's ``part_*``."""
        return np.array([self.dx, self.dy, self.dz, self.phi])

    def _rotation(self) -> np.ndarray:
        c, s = np.cos(self.phi), np.sin(self.phi)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def to_part(self, points: np.ndarray) -> np.ndarray:
        """Machine-frame points ``(..., 3)`` in the part frame."""
        return (np.asarray(points, dtype=float) - self.vector[:3]) @ self._rotation()

    def to_machine(self, points: np.ndarray) -> np.ndarray:
        """Part-frame points ``(..., 3)`` in the machine frame."""
        return np.asarray(points, dtype=float) @ self._rotation().T + self.vector[:3]


@dataclass(frozen=True)
class Pass:
    """A straight cutting pass: ``path`` (the G-code line, as text), commanded ``start`` and
    ``end`` (machine frame, ``(3,)`` m), ``axis`` (0 for x, 1 for y) it runs along."""

    path: str
    start: np.ndarray
    end: np.ndarray
    axis: int

    @property
    def direction(self) -> str:
        return "xy"[self.axis]

    @property
    def segment(self) -> np.ndarray:
        """``(6,)`` start and end — the ``commanded`` row of a part measurement."""
        return np.concatenate([self.start, self.end])

    def at(self, t: np.ndarray) -> np.ndarray:
        """Commanded points ``(k, 3)`` at parameters ``t`` ``(k,)`` (0 at start, 1 at end)."""
        t = np.asarray(t, dtype=float)
        return self.start + t[:, None] * (self.end - self.start)


def part_passes(path: Path) -> list[Pass]:
    """The measurement passes of a program (module docstring), in program order."""
    out = []
    for seg, line in zip(path.segments, path.source or range(1, len(path.segments) + 1),
                         strict=True):
        if not isinstance(seg, Line) or seg.rapid:
            continue
        d = seg.end - seg.start
        horizontal = float(np.hypot(d[0], d[1]))
        if horizontal < MIN_PASS:
            continue
        axis = int(np.argmax(np.abs(d[:2])))
        if abs(d[1 - axis]) > AXIS_TOL * abs(d[axis]):
            continue
        out.append(Pass(str(line), seg.start.copy(), seg.end.copy(), axis))
    if not out:
        raise InputError("the program has no straight feed move (G1) along x or y of at least "
                         f"{MIN_PASS * 1e3:g} mm: nothing to measure (seed 003's part is made "
                         "of straight passes)")
    return out


def seed_part_program(machine, *, levels: int = 2, size: float | None = None,
                      feed_mm_min: float = 2000.0) -> str:
    """G-code (mm, absolute) of seed 003's test part for ``machine`` (its default box):
    straight passes along x at three y positions and along y at three x positions over 80 % of
    the box's width (or ``size``, m), on ``levels`` heights 30 mm apart near the bottom of the
    box, each level's lines shifted 40 mm sideways so that no two passes share a wall; rapid
    moves 20 mm above the level between passes.

    The seed gives no dimensions for the Verne's part; this one is sized to the (illustrative)
    machine model."""
    if levels < 1:
        raise InputError(f"levels must be ≥ 1, got {levels}")
    lo, hi = (np.asarray(v, dtype=float)[:3] for v in machine.default_box())
    centre = (lo + hi) / 2
    half = 0.4 * float(min(hi[0] - lo[0], hi[1] - lo[1])) if size is None else size / 2
    z0 = lo[2] + 0.25 * (hi[2] - lo[2])
    mm = 1e3
    lines = [f"(pkmkit: seed 003 test part for {machine.id}, illustrative dimensions)",
             "G21 G90 G17"]
    for level in range(levels):
        z = z0 + level * 0.03
        shift = 0.04 * level
        for k, off in enumerate((-0.8 * half, 0.0, 0.8 * half)):
            for axis in (0, 1):
                a0, a1 = centre[axis] - half, centre[axis] + half
                b = centre[1 - axis] + off + shift
                start, end = np.empty(3), np.empty(3)
                start[axis], end[axis] = a0, a1
                start[1 - axis] = end[1 - axis] = b
                start[2] = end[2] = z
                lines.append(f"(level {level + 1}, pass along {'xy'[axis]} {k + 1})")
                lines.append(f"G0 X{start[0] * mm:.4f} Y{start[1] * mm:.4f} "
                             f"Z{(z + 0.02) * mm:.4f}")
                lines.append(f"G0 Z{z * mm:.4f}")
                lines.append(f"G1 X{end[0] * mm:.4f} Y{end[1] * mm:.4f} F{feed_mm_min:g}")
                lines.append(f"G0 Z{(z + 0.02) * mm:.4f}")
    lines.append("M30")
    return "\n".join(lines) + "\n"
