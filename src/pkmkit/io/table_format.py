"""Batch-table formats by extension, the standard-stream name, the chunk size and the chunk
value every source yields."""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pkmkit.exceptions import InputError

#: Rows per chunk when none is given (about 100 MB of working memory for a kinematics batch).
DEFAULT_CHUNK_ROWS = 500_000

#: The name that means standard input or output (CSV).
STDIO = "-"

FORMATS = {".csv": "csv", ".txt": "csv", ".parquet": "parquet", ".pq": "parquet",
           ".feather": "feather", ".arrow": "feather", ".ipc": "feather"}

_COMMENT = re.compile(rb"(?m)^[ \t]*#[^\n]*(\n|$)")
#: A ``# units: mm`` comment line (the length unit of a table's length columns).
UNIT_LINE = re.compile(r"^#\s*units?\s*[:=]\s*([A-Za-z]+)\s*$")
#: A column name with its unit: ``x [mm]``, ``q4 [deg]``.
COLUMN_UNIT = re.compile(r"^(.*?)\s*\[\s*([A-Za-z°]+)\s*\]\s*$")
#: The one angle unit of files (``°`` is read as ``deg``).
ANGLE_UNIT = "deg"
_HAS_COMMENT = re.compile(rb"(?m)^[ \t]*#")
_STRUCTURAL = re.compile(r'[,"\r\n]')


def table_format(path: str | Path) -> str:
    """``"csv"``, ``"parquet"`` or ``"feather"`` from the file's extension (``-``: CSV).

    Raises:
        InputError: an unknown extension.
    """
    if str(path) == STDIO:
        return "csv"
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise InputError(f"{path}: unknown table type {Path(path).suffix!r}; use .csv, .parquet "
                         "or .feather (or - for CSV on standard input/output)")
    return fmt


@dataclass(frozen=True)
class TableChunk:
    """Consecutive rows of an input table.

    Attributes:
        values: ``(n, k)`` float values of the wanted columns (NaN where a cell was unreadable).
        first_row: 0-based index of the chunk's first data row in the whole table.
        invalid: ``(n,)`` rows with an unreadable cell (listed in ``problems``).
        problems: messages ``"FILE:LINE: ..."`` (CSV) or ``"FILE: row R: ..."``, one per bad cell.
    """

    values: np.ndarray
    first_row: int
    invalid: np.ndarray
    problems: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.values)


def split_unit(cell: str) -> tuple[str, str | None]:
    """A header cell's column name and its ``[unit]`` (None without one): ``"x [mm]"`` →
    ``("x", "mm")``, ``"A [°]"`` → ``("A", "deg")``."""
    match = COLUMN_UNIT.match(cell.strip())
    if not match:
        return cell.strip(), None
    unit = match.group(2)
    return match.group(1).strip(), ANGLE_UNIT if unit == "°" else unit


def match_columns(header: Sequence[str], wanted: Sequence[str], where: str
                  ) -> tuple[list[int], list[str | None]]:
    """Positions in ``header`` of the ``wanted`` columns and the unit each one's cell states.

    A wanted column is the header cell of the same name, without its ``[unit]``; failing that,
    the one cell whose name differs only in case (``X`` for ``x``).

    Raises:
        InputError: (prefixed by ``where``) a missing column, or a wanted column found more
            than once (``x`` and ``x [mm]``, or ``x`` and ``X``).
    """
    cells = [split_unit(c) for c in header]
    names = [n for n, _ in cells]
    index: list[int] = []
    missing = []
    for name in wanted:
        found = [k for k, n in enumerate(names) if n.casefold() == name.casefold()]
        if len(found) > 1:
            shown = ", ".join(repr(header[k].strip()) for k in found)
            raise InputError(f"{where}: column {name!r} is ambiguous: the header has {shown}; "
                             "keep one")
        if not found:
            missing.append(name)
        else:
            index.append(found[0])
    if missing:
        raise InputError(f"{where}: missing column(s) {', '.join(missing)}; expected "
                         f"{', '.join(wanted)} (header: {', '.join(c.strip() for c in header)})")
    return index, [cells[k][1] for k in index]


def check_units(wanted: Sequence[str], stated: Sequence[str | None], expected: Sequence[
        str | None], file_unit: str | None, where: str, unit_where: str) -> None:
    """Refuse a table whose stated units differ from those the command reads.

    Args:
        wanted: the column names.
        stated: each column's ``[unit]`` (None if its header names none).
        expected: each column's unit in the command (a length unit of
            :data:`~pkmkit.model.parameters.LENGTH_UNITS`, ``"deg"``, or None for a number
            without unit).
        file_unit: the table's length unit (``# units:`` line, Parquet/Feather ``units``
            metadata), or None; it applies to the length columns without a ``[unit]``.
        where: ``FILE:LINE`` of the header (``FILE`` for Parquet/Feather).
        unit_where: where ``file_unit`` is stated.

    Raises:
        InputError: an unknown unit, a ``[unit]`` that contradicts ``file_unit``, or a column
            in another unit than the command's (naming the column, the two units and the
            ``--units`` to give).
    """
    from pkmkit.model.parameters import LENGTH_UNITS

    lengths = ", ".join(LENGTH_UNITS)
    if file_unit is not None and file_unit not in LENGTH_UNITS:
        raise InputError(f"{unit_where}: unknown unit {file_unit!r}; use one of {lengths} "
                         "(angles are in degrees)")
    for name, unit, want in zip(wanted, stated, expected, strict=True):
        if unit is not None and unit != ANGLE_UNIT and unit not in LENGTH_UNITS:
            raise InputError(f"{where}: column {name!r}: unknown unit {unit!r}; use one of "
                             f"{lengths} or {ANGLE_UNIT}")
        if unit is not None and unit in LENGTH_UNITS and file_unit not in (None, unit):
            raise InputError(f"{where}: column {name!r} is in {unit} but the file says "
                             f"{file_unit} ({unit_where})")
        if want is None:
            if unit is not None:
                raise InputError(f"{where}: column {name!r} is a number without unit, not "
                                 f"in {unit}")
            continue
        if want == ANGLE_UNIT:
            if unit is not None and unit != ANGLE_UNIT:
                raise InputError(f"{where}: column {name!r} is an angle, in degrees, not "
                                 f"in {unit}")
            continue
        if unit == ANGLE_UNIT:
            raise InputError(f"{where}: column {name!r} is a length (in {want}), not an angle")
        have = unit if unit is not None else file_unit
        if have is not None and have != want:
            raise InputError(f"{where if unit is not None else unit_where}: column {name!r} "
                             f"is in {have} but the command reads {want} (--units {want}); "
                             f"give --units {have}")
