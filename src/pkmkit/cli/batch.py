"""Batch mode of the kinematics commands: ``--input`` table → per-row results → ``--output``
table, chunk by chunk.

The input is read and the output written in chunks of ``--chunk-rows`` rows (CSV, Parquet or
Feather by extension; ``-`` is CSV on standard input/output), so memory stays bounded by the chunk
size whatever the file size, and the results are the same as in one piece. A progress bar is
drawn on standard error when it is a terminal. The output file is written atomically and its
destination checked before any work starts.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from typing import Any

import click
import numpy as np

from pkmkit.status import Status

#: How many unreadable-cell warnings are printed before they are only counted.
MAX_WARNINGS = 20

#: ``(columns, status[, source])`` from the input values of a chunk (file units) and the chunk:
#: the output columns, the status of each input row and, when output rows are not one per
#: input row, the input row of each output row.
Compute = Callable[[np.ndarray, Any], tuple]


def batch_options(func):
    """``--input``, ``--output`` and ``--chunk-rows`` options."""
    func = click.option("--chunk-rows", type=click.IntRange(min=1), default=None,
                        help="Rows per chunk in batch mode (memory bound; default 500000).")(func)
    func = click.option("--output", "output", type=click.Path(dir_okay=False, allow_dash=True),
                        help="Output table (batch mode): .csv, .parquet, .feather, or - for "
                             "CSV on standard output; it records --units (a '# units:' line, "
                             "'units' schema metadata).")(func)
    func = click.option("--input", "input_", type=click.Path(dir_okay=False, allow_dash=True),
                        help="Input table, one row per case (batch mode): .csv, .parquet, "
                             ".feather, or - for CSV on standard input. A unit it states ('# "
                             "units: mm', 'x [mm]' headers) must be --units.")(func)
    return func


def status_names() -> list[str]:
    """Labels of the :class:`Status` codes, indexed by code."""
    return [Status(code).label for code in range(max(Status) + 1)]


def run_batch(input_: str, output: str, columns: list[str], compute: Compute, *,
              chunk_rows: int | None = None, note: Callable[[], str] | None = None,
              units: str | None = None, column_units: Sequence[str | None] | None = None
              ) -> None:
    """Read ``columns`` of ``input_`` chunk by chunk, write what ``compute`` returns to
    ``output`` and report on standard error; exit with status 3 if some rows were flagged.

    ``compute(values, chunk)`` gets the chunk's values in the command's units and returns the
    output columns (name → array or :class:`~pkmkit.io.table.Labels`) and the ``(n,)`` status
    of the chunk's input rows.

    ``units`` (``--units``) is recorded in the output (``# units:`` line, ``units`` schema
    metadata); ``column_units`` gives the unit each input column is read in (``--units``,
    ``"deg"``, None), and a table stating another one (``x [mm]``, ``# units: mm``) is refused
    naming the column before any work is done.
    """
    from pkmkit.io.table import DEFAULT_CHUNK_ROWS, TableReader, TableWriter

    reader = TableReader(input_, columns, chunk_rows=chunk_rows or DEFAULT_CHUNK_ROWS,
                         units=column_units)
    counts = np.zeros(max(Status) + 1, dtype=np.int64)
    warned = 0
    rows = 0
    with TableWriter(output, units=units) as writer, _progress(reader) as bar:
        for chunk in reader:
            for message in chunk.problems:
                if warned < MAX_WARNINGS:
                    click.echo(f"warning: {message} (row flagged invalid-input)", err=True)
                warned += 1
            out, status = _compute_rows(compute, chunk)
            writer.write(out)
            counts += np.bincount(np.asarray(status, dtype=np.int64).ravel(),
                                  minlength=len(counts))
            rows += len(chunk)
            if bar.total is None and reader.total is not None:
                bar.total = reader.total
            bar.update(reader.progress - bar.n)
    if warned > MAX_WARNINGS:
        click.echo(f"warning: {warned - MAX_WARNINGS} more unreadable cells not shown", err=True)
    bad = int(rows - counts[Status.OK])
    where = "standard output" if output == "-" else output
    click.echo(f"wrote {rows} rows to {where}; {bad} flagged{note() if note else ''}", err=True)
    if bad:
        names = status_names()
        flagged = {names[c]: int(counts[c]) for c in np.flatnonzero(counts)}
        click.echo(f"statuses: {dict(sorted(flagged.items()))}", err=True)
        sys.exit(3)


class ChunkBuffers:
    """Arrays a batch command's ``compute`` reuses from one chunk to the next instead of
    fresh ones per chunk (issue 22 §2: on this 2-core machine Linux clearing an output's
    fresh pages costs about a quarter of the six-axis inverse kernel's time per pose). A
    chunk's arrays are dead once :func:`run_batch` has written its output (the writer copies
    or writes them before ``write`` returns), so the next chunk may overwrite them."""

    def __init__(self) -> None:
        self._arrays: dict[str, np.ndarray] = {}

    def take(self, name: str, rows: int, width: int, order: str = "C") -> np.ndarray:
        """A ``(rows, width)`` float64 array named ``name``: the first ``rows`` rows of one
        kept from an earlier chunk (C order: C-contiguous, e.g. for ``ik(X, out=...)``; F
        order: each column contiguous, e.g. output columns), allocated anew only when a
        chunk has more rows than any before. Its values are stale: the caller writes every
        element."""
        arr = self._arrays.get(name)
        if arr is None or arr.shape[0] < rows or arr.shape[1] != width:
            arr = self._arrays[name] = np.empty((rows, width), order=order)
        return arr[:rows]


def _compute_rows(compute: Compute, chunk: Any) -> tuple[dict[str, Any], np.ndarray]:
    """``compute`` on a chunk, never on a single row: NumPy's einsum sums in another order when
    the batch has one row, which changes the last bit of some results (singular values), and a
    row's result must not depend on how the table was cut. A one-row chunk is computed as two
    copies of the row and the copy's output dropped."""
    from pkmkit.io.table import Labels

    n = len(chunk.values)
    values = chunk.values if n != 1 else np.repeat(chunk.values, 2, axis=0)
    out, status, *rest = compute(values, chunk)
    if n != 1:
        return out, status
    source = np.asarray(rest[0]) if rest else np.arange(len(values))
    keep = source < n
    trimmed = {name: (Labels(np.asarray(col.codes)[keep], col.names) if isinstance(col, Labels)
                      else np.asarray(col)[keep]) for name, col in out.items()}
    return trimmed, np.asarray(status)[:n]


class _NoBar:
    n = 0
    total = 0

    def update(self, count: int) -> None:
        pass

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc: object) -> None:
        pass


def _progress(reader: Any) -> Any:
    """A tqdm bar on a terminal (bytes for CSV, rows otherwise), else nothing."""
    stream = sys.stderr
    if not (hasattr(stream, "isatty") and stream.isatty()):
        return _NoBar()
    from tqdm import tqdm

    unit = "B" if reader.format == "csv" else " rows"
    return tqdm(total=reader.total, unit=unit, unit_scale=True, file=stream, leave=False,
                desc=str(reader.path))
