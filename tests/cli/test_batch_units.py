"""Batch tables carry their units (issue 18 §5): ``ik`` then ``fk`` on its output gives the
poses back, in every unit and format; inputs may state their unit as measurement files do; a
table in another unit than ``--units`` is refused before any work, naming the column."""

import numpy as np
import pyarrow.parquet as pq
import pytest

from tests.cli.conftest import table_lines


def _columns(path, names):
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    header = lines[0].split(",")
    return np.array([[float(row.split(",")[header.index(n)]) for n in names]
                     for row in lines[1:]])


@pytest.mark.parametrize("ident", ["orthoglide", "gough-stewart", "tripteor-x7"])
@pytest.mark.parametrize("units", ["m", "mm"])
def test_ik_then_fk_gives_the_poses_back(run, tmp_path, ident, units):
    import warnings

    from pkmkit.cli.coordinates import pose_columns, pose_to_cli

    import pkmkit

    m = pkmkit.machine(ident)
    names = pose_columns(m)
    q = np.stack([m.home_q, np.asarray(m.home_q) * 1.001])  # home and a nearby configuration
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rows = pose_to_cli(np.atleast_2d(m.fk(q)), m, units, "xyz")
    a = tmp_path / "a.csv"
    a.write_text(",".join(names) + "\n" + "\n".join(
        ",".join(repr(float(v)) for v in r) for r in rows) + "\n")
    b, c = tmp_path / "b.csv", tmp_path / "c.csv"
    result = run("ik", ident, "--input", a, "--output", b, "--units", units)
    assert result.exit_code == 0, result.output
    assert table_lines(b.read_text(), units)[0].startswith(",".join(names))
    result = run("fk", ident, "--input", b, "--output", c, "--units", units)
    assert result.exit_code == 0, result.output
    back = _columns(c, names)
    scale = 1e3 if units == "mm" else 1.0
    np.testing.assert_allclose(back[:, :3], rows[:, :3], rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(back[:, 3:], rows[:, 3:], rtol=0, atol=1e-8)


def test_a_table_in_another_unit_is_refused_naming_the_column(run, tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("x,y,z\n0.01,0.02,0\n")
    assert run("ik", "orthoglide", "--input", a, "--output", b, "--units", "mm").exit_code == 0
    out = tmp_path / "c.csv"
    result = run("ik", "orthoglide", "--input", b, "--output", out)  # b is in mm
    assert result.exit_code == 1 and not out.exists()
    assert "b.csv:1: column 'x' is in mm but the command reads m (--units m); give --units mm" \
        in result.output
    result = run("fk", "orthoglide", "--input", b, "--output", out)
    assert "column 'rho1' is in mm but the command reads m" in result.output


def test_unit_bearing_headers_are_read_like_measurement_files(run, tmp_path):
    a = tmp_path / "a.csv"
    a.write_text("X [mm],Y [mm],Z [mm]\n10,20,0\n")
    result = run("ik", "orthoglide", "--input", a, "--output", "-", "--units", "mm")
    assert result.exit_code == 0, result.output
    lines = table_lines(result.stdout, "mm")
    assert lines[0] == "x,y,z,rho1,rho2,rho3,mode,status"
    same = run("ik", "orthoglide", "--pose", "10,20,0", "--units", "mm", "--json")
    import json

    q = json.loads(same.stdout)["q"]
    np.testing.assert_allclose([float(v) for v in lines[1].split(",")[3:6]], q, rtol=1e-12)
    result = run("ik", "orthoglide", "--input", a, "--output", "-")
    assert result.exit_code == 1 and "column 'x' is in mm" in result.output


def test_angles_are_degrees_and_parquet_records_the_unit(run, tmp_path):
    a = tmp_path / "q.csv"
    a.write_text("q1 [mm],q2 [mm],q3 [mm],q4 [mm],q5 [mm],q6 [mm]\n" + ",".join(["900"] * 6)
                 + "\n")
    out = tmp_path / "x.parquet"
    result = run("fk", "gough-stewart", "--input", a, "--output", out, "--units", "mm")
    assert result.exit_code == 0, result.output
    assert pq.read_table(out).schema.metadata[b"units"] == b"mm"
    bad = tmp_path / "p.csv"
    bad.write_text("x,y,z,A [rad],B,C\n0,0,950,0,0,0\n")
    result = run("ik", "gough-stewart", "--input", bad, "--output", "-", "--units", "mm")
    assert result.exit_code == 1
    assert "column 'A': unknown unit 'rad'" in result.output
