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

import csv
import io
import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import atomic_path, check_output_file

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


class TableReader:
    """The wanted numeric columns of a table, chunk by chunk.

    Iterate over it for :class:`TableChunk` objects; ``progress`` and ``total`` (bytes for CSV,
    rows otherwise; ``total`` is None on standard input) feed a progress bar.

    Args:
        path: the file, or ``-`` for CSV on standard input.
        columns: wanted column names (in this order).
        chunk_rows: rows per chunk (≥ 1).
        stdin: the binary stream read for ``-`` (default: the process's standard input).

    Raises:
        InputError: a missing or unreadable file, a file that is not text (CSV), not Parquet or
            not Arrow, missing columns (with the header's line), or no data rows.
    """

    def __init__(self, path: str | Path, columns: Sequence[str], *,
                 chunk_rows: int = DEFAULT_CHUNK_ROWS, stdin: BinaryIO | None = None):
        if int(chunk_rows) < 1:
            raise InputError(f"chunk size must be at least 1 row, got {chunk_rows}")
        self.path = str(path)
        self.columns = list(columns)
        self.chunk_rows = int(chunk_rows)
        self.format = table_format(path)
        self.progress = 0
        self.total: int | None = None
        self._stdin = stdin
        if self.format == "csv":
            self._source = _CsvSource(self)
        else:
            self._source = _ArrowSource(self)

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
               problems: list[str] | None = None) -> np.ndarray:
    """Read the columns ``columns`` of a table into a ``(N, len(columns))`` float array.

    Args:
        path: the file (CSV, Parquet or Feather by extension).
        columns: wanted columns.
        problems: if given, a bad cell or a short row becomes NaN (the batch call flags that
            row) and its message is appended here instead of raising.

    Raises:
        InputError: unreadable file, missing columns, no data rows, or (without ``problems``)
            a bad cell, with its line.

    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "poses.csv"
    >>> _ = path.write_text("# poses\\nz,x,y\\n0.1,0.2,0.3\\n0,abc,0\\n")
    >>> problems = []
    >>> read_table(path, ["x", "y", "z"], problems).tolist()
    [[0.2, 0.3, 0.1], [nan, 0.0, 0.0]]
    >>> problems[0].endswith("poses.csv:4: column 'x' is not a number: 'abc'")
    True
    """
    chunk = TableReader(path, columns).read_all()
    if chunk.problems and problems is None:
        raise InputError(chunk.problems[0])
    if problems is not None:
        problems.extend(chunk.problems)
    return chunk.values


# --------------------------------------------------------------------------------------- CSV


class _CsvSource:
    """CSV bytes cut at line ends into chunks of about ``chunk_rows`` lines."""

    def __init__(self, reader: TableReader):
        self.reader = reader
        self.index: list[int] = []  # column positions of the wanted columns
        self.width = 0  # columns of the header (or of the first row without one)

    def _open(self) -> BinaryIO:
        r = self.reader
        if r.path == STDIO:
            if r._stdin is not None:
                return r._stdin
            import sys

            return sys.stdin.buffer
        try:
            handle = open(r.path, "rb")
        except OSError as exc:
            raise InputError(f"{r.path}: cannot read file: {exc.strerror or exc}") from None
        try:
            import os

            r.total = os.fstat(handle.fileno()).st_size
        except OSError:
            r.total = None
        return handle

    def chunks(self) -> Iterator[TableChunk]:
        r = self.reader
        handle = self._open()
        try:
            yield from self._chunks(handle)
        finally:
            if handle is not r._stdin and r.path != STDIO:
                handle.close()

    def _read(self, handle: BinaryIO, size: int) -> bytes:
        try:
            data = handle.read(size)
        except OSError as exc:
            raise InputError(f"{self.reader.path}: cannot read file: {exc.strerror or exc}"
                             ) from None
        self.reader.progress += len(data)
        if b"\x00" in data:
            raise InputError(f"{self.reader.path}: not a text file (it holds NUL bytes); "
                             "give a CSV file, or a .parquet/.feather table")
        return data

    def _chunks(self, handle: BinaryIO) -> Iterator[TableChunk]:
        r = self.reader
        buffer = self._read(handle, 1 << 16)
        if buffer.startswith(b"\xef\xbb\xbf"):
            buffer = buffer[3:]
        line_no = 1  # file line of buffer[0]
        eof = len(buffer) == 0
        # the header: first line that is neither blank nor a comment
        while True:
            end = buffer.find(b"\n")
            if end < 0 and not eof:
                more = self._read(handle, 1 << 16)
                eof = not more
                buffer += more
                continue
            line = buffer if end < 0 else buffer[:end + 1]
            if not line:
                return  # no data at all: TableReader reports it
            text = _decode(line, r.path, line_no).strip()
            if text and not text.startswith("#") and text.strip(", \t"):
                break
            buffer = buffer[len(line):]
            line_no += 1
        try:
            cells = next(csv.reader([text]))
        except csv.Error as exc:
            raise InputError(f"{r.path}:{line_no}: the header is not a CSV line (a stray "
                             f"carriage return or line break inside it)") from exc
        if _numeric(cells):
            self.width = len(cells)
            self.index = list(range(len(r.columns)))
            if self.width < len(r.columns):
                raise InputError(f"{r.path}:{line_no}: expected at least {len(r.columns)} "
                                 f"columns ({', '.join(r.columns)}), got {self.width}")
        else:
            header = [c.strip() for c in cells]
            missing = [c for c in r.columns if c not in header]
            if missing:
                raise InputError(f"{r.path}:{line_no}: missing column(s) {', '.join(missing)}; "
                                 f"expected {', '.join(r.columns)} (header: "
                                 f"{', '.join(header)})")
            self.width = len(header)
            self.index = [header.index(c) for c in r.columns]
            buffer = buffer[len(line):]
            line_no += 1
        # data: chunks of about chunk_rows lines
        first_row = 0
        sample = buffer[:1 << 16]
        line_bytes = max(len(sample) / max(sample.count(b"\n"), 1), 8.0)
        target = max(int(line_bytes * r.chunk_rows), 1)
        newlines = buffer.count(b"\n")
        while True:
            while not eof and newlines < r.chunk_rows:
                more = self._read(handle, max(target - len(buffer), 1 << 16))
                eof = not more
                buffer += more
                newlines += more.count(b"\n")
            if not buffer:
                break
            cut = _nth_newline(buffer, r.chunk_rows, newlines)
            if cut < 0:
                if not eof:
                    continue
                cut = len(buffer)
            piece, buffer = buffer[:cut], buffer[cut:]
            chunk = self._parse(piece, line_no, first_row)
            taken = piece.count(b"\n")
            line_no += taken
            newlines -= taken
            if len(chunk):
                first_row += len(chunk)
                yield chunk
            if eof and not buffer:
                break

    def _parse(self, piece: bytes, line_no: int, first_row: int) -> TableChunk:
        """Fast path through pyarrow; the slow, line-naming path if it finds any problem."""
        values = self._parse_fast(piece)
        if values is not None:
            return TableChunk(values=values, first_row=first_row,
                              invalid=np.zeros(len(values), dtype=bool))
        return self._parse_slow(piece, line_no, first_row)

    def _parse_fast(self, piece: bytes) -> np.ndarray | None:
        import pyarrow as pa
        import pyarrow.csv as pcsv

        data = _COMMENT.sub(b"", piece) if b"#" in piece and _HAS_COMMENT.search(piece) else piece
        if not data.strip():
            return np.empty((0, len(self.index)))
        names = [f"c{i}" for i in range(self.width)]
        wanted = [names[i] for i in self.index]
        try:
            table = pcsv.read_csv(
                pa.BufferReader(data),
                read_options=pcsv.ReadOptions(column_names=names, block_size=1 << 24),
                convert_options=pcsv.ConvertOptions(
                    include_columns=wanted, column_types=dict.fromkeys(wanted, pa.float64()),
                    null_values=[], strings_can_be_null=False, quoted_strings_can_be_null=False),
            )
        except (pa.ArrowInvalid, pa.ArrowTypeError):
            return None
        values = np.empty((table.num_rows, len(wanted)))
        for j, name in enumerate(wanted):
            values[:, j] = table.column(name).to_numpy()
        if not np.isfinite(values).all():
            return None  # tell an overflow from a written nan/inf: the slow path
        return values

    def _parse_slow(self, piece: bytes, line_no: int, first_row: int) -> TableChunk:
        r = self.reader
        rows, lines = [], []
        text = piece.decode("utf-8", errors="replace")
        for offset, raw in enumerate(text.split("\n")):
            stripped = raw.strip()
            if not stripped or stripped.startswith("#") or not stripped.strip(", \t"):
                continue
            rows.append(raw.rstrip("\r"))
            lines.append(line_no + offset)
        values = np.empty((len(rows), len(self.index)))
        invalid = np.zeros(len(rows), dtype=bool)
        problems: list[str] = []
        need = max(self.index) + 1
        for k, (row, number) in enumerate(zip(rows, lines, strict=True)):
            try:
                cells = next(csv.reader([row]), [])
            except csv.Error:  # e.g. a lone carriage return inside the line
                problems.append(f"{r.path}:{number}: not a CSV line (a stray carriage return "
                                "or line break inside it)")
                values[k] = np.nan
                invalid[k] = True
                continue
            if len(cells) < need:
                problems.append(f"{r.path}:{number}: expected at least {need} columns, got "
                                f"{len(cells)}")
                values[k] = np.nan
                invalid[k] = True
                continue
            for j, col in enumerate(self.index):
                value, message = _cell(cells[col])
                values[k, j] = value
                if message:
                    problems.append(f"{r.path}:{number}: column {r.columns[j]!r} {message}")
                    invalid[k] = True
        return TableChunk(values=values, first_row=first_row, invalid=invalid,
                          problems=problems)


def _nth_newline(buffer: bytes, n: int, count: int) -> int:
    """Index just after the ``n``-th newline of ``buffer`` (which has ``count``), or after its
    last one if it has fewer; -1 if it has none."""
    if count <= n:
        last = buffer.rfind(b"\n")
        return last + 1 if last >= 0 else -1
    ends = np.flatnonzero(np.frombuffer(buffer, dtype=np.uint8) == ord("\n"))
    return int(ends[n - 1]) + 1


def _decode(line: bytes, path: str, line_no: int) -> str:
    try:
        return line.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{path}:{line_no}: not a UTF-8 text line; give a CSV file, or a "
                         ".parquet/.feather table") from None


_SPECIAL = {"nan", "+nan", "-nan", "inf", "+inf", "-inf", "infinity", "+infinity", "-infinity"}


def _cell(text: str) -> tuple[float, str]:
    """A cell's value and, if it is unusable, what is wrong with it (else ``""``)."""
    stripped = text.strip()
    if not stripped:
        return math.nan, "is empty"
    try:
        value = float(stripped)
    except ValueError:
        return math.nan, f"is not a number: {text!r}"
    if math.isinf(value) and stripped.lower() not in _SPECIAL:
        return math.nan, f"overflows a double: {text!r}"
    return value, ""


def _numeric(cells: Sequence[str]) -> bool:
    try:
        [float(c) for c in cells]
    except ValueError:
        return False
    return True


# ---------------------------------------------------------------------------- Parquet, Arrow


class _ArrowSource:
    """Record batches of a Parquet or Arrow IPC (Feather v2) file."""

    def __init__(self, reader: TableReader):
        self.reader = reader

    def _batches(self) -> Iterator[Any]:
        import pyarrow as pa

        r = self.reader
        if r.path == STDIO:
            raise InputError("standard input is read as CSV only")
        kind = "a Parquet" if r.format == "parquet" else "an Arrow/Feather"
        try:
            if r.format == "parquet":
                import pyarrow.parquet as pq

                source = pq.ParquetFile(r.path)
                names = source.schema_arrow.names
                r.total = source.metadata.num_rows
                self._check_columns(names)
                yield from source.iter_batches(batch_size=r.chunk_rows, columns=r.columns)
                return
            try:
                ipc = pa.ipc.open_file(r.path)
                names = ipc.schema.names
                self._check_columns(names)
                r.total = sum(ipc.get_batch(i).num_rows for i in range(ipc.num_record_batches))
                batches = (ipc.get_batch(i) for i in range(ipc.num_record_batches))
            except pa.ArrowInvalid:
                ipc = pa.ipc.open_stream(r.path)
                self._check_columns(ipc.schema.names)
                batches = iter(ipc)
            yield from batches
        except FileNotFoundError:
            raise InputError(f"{r.path}: cannot read file: no such file") from None
        except OSError as exc:
            if isinstance(exc, pa.ArrowException):
                raise InputError(f"{r.path}: not {kind} file ({exc})") from None
            raise InputError(f"{r.path}: cannot read file: {exc.strerror or exc}") from None
        except pa.ArrowException as exc:
            raise InputError(f"{r.path}: not {kind} file ({exc})") from None

    def _check_columns(self, names: Sequence[str]) -> None:
        r = self.reader
        missing = [c for c in r.columns if c not in names]
        if missing:
            raise InputError(f"{r.path}: missing column(s) {', '.join(missing)}; expected "
                             f"{', '.join(r.columns)} (columns: {', '.join(names)})")

    def chunks(self) -> Iterator[TableChunk]:
        import pyarrow as pa

        first_row = 0
        pending: list[Any] = []
        size = 0
        n = self.reader.chunk_rows
        for batch in self._batches():
            pending.append(batch)
            size += batch.num_rows
            while size >= n:
                table = pa.Table.from_batches(pending)  # zero-copy re-chunking
                yield self._convert(table.slice(0, n), first_row)
                first_row += n
                rest = table.slice(n)
                pending, size = rest.to_batches(), rest.num_rows
        if size:
            yield self._convert(pa.Table.from_batches(pending), first_row)

    def _convert(self, table: Any, first_row: int) -> TableChunk:
        import pyarrow as pa
        import pyarrow.compute as pc

        r = self.reader
        n = table.num_rows
        values = np.empty((n, len(r.columns)))
        invalid = np.zeros(n, dtype=bool)
        problems: list[str] = []
        for j, name in enumerate(r.columns):
            column = table.column(name)
            try:
                floats = pc.cast(column, pa.float64())
            except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
                raise InputError(f"{r.path}: column {name!r} is not numeric ({column.type})"
                                 ) from None
            values[:, j] = floats.to_numpy()
            nulls = np.asarray(floats.is_null())
            if nulls.any():
                values[nulls, j] = np.nan
                invalid |= nulls
                problems.extend(f"{r.path}: row {first_row + k + 1}: column {name!r} is empty"
                                for k in np.flatnonzero(nulls))
        self.reader.progress = first_row + n
        return TableChunk(values=values, first_row=first_row, invalid=invalid,
                          problems=problems)


# ------------------------------------------------------------------------------------ writer


class TableWriter:
    """Write a table chunk by chunk, atomically; the format follows the extension (``-``: CSV on
    standard output).

    Use as a context manager: the file appears (replacing any previous one) only when the block
    ends without an exception. Columns are given to :meth:`write` as a mapping name → values:
    float or integer arrays, or :class:`Labels` for text columns.

    Raises:
        InputError: an unknown extension or a destination that cannot be written — at
            construction, before any work is done.

    >>> import io
    >>> out = io.BytesIO()
    >>> with TableWriter("-", stdout=out) as writer:
    ...     writer.write({"q": np.array([0.042444, 0.1 + 0.2]),
    ...                   "status": Labels(np.array([0, 1]), ["ok", "unreachable"])})
    >>> print(out.getvalue().decode(), end="")
    q,status
    0.042444,ok
    0.30000000000000004,unreachable
    """

    def __init__(self, path: str | Path, *, stdout: BinaryIO | None = None):
        self.path = str(path)
        if self.path != STDIO:
            check_output_file(path)
        self.format = table_format(path)
        self._stdout = stdout
        self._writer: Any = None
        self._schema: Any = None
        self._atomic: Any = None
        self._temp: Path | None = None
        self._sink: Any = None  # CSV: the byte stream written
        self._csv_options: Any = None  # CSV: pyarrow's write options
        self._owned: Any = None  # ... when this writer opened it
        self.rows = 0
        if self.path != STDIO:
            self._atomic = atomic_path(self.path)
            self._temp = self._atomic.__enter__()

    def __enter__(self) -> TableWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(exc)

    def close(self, exc: BaseException | None = None) -> None:
        """Finish the file (or, after an exception, discard it)."""
        try:
            if self._writer is not None:
                if self._writer is not _CSV_WRITER:
                    self._writer.close()
                self._writer = None
            if self._owned is not None:
                self._owned.close()
                self._owned = None
            elif self._sink is not None:
                self._sink.flush()
            if self._schema is None and exc is None and self.path != STDIO:
                raise InputError(f"{self.path}: nothing to write")
        except BaseException as error:
            if self._atomic is not None:
                atomic, self._atomic = self._atomic, None
                atomic.__exit__(type(error), error, error.__traceback__)
            raise
        if self._atomic is not None:
            atomic, self._atomic = self._atomic, None
            if exc is None:
                atomic.__exit__(None, None, None)
            else:
                atomic.__exit__(type(exc), exc, exc.__traceback__)

    def write(self, columns: dict[str, Any]) -> None:
        """Append rows: ``columns`` maps each column name to ``(n,)`` values (same n; the same
        names in the same order at every call)."""
        import pyarrow as pa

        arrays = [_to_arrow(v) for v in columns.values()]
        table = pa.table(arrays, names=list(columns))
        if self._writer is None:
            self._schema = table.schema
            texts = [*columns, *(s for v in columns.values() if isinstance(v, Labels)
                                 for s in v.names)]
            self._writer = self._open(table.schema, any(_STRUCTURAL.search(str(t))
                                                        for t in texts))
        else:
            table = table.cast(self._schema)
        try:
            if self._csv_options is not None:
                self._write_csv(table)
            else:
                self._writer.write_table(table)
        except pa.ArrowInvalid as exc:
            raise InputError(f"{self.path}: cannot write these values as CSV: {exc}") from None
        except OSError as exc:
            raise InputError(f"{self.path}: cannot write: {exc.strerror or exc}") from None
        self.rows += table.num_rows

    def _write_csv(self, table: Any) -> None:
        """Format the rows as CSV in slices on every core (pyarrow's formatting releases the
        GIL; each row's text is the same whatever the slicing), then write them in order."""
        import pyarrow as pa
        import pyarrow.csv as pcsv

        def encode(piece: Any) -> Any:
            buffer = pa.BufferOutputStream()
            pcsv.write_csv(piece, buffer, write_options=self._csv_options)
            return buffer.getvalue()

        workers = min(_cpu_count(), max(1, table.num_rows // PARALLEL_CSV_ROWS))
        if workers == 1:
            parts = [encode(table)]
        else:
            from concurrent.futures import ThreadPoolExecutor

            step = -(-table.num_rows // workers)
            slices = [table.slice(k, step) for k in range(0, table.num_rows, step)]
            with ThreadPoolExecutor(workers) as pool:
                parts = list(pool.map(encode, slices))
        for part in parts:
            self._sink.write(memoryview(part))

    def _open(self, schema: Any, quote: bool) -> Any:
        """The pyarrow writer; CSV texts are quoted only if some text needs it (pyarrow then
        quotes every text)."""
        import pyarrow as pa

        if self.format == "csv":
            import pyarrow.csv as pcsv

            if self.path == STDIO:
                if self._stdout is not None:
                    self._sink = self._stdout
                else:
                    import sys

                    self._sink = sys.stdout.buffer
            else:
                self._sink = self._owned = open(self._temp, "wb")
            header = io.StringIO()
            csv.writer(header, lineterminator="\n").writerow(schema.names)
            self._sink.write(header.getvalue().encode("utf-8"))
            self._csv_options = pcsv.WriteOptions(
                include_header=False, quoting_style="needed" if quote else "none",
                batch_size=1 << 16)
            return _CSV_WRITER
        if self.format == "parquet":
            import pyarrow.parquet as pq

            return pq.ParquetWriter(str(self._temp), schema)
        return pa.ipc.new_file(str(self._temp), schema)


#: Rows per thread below which a CSV chunk is formatted in one piece.
PARALLEL_CSV_ROWS = 50_000
#: Marks a CSV output (formatted by :meth:`TableWriter._write_csv`, no pyarrow writer object).
_CSV_WRITER = object()


def _cpu_count() -> int:
    import os

    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class Labels:
    """A text column coded as integers: ``names[codes[k]]`` is row k's text.

    Attributes:
        codes: ``(n,)`` integer array (0 ≤ code < len(names)).
        names: the distinct texts.
    """

    codes: np.ndarray
    names: Sequence[str]


def _to_arrow(values: Any) -> Any:
    import pyarrow as pa

    if isinstance(values, Labels):
        names = [str(s) for s in values.names]
        codes = np.asarray(values.codes, dtype=np.int32)
        return pa.DictionaryArray.from_arrays(pa.array(codes), pa.array(names, pa.string()))
    arr = np.asarray(values)
    if arr.dtype.kind == "f":
        return pa.array(np.ascontiguousarray(arr, dtype=np.float64))
    if arr.dtype.kind in "iub":
        return pa.array(np.ascontiguousarray(arr))
    return pa.array([str(v) for v in arr], pa.string())


def write_table(path: str | Path, header: Sequence[str], rows: Sequence[Sequence]) -> None:
    """Write a small table given row by row (floats in shortest round-trip form), atomically.

    Raises:
        InputError: the file cannot be written (missing directory, permissions).
    """
    columns: dict[str, Any] = {}
    data = list(rows)
    for j, name in enumerate(header):
        cells = [row[j] for row in data]
        if all(isinstance(c, float | int | np.number) and not isinstance(c, bool)
               for c in cells):
            columns[name] = np.asarray(cells, dtype=float if any(
                isinstance(c, float | np.floating) for c in cells) else np.int64)
        else:
            names = sorted({str(c) for c in cells})
            lookup = {s: k for k, s in enumerate(names)}
            columns[name] = Labels(np.array([lookup[str(c)] for c in cells], dtype=np.int32),
                                   names)
    with TableWriter(path) as writer:
        writer.write(columns)


def csv_text(columns: dict[str, Any]) -> str:
    """The CSV text of a small table (as :class:`TableWriter` writes it)."""
    buffer = io.BytesIO()
    writer = TableWriter(STDIO, stdout=buffer)
    writer.write(columns)
    writer.close()
    return buffer.getvalue().decode("utf-8")
