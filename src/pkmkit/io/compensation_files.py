"""Files of a compensation: a corrected G-code program and correction tables (CSV)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from pkmkit.model.parameters import length_scale

if TYPE_CHECKING:  # io depends on no algorithm: the type is only named here
    from pkmkit.calibration.corrected_program import CorrectedPath

_LETTERS = "XYZ"
#: Plane code and centre-offset letters of an arc by the axis of its normal.
_PLANE_OF_AXIS = {2: (17, "IJ", (0, 1)), 1: (18, "IK", (0, 2)), 0: (19, "JK", (1, 2))}


def corrected_gcode(path: CorrectedPath, *, origin=(0.0, 0.0, 0.0), header: str = "",
                    decimals: int = 4) -> str:
    """A G-code program (G21, G90, millimetres) of the corrected moves, one line each: G0 to
    the corrected end of a rapid, G1 and G2/G3 (centre by I/J/K offsets, G17/G18/G19 as the
    arc's plane) with the programmed feed (mm/min). Program coordinates are the corrected
    machine coordinates minus ``origin`` (the work offset the program was read with).
    """
    offset = np.asarray(origin, dtype=float).reshape(3)
    lines = ["%"]
    for line in header.splitlines():
        lines.append("(" + line.replace("(", "[").replace(")", "]") + ")")
    lines.append("G21 G90 G17")
    feed, plane = None, 17
    fmt = f"{{:.{decimals}f}}"
    previous = np.zeros(3)  # an arc never comes first (correct_path refuses it)
    for k in range(len(path.corrected)):
        p = (path.corrected[k, :3] - offset) * 1e3
        kind = str(path.kind[k])
        words = [kind]
        if kind in ("G2", "G3"):
            axis = int(np.argmax(np.abs(path.normal[k])))
            code, letters, columns = _PLANE_OF_AXIS[axis]
            if code != plane:
                words.insert(0, f"G{code}")
                plane = code
        words += [f"{_LETTERS[i]}{fmt.format(p[i] + 0.0)}" for i in range(3)]
        if kind in ("G2", "G3"):
            centre = (path.center[k] - previous) * 1e3
            words += [f"{letters[n]}{fmt.format(centre[c] + 0.0)}"
                      for n, c in enumerate(columns)]
        if not path.rapid[k] and np.isfinite(path.feed[k]) and path.feed[k] != feed:
            feed = path.feed[k]
            words.append(f"F{feed * 60e3:.6g}")
        lines.append(" ".join(words))
        previous = path.corrected[k, :3]
    lines.append("%")
    return "\n".join(lines) + "\n"


def correction_table(targets: np.ndarray, corrected: np.ndarray, *, units: str = "m",
                     comment: str = "", orientation: str = "axis",
                     status: Sequence[str] | None = None) -> str:
    """CSV of targets, corrected targets and corrections (``dx = cx − x``…); for 6-column
    targets also the orientation: tool axes of a 5-axis machine (``orientation="axis"``:
    ``i, j, k``, ``ci, cj, ck``) or rotation vectors of a six-actuator machine
    (``"rotvec"``: ``rx, ry, rz``, ``crx, cry, crz`` in degrees). ``status``: a last column
    (``ok`` or why the row is flagged); the corrected columns of a flagged row are left
    empty."""
    scale = length_scale(units)
    axes = targets.shape[1] == 6
    cols = ["x", "y", "z", "cx", "cy", "cz", "dx", "dy", "dz"]
    names = ("i", "j", "k") if orientation == "axis" else ("rx", "ry", "rz")
    factor = 1.0 if orientation == "axis" else np.degrees(1.0)
    if axes:
        cols += [*names, *(f"c{n}" for n in names)]
    if status is not None:
        cols.append("status")
    lines = [f"# {c}" for c in comment.splitlines()] + [f"# units: {units}", ",".join(cols)]
    for k, (t, c) in enumerate(zip(targets, corrected, strict=True)):
        row = [*(t[:3] / scale), *(c[:3] / scale), *((c[:3] - t[:3]) / scale)]
        if axes:
            row += [*(t[3:] * factor), *(c[3:] * factor)]
        cells = ["" if not np.isfinite(v) else f"{v:.10g}" for v in row]
        if status is not None:
            cells.append(str(status[k]).replace(",", ";"))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"
