"""Batch-table formats by extension, the standard-stream name, the chunk size and the chunk
value every source yields."""

from __future__ import annotations

import re
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
