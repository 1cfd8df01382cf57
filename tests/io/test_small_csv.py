""":func:`pkmkit.io.table_writer.write_table` writes a CSV without pyarrow
(:func:`~pkmkit.io.table_writer.small_csv`): the same bytes as pyarrow's writer (the
oracle, :func:`~pkmkit.io.table_writer.csv_text`) on floats of every magnitude and bit pattern,
integers, and text columns with and without characters that need quoting."""

import numpy as np
import pytest

from pkmkit.io.table import read_table
from pkmkit.io.table_writer import Labels, csv_text, shortest_text, small_csv, write_table

pytest.importorskip("pyarrow")


def _floats(seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    bits = rng.integers(0, 2**64 - 1, 20_000, dtype=np.uint64, endpoint=True)
    magnitudes = 10.0 ** rng.uniform(-12, 20, 20_000) * rng.choice([-1.0, 1.0], 20_000)
    edges = [0.0, -0.0, np.nan, np.inf, -np.inf, 5e-324, 1.7976931348623157e308, 1e-6, 1e-7,
             999999999.0, 1e9, 1e10, 0.1 + 0.2, 100.0, -1.5e-7, 123.456]
    return np.concatenate([bits.view(np.float64), magnitudes, np.round(magnitudes, 3), edges])


@pytest.mark.parametrize("native", ["0", "1"])
@pytest.mark.parametrize("seed", [0, 1])
def test_the_same_bytes_as_pyarrow(seed, native, monkeypatch):
    """``PKMKIT_NATIVE=0``: pyarrow's own writer is the oracle; ``1``: the C formatter
    (``native/csv_text.c``) where built, the same bytes."""
    monkeypatch.setenv("PKMKIT_NATIVE", native)
    x = _floats(seed)
    n = len(x)
    plain = {"q 1": x, "k": np.arange(n, dtype=np.int64) - 7,
             "t": Labels(np.arange(n) % 2, ["ok", "x y"])}
    quoted = {**plain, "t": Labels(np.arange(n) % 3, ["ok", 'a,"b', "c"])}
    for columns in (plain, quoted):
        assert small_csv(columns, "mm") == csv_text(columns, "mm")
        assert small_csv(columns) == csv_text(columns)


def test_a_planted_format_fails():
    """The oracle notices a different float format (Python's repr: ``1.0``, ``1e-05``)."""
    x = np.array([1.0, 1e-5])
    assert [shortest_text(v) for v in x] == ["1", "0.00001"]
    assert csv_text({"a": x}) != "a\n" + "".join(f"{v!r}\n" for v in x.tolist())


def test_write_table_round_trips(tmp_path):
    path = tmp_path / "t.csv"
    rows = [[0.1, 2, "ok"], [1e-7, -3, "far"]]
    write_table(path, ["a", "b", "c"], rows, units="mm")
    text = path.read_text()
    assert text == csv_text({"a": np.array([0.1, 1e-7]), "b": np.array([2, -3]),
                             "c": Labels(np.array([1, 0]), ["far", "ok"])}, units="mm")
    np.testing.assert_array_equal(read_table(path, ["a", "b"]), [[0.1, 2.0], [1e-7, -3.0]])
