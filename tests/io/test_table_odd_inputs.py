"""Batch tables of odd make read and written as a demanding user's would be (session 33 audit
of issue 22's fast paths; docs/testing.md "Audit of the fast paths").

The readers take plain-encoded float64 columns straight from their Arrow buffers and null
flags from the validity bitmaps, CSV chunks through pyarrow's parser with a line-by-line
fallback; the writer builds Arrow arrays from NumPy buffers. The same rows stored every way a
tool may store them — Parquet with dictionary-encoded or integer columns, Feather with an
Arrow dictionary column, columns in another order under unicode names, nulls at a chunk
boundary, CRLF CSV — must read as the values written (the oracle: the Python values the test
wrote, and pyarrow's own reading of the file).

Defects the audit found (each test below failed before its fix):
- the writer wrote integer arrays of the other byte order (``>i8``, ``>i4``, ``>u2``)
  byte-swapped: ``[1, 2, 300]`` became ``72057594037927936, ...``;
- a Parquet/Feather int64 column with a value beyond 2**53 was refused as "not numeric
  (int64)", where the CSV of the same numbers reads them (rounded to the nearest double);
- the CSV fallback took what Python's ``float`` takes and CSV does not: ``1_000`` read as
  1000, digits of other scripts (``١٢``, ``１２``) as 12.
"""

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as pq
import pytest

from pkmkit.exceptions import InputError
from pkmkit.io.table import TableReader, TableWriter, read_table

NAMES = ["x", "y", "z"]


def _read(path, chunk_rows=100, columns=NAMES):
    chunks = list(TableReader(path, columns, chunk_rows=chunk_rows))
    return (np.concatenate([c.values for c in chunks]),
            np.concatenate([c.invalid for c in chunks]), [m for c in chunks for m in c.problems])


# ---------------------------------------------------------------- the writer
@pytest.mark.parametrize("suffix", [".parquet", ".feather", ".csv"])
def test_integer_columns_of_either_byte_order_are_written_as_their_values(tmp_path, suffix):
    columns = {"big64": np.array([1, 2, 300, -7], dtype=">i8"),
               "big32": np.array([1, -2, 3, 70000], dtype=">i4"),
               "big_u16": np.array([1, 2, 3, 65535], dtype=">u2"),
               "little64": np.array([5, 6, 7, 8], dtype="<i8"),
               "big_float": np.array([1.5, np.nan, -3.25, 1e300], dtype=">f8")}
    path = tmp_path / f"t{suffix}"
    with TableWriter(path) as writer:
        writer.write(columns)
    if suffix == ".csv":
        lines = path.read_text().splitlines()
        got = {name: [row.split(",")[k] for row in lines[1:]]
               for k, name in enumerate(lines[0].split(","))}
        expected = {name: [repr(float(v)) if v.dtype.kind == "f" else str(int(v))
                           for v in values] for name, values in columns.items()}
        expected["big_float"] = ["1.5", "nan", "-3.25", "1e+300"]
        assert got == expected
    else:
        table = pq.read_table(path) if suffix == ".parquet" else feather.read_table(path)
        for name, values in columns.items():  # pyarrow's own reading: the values written
            read = table.column(name).to_pylist()
            np.testing.assert_array_equal(np.array(read, dtype=float),
                                          values.astype(float))
    values, invalid, _ = _read(path, columns=list(columns))
    np.testing.assert_array_equal(values, np.stack([v.astype(float) for v in
                                                    columns.values()], axis=1))
    assert not invalid.any()


# ---------------------------------------------------------------- integer columns
@pytest.mark.parametrize("suffix", [".parquet", ".feather"])
def test_an_int64_column_beyond_two_to_the_53_reads_as_the_csv_of_its_numbers(tmp_path,
                                                                                suffix):
    big = [1, 2 ** 53 + 1, 2 ** 60 + 3, -(2 ** 62)]
    table = pa.table({"x": pa.array(big, pa.int64()), "y": pa.array([1, 2, 3, 4], pa.uint8()),
                      "z": pa.array([0.5, 1.5, 2.5, 3.5], pa.float32())})
    path = tmp_path / f"t{suffix}"
    (pq.write_table if suffix == ".parquet" else feather.write_feather)(table, path)
    csv = tmp_path / "t.csv"
    csv.write_text("x,y,z\n" + "".join(f"{a},{b},{c}\n" for a, b, c in
                                       zip(big, [1, 2, 3, 4], [0.5, 1.5, 2.5, 3.5],
                                           strict=True)))
    values, invalid, problems = _read(path)
    expected = np.array([[float(a), b, c] for a, b, c in
                         zip(big, [1, 2, 3, 4], [0.5, 1.5, 2.5, 3.5], strict=True)])
    np.testing.assert_array_equal(values, expected)
    np.testing.assert_array_equal(_read(csv)[0], expected)
    assert not invalid.any() and problems == []


@pytest.mark.parametrize("suffix", [".parquet", ".feather"])
@pytest.mark.parametrize("chunk_rows", [1, 2, 100])
def test_a_text_column_flags_only_its_bad_cells_as_a_csv_does(tmp_path, suffix, chunk_rows):
    """A string column of numbers with one bad cell: that row flagged, naming the file, the
    column and the row, the good rows kept (defect found by the audit: the whole column was
    refused, "not numeric (string)", where the CSV of the same table flags only that row)."""
    x = ["1", "a", "3", None, "1_000", " 2.5e1 "]
    table = pa.table({"x": pa.array(x, pa.string()), "y": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                      "z": [7.0] * 6})
    path = tmp_path / f"t{suffix}"
    (pq.write_table if suffix == ".parquet" else feather.write_feather)(table, path)
    values, invalid, problems = _read(path, chunk_rows)
    np.testing.assert_array_equal(values[[0, 2, 5]], [[1.0, 1.0, 7.0], [3.0, 3.0, 7.0],
                                                      [25.0, 6.0, 7.0]])
    assert invalid.tolist() == [False, True, False, True, True, False]
    assert np.isnan(values[[1, 3, 4], 0]).all()
    assert problems == [f"{path}: row 2: column 'x' is not a number: 'a'",
                        f"{path}: row 4: column 'x' is empty",
                        f"{path}: row 5: column 'x' is not a number: '1_000'"]
    csv = tmp_path / "t.csv"  # the same table as a CSV: the same rows flagged
    csv.write_text("x,y,z\n1,1,7\na,2,7\n3,3,7\n,4,7\n1_000,5,7\n 2.5e1 ,6,7\n")
    csv_values, csv_invalid, _ = _read(csv, chunk_rows)
    np.testing.assert_array_equal(csv_invalid, invalid)
    np.testing.assert_array_equal(csv_values[~invalid], values[~invalid])


def test_a_column_of_another_type_is_still_refused_naming_it(tmp_path):
    path = tmp_path / "t.parquet"
    pq.write_table(pa.table({"x": pa.array([1, 2, 3], pa.timestamp("s")),
                             "y": [1.0, 2.0, 3.0], "z": [1.0, 2.0, 3.0]}), path)
    with pytest.raises(InputError, match=r"column 'x' is not numeric \(timestamp"):
        _read(path)


@pytest.mark.parametrize("suffix", [".parquet", ".feather", ".csv"])
def test_a_bool_column_round_trips_as_zero_and_one(tmp_path, suffix):
    """A bool column written by TableWriter reads back as 0/1 in every format (defect found
    by the audit: the CSV writer wrote ``true``/``false``, which the reader flags as not a
    number, while Parquet and Feather read 0/1)."""
    flags = np.array([True, False, True, True])
    columns = {"x": np.array([0.5, 1.5, 2.5, 3.5]), "y": flags, "z": ~flags}
    path = tmp_path / f"t{suffix}"
    with TableWriter(path) as writer:
        writer.write(columns)
        writer.write(columns)  # a second chunk, the first's types
    if suffix == ".csv":
        assert path.read_text().splitlines()[:3] == ["x,y,z", "0.5,1,0", "1.5,0,1"]
    values, invalid, problems = _read(path)
    expected = np.stack([columns["x"], flags.astype(float), (~flags).astype(float)], axis=1)
    np.testing.assert_array_equal(values, np.concatenate([expected, expected]))
    assert not invalid.any() and problems == []


# ---------------------------------------------------------------- CSV cells
@pytest.mark.parametrize("chunk_rows", [1, 2, 100])
def test_csv_cells_python_reads_but_csv_does_not_are_flagged(tmp_path, chunk_rows):
    path = tmp_path / "t.csv"
    path.write_bytes("x,y,z\r\n1,2,3\r\n1_000,2,3\r\n\u0661\u0662,2,3\r\n4,\uff11\uff12,6\r\n"
                     "7,8,9\r\n".encode())
    values, invalid, problems = _read(path, chunk_rows)
    np.testing.assert_array_equal(values, [[1, 2, 3], [np.nan, 2, 3], [np.nan, 2, 3],
                                           [4, np.nan, 6], [7, 8, 9]])
    assert invalid.tolist() == [False, True, True, True, False]
    assert problems == [f"{path}:3: column 'x' is not a number: '1_000'",
                        f"{path}:4: column 'x' is not a number: '\u0661\u0662'",
                        f"{path}:5: column 'y' is not a number: '\uff11\uff12'"]


# ---------------------------------------------------------------- every storage, one table
ROWS = [[0.5, -1.25, 3.0], [None, 2.0, 1e-300], [np.nan, 4.0, -0.0], [7.0, None, 8.5],
        [9.0, 10.0, 11.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]


def _expected():
    values = np.array([[np.nan if v is None else v for v in row] for row in ROWS])
    invalid = np.array([any(v is None for v in row) for row in ROWS])
    return values, invalid


def _stored(tmp_path, how):
    """ROWS stored ``how``: the columns in the order z, x, y under unicode-decorated names
    where the format allows, nulls as nulls (or empty CSV cells)."""
    cols = {name: [row[k] for row in ROWS] for k, name in enumerate(NAMES)}
    if how == "csv-crlf":
        path = tmp_path / "t.csv"
        text = "\ufeffZ,x,y [m],\u00e9t\u00e9\r\n" + "".join(
            ",".join("" if v is None else repr(float(v)) for v in (z, x, y)) + ",\u00e0\r\n"
            for x, y, z in ROWS)
        path.write_bytes(text.encode())
        return path
    table = pa.table({"Z": pa.array(cols["z"], pa.float64()),
                      "\u00e9t\u00e9": pa.array(["a"] * len(ROWS)),
                      "x": pa.array(cols["x"], pa.float64()),
                      "y [m]": pa.array(cols["y"], pa.float64())})
    if how == "parquet-dictionary":  # every float column dictionary-encoded, 3-row groups
        path = tmp_path / "t.parquet"
        pq.write_table(table, path, use_dictionary=True, row_group_size=3)
        encodings = pq.ParquetFile(path).metadata.row_group(0).column(0).encodings
        assert "RLE_DICTIONARY" in encodings or "PLAIN_DICTIONARY" in encodings
        return path
    if how == "parquet-float32":
        path = tmp_path / "t.parquet"
        pq.write_table(table.set_column(2, "x", pa.array(cols["x"], pa.float32())), path,
                       row_group_size=2)
        return path
    path = tmp_path / "t.feather"  # an Arrow dictionary column, in 2-row record batches
    table = table.set_column(0, "Z", table.column("Z").dictionary_encode())
    feather.write_feather(table, path, chunksize=2)
    return path


@pytest.mark.parametrize("how", ["csv-crlf", "parquet-dictionary", "parquet-float32",
                                 "feather-dictionary"])
@pytest.mark.parametrize("chunk_rows", [1, 2, 3, 100])
def test_one_table_stored_every_way_reads_the_same_whatever_the_chunks(tmp_path, how,
                                                                       chunk_rows):
    path = _stored(tmp_path, how)
    values, invalid, problems = _read(path, chunk_rows)
    expected, flagged = _expected()
    np.testing.assert_array_equal(values, expected)
    assert np.signbit(values[2, 2])  # -0.0 kept
    assert invalid.tolist() == flagged.tolist()
    where = [f"{path}:3", f"{path}:5"] if how == "csv-crlf" else [f"{path}: row 2",
                                                                  f"{path}: row 4"]
    assert problems == [f"{where[0]}: column 'x' is empty", f"{where[1]}: column 'y' is empty"]


@pytest.mark.parametrize("suffix", [".parquet", ".feather", ".csv"])
def test_one_row_and_no_rows(tmp_path, suffix):
    path = tmp_path / f"t{suffix}"
    with TableWriter(path) as writer:
        writer.write({"x": np.array([1.0]), "y": np.array([2]), "z": np.array([3.5])})
    values, invalid, _ = _read(path)
    np.testing.assert_array_equal(values, [[1.0, 2.0, 3.5]])
    assert invalid.tolist() == [False]
    empty = tmp_path / f"e{suffix}"
    with TableWriter(empty) as writer:
        writer.write({n: np.zeros(0) for n in NAMES})
    with pytest.raises(InputError, match="no data rows"):
        _read(empty)


@pytest.mark.parametrize("suffix", [".parquet", ".feather"])
def test_empty_cells_are_reported_row_by_row_whatever_the_chunks(tmp_path, suffix):
    """The first message names the first bad row, as a CSV's does (defect found by the audit:
    a chunk's messages came column by column, so a null in column x at row 5 was reported
    before one in y at row 2 when both rows fell in one chunk)."""
    x = pa.array([1.0, 2.0, 3.0, 4.0, None, 6.0])
    y = pa.array([1.0, None, 3.0, 4.0, 5.0, 6.0])
    table = pa.table({"x": x, "y": y, "z": [1.0] * 6})
    path = tmp_path / f"t{suffix}"
    if suffix == ".parquet":
        pq.write_table(table, path, row_group_size=4)
    else:
        feather.write_feather(table, path, chunksize=4)
    expected = [f"{path}: row 2: column 'y' is empty", f"{path}: row 5: column 'x' is empty"]
    for chunk_rows in (1, 3, 100):
        assert _read(path, chunk_rows)[2] == expected
    with pytest.raises(InputError, match="row 2: column 'y'"):
        read_table(path, NAMES)
    csv = tmp_path / "t.csv"
    csv.write_text("x,y,z\n1,1,1\n2,,1\n3,3,1\n4,4,1\n,5,1\n6,6,1\n")
    with pytest.raises(InputError, match=r"t\.csv:3: column 'y'"):
        read_table(csv, NAMES)
