"""Writing batch tables chunk by chunk, atomically (CSV, Parquet, Feather)."""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import atomic_path, check_output_file, write_bytes_atomic
from pkmkit.io.table_format import _STRUCTURAL, STDIO, table_format


class TableWriter:
    """Write a table chunk by chunk, atomically; the format follows the extension (``-``: CSV on
    standard output).

    Use as a context manager: the file appears (replacing any previous one) only when the block
    ends without an exception. Columns are given to :meth:`write` as a mapping name → values:
    float or integer arrays, or :class:`Labels` for text columns.

    ``units`` (a length unit) records the unit of the table's length columns: a
    ``# units: mm`` line before a CSV header, a ``units`` key in the schema metadata of a
    Parquet or Feather file (angles are in degrees) — what :class:`~pkmkit.io.table.TableReader`
    reads back.

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

    def __init__(self, path: str | Path, *, stdout: BinaryIO | None = None,
                 units: str | None = None):
        self.path = str(path)
        self.units = units
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
        self._quote = False  # CSV: every text cell quoted (some text needs it)
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

        csv_text = self.format == "csv"  # a CSV's bools are written 0/1, as they read back
        arrays = [_to_arrow(v, csv_text) for v in columns.values()]
        table = pa.Table.from_arrays(arrays, names=list(columns))  # pa.table imports pandas
        if self._writer is None:
            if self.units is not None:
                table = table.replace_schema_metadata({"units": self.units})
            self._schema = table.schema
            texts = [*columns, *(s for v in columns.values() if isinstance(v, Labels)
                                 for s in v.names)]
            self._writer = self._open(table.schema, any(_STRUCTURAL.search(str(t))
                                                        for t in texts))
        elif table.schema.equals(self._schema, check_metadata=False):
            # the usual later chunk: the same types, the first's metadata (no copy; cast
            # would import pyarrow.compute, ≈ 0.05–0.2 s)
            table = table.replace_schema_metadata(self._schema.metadata)
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
        """Format the rows as CSV in slices on every core (the formatting releases the GIL;
        each row's text is the same whatever the slicing), then write them in order: by the C
        formatter (:func:`_native_columns`) when the table's columns are its kinds, else by
        pyarrow."""
        columns = _native_columns(table, self._quote)
        if columns is not None:
            self._write_native_csv(columns, table.num_rows)
            return
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

    def _write_native_csv(self, columns: tuple, rows: int) -> None:
        """Rows formatted by ``pkmkit.native.kernels.csv_rows`` in pieces of
        :data:`NATIVE_CSV_ROWS` rows over the cores, written in order as they come (the
        pieces finished ahead of the one being written wait for it: at most the chunk's text,
        as with pyarrow's slices)."""
        from pkmkit.numerics.jit import native_kernels

        csv_rows = native_kernels().csv_rows
        pieces = [(k, min(rows, k + NATIVE_CSV_ROWS)) for k in range(0, rows, NATIVE_CSV_ROWS)]
        workers = min(_cpu_count(), max(1, rows // PARALLEL_CSV_ROWS), len(pieces))
        if workers <= 1:
            for start, stop in pieces:
                self._sink.write(csv_rows(columns, start, stop))
            return
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(workers) as pool:
            for part in pool.map(lambda piece: csv_rows(columns, *piece), pieces):
                self._sink.write(part)

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
            if self.units is not None:
                header.write(f"# units: {self.units}\n")
            csv.writer(header, lineterminator="\n").writerow(schema.names)
            self._sink.write(header.getvalue().encode("utf-8"))
            self._quote = quote
            self._csv_options = pcsv.WriteOptions(
                include_header=False, quoting_style="needed" if quote else "none",
                batch_size=1 << 16)
            return _CSV_WRITER
        if self.format == "parquet":
            import pyarrow.parquet as pq

            return pq.ParquetWriter(str(self._temp), schema,
                                    use_dictionary=_dictionary_columns(schema))
        return pa.ipc.new_file(str(self._temp), schema)


def _dictionary_columns(schema: Any) -> list[str]:
    """The Parquet columns written dictionary-encoded: the text columns (:class:`Labels`:
    ``status``, ``mode``, a handful of distinct values). Numbers are written plain (still
    Snappy-compressed, pyarrow's default): pyarrow's default dictionary-encodes every column,
    and on floats that rarely repeat (poses, actuator coordinates) it hashes a megabyte of
    values per column and row group before falling back to plain pages — two thirds of the
    write's time, for a file no larger (5 % smaller on random poses). Every Parquet
    reader reads both encodings (pyarrow, pandas, Polars, DuckDB, Spark)."""
    import pyarrow as pa

    return [field.name for field in schema
            if pa.types.is_dictionary(field.type) or pa.types.is_string(field.type)]


#: Rows per thread below which a CSV chunk is formatted in one piece.
PARALLEL_CSV_ROWS = 50_000
#: Rows per piece the C formatter formats at once (a few MB of text).
NATIVE_CSV_ROWS = 1 << 15
#: Marks a CSV output (formatted by :meth:`TableWriter._write_csv`, no pyarrow writer object).
_CSV_WRITER = object()


def _native_columns(table: Any, quote: bool) -> tuple | None:
    """The table's columns as ``pkmkit.native.kernels.csv_rows`` takes them (float64 and
    integer arrays; a text column of :class:`Labels` as its codes and its texts, quoted when
    ``quote``), or None where pyarrow writes the table: no extension (or ``PKMKIT_NATIVE=0``),
    a column of another type (strings, bools), nulls, several chunks, or a text that needs
    quotes in a file whose texts are not quoted (pyarrow's error then)."""
    from pkmkit.numerics.jit import native_kernels

    kernels = native_kernels()
    if kernels is None or not hasattr(kernels, "csv_rows"):
        return None
    import pyarrow as pa

    columns: list[Any] = []
    for column in table.columns:
        if column.num_chunks != 1 or column.null_count:
            return None
        values = column.chunk(0)
        kind = values.type
        if pa.types.is_float64(kind) or pa.types.is_integer(kind):
            columns.append(_values_of(values, np.dtype(np.float64) if pa.types.is_float64(kind)
                                      else _integer_dtype(kind)))
            continue
        if not (pa.types.is_dictionary(kind) and pa.types.is_string(kind.value_type)
                and values.dictionary.null_count == 0):
            return None
        texts = values.dictionary.to_pylist()
        if not quote and any(_STRUCTURAL.search(t) for t in texts):
            return None
        cells = tuple(('"' + t.replace('"', '""') + '"' if quote else t).encode("utf-8")
                      for t in texts)
        indices = values.indices
        columns.append((_values_of(indices, _integer_dtype(indices.type)), cells))
    return tuple(columns)


def _integer_dtype(kind: Any) -> np.dtype:
    """The NumPy dtype of an Arrow integer type (int8 … uint64)."""
    import pyarrow as pa

    return np.dtype(f"{'i' if pa.types.is_signed_integer(kind) else 'u'}{kind.bit_width // 8}")


def _values_of(values: Any, dtype: np.dtype) -> np.ndarray:
    """A null-free Arrow array's values ``(n,)`` as a read-only NumPy view of its data buffer
    (no copy). Not ``to_numpy``: pyarrow's conversion consults its pandas shim, which imports
    pandas when it is installed (0.3 to 0.9 s; ``tests/io/test_table_no_pandas.py``), as
    ``table_sources._fill`` says."""
    return np.frombuffer(values.buffers()[1], dtype=dtype, count=len(values),
                         offset=dtype.itemsize * values.offset)


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


def _to_arrow(values: Any, csv_text: bool = False) -> Any:
    """An Arrow array of ``(n,)`` values, built from buffers: ``pa.array`` and ``pa.table`` ask
    pyarrow's pandas shim whether their argument is a pandas object, which imports pandas
    (0.3 to 0.9 s) when it is installed. With ``csv_text`` a bool array is written as uint8
    0/1: pyarrow's CSV writer would write ``true``/``false``, which no number column reads
    (pkmkit's reader flags them), while a Parquet/Feather bool column reads as 0/1."""
    import pyarrow as pa

    if isinstance(values, Labels):
        codes = np.ascontiguousarray(values.codes, dtype=np.int32)
        return pa.DictionaryArray.from_arrays(_numeric_array(codes), _string_array(values.names))
    arr = np.asarray(values)
    if arr.dtype.kind == "f":
        return _numeric_array(np.ascontiguousarray(arr, dtype=np.float64))
    if csv_text and arr.dtype.kind == "b":
        return _numeric_array(np.ascontiguousarray(arr, dtype=np.uint8))
    if arr.dtype.kind in "iub":  # in the machine's byte order: Arrow's buffers are little-endian
        return _numeric_array(np.ascontiguousarray(arr, dtype=arr.dtype.newbyteorder("=")))
    return _string_array(arr)


def _numeric_array(arr: np.ndarray) -> Any:
    """Arrow array of a contiguous ``(n,)`` float, integer or bool array (no pandas check)."""
    import pyarrow as pa

    if arr.dtype.kind == "b":
        bits = np.packbits(arr.astype(np.uint8), bitorder="little")
        return pa.Array.from_buffers(pa.bool_(), len(arr), [None, pa.py_buffer(bits)])
    kind = pa.from_numpy_dtype(arr.dtype)
    return pa.Array.from_buffers(kind, len(arr), [None, pa.py_buffer(arr)])


def _string_array(values: Any) -> Any:
    """Arrow string array of ``(n,)`` values (``str`` of each; no pandas check)."""
    import pyarrow as pa

    encoded = [str(v).encode("utf-8") for v in values]
    offsets = np.zeros(len(encoded) + 1, dtype=np.int32)
    np.cumsum([len(b) for b in encoded], out=offsets[1:])
    return pa.Array.from_buffers(pa.string(), len(encoded),
                                 [None, pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))])


def write_table(path: str | Path, header: Sequence[str], rows: Sequence[Sequence], *,
                units: str | None = None) -> None:
    """Write a small table given row by row (floats in shortest round-trip form), atomically;
    ``units`` is recorded as :class:`TableWriter` does.

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
    if str(path) != STDIO and table_format(path) == "csv":  # no pyarrow (≈ 0.1 s to import)
        write_bytes_atomic(path, small_csv(columns, units).encode("utf-8"))
        return
    with TableWriter(path, units=units) as writer:
        writer.write(columns)


def small_csv(columns: dict[str, Any], units: str | None = None) -> str:
    """The CSV text :class:`TableWriter` writes for ``columns`` (float64 or int64 arrays, or
    :class:`Labels`), the same bytes, formatted in Python (:func:`shortest_text`): what
    :func:`write_table` writes to a CSV file without importing pyarrow."""
    header = io.StringIO()
    if units is not None:
        header.write(f"# units: {units}\n")
    csv.writer(header, lineterminator="\n").writerow(list(columns))
    texts = [*columns, *(s for v in columns.values() if isinstance(v, Labels) for s in v.names)]
    quote = any(_STRUCTURAL.search(str(t)) for t in texts)
    cells = []
    for values in columns.values():
        if isinstance(values, Labels):
            names = ['"' + n.replace('"', '""') + '"' if quote else n
                     for n in map(str, values.names)]
            cells.append([names[int(k)] for k in values.codes])
        elif np.asarray(values).dtype.kind == "f":
            cells.append([shortest_text(v) for v in np.asarray(values, dtype=float).tolist()])
        else:
            cells.append([str(int(v)) for v in np.asarray(values).tolist()])
    body = "".join(",".join(row) + "\n" for row in zip(*cells, strict=True))
    return header.getvalue() + body


def shortest_text(x: float) -> str:
    """``x`` as pyarrow's CSV writer formats a float64: the shortest digits that read back to
    ``x`` (Python's ``repr``), in positional notation when the decimal exponent ``e`` of the
    leading digit is −6 ≤ e ≤ 9 (``100``, ``0.000001``), else ``1.5e+16``, ``2.5e-7``; ``nan``,
    ``inf``, ``-inf``, ``-0``."""
    x = float(x)
    if x != x or x in (math.inf, -math.inf):
        return repr(x)
    sign = "-" if math.copysign(1.0, x) < 0 else ""
    if x == 0:
        return sign + "0"
    mantissa, _, exponent = repr(abs(x)).partition("e")
    whole, _, fraction = mantissa.partition(".")
    joined = whole + fraction
    digits = joined.lstrip("0")
    e10 = len(whole) - 1 - (len(joined) - len(digits)) + int(exponent or 0)
    digits = digits.rstrip("0")
    if not -7 < e10 < 10:
        rest = f".{digits[1:]}" if len(digits) > 1 else ""
        return f"{sign}{digits[0]}{rest}e{'+' if e10 >= 0 else '-'}{abs(e10)}"
    if e10 < 0:
        return f"{sign}0.{'0' * (-e10 - 1)}{digits}"
    rest = digits[e10 + 1:]
    return sign + digits[:e10 + 1].ljust(e10 + 1, "0") + (f".{rest}" if rest else "")


def csv_text(columns: dict[str, Any], units: str | None = None) -> str:
    """The CSV text of a small table (as :class:`TableWriter` writes it)."""
    buffer = io.BytesIO()
    writer = TableWriter(STDIO, stdout=buffer, units=units)
    writer.write(columns)
    writer.close()
    return buffer.getvalue().decode("utf-8")
