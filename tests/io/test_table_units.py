"""Units of batch tables (issue 18 §5): outputs record their length unit (a ``# units:`` line
before a CSV header, a ``units`` key in the Parquet/Feather schema metadata) and inputs state
theirs as measurement files do (``# units: mm``, ``x [mm]``, ``q4 [deg]``, a column name in
another case); a column stated in another unit than the caller reads is refused, naming it."""

import io

import numpy as np
import pyarrow as pa
import pyarrow.feather as feather
import pyarrow.parquet as pq
import pytest

from pkmkit.exceptions import InputError
from pkmkit.io.table import TableReader, TableWriter, csv_text, write_table
from pkmkit.io.table_format import check_units, match_columns, split_unit


def _read(path, columns, units=None):
    reader = TableReader(path, columns, units=units)
    return reader.read_all().values, reader


@pytest.mark.parametrize("suffix", ["csv", "parquet", "feather"])
def test_the_writer_records_the_unit_and_the_reader_finds_it(tmp_path, suffix):
    path = tmp_path / f"t.{suffix}"
    with TableWriter(path, units="mm") as writer:
        writer.write({"x": np.array([1.5, 2.0]), "A": np.array([90.0, 0.0])})
        writer.write({"x": np.array([3.0]), "A": np.array([1.0])})
    if suffix == "csv":
        assert path.read_text().splitlines()[:2] == ["# units: mm", "x,A"]
    else:
        read = pq.read_table if suffix == "parquet" else feather.read_table
        table = read(path)
        assert table.schema.metadata[b"units"] == b"mm" and table.column_names == ["x", "A"]
    values, reader = _read(path, ["x", "A"], ["mm", "deg"])
    assert reader.file_unit == "mm"
    np.testing.assert_array_equal(values, [[1.5, 90.0], [2.0, 0.0], [3.0, 1.0]])
    with pytest.raises(InputError, match=r"column 'x' is in mm but the command reads m "
                                         r"\(--units m\); give --units mm"):
        _read(path, ["x", "A"], ["m", "deg"])


def test_without_units_nothing_is_recorded():
    assert csv_text({"x": np.array([1.0])}) == "x\n1\n"
    assert csv_text({"x": np.array([1.0])}, units="m") == "# units: m\nx\n1\n"


def test_write_table_records_units(tmp_path):
    write_table(tmp_path / "t.csv", ["q1", "status"], [[1.0, "ok"]], units="mm")
    assert (tmp_path / "t.csv").read_text() == "# units: mm\nq1,status\n1,ok\n"


def test_unit_bearing_and_differently_cased_headers(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_text("# exported by a CMM\n# units: mm\nX [mm],Y,z,q4 [deg],note\n"
                    "1,2,3,45,a\n")
    values, reader = _read(path, ["x", "y", "z", "q4"], ["mm", "mm", "mm", "deg"])
    np.testing.assert_array_equal(values, [[1, 2, 3, 45]])
    assert reader.file_unit == "mm"
    # the same columns read by a caller that takes any unit
    np.testing.assert_array_equal(_read(path, ["x", "q4"])[0], [[1, 45]])


@pytest.mark.parametrize("header, units, message", [
    ("x [mm],y", ["m", "m"], r"poses.csv:1: column 'x' is in mm but the command reads m"),
    ("# units: mm\nx,y", ["m", "m"], r"poses.csv:1: column 'x' is in mm but the command"),
    ("# units: m\nx [mm],y", ["mm", "mm"], r"poses.csv:2: column 'x' is in mm but the file "
                                           r"says m \(.*poses.csv:1\)"),
    ("x,A [mm]", ["m", "deg"], r"column 'A' is an angle, in degrees, not in mm"),
    ("x [deg],y", ["m", "m"], r"column 'x' is a length \(in m\), not an angle"),
    ("x [ft],y", ["m", "m"], r"column 'x': unknown unit 'ft'"),
    ("# units: inch\nx,y", ["m", "m"], r"poses.csv:1: unknown unit 'inch'"),
    ("i [mm],y", [None, "m"], r"column 'i' is a number without unit, not in mm"),
    ("x,X,y", ["m", "m"], r"column 'x' is ambiguous: the header has 'x', 'X'"),
    ("x,x [mm],y", ["m", "m"], r"column 'x' is ambiguous"),
])
def test_units_that_contradict_the_command_are_refused(tmp_path, header, units, message):
    path = tmp_path / "poses.csv"
    path.write_text(f"{header}\n1,2,3\n")
    cols = ["i" if header.startswith("i") else "x", "A" if "A" in header else "y"]
    with pytest.raises(InputError, match=message):
        _read(path, cols, units)


def test_parquet_columns_with_units_and_conflicting_metadata(tmp_path):
    path = tmp_path / "t.parquet"
    table = pa.table({"X [mm]": [1.0], "y": [2.0]}).replace_schema_metadata({"units": "m"})
    pq.write_table(table, path)
    with pytest.raises(InputError, match="column 'x' is in mm but the file says m"):
        _read(path, ["x", "y"], ["mm", "mm"])
    pq.write_table(pa.table({"X [mm]": [1.0], "y": [2.0]}), path)
    np.testing.assert_array_equal(_read(path, ["x", "y"], ["mm", "mm"])[0], [[1.0, 2.0]])


@pytest.mark.parametrize("suffix", [".csv", ".parquet", ".feather"])
def test_a_header_that_repeats_a_column_is_refused_with_its_line(tmp_path, suffix):
    """``x,y,z,x``: which x is meant cannot be guessed (issue 18 §5): refused, naming the
    column and the header's line (CSV) or the file (Parquet/Feather, which allow duplicate
    field names)."""
    import pyarrow.feather as pf

    path = tmp_path / f"poses{suffix}"
    if suffix == ".csv":
        path.write_text("# units: m\nx,y,z,x\n0,0,0,0.1\n")
        where = r"poses\.csv:2"
    else:
        table = pa.table([pa.array([0.0])] * 3 + [pa.array([0.1])], names=["x", "y", "z", "x"])
        (pq.write_table if suffix == ".parquet" else pf.write_feather)(table, path)
        where = rf"poses\{suffix}"
    with pytest.raises(InputError, match=rf"{where}: column 'x' is ambiguous: the header has "
                                         r"'x', 'x'; keep one"):
        _read(path, ["x", "y", "z"])


def test_header_helpers():
    assert split_unit(" x [ mm ] ") == ("x", "mm")
    assert split_unit("A [°]") == ("A", "deg")
    assert split_unit("status") == ("status", None)
    assert match_columns(["Z", "x [m]", "y"], ["x", "y", "z"], "f") == ([1, 2, 0],
                                                                       ["m", None, None])
    with pytest.raises(InputError, match="f: missing column"):
        match_columns(["x"], ["x", "y"], "f")
    check_units(["x", "A", "i"], [None, "deg", None], ["mm", "deg", None], "mm", "f:2", "f:1")


def test_standard_output_records_the_unit_too():
    out = io.BytesIO()
    with TableWriter("-", stdout=out, units="mm") as writer:
        writer.write({"x": np.array([1.0])})
    assert out.getvalue() == b"# units: mm\nx\n1\n"
