"""``pkmkit ik --input`` reuses its q and actuator-column arrays from chunk to chunk
(:class:`pkmkit.cli.batch.ChunkBuffers`, ``ik(X, out=...)``): the table written in chunks —
the last one smaller, one-row chunks computed as two rows — is the one-chunk table, for every
family, and its actuator columns are ``m.ik`` of the poses."""

import numpy as np
import pyarrow.parquet as pq
import pytest

import pkmkit
from pkmkit.boundary.coordinates import pose_columns, pose_to_cli
from pkmkit.cli.batch import ChunkBuffers

ROWS = 11


def test_chunk_buffers_hand_out_the_same_memory():
    buffers = ChunkBuffers()
    first = buffers.take("q", 10, 3)
    assert first.shape == (10, 3) and first.flags.c_contiguous
    again = buffers.take("q", 7, 3)  # a smaller last chunk: the first rows of the same array
    assert again.shape == (7, 3) and again.flags.c_contiguous
    assert again.ctypes.data == first.ctypes.data
    columns = buffers.take("columns", 7, 3, "F")
    assert not np.shares_memory(columns, first)
    assert all(columns[:, j].flags.c_contiguous for j in range(3))  # contiguous columns
    grown = buffers.take("q", 12, 3)  # a larger chunk: a new array
    assert grown.shape == (12, 3) and not np.shares_memory(grown, first)


def _input(m, path) -> list[str]:
    """ROWS poses near home in the command's columns (one NaN, one out of reach)."""
    if m.position_controlled:
        names = ["x", "y", "z"]
        values = np.tile(np.asarray(m.home_pose[:3], dtype=float), (ROWS, 1))
    else:
        names = pose_columns(m)
        values = np.tile(pose_to_cli(np.asarray(m.home_pose, dtype=float)[None], m, "m", "xyz"),
                         (ROWS, 1))
    k = min(3, m.dims)
    values[:, :k] += 1e-3 * np.sin(np.arange(ROWS * k, dtype=float)).reshape(ROWS, k)
    values[2, 0] += 100.0  # out of reach
    values[5, :] = np.nan
    import pyarrow as pa

    pq.write_table(pa.table({name: values[:, j] for j, name in enumerate(names)}), path)
    return names


@pytest.mark.parametrize("ident", ["linear-delta", "five-bar", "gough-stewart", "verne",
                                   "tripteor-x7"])
def test_chunked_tables_are_the_one_chunk_table(run, tmp_path, ident):
    m = pkmkit.machine(ident)
    src = tmp_path / "in.parquet"
    _input(m, src)
    tables = {}
    for chunk in (None, 4, 1):
        dst = tmp_path / f"out-{chunk}.parquet"
        result = run("ik", ident, "--input", src, "--output", dst,
                     *(["--chunk-rows", chunk] if chunk else []))
        assert result.exit_code == 3, result.output  # flagged rows
        tables[chunk] = pq.read_table(dst)
    whole = tables[None]
    for chunk, table in tables.items():
        assert table.column_names == whole.column_names, chunk
        for name in whole.column_names:
            a, b = table.column(name), whole.column(name)
            if a.type == "double":  # bit for bit, NaN included
                assert a.to_numpy().tobytes() == b.to_numpy().tobytes(), (chunk, name)
            else:
                assert a.cast("string").to_pylist() == b.cast("string").to_pylist(), chunk
    status = whole.column("status").cast("string").to_pylist()
    assert status[5] != "ok"
    q = np.column_stack([whole.column(name).to_numpy() for name in m.actuator_names])
    x = np.column_stack([whole.column(name).to_numpy()
                         for name in (["x", "y", "z"] if m.position_controlled
                                      else pose_columns(m))])
    from pkmkit.boundary.coordinates import actuator_scales, pose_from_cli

    expected = m.ik(pose_from_cli(x, m, "m", "xyz"), strokes="ignore")
    scaled = expected / actuator_scales(m, "m")
    np.testing.assert_array_equal(q, scaled)  # NaN where NaN: rows out of reach, not numbers
