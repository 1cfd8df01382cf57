"""Batch tables through pyarrow: formats, chunks, line-naming errors, shortest floats, atomic
writes."""

import io
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pkmkit.exceptions import InputError
from pkmkit.io.atomic import atomic_path, check_output_dir
from pkmkit.io.table import Labels, TableReader, TableWriter, csv_text, read_table, table_format

MESSY = (b"\xef\xbb\xbf# exported poses\n"
         b"x,y,z,note\n"
         b"0.042444,1,2,a\n"
         b"\n"
         b"   # a comment in the middle\n"
         b"3,abc,5,b\n"
         b"6,7\n"
         b"1e400,1,1,c\n"
         b"nan,inf,-inf,d\n"
         b" 8 , 9 ,10,e\n"
         b"11,,13,f\r\n"
         b",,,\n"
         b"14,15,16,g")  # no final newline


def _read(path, columns, chunk_rows):
    chunks = list(TableReader(path, columns, chunk_rows=chunk_rows))
    assert all(len(c) <= chunk_rows for c in chunks)
    assert [c.first_row for c in chunks] == list(np.cumsum([0] + [len(c) for c in chunks])[:-1])
    return (np.concatenate([c.values for c in chunks]),
            np.concatenate([c.invalid for c in chunks]), [m for c in chunks for m in c.problems])


@pytest.mark.parametrize("chunk_rows", [1, 2, 3, 5, 1000])
def test_messy_csv_same_rows_lines_and_messages_whatever_the_chunks(tmp_path, chunk_rows):
    path = tmp_path / "in.csv"
    path.write_bytes(MESSY)
    values, invalid, problems = _read(path, ["x", "y", "z"], chunk_rows)
    expected = np.array([[0.042444, 1, 2], [3, np.nan, 5], [np.nan] * 3, [np.nan, 1, 1],
                         [np.nan, np.inf, -np.inf], [8, 9, 10], [11, np.nan, 13], [14, 15, 16]])
    np.testing.assert_array_equal(values, expected)
    assert invalid.tolist() == [False, True, True, True, False, False, True, False]
    assert problems == [
        f"{path}:6: column 'y' is not a number: 'abc'",
        f"{path}:7: expected at least 3 columns, got 2",
        f"{path}:8: column 'x' overflows a double: '1e400'",
        f"{path}:11: column 'y' is empty",
    ]


def test_columns_by_name_and_without_header(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("# poses\nz,x,y,note\n0.5,0.1,0.2,a\n")
    np.testing.assert_array_equal(read_table(path, ["x", "y", "z"]), [[0.1, 0.2, 0.5]])
    path.write_text("1,2,9\n3,4,9\n")
    np.testing.assert_array_equal(read_table(path, ["q1", "q2"]), [[1, 2], [3, 4]])


@pytest.mark.parametrize("data, message", [
    (b"x,y\n1,2\n", r"in.csv:1: missing column\(s\) z"),
    (b"# c\n\nx,y\n1,2\n", r"in.csv:3: missing column"),
    (b"1,2\n", "in.csv:1: expected at least 3 columns"),
    (b"x,y,z\n", "no data rows"),
    (b"", "no data rows"),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "not a text file"),
    (b"x,y,z\n\xff\xfe,1,2\n", r"in.csv:2: column 'x' is not a number"),
    (b"\xff\xfex,y,z\n1,2,3\n", "in.csv:1: not a UTF-8 text line"),
    (b"0\rx,y,z\n1,2,3\n", "in.csv:1: the header is not a CSV line"),
])
def test_errors_name_file_and_line(tmp_path, data, message):
    path = tmp_path / "in.csv"
    path.write_bytes(data)
    with pytest.raises(InputError, match=message):
        read_table(path, ["x", "y", "z"])


def test_unknown_extension_and_missing_file(tmp_path):
    with pytest.raises(InputError, match=r"unknown table type '\.xlsx'"):
        table_format(tmp_path / "a.xlsx")
    with pytest.raises(InputError, match="cannot read file"):
        read_table(tmp_path / "none.csv", ["x"])
    with pytest.raises(InputError, match="cannot read file"):
        read_table(tmp_path / "none.parquet", ["x"])
    (tmp_path / "bad.parquet").write_text("x,y\n1,2\n")
    with pytest.raises(InputError, match="not a Parquet file"):
        read_table(tmp_path / "bad.parquet", ["x"])
    (tmp_path / "bad.feather").write_text("x,y\n1,2\n")
    with pytest.raises(InputError, match="not an Arrow/Feather file"):
        read_table(tmp_path / "bad.feather", ["x"])


def test_shortest_round_trip_floats():
    values = np.array([0.042444, 0.1 + 0.2, 1 / 3, -0.0, 5e-324, 1.7976931348623157e308,
                       123456789.0, np.nan])
    text = csv_text({"v": values})
    lines = text.splitlines()
    assert lines[:5] == ["v", "0.042444", "0.30000000000000004", "0.3333333333333333", "-0"]
    assert lines[-1] == "nan"
    back = np.array([float(s) for s in lines[1:]])
    np.testing.assert_array_equal(back, values)
    # each written number is the shortest one that reads back (no digit can be dropped)
    for s, v in zip(lines[2:-1], values[1:-1], strict=True):
        mantissa = s.split("e")[0].replace("-", "").replace(".", "").lstrip("0")
        assert len(mantissa) <= 17 and float(repr(float(s))) == v


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=30),
       st.integers(1, 7))
def test_any_double_round_trips_through_csv_in_any_chunks(tmp_path_factory, numbers, chunk):
    path = tmp_path_factory.mktemp("rt") / "t.csv"
    values = np.array(numbers)
    with TableWriter(path) as writer:
        for start in range(0, len(values), chunk):
            writer.write({"a": values[start:start + chunk]})
    back = read_table(path, ["a"])[:, 0]
    np.testing.assert_array_equal(back, values)
    assert np.array_equal(np.signbit(back), np.signbit(values))
    for line, v in zip(path.read_text().splitlines()[1:], values, strict=True):
        assert _digits(line) == _digits(repr(float(v)))  # as few digits as Python's repr


def _digits(text: str) -> int:
    """Significant digits of a decimal number's text."""
    return len(text.lower().split("e")[0].lstrip("+-").replace(".", "").strip("0"))


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".feather"])
@pytest.mark.parametrize("chunk_rows", [1, 4, 100])
def test_formats_give_identical_values(tmp_path, suffix, chunk_rows):
    rng = np.random.default_rng(3)
    values = rng.normal(size=(11, 3)) * 10.0 ** rng.integers(-8, 8, size=(11, 3))
    values[4, 1] = np.nan
    path = tmp_path / f"t{suffix}"
    with TableWriter(path) as writer:
        for start in range(0, 11, 5):
            rows = slice(start, start + 5)
            writer.write({"b": values[rows, 1], "a": values[rows, 0], "c": values[rows, 2],
                          "s": Labels(np.zeros(len(values[rows]), dtype=int), ["ok"])})
    got, invalid, problems = _read(path, ["a", "b", "c"], chunk_rows)
    np.testing.assert_array_equal(got, values)
    assert not invalid.any() and problems == []


def test_parquet_nulls_and_text_columns_are_named(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq

    path = tmp_path / "t.parquet"
    pq.write_table(pa.table({"x": [1.0, None, 3.0], "y": [1, 2, 3], "s": ["a", "b", "c"]}),
                   path)
    values, invalid, problems = _read(path, ["x", "y"], 2)
    assert invalid.tolist() == [False, True, False] and np.isnan(values[1, 0])
    assert problems == [f"{path}: row 2: column 'x' is empty"]
    with pytest.raises(InputError, match="row 1: column 's' is not a number: 'a'"):
        read_table(path, ["s"])  # a text cell flags its row, as a CSV's
    with pytest.raises(InputError, match=r"missing column\(s\) z"):
        read_table(path, ["z"])


def test_stdin_and_stdout():
    reader = TableReader("-", ["x"], stdin=io.BytesIO(b"x\n1.5\n2\n"))
    np.testing.assert_array_equal(reader.read_all().values, [[1.5], [2.0]])
    sink = io.BytesIO()
    with TableWriter("-", stdout=sink) as writer:
        writer.write({"x": np.array([1.5]), "s": Labels(np.array([0]), ["a,b"])})
    assert sink.getvalue().decode().splitlines() == ["x,s", '1.5,"a,b"']


def test_failed_write_leaves_nothing_and_keeps_the_old_file(tmp_path):
    path = tmp_path / "out.csv"
    with pytest.raises(RuntimeError), TableWriter(path) as writer:
        writer.write({"a": np.arange(3.0)})
        raise RuntimeError("interrupted")
    assert os.listdir(tmp_path) == []
    path.write_text("old\n")
    with pytest.raises(RuntimeError), TableWriter(path) as writer:
        writer.write({"a": np.arange(3.0)})
        raise RuntimeError("interrupted")
    assert path.read_text() == "old\n" and os.listdir(tmp_path) == ["out.csv"]


def test_output_destinations_checked_before_work(tmp_path):
    with pytest.raises(InputError, match="is a directory"):
        TableWriter(tmp_path)
    with pytest.raises(InputError, match="does not exist"):
        TableWriter(tmp_path / "missing" / "o.csv")
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="not a directory"):
        TableWriter(tmp_path / "file" / "o.csv")
    with pytest.raises(InputError, match="not a directory"):
        check_output_dir(tmp_path / "file")
    if os.geteuid() != 0:  # root writes anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(InputError, match="not writable"):
            TableWriter(locked / "o.csv")


def test_atomic_path_keeps_suffix_and_permissions(tmp_path):
    with atomic_path(tmp_path / "fig.png") as temp:
        assert temp.suffix == ".png" and temp.parent == tmp_path
        temp.write_bytes(b"x")
    assert (tmp_path / "fig.png").read_bytes() == b"x"
    assert oct((tmp_path / "fig.png").stat().st_mode & 0o777) == oct(0o666 & ~_umask())


def _umask():
    current = os.umask(0)
    os.umask(current)
    return current


def test_csv_formatted_in_parallel_slices_is_identical(tmp_path, monkeypatch):
    import pkmkit.io.table_writer as table

    rng = np.random.default_rng(5)
    columns = {"a": rng.normal(size=5000) * 10.0 ** rng.integers(-6, 6, 5000),
               "s": Labels(rng.integers(0, 2, 5000), ["ok", "unreachable"])}
    texts = []
    for rows in (10**9, 100):
        monkeypatch.setattr(table, "PARALLEL_CSV_ROWS", rows)
        monkeypatch.setattr(table, "_cpu_count", lambda: 4)
        path = tmp_path / f"out{rows}.csv"
        with TableWriter(path) as writer:
            writer.write(columns)
        texts.append(path.read_text())
    assert texts[0] == texts[1] and texts[0].count("\n") == 5001


def test_a_stray_carriage_return_flags_its_row(tmp_path):
    """A lone \\r inside a data line (found by fuzzing: the csv module raised) flags that row
    and keeps the others."""
    path = tmp_path / "in.csv"
    path.write_bytes(b"x,y,z\n0,0,0\n0.1\r,0,0\n0,0.1,0\n")
    values, invalid, problems = _read(path, ["x", "y", "z"], 1000)
    assert invalid.tolist() == [False, True, False]
    np.testing.assert_array_equal(values[[0, 2]], [[0, 0, 0], [0, 0.1, 0]])
    assert problems == [f"{path}:3: not a CSV line (a stray carriage return or line break "
                        "inside it)"]


def test_a_first_line_of_megabytes_reads_in_bounded_pieces(tmp_path, monkeypatch):
    """A 2 MB first data line (no newline in the 64 kB sample) made the chunk estimate
    64 kB × 500 000 rows = 32 GB, asked of read() at once: MemoryError (issue 18 §7 fuzz). The
    reads stay ≤ 64 MiB, the long row is flagged, the other kept."""
    from pkmkit.io.table_sources import CsvSource

    sizes = []
    original = CsvSource._read

    def recording(self, handle, size):
        sizes.append(size)
        return original(self, handle, size)

    monkeypatch.setattr(CsvSource, "_read", recording)
    path = tmp_path / "long.csv"
    path.write_text("x,y,z\n" + "7" * 200_000 + ",0,0\n0.1,0.2,0.3\n")
    problems: list[str] = []
    table = read_table(path, ("x", "y", "z"), problems)
    assert max(sizes) <= 1 << 26
    assert np.isnan(table[0]).all() and table[1].tolist() == [0.1, 0.2, 0.3]
    assert len(problems) == 1 and "long.csv:2" in problems[0]
