"""CMM probing of the machined part per section (seed 003 §4.2) and the CMM file format.

In each section plane (perpendicular to its pass, part frame R_m) the CMM takes three points:

- ``Q`` — the bottom of the slot: the lowest point of the slot's profile in the section (found
  by scanning across the slot, or by a circle fit);
- ``M`` and ``N`` — two points on the contour wall, at two heights.

**What the file holds.** By default *surface points*: the CMM has compensated its tip radius
along the surface normal, as CMM reports do (``# points: surface``). A file of *tip centres*
says ``# points: tip`` and gives ``# probe_radius: R`` (file length unit): tip centres lie on
the machined surfaces offset by the tip radius, so the reconstruction uses each cutter radius
minus the tip radius (:meth:`~.part.Cutters.reduced`).

**Noise model.** Each reported coordinate carries independent Gaussian noise of σ (default
1.5 µm, pkmkit's ``cmm`` instrument).

**File format** (CSV, ``#`` comment lines, a header row; errors name the file line and column)::

    # units: mm
    # points: surface
    section,label,x,y,z,path,direction
    1,Q,12.5,-3.2101,-8.0004,12,x
    1,M,12.5,6.7898,3.0001,12,x
    1,N,12.5,6.7899,7.0002,12,x

``section`` a label shared by the three points of a section; ``label`` Q, M or N; ``x, y, z``
the point in the part frame; ``path`` the G-code line of the pass that cut the section (the
straight G1 move); ``direction`` the part axis the pass runs along (``x`` or ``y``: the section
plane is x = const or y = const). An optional ``id`` column is kept as a free label.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pkmkit.calibration.simulate import NOISE_SIGMA
from pkmkit.exceptions import InputError
from pkmkit.machining.sweep import MachinedPart
from pkmkit.model.parameters import length_scale

COLUMNS = ("section", "label", "x", "y", "z", "path", "direction")
LABELS = ("Q", "M", "N")
POINT_KINDS = ("surface", "tip")
#: Default CMM noise: σ per coordinate (m).
CMM_SIGMA = NOISE_SIGMA["cmm"]
_KEY_LINE = re.compile(r"^#\s*(points|probe_radius)\s*[:=]\s*(\S+)\s*$")


@dataclass(frozen=True)
class CmmPoints:
    """Probe points of a part (part frame, m), three per section.

    Attributes:
        section: ``(P,)`` section labels. label: ``(P,)`` Q, M or N.
        points: ``(P, 3)`` the points.
        path: ``(P,)`` pass (G-code line) of each point's section.
        direction: ``(P,)`` ``x`` or ``y``.
        points_kind: ``surface`` or ``tip`` (module docstring). probe_radius: tip radius (m).
        lines: ``(P,)`` where each point came from (``file:line``), for errors.
        source: the file or a description.
    """

    section: tuple[str, ...]
    label: tuple[str, ...]
    points: np.ndarray
    path: tuple[str, ...]
    direction: tuple[str, ...]
    points_kind: str = "surface"
    probe_radius: float = 0.0
    lines: tuple[str, ...] = ()
    source: str = ""


def probe(part: MachinedPart, rng: np.random.Generator | None = None, *,
          sigma: float = CMM_SIGMA, points: str = "surface") -> CmmPoints:
    """The CMM's points of every section of ``part`` (module docstring): Q, M, N each with
    Gaussian noise σ (m) per coordinate (``rng`` required when σ > 0); tip centres (``points=
    "tip"``) are those of ``part.probe_radius``."""
    if points not in POINT_KINDS:
        raise InputError(f"points must be one of {', '.join(POINT_KINDS)}, got {points!r}")
    if not (np.isfinite(sigma) and sigma >= 0):
        raise InputError(f"the CMM noise σ must be ≥ 0, got {sigma!r}")
    k = len(part.s)
    idx = np.arange(k)
    a, b = part.axis, 1 - part.axis
    tip = part.probe_radius if points == "tip" else 0.0
    wall, q = (part.tip_wall, part.tip_slot) if points == "tip" else (part.wall, part.slot)
    pts = np.empty((k, 3, 3))
    pts[:, 0] = q
    pts[idx, 0, a] = part.s  # exactly in the section plane (the root is to ~1e-16 m)
    for j in (1, 2):
        pts[idx, j, a] = part.s
        pts[idx, j, b] = wall
        pts[:, j, 2] = part.heights[:, j - 1]
    pts = pts.reshape(-1, 3)
    if sigma > 0:
        if rng is None:
            raise InputError("a random generator is needed for CMM noise")
        pts = pts + sigma * rng.standard_normal(pts.shape)
    names = tuple(str(i + 1) for i in range(k))
    return CmmPoints(section=tuple(n for n in names for _ in LABELS),
                     label=LABELS * k, points=pts,
                     path=tuple(p for p in part.path for _ in LABELS),
                     direction=tuple("xy"[int(x)] for x in part.axis for _ in LABELS),
                     points_kind=points, probe_radius=tip,
                     source="simulated CMM")


def format_cmm(cmm: CmmPoints, *, units: str = "mm", comment: str = "") -> str:
    """The CMM file text of ``cmm`` (module docstring), lengths in ``units``."""
    scale = length_scale(units)
    out = [f"# {line}" for line in comment.splitlines() if line.strip()]
    out += [f"# units: {units}", f"# points: {cmm.points_kind}"]
    if cmm.points_kind == "tip":
        out.append(f"# probe_radius: {cmm.probe_radius / scale:.10g}")
    out.append(",".join(COLUMNS))
    for i in range(len(cmm.label)):
        x, y, z = cmm.points[i] / scale
        out.append(f"{cmm.section[i]},{cmm.label[i]},{x:.10f},{y:.10f},{z:.10f},"
                   f"{cmm.path[i]},{cmm.direction[i]}")
    return "\n".join(out) + "\n"


def read_cmm(path: str | Path, *, units: str | None = None) -> CmmPoints:
    """Read a CMM file (module docstring) into SI units.

    Raises:
        InputError: naming the file line and column: a missing or unknown column, a cell that
            is not a number, a label other than Q/M/N, a direction other than x/y, a bad
            ``# points`` or ``# probe_radius`` line. (Sections are checked by the
            reconstruction.)
    """
    from pkmkit.io.measurements import read_csv_table

    label = str(path)
    table = read_csv_table(path, COLUMNS, ("id",), units=units,
                           text_columns=("section", "label", "path", "direction", "id"),
                           what=" (a CMM file: docs/calibration.md)")
    kind, radius, radius_line = "surface", 0.0, None
    text = Path(path).read_text(encoding="utf-8-sig")
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped and not stripped.startswith("#"):
            break
        match = _KEY_LINE.match(stripped)
        if not match:
            continue
        key, value = match.groups()
        if key == "points":
            if value not in POINT_KINDS:
                raise InputError(f"{label}:{number}: '# points:' must be surface or tip, got "
                                 f"{value!r}")
            kind = value
        else:
            try:
                radius = float(value) * table.scale
            except ValueError:
                raise InputError(f"{label}:{number}: '# probe_radius:' {value!r} is not a "
                                 "number") from None
            if not (np.isfinite(radius) and radius >= 0):
                raise InputError(f"{label}:{number}: the probe radius must be ≥ 0")
            radius_line = number
    if kind == "tip" and radius_line is None:
        raise InputError(f"{label}: '# points: tip' needs '# probe_radius: R' (the tip radius, "
                         "in the file's unit)")
    for column, allowed in (("label", LABELS), ("direction", ("x", "y"))):
        for value, where in zip(table.texts[column], table.lines, strict=True):
            if value not in allowed:
                raise InputError(f"{where}: column {column!r}: {value!r} is not "
                                 f"{' or '.join(allowed)}")
    pts = np.column_stack([table.numbers[c] for c in "xyz"]) * table.scale
    return CmmPoints(section=tuple(table.texts["section"]), label=tuple(table.texts["label"]),
                     points=pts, path=tuple(table.texts["path"]),
                     direction=tuple(table.texts["direction"]), points_kind=kind,
                     probe_radius=radius if kind == "tip" else 0.0, lines=table.lines,
                     source=label)
