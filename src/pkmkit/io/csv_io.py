"""Batch tables in CSV: numeric input columns, mixed output columns.

Input files have one row per pose (or actuator vector), an optional header naming the columns,
and ``#`` comment lines; a UTF-8 byte-order mark (spreadsheet exports) is accepted. Cells
``nan``/``inf`` are read as such (the batch call flags those rows). Any other non-numeric cell is
an error naming the file line and column — or, when the caller collects problems, a NaN that
flags only that row.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pkmkit.errors import InputError


def read_table(path: str | Path, columns: Sequence[str],
               problems: list[str] | None = None) -> np.ndarray:
    """Read the columns ``columns`` of a CSV file into a ``(N, len(columns))`` float array.

    With a header, columns are matched by name (extra columns are ignored); without one, the
    first ``len(columns)`` columns are used in order.

    Args:
        path: the file.
        columns: wanted columns.
        problems: if given, a bad cell or a short row becomes NaN (the batch call flags that
            row) and a message ``"FILE:LINE: ..."`` is appended here instead of raising.

    Raises:
        InputError: unreadable file, missing columns, no data rows, or (without ``problems``)
            a non-numeric cell or a short row, with its line.
    """
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            rows = [
                (number, row)
                for number, row in enumerate(csv.reader(handle), start=1)
                if row and not row[0].lstrip().startswith("#") and any(c.strip() for c in row)
            ]
    except OSError as exc:
        raise InputError(f"{path}: cannot read file: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: not a CSV text file: {exc}") from None
    if not rows:
        raise InputError(f"{path}: no data rows")
    index = list(range(len(columns)))
    first_line, first = rows[0]
    if not _numeric(first):
        header = [c.strip() for c in first]
        missing = [c for c in columns if c not in header]
        if missing:
            raise InputError(
                f"{path}:{first_line}: missing column(s) {', '.join(missing)}; "
                f"expected {', '.join(columns)}"
            )
        index = [header.index(c) for c in columns]
        rows = rows[1:]
    if not rows:
        raise InputError(f"{path}: no data rows after the header")
    out = np.empty((len(rows), len(columns)))

    def problem(message: str) -> None:
        if problems is None:
            raise InputError(message)
        problems.append(message)

    for k, (number, row) in enumerate(rows):
        if len(row) <= max(index):
            problem(f"{path}:{number}: expected at least {max(index) + 1} columns, got {len(row)}")
            out[k] = np.nan
            continue
        for j, col in enumerate(index):
            try:
                out[k, j] = float(row[col])
            except ValueError:
                problem(f"{path}:{number}: column {columns[j]!r} is not a number: {row[col]!r}")
                out[k, j] = np.nan
    return out


def _numeric(row: Sequence[str]) -> bool:
    try:
        [float(c) for c in row]
    except ValueError:
        return False
    return True


def write_table(path: str | Path, header: Sequence[str], rows: Sequence[Sequence]) -> None:
    """Write a CSV file with a header row; floats are written with 17 significant digits.

    Raises:
        InputError: the file cannot be written (missing directory, permissions).
    """
    try:
        with open(path, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(header)
            for row in rows:
                writer.writerow([f"{float(v):.17g}" if isinstance(v, float | np.floating) else v
                                 for v in row])
    except OSError as exc:
        raise InputError(f"{path}: cannot write file: {exc.strerror or exc}") from None
