"""The C CSV formatter (``pkmkit.native.kernels.csv_rows``, ``native/csv_text.c``) against
independent oracles: pyarrow's own cast of float64 to text (the bytes its CSV writer writes),
``float()`` reading every text back to the same double, Python's ``repr`` for the count of
significant digits (the shortest round trip), and :class:`~pkmkit.io.table.TableWriter`'s CSV
with the extension switched off (``PKMKIT_NATIVE=0``: pyarrow's writer) byte for byte.

The doubles: random bit patterns (subnormals, NaN payloads, both signs), magnitudes 10^-12 to
10^20, values rounded to a few decimals (a table's inputs), every power of ten and of two a
double holds, their neighbours one ulp away, the integers about 2^53, the layout's edges
(1e-7, 1e10) and ±0, ±inf, NaN."""

from __future__ import annotations

import numpy as np
import pytest

from pkmkit.io.table_writer import Labels, TableWriter, shortest_text

pa = pytest.importorskip("pyarrow")
pc = pytest.importorskip("pyarrow.compute")
kernels = pytest.importorskip("pkmkit.native.kernels")
if not hasattr(kernels, "csv_rows"):
    pytest.skip("the extension was built without csv_text.c", allow_module_level=True)


def _doubles(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    bits = rng.integers(0, 2**64 - 1, n, dtype=np.uint64, endpoint=True).view(np.float64)
    tiny = rng.integers(0, 2**52, n // 8, dtype=np.uint64).view(np.float64)  # subnormals
    magnitudes = 10.0 ** rng.uniform(-12, 20, n) * rng.choice([-1.0, 1.0], n)
    rounded = np.concatenate([np.round(rng.uniform(-1, 1, n // 4), d) for d in (1, 3, 4, 6)])
    powers = np.concatenate([10.0 ** np.arange(-323, 309), 2.0 ** np.arange(-1074, 1024)])
    near = np.concatenate([np.nextafter(powers, np.inf), np.nextafter(powers, 0)])
    integers = 2.0**53 + np.arange(-200, 200)
    edges = np.array([0.0, -0.0, np.nan, -np.nan, np.inf, -np.inf, 5e-324, 1e-323, 1.5e-323,
                      2.2250738585072014e-308, 2.225073858507201e-308, 1.7976931348623157e308,
                      1e-6, 1e-7, 9.999999999999999e-7, 999999999.0, 9999999999.0, 1e9, 1e10,
                      0.1 + 0.2, 100.0, 0.5, -1.5e-7, 123.456, 1.0, 9007199254740993.0])
    parts = [bits, tiny, magnitudes, rounded, powers, -powers, near, integers, edges]
    return np.concatenate(parts)


def _pyarrow_lines(x: np.ndarray) -> list[bytes]:
    return [t.encode() for t in pc.cast(pa.array(x), pa.string()).to_pylist()]


def _check(x: np.ndarray) -> None:
    lines = kernels.csv_rows((x,), 0, len(x)).split(b"\n")
    assert lines.pop() == b""
    expected = _pyarrow_lines(x)
    wrong = [(repr(x[k]), lines[k], expected[k]) for k in range(len(x))
             if lines[k] != expected[k]]
    assert not wrong, (len(wrong), wrong[:5])
    finite = np.isfinite(x)
    back = np.array([float(t) for t in lines])
    np.testing.assert_array_equal(back[finite].view(np.uint64), x[finite].view(np.uint64))
    assert np.isnan(back[np.isnan(x)]).all()


@pytest.mark.parametrize("seed", [0, 1])
def test_the_bytes_of_pyarrow_and_a_round_trip(seed):
    _check(_doubles(40_000, seed))


@pytest.mark.ci
def test_ten_million_doubles():
    """The oracle of the session-35 notes: 10⁷ doubles of every kind (≈ 30 s of CPU)."""
    for seed in range(10, 20):
        _check(_doubles(700_000, seed))


def test_the_fewest_digits():
    """Shortest: as many significant digits as Python's repr (shortest round trip, closest)
    — and :func:`shortest_text` (the Python twin) writes the same text."""
    x = _doubles(5_000, 2)
    x = x[np.isfinite(x) & (x != 0)]
    lines = kernels.csv_rows((x,), 0, len(x)).decode().split("\n")[:-1]
    for value, text in zip(x.tolist(), lines, strict=True):
        mantissa = text.lstrip("-").split("e")[0].replace(".", "").strip("0")
        shortest = repr(abs(value)).split("e")[0].replace(".", "").strip("0")
        assert mantissa == shortest, (value, text)
        assert text == shortest_text(value)


def test_integers_and_labels_and_row_ranges():
    codes = np.array([2, 0, 1, 2], dtype=np.int32)
    labels = (b"ok", b'"a,""b"', b"")
    ints = [np.array([0, -1, 2**63 - 1, -(2**63)], dtype=np.int64),
            np.array([0, 255, 7, 1], dtype=np.uint8), np.array([-5, 5, 0, -(2**31)], np.int32),
            np.array([2**64 - 1, 0, 1, 10], dtype=np.uint64)]
    x = np.array([[0.25, 1e21], [-0.0, np.nan], [3.0, 1e-7], [np.inf, 123456789.125]])
    text = kernels.csv_rows((x[:, 0], *ints, (codes, labels), x[:, 1]), 1, 4)
    assert text == (b"-0,-1,255,5,0,ok,nan\n"
                    b'3,9223372036854775807,7,0,1,"a,""b",1e-7\n'
                    b"inf,-9223372036854775808,1,-2147483648,10,,123456789.125\n")
    assert kernels.csv_rows((x[:, 0],), 2, 2) == b""


@pytest.mark.parametrize(("columns", "start", "stop", "error", "match"), [
    ((np.zeros(3, np.float32),), 0, 3, TypeError, "format f"),
    ((np.zeros((3, 2)),), 0, 3, TypeError, "one-dimensional"),
    ((np.zeros(3),), 0, 4, ValueError, "beyond a column"),
    ((np.zeros(3),), 2, 1, ValueError, "start <= stop"),
    ((), 0, 0, ValueError, "no columns"),
    (((np.array([0, 3]), (b"a", b"b")),), 0, 2, ValueError, "outside its labels"),
    (((np.array([0, -1]), (b"a",)),), 0, 2, ValueError, "outside its labels"),
    (((np.array([0]), ("a",)),), 0, 1, TypeError, "bytes"),
    (((np.array([0]),),), 0, 1, TypeError, "codes, labels"),
    (("text",), 0, 1, TypeError, "bytes-like"),
    ([np.zeros(3)], 0, 3, TypeError, "tuple"),
])
def test_bad_input_is_a_typed_error(columns, start, stop, error, match):
    with pytest.raises(error, match=match):
        kernels.csv_rows(columns, start, stop)


@pytest.mark.ci
def test_the_table_of_powers_of_ten_is_the_exact_one():
    """``native/shortest_table.h`` is what ``tools/shortest_table.py`` computes with exact
    integers (its integer logarithms checked against exact ones on the way; ≈ 3 s of CPU)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "tools" / "shortest_table.py"
    if not path.exists():
        pytest.skip("tools/ is not beside the tests")
    spec = importlib.util.spec_from_file_location("shortest_table", path)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    tool.check_logarithms()
    assert tool.HEADER.read_text() == tool.text()
    k_min, k_max, rows = tool.table()
    assert (k_min, k_max, len(rows)) == (-324, 292, 617)


def _table(n: int, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    x = _doubles(n, seed)[:n]
    return {"x [mm]": x, "q": np.round(rng.uniform(-1, 1, n), 5),
            "k": np.arange(n, dtype=np.int64) - 3, "flag": np.arange(n) % 3 == 0,
            "mode": Labels(rng.integers(0, 3, n).astype(np.int32), ["", "up", "down"]),
            "status": Labels(rng.integers(0, 2, n), ["ok", "out-of-stroke"])}


def _written(path, chunks, units=None) -> bytes:
    with TableWriter(path, units=units) as writer:
        for columns in chunks:
            writer.write(columns)
    return path.read_bytes()


@pytest.mark.parametrize("quoted", [False, True])
def test_the_writer_writes_pyarrow_s_bytes(tmp_path, monkeypatch, quoted):
    """A table of chunks through the C formatter, in pieces over several threads, against the
    same table through pyarrow's writer; quoted texts when a text needs quotes."""
    import pkmkit.io.table_writer as table

    chunks = [_table(3000, 3), _table(1, 4), _table(2500, 5)]
    if quoted:
        chunks[0]["status"] = Labels(chunks[0]["status"].codes, ["ok", 'a "b", c'])
    monkeypatch.setattr(table, "NATIVE_CSV_ROWS", 700)
    monkeypatch.setattr(table, "PARALLEL_CSV_ROWS", 500)
    monkeypatch.setattr(table, "_cpu_count", lambda: 3)
    native = _written(tmp_path / "c.csv", chunks, "mm")
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    assert table._native_columns(pa.table({"a": [1.0]}), False) is None
    assert native == _written(tmp_path / "p.csv", chunks, "mm")
    assert native.count(b"\n") == 5503 and (b'"ok"' in native) == quoted


def test_what_the_formatter_leaves_to_pyarrow(tmp_path):
    """Strings that are not labels go to pyarrow (the same bytes as ever); a later chunk's text
    that needs quotes in an unquoted file is pyarrow's error."""
    import pkmkit.io.table_writer as table
    from pkmkit.exceptions import InputError

    strings = pa.table({"s": pa.array(["a", "b"])})
    assert table._native_columns(strings, False) is None
    assert _written(tmp_path / "s.csv", [{"x": np.array([0.5, 2.0]),
                                          "s": np.array(["a", "b"])}]) == b"x,s\n0.5,a\n2,b\n"
    bad = Labels(np.array([0, 1]), ["ok", "x,y"])
    with pytest.raises(InputError, match="cannot write these values"):
        _written(tmp_path / "q.csv", [{"s": Labels(np.array([0, 0]), ["ok", "y"])},
                                      {"s": bad}])
    assert not (tmp_path / "q.csv").exists()
