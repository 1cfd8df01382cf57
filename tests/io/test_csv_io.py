import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.io.json_io import to_jsonable
from pkmkit.io.table import read_table, write_table


def test_header_matched_by_name(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("# poses\nz,x,y,note\n0.5,0.1,0.2,a\n0,nan,0,b\n")
    table = read_table(path, ["x", "y", "z"])
    np.testing.assert_array_equal(table[0], [0.1, 0.2, 0.5])
    assert np.isnan(table[1, 0])


def test_no_header_uses_column_order(tmp_path):
    path = tmp_path / "in.csv"
    path.write_text("1,2\n3,4\n")
    np.testing.assert_array_equal(read_table(path, ["q1", "q2"]), [[1, 2], [3, 4]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("x,y\n1,2\n", "missing column"),
        ("x,y,z\n1,2,abc\n", "in.csv:2: column 'z' is not a number"),
        ("x,y,z\n1,2\n", "in.csv:2: expected at least 3"),
        ("x,y,z\n", "no data rows"),
        ("", "no data rows"),
    ],
)
def test_errors_name_the_line(tmp_path, text, message):
    path = tmp_path / "in.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_table(path, ["x", "y", "z"])


def test_write_round_trip(tmp_path):
    path = tmp_path / "out.csv"
    write_table(path, ["a", "status"], [[0.1, "ok"], [float("nan"), "unreachable"]])
    lines = path.read_text().splitlines()
    assert lines == ["a,status", "0.1,ok", "nan,unreachable"]
    assert read_table(path, ["a"])[0, 0] == 0.1


def test_json_conversion_maps_non_finite_to_null():
    value = {"a": np.array([1.0, np.nan]), "b": (np.float64(np.inf), 2), "c": np.int64(3)}
    assert to_jsonable(value) == {"a": [1.0, None], "b": [None, 2], "c": 3}


def test_bom_header_and_collected_problems(tmp_path):
    path = tmp_path / "in.csv"
    path.write_bytes(b"\xef\xbb\xbfx,y,z\n0,0,0\n0,,0\n1,2\n")
    problems = []
    table = read_table(path, ["x", "y", "z"], problems)
    assert table.shape == (3, 3) and np.isfinite(table[0]).all()
    assert np.isnan(table[1, 1]) and np.isnan(table[2]).all()
    assert len(problems) == 2 and "in.csv:3" in problems[0] and "in.csv:4" in problems[1]


def test_unwritable_output(tmp_path):
    with pytest.raises(InputError, match="cannot write"):
        write_table(tmp_path / "missing" / "out.csv", ["a"], [[1.0]])


@pytest.mark.parametrize("header", [" z , x,y ", "\ufeffz,x , y", "z,\tx,y,note"])
def test_header_cells_with_spaces_bom_and_mixed_order(tmp_path, header):
    """Spreadsheet exports: spaces around names, a byte-order mark, columns in another order.
    The values must land in the requested order (a header that is not stripped would be
    reported as missing columns, and a BOM glued to the first name would hide it)."""
    path = tmp_path / "in.csv"
    path.write_text(f"{header}\n3.5,1.25,-2,a\n0,0.5,7,b\n", encoding="utf-8")
    table = read_table(path, ["x", "y", "z"])
    np.testing.assert_array_equal(table, [[1.25, -2.0, 3.5], [0.5, 7.0, 0.0]])
