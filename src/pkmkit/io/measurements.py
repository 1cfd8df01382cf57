"""Calibration measurement files (CSV): one format per measurement type, read with errors that
name the file line and column, written atomically.

A file is a CSV table with a header row naming its columns; ``#`` lines are comments. The
length unit is given by a comment line ``# units: mm`` (or ``m``) before the header, or by
``[mm]`` after a column name (``x [mm]``), or by the caller (``--units``); when two of these are
given they must agree. Column names may differ in case (``X`` for ``x``); a column given twice
(``x`` and ``X``) is refused. Batch tables (:mod:`pkmkit.io.table`) follow the same
conventions. Angles (revolute actuators, rotation vectors) are always in degrees.

Columns by type (the actuator columns are named as the machine's actuators, e.g. ``Q1 … Q5``
for the Tripteor X7, ``q1 q2 q3`` for a linear Delta):

=========== ==============================================================================
``point``   actuators, ``x, y, z`` (tool point, measurement frame); optional ``tool_length``
            and ``tool`` (a label)
``pose``    actuators, ``x, y, z, rx, ry, rz`` (tool point and rotation vector of the tool
            frame, degrees); optional ``tool_length``, ``tool``
``ballbar`` actuators, ``px, py, pz`` (nominal pivot), ``length`` (measured bar length);
            optional ``tool_length``, ``tool``
``height``  actuators, ``z`` (probe reading: the tool's height above the bed)
``part``    ``path`` (a label), ``x0, y0, z0, x1, y1, z1`` (the commanded straight line,
            machine frame), ``x, y, z`` (the measured tool centre in the part frame)
=========== ==============================================================================

Every type accepts an optional ``id`` column (a free label kept in reports). Anything else is
an error: a missing or unknown column, a cell that is not a finite number, a short row, two
identical rows, an id used twice.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import write_text_atomic
from pkmkit.model.measurement_set import KINDS, MeasurementSet
from pkmkit.model.parameters import LENGTH_UNITS, length_scale

READINGS = {"point": ("x", "y", "z"), "pose": ("x", "y", "z", "rx", "ry", "rz"),
            "ballbar": ("px", "py", "pz", "length"), "height": ("z",),
            "part": ("x0", "y0", "z0", "x1", "y1", "z1", "x", "y", "z")}
OPTIONAL = {"point": ("tool_length", "tool", "id"), "pose": ("tool_length", "tool", "id"),
            "ballbar": ("tool_length", "tool", "id"), "height": ("id",), "part": ("id",)}
#: Columns holding labels rather than numbers.
TEXT_COLUMNS = ("tool", "path", "id")
#: Columns in degrees.
ANGLE_COLUMNS = ("rx", "ry", "rz")
#: Largest magnitude of a number in a measurement-like file, m (angles: degrees times the
#: file's metres per unit): beyond, a unit mistake (and squares in distances overflow). In
#: metres, so that a file written back in another unit reads the same.
MAX_CELL = 1e6
_UNIT_LINE = re.compile(r"^#\s*units?\s*[:=]\s*([A-Za-z]+)\s*$")
_COLUMN_UNIT = re.compile(r"^(.*?)\s*\[\s*([A-Za-z°]+)\s*\]\s*$")


def actuator_columns(machine) -> tuple[tuple[str, ...], np.ndarray]:
    """The machine's actuator column names and which are angles (degrees in files)."""
    return tuple(machine.actuator_names), machine.angular_actuators


def expected_columns(machine, kind: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(required, optional) columns of a ``kind`` file for ``machine``."""
    if kind not in KINDS:
        raise InputError(f"unknown measurement type {kind!r}; valid types: {', '.join(KINDS)}")
    names, _ = actuator_columns(machine)
    required = ("path", *READINGS[kind]) if kind == "part" else (*names, *READINGS[kind])
    optional = tuple(c for c in OPTIONAL[kind] if c not in required)
    return required, optional


@dataclass(frozen=True)
class CsvTable:
    """A checked CSV table: numeric columns (file units, angles in degrees), text columns, the
    file line of each data row, the length unit and its metres."""

    numbers: dict[str, np.ndarray]
    texts: dict[str, list[str]]
    lines: tuple[str, ...]
    unit: str
    scale: float


def read_csv_table(path: str | Path, required: tuple[str, ...], optional: tuple[str, ...] = (),
                   *, units: str | None = None, text_columns: tuple[str, ...] = TEXT_COLUMNS,
                   what: str = "") -> CsvTable:
    """Read a CSV table with exactly the columns ``required`` (and any of ``optional``), in the
    conventions of the module docstring (units, comments, errors naming line and column).

    Raises:
        InputError: see :func:`read_measurements`.
    """
    label = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise InputError(f"{label}: cannot read file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{label}: not a UTF-8 text file: {exc.reason}") from None
    file_unit, unit_line = None, None
    rows: list[tuple[int, list[str]]] = []
    try:
        for number, row in enumerate(csv.reader(io.StringIO(text)), start=1):
            if not row or not any(c.strip() for c in row):
                continue
            if row[0].lstrip().startswith("#"):
                match = _UNIT_LINE.match(",".join(row).strip())
                if match and not rows:
                    file_unit, unit_line = match.group(1), number
                continue
            rows.append((number, [c.strip() for c in row]))
    except csv.Error as exc:
        raise InputError(f"{label}: not a CSV file: {exc}") from None
    if not rows:
        raise InputError(f"{label}: no header and no data")
    header_line, header = rows[0]
    columns = []
    for k, cell in enumerate(header):
        match = _COLUMN_UNIT.match(cell)
        name = cell
        if match:
            name, unit = match.group(1).strip(), match.group(2)
            if unit not in ("deg", "°"):
                if unit not in LENGTH_UNITS:
                    raise InputError(f"{label}:{header_line}: column {name!r}: unknown unit "
                                     f"{unit!r}; use one of {', '.join(LENGTH_UNITS)} (angles "
                                     "are in degrees)")
                if file_unit is not None and unit != file_unit:
                    raise InputError(f"{label}:{header_line}: column {name!r} is in {unit} but "
                                     f"the file says {file_unit} (line {unit_line})")
                file_unit, unit_line = unit, header_line
        if not name:
            raise InputError(f"{label}:{header_line}: column {k + 1} has no name")
        columns.append(name)
    known = {c.casefold(): c for c in (*required, *optional)}
    columns = [c if c in known.values() else known.get(c.casefold(), c) for c in columns]
    if _looks_numeric(columns):
        raise InputError(f"{label}:{header_line}: the first row must be a header naming the "
                         f"columns: {', '.join(required)}")
    if file_unit is not None and file_unit not in LENGTH_UNITS:
        raise InputError(f"{label}:{unit_line}: unknown unit {file_unit!r}; use one of "
                         f"{', '.join(LENGTH_UNITS)}")
    if units is not None and file_unit is not None and units != file_unit:
        raise InputError(f"{label}:{unit_line}: measurement units mismatch: the file is in "
                         f"{file_unit}, the command says {units}")
    unit = file_unit or units or "m"
    scale = length_scale(unit)
    dup = sorted({c for c in columns if columns.count(c) > 1})
    if dup:
        raise InputError(f"{label}:{header_line}: repeated column(s) {', '.join(dup)}")
    opt = f" (optional: {', '.join(optional)})" if optional else ""
    missing = [c for c in required if c not in columns]
    if missing:
        raise InputError(f"{label}:{header_line}: missing column(s) {', '.join(missing)}"
                         f"{what}; expected {', '.join(required)}{opt}")
    extra = [c for c in columns if c not in required and c not in optional]
    if extra:
        raise InputError(f"{label}:{header_line}: unknown column(s) {', '.join(extra)}; "
                         f"expected {', '.join(required)}{opt}")
    data = rows[1:]
    if not data:
        raise InputError(f"{label}: no data rows after the header (line {header_line})")
    index = {c: columns.index(c) for c in columns}
    numeric = [c for c in columns if c not in text_columns]
    values = np.empty((len(data), len(numeric)))
    texts: dict[str, list[str]] = {c: [] for c in columns if c in text_columns}
    seen: dict[tuple[str, ...], int] = {}
    for i, (line, row) in enumerate(data):
        if len(row) != len(columns):
            raise InputError(f"{label}:{line}: {len(row)} cells for {len(columns)} columns "
                             f"({', '.join(columns)})")
        key = tuple(row)
        if key in seen:
            raise InputError(f"{label}:{line}: duplicate row: identical to line {seen[key]}")
        seen[key] = line
        for k, c in enumerate(numeric):
            cell = row[index[c]]
            try:
                v = float(cell)
            except ValueError:
                raise InputError(f"{label}:{line}: column {c!r}: {_short(cell)} is not a "
                                 "number") from None
            if not np.isfinite(v):
                raise InputError(f"{label}:{line}: column {c!r}: {_short(cell)} is not a "
                                 "finite number")
            if abs(v) * scale > MAX_CELL:  # squared in distances: overflow, a unit mistake
                raise InputError(f"{label}:{line}: column {c!r}: {v:g} {unit} is beyond "
                                 f"{MAX_CELL:g} m (or degrees): check the units")
            values[i, k] = v
        for c in texts:
            texts[c].append(row[index[c]])
    if "id" in texts:  # an id names one row: a repeated one is a copy or a mislabelled row
        first: dict[str, int] = {}
        for (line, _), ident in zip(data, texts["id"], strict=True):
            if ident in first:
                raise InputError(f"{label}:{line}: repeated id {ident!r} (first on line "
                                 f"{first[ident]})")
            first[ident] = line
    return CsvTable(numbers={c: values[:, k] for k, c in enumerate(numeric)}, texts=texts,
                    lines=tuple(f"{label}:{line}" for line, _ in data), unit=unit, scale=scale)


def read_measurements(path: str | Path, machine, kind: str, *, units: str | None = None
                      ) -> MeasurementSet:
    """Read a measurement file of type ``kind`` for ``machine`` into SI units.

    Args:
        path: the CSV file.
        machine: the machine (its actuator names and which are angles).
        kind: point, pose, ballbar, height or part.
        units: the caller's length unit, or None (the file's, else metres).

    Raises:
        InputError: naming ``file:line`` and the column: unreadable file, unit mismatch,
            missing/unknown columns, non-numeric or non-finite cells, short rows, duplicate
            rows, no data.
    """
    required, optional = expected_columns(machine, kind)
    table = read_csv_table(path, required, optional, units=units,
                           what=f" for {kind} measurements of {machine.id!r}")
    col, texts, lines, scale = table.numbers, table.texts, table.lines, table.scale
    label = str(path)
    names, angle = actuator_columns(machine)
    q = None
    if kind != "part":
        q = np.column_stack([np.radians(col[n]) if a else col[n] * scale
                             for n, a in zip(names, angle, strict=True)])
    tool_length = col["tool_length"] * scale if "tool_length" in col else None
    if tool_length is not None and not (tool_length >= 0).all():
        i = int(np.flatnonzero(tool_length < 0)[0])
        raise InputError(f"{lines[i]}: column 'tool_length' must be ≥ 0")
    if kind == "point":
        readings = np.column_stack([col[c] for c in "xyz"]) * scale
    elif kind == "pose":
        readings = np.column_stack([col[c] * scale for c in "xyz"]
                                   + [np.radians(col[c]) for c in ANGLE_COLUMNS])
    elif kind == "ballbar":
        readings = col["length"][:, None] * scale
        if not (readings > 0).all():
            i = int(np.flatnonzero(~(readings[:, 0] > 0))[0])
            raise InputError(f"{lines[i]}: column 'length' must be > 0")
    elif kind == "height":
        readings = col["z"][:, None] * scale
    else:
        readings = np.column_stack([col[c] for c in "xyz"]) * scale
    pivot = (np.column_stack([col[c] for c in ("px", "py", "pz")]) * scale
             if kind == "ballbar" else None)
    commanded = (np.column_stack([col[c] for c in READINGS["part"][:6]]) * scale
                 if kind == "part" else None)
    return MeasurementSet(kind=kind, values=readings, q=q, tool_length=tool_length,
                          tool=tuple(texts["tool"]) if "tool" in texts else None,
                          pivot=pivot, path=tuple(texts["path"]) if "path" in texts else None,
                          commanded=commanded, labels=lines, source=label)


def _short(cell: str) -> str:
    """``repr(cell)`` cut to 40 characters (an oversized field in an error message)."""
    text = repr(cell)
    return text if len(text) <= 40 else f"{text[:37]}…"


def _looks_numeric(cells: list[str]) -> bool:
    try:
        [float(c) for c in cells]
    except ValueError:
        return False
    return True


def format_measurements(data: MeasurementSet, machine, *, units: str = "m",
                        comment: str | None = None) -> str:
    """CSV text of ``data`` in the file format of its type (lengths in ``units``); a ``part``
    file has no actuator columns (``machine`` may be None)."""
    scale = length_scale(units)
    cols: list[str] = []
    table: list[np.ndarray | list[str]] = []
    if data.kind != "part":
        names, angle = actuator_columns(machine)
        for k, (n, a) in enumerate(zip(names, angle, strict=True)):
            cols.append(n)
            table.append(np.degrees(data.q[:, k]) if a else data.q[:, k] / scale)
    if data.kind == "part":
        cols.append("path")
        table.append(list(data.path))
        for k, c in enumerate(READINGS["part"][:6]):
            cols.append(c)
            table.append(data.commanded[:, k] / scale)
        for k, c in enumerate("xyz"):
            cols.append(c)
            table.append(data.values[:, k] / scale)
    else:
        if data.kind == "ballbar":
            for k, c in enumerate(("px", "py", "pz")):
                cols.append(c)
                table.append(data.pivot[:, k] / scale)
        for k, c in enumerate(READINGS[data.kind] if data.kind != "ballbar" else ("length",)):
            cols.append(c)
            table.append(np.degrees(data.values[:, k]) if c in ANGLE_COLUMNS
                         else data.values[:, k] / scale)
        if data.tool_length is not None and data.kind != "height":
            cols.append("tool_length")
            table.append(data.tool_length / scale)
        if data.tool is not None and data.kind != "height":
            cols.append("tool")
            table.append(list(data.tool))
    out = io.StringIO()
    if comment:
        for line in comment.splitlines():
            out.write(f"# {line}\n")
    out.write(f"# units: {units}\n")
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(cols)
    for i in range(len(data)):
        writer.writerow([col[i] if isinstance(col, list) else f"{col[i]:.12g}"
                         for col in table])
    return out.getvalue()


def write_measurements(path: str | Path, data: MeasurementSet, machine, *, units: str = "m",
                       comment: str | None = None) -> None:
    """Write ``data`` as a measurement file, atomically
    (:func:`pkmkit.io.atomic.write_text_atomic`)."""
    write_text_atomic(path, format_measurements(data, machine, units=units, comment=comment))


def file_unit(path: str | Path) -> str | None:
    """The unit named by a ``# units: mm`` line among the comment lines heading a file, or
    None (no such line, or the file cannot be read)."""
    try:
        with open(path, encoding="utf-8-sig") as handle:
            for line in handle:
                if not line.lstrip().startswith("#"):
                    return None
                match = _UNIT_LINE.match(line.strip())
                if match:
                    return match.group(1)
    except OSError:
        return None
    return None
