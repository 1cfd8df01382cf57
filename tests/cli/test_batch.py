"""Batch mode of ik/fk/jacobian: identical results across CSV, Parquet, Feather, standard
input/output, chunked and one-shot runs; errors keep their file line and column."""

import io

import numpy as np
import pyarrow as pa
import pyarrow.csv as pcsv
import pyarrow.feather as feather
import pyarrow.parquet as pq
import pytest

import pkmkit

ROWS = 23


def _poses(tmp_path):
    rng = np.random.default_rng(7)
    x = rng.uniform(-0.3, 0.3, (ROWS, 3))
    x[3] = [2.0, 0.0, 0.0]  # unreachable
    x[5, 1] = np.nan
    return x


def _table(result_bytes: bytes) -> pa.Table:
    """A CSV output of a batch (its first line the ``# units:`` line) as a table."""
    units, _, result_bytes = result_bytes.partition(b"\n")
    assert units.startswith(b"# units: "), units
    return pcsv.read_csv(io.BytesIO(result_bytes),
                         convert_options=pcsv.ConvertOptions(null_values=[""],
                                                             strings_can_be_null=True))


def _as_frame(path) -> dict:
    path = str(path)
    if path.endswith(".parquet"):
        table = pq.read_table(path)
    elif path.endswith(".feather"):
        table = feather.read_table(path)
    else:
        table = _table(open(path, "rb").read())
    out = {}
    for name in table.column_names:
        col = table.column(name)
        if pa.types.is_dictionary(col.type):
            col = col.cast(pa.string())
        out[name] = [("" if v is None else v) for v in col.to_pylist()]
    return out


def _write_input(path, columns: dict):
    table = pa.table(columns)
    if str(path).endswith(".parquet"):
        pq.write_table(table, path)
    elif str(path).endswith(".feather"):
        feather.write_feather(table, path)
    else:
        pcsv.write_csv(table, path)


def _same(a: dict, b: dict):
    assert list(a) == list(b)
    for name in a:
        va, vb = a[name], b[name]
        if va and isinstance(va[0], float):
            np.testing.assert_array_equal(np.array(va, dtype=float), np.array(vb, dtype=float))
        else:
            assert va == vb, name


@pytest.mark.parametrize("command, extra", [
    ("ik", []), ("jacobian", []), ("fk", []), ("fk", ["--all"]),
])
def test_batch_identical_across_formats_chunks_and_pipes(run, tmp_path, command, extra):
    x = _poses(tmp_path)
    m = pkmkit.machine("linear-delta")
    if command == "fk":
        values = m.ik(np.nan_to_num(x, nan=0.0), full_output=True).q.copy()  # records: read-only
        values[5, 1] = np.nan
        values[7] = [0.1, 0.1, 3.0]  # no assembly
        columns = {"q1": values[:, 0], "q2": values[:, 1], "q3": values[:, 2]}
    else:
        columns = {"x": x[:, 0], "y": x[:, 1], "z": x[:, 2]}
    outputs = {}
    for fmt in ("csv", "parquet", "feather"):
        src = tmp_path / f"in.{fmt}"
        _write_input(src, columns)
        for chunk in (None, 1, 4):
            dst = tmp_path / f"out-{fmt}-{chunk}.{fmt}"
            args = [command, "linear-delta", *extra, "--input", src, "--output", dst]
            result = run(*args, *(["--chunk-rows", chunk] if chunk else []))
            assert result.exit_code == 3, result.output
            outputs[(fmt, chunk)] = _as_frame(dst)
    csv_text = (tmp_path / "in.csv").read_bytes()
    piped = run(command, "linear-delta", *extra, "--input", "-", "--output", "-",
                "--chunk-rows", 5, input=csv_text)
    assert piped.exit_code == 3
    reference = outputs[("csv", None)]
    _same(reference, _as_frame_bytes(piped.stdout_bytes))
    for key, frame in outputs.items():
        _same(reference, frame), key
    status = reference["status"]
    assert status.count("invalid-input") >= 1 and ("unreachable" in status or command == "fk")
    if command == "fk" and extra:
        rows = reference["row"]
        assert rows == sorted(rows) and sorted(set(rows)) == list(range(ROWS))
        assert len(rows) > ROWS  # some rows have two real assembly modes


def _as_frame_bytes(data: bytes) -> dict:
    table = _table(data)
    return {name: [("" if v is None else v) for v in table.column(name).to_pylist()]
            for name in table.column_names}


def test_batch_inputs_echo_exactly_and_floats_are_shortest(run, tmp_path):
    src = tmp_path / "poses.csv"
    src.write_text("x,y,z\n0.042444,0.1,0\n")
    out = tmp_path / "q.csv"
    assert run("ik", "linear-delta", "--input", src, "--output", out).exit_code == 0
    units, header, row = out.read_text().splitlines()
    assert units == "# units: m" and header.startswith("x,y,z,")
    line = row.split(",")
    assert line[:3] == ["0.042444", "0.1", "0"]
    q = pkmkit.machine("linear-delta").ik([0.042444, 0.1, 0.0])
    assert [float(v) for v in line[3:6]] == q.tolist()
    assert all(v == repr(float(v)) or len(v) <= len(repr(float(v))) for v in line[3:6])


def test_batch_errors_keep_file_line_and_column(run, tmp_path):
    src = tmp_path / "poses.csv"
    src.write_text("# poses\nx,y,z\n0,0,0\n\n0,zz,0\n0,0\n0,0,1e999\n0.1,0,0\n")
    out = tmp_path / "q.parquet"
    result = run("ik", "linear-delta", "--input", src, "--output", out, "--chunk-rows", 2)
    assert result.exit_code == 3
    assert f"{src}:5: column 'y' is not a number: 'zz'" in result.output
    assert f"{src}:6: expected at least 3 columns, got 2" in result.output
    assert f"{src}:7: column 'z' overflows a double: '1e999'" in result.output
    frame = _as_frame(out)
    assert frame["status"] == ["ok", "invalid-input", "invalid-input", "invalid-input", "ok"]


def test_batch_refuses_bad_destinations_before_work(run, tmp_path):
    src = tmp_path / "poses.csv"
    src.write_text("x,y,z\n0,0,0\n")
    result = run("ik", "linear-delta", "--input", src, "--output", tmp_path / "no" / "q.csv")
    assert result.exit_code == 1 and "does not exist" in result.output
    result = run("ik", "linear-delta", "--input", src, "--output", tmp_path / "q.xlsx")
    assert result.exit_code == 1 and "unknown table type" in result.output
    (tmp_path / "bin.csv").write_bytes(b"\x00\x01\x02")
    result = run("ik", "linear-delta", "--input", tmp_path / "bin.csv", "--output",
                 tmp_path / "q.csv")
    assert result.exit_code == 1 and "not a text file" in result.output
    assert not (tmp_path / "q.csv").exists()
    result = run("ik", "linear-delta", "--output", tmp_path / "q.csv", "--pose", "0,0,0")
    assert result.exit_code == 2 and "--output goes with --input" in result.output


def test_help_documents_the_batch_columns(run):
    text = " ".join(run("ik", "--help").output.split())
    assert "Batch input columns: the pose, named x,y" in text and "status (ok," in text
    assert ".parquet" in text and "- for CSV on standard input" in text
    assert "row" in run("fk", "--help").output
    assert "sv1..svn" in run("jacobian", "--help").output


@pytest.mark.parametrize("command, machine, rows", [
    ("ik", "verne", ["0,0,0", "inf,0,0", "0.01,0,0"]),  # a position-controlled module
    ("fk", "gough-stewart", ["0.9,0.9,0.9,0.9,0.9,0.9", "0.9,0.9,0.9,0.9,0.9,1e300",
                             "0.91,0.9,0.9,0.9,0.9,0.9"]),
])
def test_one_bad_row_flags_that_row_only(run, tmp_path, command, machine, rows):
    """Issue 18 §5: an infinite row of a Verne batch made every row invalid-input; a full-pose
    row beyond 1e9 raised from the first-order guess and lost the whole batch."""
    m = pkmkit.machine(machine)
    names = ["x", "y", "z"] if command == "ik" else list(m.actuator_names)
    src = tmp_path / "in.csv"
    src.write_text(",".join(names) + "\n" + "\n".join(rows) + "\n")
    result = run(command, machine, "--input", src, "--output", "-")
    assert result.exit_code == 3, result.output
    lines = [line for line in result.stdout.splitlines() if not line.startswith("#")]
    assert [line.rsplit(",", 1)[1] for line in lines[1:]] == ["ok", "invalid-input", "ok"]
