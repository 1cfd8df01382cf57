"""The CSV source's cut of a chunk after its n-th line (``_nth_newline``: an estimate from the
lines' mean length, then a few steps, else a scan of every byte) against the scan alone, on
even and uneven lines — and chunks of a table whatever their size (issue 22 §5)."""

import numpy as np
import pytest

from pkmkit.io import table_sources
from pkmkit.io.table import TableReader


def _scan(buffer: bytes, n: int, count: int) -> int:
    """The plain oracle: every line end's position, the n-th taken."""
    if count <= n:
        last = buffer.rfind(b"\n")
        return last + 1 if last >= 0 else -1
    return [k for k, byte in enumerate(buffer) if byte == 10][n - 1] + 1


@pytest.mark.parametrize("steps", [0, 2, 4096])
def test_cut_after_the_nth_line_end(monkeypatch, steps):
    monkeypatch.setattr(table_sources, "_NEWLINE_STEPS", steps)
    rng = np.random.default_rng(3)
    for trial in range(400):
        lines = rng.integers(0, 60, rng.integers(1, 300))
        if trial % 3 == 0:  # a long first half: the estimate far off
            lines[: len(lines) // 2] = rng.integers(0, 3000)
        buffer = b"".join(b"a" * int(k) + b"\n" for k in lines) + b"x" * int(trial % 4)
        count = buffer.count(b"\n")
        for n in {1, max(1, count // 2), max(1, count - 1), count, count + 1,
                  int(rng.integers(1, count + 1))}:
            assert table_sources._nth_newline(buffer, n, count) == _scan(buffer, n, count)


def test_chunks_of_uneven_lines_are_the_table(tmp_path):
    rng = np.random.default_rng(5)
    values = rng.uniform(-1, 1, (3000, 3))
    values[::17] *= 1e-300  # long cells among short ones
    lines = ["x,y,z"] + [",".join(repr(float(v)) for v in row) for row in values]
    path = tmp_path / "t.csv"
    path.write_text("\n".join(lines) + "\n")
    for rows in (1, 7, 999, 5000):
        chunks = list(TableReader(path, ["x", "y", "z"], chunk_rows=rows))
        assert [len(c) for c in chunks[:-1]] == [rows] * (len(chunks) - 1)
        np.testing.assert_array_equal(np.concatenate([c.values for c in chunks]), values)
        assert [c.first_row for c in chunks] == list(range(0, 3000, rows))[:len(chunks)]
