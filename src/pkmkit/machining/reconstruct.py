"""Tool-centre positions from CMM points and cutter radii (seed 003 §4.2), the step a user runs on
their own CMM file.

In a section plane ``a = s`` across a pass (``a`` the part axis it runs along, ``b`` the other
horizontal axis), with ``R_e`` the end mill's radius and ``R_b`` the ball's (each minus the tip
radius for a file of tip centres):

- ``s`` is the mean of the section's three ``a`` coordinates;
- the wall is vertical (cutter axis vertical): its ``b`` is the mean of ``M_b`` and ``N_b``; the
  material side is the side of the wall from the slot bottom Q (the contour and the slot follow
  the same path);
- ``b_centre = b_wall − side · R_e · √(1 + g²)`` and ``z_centre = Q_z + R_b · √(1 + h²)``, with
  ``g`` and ``h`` the slopes of the wall's ``b`` and of ``Q_z`` along the pass at ``s`` (a
  cubic fitted to the pass's sections; lower degrees for fewer): the swept cylinder and tube
  of a path crossing the section plane obliquely meet the plane farther from the path than the
  radius. Exact for a straight path at any slope (tested to 1e-12 m); on a path bent by the
  defects, the error is of order ``R g δg`` (~10⁻⁹ m).

The tool centre is the point of the centre path in the section plane, ``(s, b_centre,
z_centre)`` in the part frame: what pkmkit's machined-part identification takes
(:func:`reconstructed_measurements` → a ``part`` :class:`MeasurementSet`, file format
:mod:`pkmkit.io.measurements`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machining.cmm import LABELS, CmmPoints
from pkmkit.machining.part import Cutters, Pass
from pkmkit.model.measurement_set import MeasurementSet

#: Largest spread (m) of a section's points along its pass: they must lie in one plane.
PLANE_TOL = 1e-4
#: Wall lean (rad) beyond which a section is doubtful: 5 mrad, ten times the lean a 1.5 µm CMM
#: noise gives between wall points 4 mm apart.
LEAN_LIMIT = 5e-3
#: Accepted ratio of the measured wall-to-slot distance to the end mill's radius.
WALL_RATIO = (0.5, 1.5)


@dataclass(frozen=True)
class Reconstruction:
    """Reconstructed tool centres, one per section (part frame, m).

    Attributes:
        section: ``(K,)`` section labels. path: ``(K,)`` pass (G-code line) of each.
        axis: ``(K,)`` 0 (pass along x) or 1 (along y). side: ``(K,)`` ±1, the wall's side.
        centre: ``(K, 3)`` tool centres. slopes: ``(K, 2)`` g and h (module docstring).
        lines: ``(K,)`` the section's first line (``file:line``). source: the CMM file.
        lean: ``(K,)`` the wall's lean between M and N (rad, from the vertical; NaN when M and
            N are at one height): a vertical cutter leaves 0 plus the CMM's noise.
    """

    section: tuple[str, ...]
    path: tuple[str, ...]
    axis: np.ndarray
    side: np.ndarray
    centre: np.ndarray
    slopes: np.ndarray
    lines: tuple[str, ...]
    source: str = ""
    lean: np.ndarray | None = None

    def leaning(self, limit: float = LEAN_LIMIT) -> np.ndarray:
        """Indices of the sections whose wall leans by more than ``limit`` (rad): the cutter
        was not vertical there (seed 003's hypothesis), and the centre is off by about the
        probing height × the lean."""
        lean = np.nan_to_num(np.abs(self.lean), nan=0.0) if self.lean is not None else []
        return np.flatnonzero(np.asarray(lean) > limit)


def _where(cmm: CmmPoints, row: int) -> str:
    return cmm.lines[row] if cmm.lines else f"{cmm.source or 'CMM points'}: point {row + 1}"


def _sections(cmm: CmmPoints) -> dict[str, dict[str, int]]:
    """Rows of each section by label, checked (one pass, one direction, Q, M and N once)."""
    sections: dict[str, dict[str, int]] = {}
    for row, (sec, lab) in enumerate(zip(cmm.section, cmm.label, strict=True)):
        rows = sections.setdefault(sec, {})
        first = next(iter(rows.values()), None)
        if first is not None:
            for column, values in (("path", cmm.path), ("direction", cmm.direction)):
                if values[row] != values[first]:
                    raise InputError(f"{_where(cmm, row)}: column {column!r}: section {sec} is "
                                     f"{column} {values[first]!r} at {_where(cmm, first)}, "
                                     f"{values[row]!r} here (inconsistent section)")
        if lab in rows:
            raise InputError(f"{_where(cmm, row)}: column 'label': section {sec} has a second "
                             f"{lab} point (first at {_where(cmm, rows[lab])})")
        rows[lab] = row
    for sec, rows in sections.items():
        missing = [lab for lab in LABELS if lab not in rows]
        if missing:
            first = min(rows.values())
            raise InputError(f"{_where(cmm, first)}: column 'label': section {sec} has no "
                             f"{' and no '.join(missing)} point (each section needs Q, M and "
                             "N)")
    return sections


def reconstruct(cmm: CmmPoints, cutters: Cutters | None = None) -> Reconstruction:
    """Tool centres from a CMM file's points (module docstring).

    Raises:
        InputError: naming the file line and column: a section without its Q, M or N point or
            with two of one, points of a section off one plane, a section whose rows name
            different passes or directions, a wall on both sides of the slot or at a distance
            that does not match the end mill (wrong cutter or labels), a pass with fewer than
            two sections.
    """
    cutters = cutters or Cutters()
    radii = cutters.reduced(cmm.probe_radius) if cmm.points_kind == "tip" else cutters
    sections = _sections(cmm)
    names = list(sections)
    k = len(names)
    axis = np.array([0 if cmm.direction[sections[n]["Q"]] == "x" else 1 for n in names])
    rows = np.array([[sections[n][lab] for lab in LABELS] for n in names])  # (K, 3): Q, M, N
    pts = cmm.points[rows]  # (K, 3, 3)
    idx = np.arange(k)
    along = pts[idx, :, axis]  # (K, 3)
    spread = along.max(axis=1) - along.min(axis=1)
    _check_planes(cmm, names, rows, axis, along, spread)
    s = along.mean(axis=1)
    b = 1 - axis
    q_b, m_b, n_b = pts[idx, 0, b], pts[idx, 1, b], pts[idx, 2, b]
    _check_walls(cmm, names, rows, b, q_b, m_b, n_b, cutters, radii)
    side = np.sign(m_b - q_b)
    wall = (m_b + n_b) / 2
    rise = pts[idx, 2, 2] - pts[idx, 1, 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        lean = np.where(np.abs(rise) > 1e-4, np.arctan((n_b - m_b) * side / rise), np.nan)
    q_z = pts[idx, 0, 2]
    paths = [cmm.path[sections[n]["Q"]] for n in names]
    slopes = _pass_slopes(cmm, names, rows, paths, axis, s, wall, q_z)
    centre = np.empty((k, 3))
    centre[idx, axis] = s
    centre[idx, b] = wall - side * radii.end_mill * np.sqrt(1 + slopes[:, 0] ** 2)
    centre[:, 2] = q_z + radii.ball * np.sqrt(1 + slopes[:, 1] ** 2)
    return Reconstruction(section=tuple(names), path=tuple(paths), axis=axis, side=side,
                          centre=centre, slopes=slopes,
                          lines=tuple(_where(cmm, r) for r in rows[:, 0]), source=cmm.source,
                          lean=lean)


def _check_planes(cmm: CmmPoints, names: list, rows: np.ndarray, axis: np.ndarray,
                  along: np.ndarray, spread: np.ndarray) -> None:
    """Each section's three points in one plane across its pass (within PLANE_TOL)."""
    for i in np.flatnonzero(spread > PLANE_TOL):
        col = "xy"[axis[i]]
        worst = rows[i, np.argmax(np.abs(along[i] - np.median(along[i])))]
        raise InputError(f"{_where(cmm, worst)}: column {col!r}: section {names[i]}'s points "
                         f"are not in one section plane {col} = const (they spread over "
                         f"{spread[i] * 1e3:.3g} mm; at most {PLANE_TOL * 1e3:g} mm)")


def _check_walls(cmm: CmmPoints, names: list, rows: np.ndarray, b: np.ndarray,
                 q_b: np.ndarray, m_b: np.ndarray, n_b: np.ndarray, cutters: Cutters,
                 radii: Cutters) -> None:
    """M and N on one side of the slot bottom Q, at about the end mill's radius from it."""
    for i in range(len(names)):
        dm, dn = m_b[i] - q_b[i], n_b[i] - q_b[i]
        if np.sign(dm) != np.sign(dn):
            raise InputError(f"{_where(cmm, rows[i, 2])}: column {'xy'[b[i]]!r}: section "
                             f"{names[i]}: M and N lie on opposite sides of the slot bottom Q; "
                             "both are on the contour wall")
        for j, d in ((1, dm), (2, dn)):
            ratio = abs(d) / radii.end_mill
            if not WALL_RATIO[0] <= ratio <= WALL_RATIO[1]:
                raise InputError(
                    f"{_where(cmm, rows[i, j])}: column {'xy'[b[i]]!r}: section {names[i]}: the "
                    f"wall point {LABELS[j]} is {abs(d) * 1e3:.4g} mm from the slot bottom; "
                    f"with an end mill of radius {cutters.end_mill * 1e3:g} mm it should be "
                    f"about {radii.end_mill * 1e3:.4g} mm (wrong cutter, labels or section)")


def _pass_slopes(cmm: CmmPoints, names: list, rows: np.ndarray, paths: list,
                 axis: np.ndarray, s: np.ndarray, wall: np.ndarray,
                 q_z: np.ndarray) -> np.ndarray:
    """``(K, 2)`` slopes of the wall and of the slot bottom along each pass, from a
    polynomial fit (degree ≤ 3) of its sections; a pass must run along one axis and have
    sections at two positions at least."""
    k = len(names)
    slopes = np.zeros((k, 2))
    for p in dict.fromkeys(paths):
        sel = np.array([i for i in range(k) if paths[i] == p])
        if len(set(axis[sel])) > 1:
            i = sel[np.flatnonzero(axis[sel] != axis[sel[0]])[0]]
            raise InputError(f"{_where(cmm, rows[i, 0])}: column 'direction': pass {p} runs "
                             f"along {'xy'[axis[sel[0]]]} in section {names[sel[0]]} and along "
                             f"{'xy'[axis[i]]} here")
        if len(np.unique(s[sel])) < 2:
            raise InputError(f"{_where(cmm, rows[sel[0], 0])}: column 'path': pass {p} has "
                             f"{len(sel)} section(s) at one position: at least two sections "
                             "along a pass are needed (the wall's and the slot's slopes)")
        deg = min(3, len(np.unique(s[sel])) - 1)
        for c, values in enumerate((wall[sel], q_z[sel])):
            fit = np.polynomial.Polynomial.fit(s[sel], values, deg)
            slopes[sel, c] = fit.deriv()(s[sel])
    return slopes


def reconstructed_measurements(rec: Reconstruction, passes: list[Pass], *,
                               program: str = "the program") -> MeasurementSet:
    """The reconstructed centres as machined-part measurements (``kind="part"``), each tied to
    the commanded line of its pass.

    Raises:
        InputError: a section whose pass is not a straight pass of the program, or whose
            direction is not the pass's.
    """
    by_line = {p.path: p for p in passes}
    commanded = np.empty((len(rec.path), 6))
    for i, (path, where) in enumerate(zip(rec.path, rec.lines, strict=True)):
        p = by_line.get(path)
        if p is None:
            raise InputError(f"{where}: column 'path': {program} has no straight pass along x "
                             f"or y at line {path!r} (its passes are at lines "
                             f"{', '.join(by_line)})")
        if p.axis != rec.axis[i]:
            raise InputError(f"{where}: column 'direction': the pass at line {path} of "
                             f"{program} runs along {p.direction}, the section says "
                             f"{'xy'[rec.axis[i]]}")
        commanded[i] = p.segment
    return MeasurementSet(kind="part", values=rec.centre, path=rec.path, commanded=commanded,
                          labels=rec.lines, source=rec.source)
