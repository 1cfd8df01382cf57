"""How batch tables go through Parquet: numbers written plain and texts dictionary-encoded
(:func:`~pkmkit.io.table_writer._dictionary_columns`), the file read back the same by pyarrow
and pandas, later chunks keeping the first chunk's schema, and a float64 table read and written
without ``pyarrow.compute`` (its import costs 0.05–0.2 s of a one-shot command)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

from pkmkit.io.table import Labels, TableReader, TableWriter  # noqa: E402
from pkmkit.io.table_sources import _null_flags  # noqa: E402


def _write(path: Path, values: np.ndarray, status: np.ndarray) -> None:
    with TableWriter(path, units="mm") as writer:
        for start in range(0, len(values), 7):
            rows = slice(start, start + 7)
            writer.write({"x": values[rows, 0], "q1": values[rows, 1],
                          "status": Labels(status[rows], ["ok", "unreachable"])})


def test_numbers_plain_texts_dictionary_and_every_reader_agrees(tmp_path):
    rng = np.random.default_rng(5)
    values = rng.normal(size=(20, 2))
    values[3, 1] = np.nan
    status = (rng.random(20) > 0.7).astype(np.int32)
    path = tmp_path / "out.parquet"
    _write(path, values, status)
    meta = pq.ParquetFile(path).metadata
    assert meta.num_rows == 20 and meta.num_row_groups == 3  # one per chunk written
    for group in range(meta.num_row_groups):
        encodings = {meta.row_group(group).column(k).path_in_schema:
                     set(meta.row_group(group).column(k).encodings) for k in range(3)}
        assert "RLE_DICTIONARY" not in encodings["x"] | encodings["q1"], encodings
        assert "RLE_DICTIONARY" in encodings["status"], encodings
        assert meta.row_group(group).column(0).compression == "SNAPPY"
    table = pq.read_table(path)
    assert table.schema.metadata == {b"units": b"mm"}
    np.testing.assert_array_equal(table.column("x").to_numpy(), values[:, 0])
    np.testing.assert_array_equal(table.column("q1").to_numpy(), values[:, 1])
    labels = np.array(["ok", "unreachable"])[status]
    assert table.column("status").to_pylist() == labels.tolist()


def test_pandas_reads_the_file(tmp_path):
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(5)
    values = rng.normal(size=(20, 2))
    status = (rng.random(20) > 0.7).astype(np.int32)
    labels = np.array(["ok", "unreachable"])[status]
    path = tmp_path / "out.parquet"
    _write(path, values, status)
    frame = pd.read_parquet(path)
    assert list(frame.columns) == ["x", "q1", "status"]
    np.testing.assert_array_equal(frame["q1"].to_numpy(), values[:, 1])
    assert frame["status"].astype(str).tolist() == labels.tolist()


def test_a_later_chunk_of_other_types_is_cast_to_the_first_schema(tmp_path):
    path = tmp_path / "mixed.parquet"
    with TableWriter(path, units="m") as writer:
        writer.write({"a": np.array([0.5, 1.5])})
        writer.write({"a": np.array([2, 3], dtype=np.int64)})  # cast to float64
    table = pq.read_table(path)
    assert table.schema.field("a").type == pa.float64()
    assert table.column("a").to_pylist() == [0.5, 1.5, 2.0, 3.0]
    assert table.schema.metadata == {b"units": b"m"}


def test_null_flags_are_pyarrows_is_null():
    """The validity bitmaps read directly against pyarrow's own ``is_null`` (the oracle), on
    chunks that start inside their buffers (slices) and chunks without nulls."""
    import pyarrow.compute as pc

    rng = np.random.default_rng(8)
    pieces = []
    for size in (1, 9, 17, 64, 3):
        cells = [None if rng.random() < 0.3 else float(k) for k in range(size + 11)]
        offset = int(rng.integers(0, 11))
        pieces.append(pa.array(cells, pa.float64()).slice(offset, size))
    pieces.append(pa.array(np.arange(5.0)))
    column = pa.chunked_array(pieces)
    expected = np.asarray(pc.is_null(column).to_pylist())
    assert expected.any() and not expected.all()
    np.testing.assert_array_equal(_null_flags(column, len(column)), expected)
    one = pieces[2]
    np.testing.assert_array_equal(_null_flags(one, len(one)),
                                  np.asarray(pc.is_null(one).to_pylist()))


def test_parquet_nulls_in_a_sliced_chunk_are_flagged(tmp_path):
    path = tmp_path / "nulls.parquet"
    x = [0.1, None, 0.3, 0.4, None, 0.6, 0.7]
    pq.write_table(pa.table({"x": pa.array(x, pa.float64())}), path, row_group_size=3)
    for chunk_rows in (1, 2, 4, 7):
        reader = TableReader(path, ["x"], chunk_rows=chunk_rows)
        chunk = reader.read_all()
        assert chunk.invalid.tolist() == [v is None for v in x], chunk_rows
        assert np.isnan(chunk.values[[1, 4], 0]).all()
        np.testing.assert_array_equal(chunk.values[[0, 2, 3, 5, 6], 0],
                                      [0.1, 0.3, 0.4, 0.6, 0.7])


ROUND_TRIP = r"""
import sys
import numpy as np
from pkmkit.io.table import Labels, TableReader, TableWriter
with TableWriter(sys.argv[2]) as writer:
    for chunk in TableReader(sys.argv[1], ["x", "y"], chunk_rows=4):
        writer.write({"x": chunk.values[:, 0], "y": chunk.values[:, 1],
                      "status": Labels(chunk.invalid.astype(np.int32), ["ok", "bad"])})
print("pyarrow.compute" in sys.modules)
"""


def test_a_float64_table_goes_through_without_pyarrow_compute(tmp_path):
    source = tmp_path / "in.parquet"
    pq.write_table(pa.table({"x": np.arange(10.0), "y": np.arange(10.0) / 3}), source,
                   row_group_size=3)
    out = tmp_path / "out.parquet"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[2] / "src"),
                                                        os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-c", ROUND_TRIP, str(source), str(out)],
                          capture_output=True, text=True, env=env, timeout=300)
    assert done.stdout.strip() == "False", done.stdout + done.stderr
    np.testing.assert_array_equal(pq.read_table(out).column("y").to_numpy(),
                                  np.arange(10.0) / 3)
