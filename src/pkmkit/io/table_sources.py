"""Chunked sources of batch tables: CSV (pyarrow's parser, line-by-line diagnosis of bad
chunks) and Parquet/Feather, yielding :class:`~pkmkit.io.table.TableChunk` values."""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.table_format import (
    _COMMENT,
    _HAS_COMMENT,
    STDIO,
    UNIT_LINE,
    TableChunk,
    match_columns,
)

if TYPE_CHECKING:  # a source reads the options of the reader that owns it
    from pkmkit.io.table import TableReader


class CsvSource:
    """CSV bytes cut at line ends into chunks of about ``chunk_rows`` lines."""

    def __init__(self, reader: TableReader):
        self.reader = reader
        self.index: list[int] = []  # column positions of the wanted columns
        self.width = 0  # columns of the header (or of the first row without one)

    def _open(self) -> BinaryIO:
        r = self.reader
        if r.path == STDIO:
            if r.stdin is not None:
                return r.stdin
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
            if handle is not r.stdin and r.path != STDIO:
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
            unit = UNIT_LINE.match(text.strip(' ,"'))
            if unit:  # a "# units: mm" line before the header
                r.declare_file_unit(unit.group(1), f"{r.path}:{line_no}")
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
            r.check_units([None] * len(r.columns), f"{r.path}:{line_no}")
        else:
            header = [c.strip() for c in cells]
            self.index, stated = match_columns(header, r.columns, f"{r.path}:{line_no}")
            r.check_units(stated, f"{r.path}:{line_no}")
            self.width = len(header)
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
                # at most 64 MiB a read: a first line of megabytes made the estimate of a
                # chunk's size terabytes, and read() allocates it up front (MemoryError)
                more = self._read(handle, min(max(target - len(buffer), 1 << 16), 1 << 26))
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
            taken = min(newlines, r.chunk_rows)  # the piece's line ends (_nth_newline's cut)
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
        if not data or data.isspace():  # strip()'s test without its copy of the piece
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
            _fill(values[:, j], table.column(name))
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


def _fill(out: np.ndarray, column: Any) -> None:
    """Copy a float64 Arrow (chunked) array into ``out`` ``(n,)`` from its data buffers (the
    values of null slots are undefined: the callers mark them). Not ``to_numpy``: pyarrow's
    conversion of a chunked array consults its pandas shim, which imports pandas (0.3 to 0.9 s)
    when it is installed."""
    start = 0
    for chunk in getattr(column, "chunks", [column]):
        n = len(chunk)
        if n:
            data = chunk.buffers()[1]
            out[start:start + n] = np.frombuffer(data, dtype=np.float64, count=n,
                                                 offset=8 * chunk.offset)
        start += n


def _nth_newline(buffer: bytes, n: int, count: int) -> int:
    """Index just after the ``n``-th newline of ``buffer`` (which has ``count``), or after its
    last one if it has fewer; -1 if it has none."""
    if count <= n:
        last = buffer.rfind(b"\n")
        return last + 1 if last >= 0 else -1
    # from where the lines' mean length puts it: count the line ends before that byte, then
    # step to the n-th (a few finds on tables of even lines; bounded, else NumPy's scan)
    guess = int(len(buffer) * (n / count))
    seen = buffer.count(b"\n", 0, guess)
    if 0 < n - seen <= _NEWLINE_STEPS:  # forward to the n-th line end
        at = guess
        for _ in range(n - seen):
            at = buffer.index(b"\n", at) + 1
        return at
    if 0 <= seen - n <= _NEWLINE_STEPS:  # back from the seen-th, the last one before guess
        at = buffer.rindex(b"\n", 0, guess)
        for _ in range(seen - n):
            at = buffer.rindex(b"\n", 0, at)
        return at + 1
    ends = np.flatnonzero(np.frombuffer(buffer, dtype=np.uint8) == ord("\n"))
    return int(ends[n - 1]) + 1


#: Line ends :func:`_nth_newline` steps over from its estimate before it scans the chunk.
_NEWLINE_STEPS = 4096


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
    if "_" in stripped or not stripped.isascii():  # float() takes 1_000 and other scripts' digits
        return math.nan, f"is not a number: {text!r}"
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


class ArrowSource:
    """Record batches of a Parquet or Arrow IPC (Feather v2) file."""

    def __init__(self, reader: TableReader):
        self.reader = reader
        self.names: list[str] = []  # the wanted columns' names in the file

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
                r.total = source.metadata.num_rows
                self._check_columns(source.schema_arrow)
                yield from source.iter_batches(batch_size=r.chunk_rows, columns=self.names)
                return
            try:
                ipc = pa.ipc.open_file(r.path)
                self._check_columns(ipc.schema)
                r.total = sum(ipc.get_batch(i).num_rows for i in range(ipc.num_record_batches))
                batches = (ipc.get_batch(i) for i in range(ipc.num_record_batches))
            except pa.ArrowInvalid:
                ipc = pa.ipc.open_stream(r.path)
                self._check_columns(ipc.schema)
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

    def _check_columns(self, schema: Any) -> None:
        """Find the wanted columns (``self.names``: their names in the file) and check their
        units against the schema's ``units`` metadata and their ``[unit]`` suffixes."""
        r = self.reader
        names = list(schema.names)
        index, stated = match_columns(names, r.columns, r.path)
        self.names = [names[k] for k in index]
        unit = (schema.metadata or {}).get(b"units")
        if unit is not None:
            r.declare_file_unit(unit.decode("utf-8", errors="replace"),
                                f"{r.path}: schema metadata 'units'")
        r.check_units(stated, r.path)

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

        r = self.reader
        n = table.num_rows
        values = np.empty((n, len(r.columns)))
        invalid = np.zeros(n, dtype=bool)
        problems: list[tuple[int, int, str]] = []  # (row, column, message)
        for j, (name, actual) in enumerate(zip(r.columns, self.names, strict=True)):
            column = table.column(actual)
            try:
                floats = column if column.type == pa.float64() else _cast_to_float(column, name,
                                                                                    r.path)
            except InputError:
                if not _is_text(column.type):
                    raise
                # a text column with some cells not numbers: those rows flagged, as a CSV's
                bad = _text_cells(column, values[:, j])
                invalid[[k for k, _ in bad]] = True
                problems.extend((k, j, f"{r.path}: row {first_row + k + 1}: column {name!r} "
                                 f"{what}") for k, what in bad)
                continue
            _fill(values[:, j], floats)
            nulls = np.zeros(n, dtype=bool)
            if floats.null_count:
                nulls = _null_flags(floats, n)
            if nulls.any():
                values[nulls, j] = np.nan
                invalid |= nulls
                problems.extend((k, j, f"{r.path}: row {first_row + k + 1}: column {name!r} "
                                 "is empty") for k in np.flatnonzero(nulls))
        self.reader.progress = first_row + n
        # row by row, as a CSV's (the first message names the first bad row in any chunks)
        return TableChunk(values=values, first_row=first_row, invalid=invalid,
                          problems=[text for _, _, text in sorted(problems)])


def _cast_to_float(column: Any, name: str, path: str) -> Any:
    """A numeric column that is not float64 (integers, float32, decimals) cast to float64.
    Only here is ``pyarrow.compute`` imported (≈ 0.05–0.2 s: it builds its function wrappers
    and their docstrings); a float64 column, what pkmkit and most tools write, is read as it
    is.

    Raises:
        InputError: the column is not numeric (text, dates), naming it and its type.
    """
    import pyarrow as pa
    import pyarrow.compute as pc

    try:  # integers beyond 2**53 rounded to the nearest double, as a CSV cell's text is
        return pc.cast(column, pa.float64(), safe=not pa.types.is_integer(column.type))
    except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
        raise InputError(f"{path}: column {name!r} is not numeric ({column.type})") from None


def _is_text(kind: Any) -> bool:
    """A string column, plain or dictionary-encoded."""
    import pyarrow as pa

    if pa.types.is_dictionary(kind):
        kind = kind.value_type
    return pa.types.is_string(kind) or pa.types.is_large_string(kind)


def _text_cells(column: Any, out: np.ndarray) -> list[tuple[int, str]]:
    """A text column's cells read as a CSV's (:func:`_cell`) into ``out`` ``(n,)``; the rows
    whose cell is not a number (or null), with what is wrong with each."""
    bad = []
    for k, text in enumerate(column.to_pylist()):
        out[k], what = (math.nan, "is empty") if text is None else _cell(text)
        if what:
            bad.append((k, what))
    return bad


def _null_flags(column: Any, n: int) -> np.ndarray:
    """``(n,)`` bool: the null slots of a (chunked) Arrow column, from its validity bitmaps
    (no ``pyarrow.compute``)."""
    flags = np.zeros(n, dtype=bool)
    start = 0
    for chunk in getattr(column, "chunks", [column]):
        size = len(chunk)
        bitmap = chunk.buffers()[0]
        if size and chunk.null_count and bitmap is not None:
            bits = np.unpackbits(np.frombuffer(bitmap, dtype=np.uint8), bitorder="little")
            flags[start:start + size] = bits[chunk.offset:chunk.offset + size] == 0
        start += size
    return flags


# ------------------------------------------------------------------------------------ writer
