"""Batch tables in CSV, Parquet and Arrow/Feather files, read and written in chunks by pyarrow.

The format follows the file's extension: ``.csv`` (and ``.txt``), ``.parquet``/``.pq``,
``.feather``/``.arrow``/``.ipc``; ``-`` is CSV on standard input or output, so commands compose in
pipelines.

**Input tables** hold one row per case. Columns are matched by name (extra columns are ignored);
a CSV file without a header row uses its first columns in order. CSV files may contain ``#``
comment lines and blank lines and may start with a UTF-8 byte-order mark (spreadsheet exports).
Cells ``nan``/``inf`` are read as such (the batch call flags those rows). A cell that is not a
number, an empty cell, a short row or a number that overflows a double (``1e400``) becomes NaN —
the row is flagged, the others are kept — with a message naming the file line (the row for
Parquet/Feather) and the column.

**Units.** A table states the length unit of its length columns by a ``# units: mm`` comment
line before a CSV header, a ``units`` key in a Parquet/Feather schema's metadata, or per column
as measurement files do (``x [mm]``, ``q4 [deg]``; a ``[unit]`` must agree with the file's
unit); angles are in degrees. A wanted column matches a header cell of the same name without
its ``[unit]``, or failing that the one cell whose name differs only in case (``X``); two
candidates are refused as ambiguous. A reader given ``units`` (the unit the caller reads each
column in) refuses a column stated in another unit, naming it; :class:`TableWriter` given
``units`` records them.

Reading is streamed: :class:`TableReader` yields :class:`TableChunk` objects of at most
``chunk_rows`` rows, so a file larger than memory is processed piece by piece, and the values are
the same whatever the chunk size (each row is parsed on its own). CSV chunks go through pyarrow's
multi-threaded parser; a chunk in which it finds a problem is parsed again line by line to name
the lines.

**Output tables** (:class:`TableWriter`) are written chunk by chunk, atomically (to a temporary
file that replaces the destination only when complete). Floats are written in the shortest form
that reads back to the same double (``0.042444``, not ``0.042444000000000003``); NaN as ``nan``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import BinaryIO

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.table_format import (
    DEFAULT_CHUNK_ROWS,
    FORMATS,
    STDIO,
    TableChunk,
    check_units,
    table_format,
)
from pkmkit.io.table_sources import ArrowSource, CsvSource
from pkmkit.io.table_writer import Labels, TableWriter, csv_text, write_table

__all__ = ["DEFAULT_CHUNK_ROWS", "FORMATS", "STDIO", "Labels", "TableChunk", "TableReader",
           "TableWriter", "csv_text", "read_table", "table_format", "write_table"]


class TableReader:
    """The wanted numeric columns of a table, chunk by chunk.

    Iterate over it for :class:`TableChunk` objects; ``progress`` and ``total`` (bytes for CSV,
    rows otherwise; ``total`` is None on standard input) feed a progress bar.

    Args:
        path: the file, or ``-`` for CSV on standard input.
        columns: wanted column names (in this order).
        chunk_rows: rows per chunk (≥ 1).
        stdin: the binary stream read for ``-`` (default: the process's standard input).
        units: the unit the caller reads each column in (a length unit such as ``"mm"``,
            ``"deg"`` for angles, None for numbers without unit), or None to accept any unit
            the file states (see :func:`~pkmkit.io.table_format.check_units`).

    Attributes:
        file_unit: the length unit the file states (``# units:`` line, ``units`` schema
            metadata), or None; known once the header is read.

    Raises:
        InputError: a missing or unreadable file, a file that is not text (CSV), not Parquet or
            not Arrow, missing or ambiguous columns (with the header's line), a column in
            another unit than ``units`` says, or no data rows.
    """

    def __init__(self, path: str | Path, columns: Sequence[str], *,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS, stdin: BinaryIO | None = None,
                 units: Sequence[str | None] | None = None):
        if int(chunk_rows) < 1:
            raise InputError(f"chunk size must be at least 1 row, got {chunk_rows}")
        self.path = str(path)
        self.columns = list(columns)
        if units is not None and len(units) != len(self.columns):
            raise InputError(f"{len(units)} units for {len(self.columns)} columns")
        self.units = None if units is None else list(units)
        self.file_unit: str | None = None
        self._unit_where = ""
        self.chunk_rows = int(chunk_rows)
        self.format = table_format(path)
        self.progress = 0
        self.total: int | None = None
        self.stdin = stdin  # the stream read for "-" (None: sys.stdin)
        if self.format == "csv":
            self._source = CsvSource(self)
        else:
            self._source = ArrowSource(self)

    def declare_file_unit(self, unit: str, where: str) -> None:
        """Record the file's length unit (a source found it where ``where`` says)."""
        if self.file_unit is not None and unit != self.file_unit:
            raise InputError(f"{where}: the file says {unit} but also {self.file_unit} "
                             f"({self._unit_where})")
        self.file_unit, self._unit_where = unit, where

    def check_units(self, stated: Sequence[str | None], where: str) -> None:
        """Check the units the header states (``stated``: each wanted column's ``[unit]``)
        against those of the caller; nothing to check without them."""
        if self.units is not None:
            check_units(self.columns, stated, self.units, self.file_unit, where,
                        self._unit_where)

    def __iter__(self) -> Iterator[TableChunk]:
        rows = 0
        for chunk in self._source.chunks():
            rows += len(chunk)
            yield chunk
        if rows == 0:
            raise InputError(f"{self.path}: no data rows")

    def read_all(self) -> TableChunk:
        """The whole table as one chunk."""
        parts = list(self)
        return TableChunk(values=np.concatenate([p.values for p in parts]), first_row=0,
                          invalid=np.concatenate([p.invalid for p in parts]),
                          problems=[m for p in parts for m in p.problems])


def read_table(path: str | Path, columns: Sequence[str],
               problems: list[str] | None = None, *,
               units: Sequence[str | None] | None = None) -> np.ndarray:
    """Read the columns ``columns`` of a table into a ``(N, len(columns))`` float array.

    Args:
        path: the file (CSV, Parquet or Feather by extension).
        columns: wanted columns.
        problems: if given, a bad cell or a short row becomes NaN (the batch call flags that
            row) and its message is appended here instead of raising.
        units: the unit each column is read in (see :class:`TableReader`); None accepts the
            values in whatever unit the file states.

    Raises:
        InputError: unreadable file, missing columns, no data rows, a column in another unit
            than ``units``, or (without ``problems``) a bad cell, with its line.

    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "poses.csv"
    >>> _ = path.write_text("# poses\\nz,x,y\\n0.1,0.2,0.3\\n0,abc,0\\n")
    >>> problems = []
    >>> read_table(path, ["x", "y", "z"], problems).tolist()
    [[0.2, 0.3, 0.1], [nan, 0.0, 0.0]]
    >>> problems[0].endswith("poses.csv:4: column 'x' is not a number: 'abc'")
    True
    """
    chunk = TableReader(path, columns, units=units).read_all()
    if chunk.problems and problems is None:
        raise InputError(chunk.problems[0])
    if problems is not None:
        problems.extend(chunk.problems)
    return chunk.values


# --------------------------------------------------------------------------------------- CSV
