"""Measurement CSV files: round trips of every type, units, and errors naming line and column;
atomic writes."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import simulate
from pkmkit.exceptions import InputError
from pkmkit.io.atomic import write_text_atomic as atomic_write_text
from pkmkit.io.measurements import (
    format_measurements,
    read_measurements,
    write_measurements,
)


@pytest.mark.parametrize(("name", "kind"), [("tripteor-x7", "point"), ("gough-stewart", "pose"),
                                            ("verne", "ballbar"), ("linear-delta", "height"),
                                            ("verne", "part")])
@pytest.mark.parametrize("units", ["m", "mm"])
def test_round_trip(tmp_path, name, kind, units):
    m = pkmkit.machine(name)
    data = simulate(m, m, kind, 12, np.random.default_rng(0), noise="none")
    path = tmp_path / f"{kind}.csv"
    write_measurements(path, data, m, units=units, comment="a test\nsecond line")
    back = read_measurements(path, m, kind)
    np.testing.assert_allclose(back.values, data.values, rtol=1e-11, atol=1e-14)
    if data.q is not None:
        np.testing.assert_allclose(back.q, data.q, rtol=1e-11, atol=1e-14)
    for field in ("tool_length", "pivot", "commanded"):
        if getattr(data, field) is not None:
            np.testing.assert_allclose(getattr(back, field), getattr(data, field), rtol=1e-11)
    assert back.labels[0] == f"{path}:5"  # 2 comments, the units line, the header
    # the actuator columns are the machine's actuators
    header = path.read_text().splitlines()[3].split(",")
    if kind != "part":
        assert header[:m.n_actuators] == list(m.actuator_names)


def test_tripteor_angles_are_degrees(tmp_path):
    m = pkmkit.machine("tripteor-x7")
    path = tmp_path / "p.csv"
    path.write_text("# units: mm\nQ1,Q2,Q3,Q4,Q5,x,y,z,tool_length\n"
                    "983.186,1064.076,988.005,10,30,-340.391,2564.142,383.470,169.889\n")
    data = read_measurements(path, m, "point")
    np.testing.assert_allclose(data.q[0], [0.983186, 1.064076, 0.988005, np.radians(10),
                                           np.radians(30)])
    np.testing.assert_allclose(data.values[0], [-0.340391, 2.564142, 0.383470])
    np.testing.assert_allclose(data.tool_length, [0.169889])


BAD = {
    "missing": ("q1,q2,q3,x,y\n1,1,1,0,0\n", r"f\.csv:1: missing column\(s\) z"),
    "extra": ("q1,q2,q3,x,y,z,w\n1,1,1,0,0,0,0\n", r"f\.csv:1: unknown column\(s\) w"),
    "nan": ("q1,q2,q3,x,y,z\n1,1,1,0,0,0\n1,1,1,nan,0,0\n",
            r"f\.csv:3: column 'x': 'nan' is not a finite number"),
    "text": ("q1,q2,q3,x,y,z\n1,1,1,0,0,0\n1,1,1,0,abc,0\n",
             r"f\.csv:3: column 'y': 'abc' is not a number"),
    "short": ("q1,q2,q3,x,y,z\n1,1,1,0,0\n", r"f\.csv:2: 5 cells for 6 columns"),
    "duplicate": ("q1,q2,q3,x,y,z\n1,1,1,0,0,0\n1.2,1,1,0,0,0\n1,1,1,0,0,0\n",
                  r"f\.csv:4: duplicate row: identical to line 2"),
    "headerless": ("1,1,1,0,0,0\n", r"f\.csv:1: the first row must be a header"),
    "empty": ("# nothing\n", r"f\.csv: no header and no data"),
    "no rows": ("q1,q2,q3,x,y,z\n", r"no data rows after the header"),
    "column units": ("# units: mm\nq1,q2,q3,x [m],y,z\n1,1,1,0,0,0\n",
                     r"f\.csv:2: column 'x' is in m but the file says mm \(line 1\)"),
    "bad unit": ("q1,q2,q3,x [inch],y,z\n1,1,1,0,0,0\n", r"unknown unit 'inch'"),
    # issue 18 §7 fuzz: 1e308 overflowed in the norms of a ball-bar plan (RuntimeWarning); a
    # 100 000-character cell filled the error message
    "huge": ("q1,q2,q3,x,y,z\n1,1,1,0,-1e308,0\n",
             r"f\.csv:2: column 'y': -1e\+308 m is beyond 1e\+06 m .* check the units"),
    # the bound is in metres: 2e9 mm (2e6 m) is refused as 2e6 m is, 1e9 mm (1e6 m) is not
    "huge mm": ("# units: mm\nq1,q2,q3,x,y,z\n1,1,1,0,2e9,0\n",
                r"f\.csv:3: column 'y': 2e\+09 mm is beyond 1e\+06 m"),
    "oversized": ("q1,q2,q3,x,y,z\n1,1,1,0," + "7" * 100_000 + "x,0\n",
                  r"f\.csv:2: column 'y': '7{36}… is not a number$"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_files_name_line_and_column(tmp_path, case):
    text, message = BAD[case]
    path = tmp_path / "f.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        read_measurements(path, pkmkit.machine("linear-delta"), "point")


def test_units_mismatch_with_the_command(tmp_path):
    path = tmp_path / "f.csv"
    path.write_text("# units: mm\nq1,q2,q3,x,y,z\n1000,1000,1000,0,0,0\n")
    m = pkmkit.machine("linear-delta")
    with pytest.raises(InputError, match="units mismatch: the file is in mm, the command says m"):
        read_measurements(path, m, "point", units="m")
    assert read_measurements(path, m, "point", units="mm").q[0, 0] == pytest.approx(1.0)
    path.write_text("q1,q2,q3,x,y,z\n1000,1000,1000,0,0,0\n")
    assert read_measurements(path, m, "point", units="mm").q[0, 0] == pytest.approx(1.0)
    assert read_measurements(path, m, "point").q[0, 0] == pytest.approx(1000.0)


def test_atomic_write_leaves_nothing_on_failure(tmp_path, monkeypatch):
    target = tmp_path / "out.csv"
    target.write_text("old content\n")
    import os

    def broken(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", broken)
    with pytest.raises(InputError, match="disk full"):  # a typed error, not a raw OSError
        atomic_write_text(target, "new content\n")
    assert target.read_text() == "old content\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]
    monkeypatch.undo()
    with pytest.raises(InputError, match="cannot write"):
        atomic_write_text(tmp_path / "missing" / "x.csv", "x")


@pytest.mark.parametrize("umask", [0o022, 0o002, 0o077])
def test_written_files_follow_the_umask(tmp_path, umask):
    """Every output (measurement files, machine files, reports) goes through one writer whose
    files get the mode a new file gets under the umask, not 0600 (issue 18 §6)."""
    import os

    old = os.umask(umask)
    try:
        atomic_write_text(tmp_path / "out.csv", "x\n")
    finally:
        os.umask(old)
    assert (tmp_path / "out.csv").stat().st_mode & 0o777 == 0o666 & ~umask
    m = pkmkit.machine("linear-delta")
    data = simulate(m, m, "point", 3, np.random.default_rng(0), noise="none")
    assert format_measurements(data, m, units="mm").splitlines()[0] == "# units: mm"


def test_column_names_in_another_case(tmp_path):
    """As batch tables: a CMM export's X, Y, Z [mm] columns are x, y, z; x and X both are
    refused as a repeated column."""
    path = tmp_path / "f.csv"
    path.write_text("Q1,Q2,Q3,X [mm],Y [mm],Z [mm],ID\n1000,1000,1000,1,2,3,a\n")
    data = read_measurements(path, pkmkit.machine("linear-delta"), "point")
    np.testing.assert_allclose(data.values[0], [0.001, 0.002, 0.003])
    np.testing.assert_allclose(data.q[0], [1.0, 1.0, 1.0])
    path.write_text("q1,q2,q3,x,X,y,z\n1,1,1,0,0,0,0\n")
    with pytest.raises(InputError, match=r"f\.csv:1: repeated column"):
        read_measurements(path, pkmkit.machine("linear-delta"), "point")


def test_a_ballbar_length_not_positive_names_its_line(tmp_path):
    """A bar length ≤ 0 is refused with its file line (a typed error, not an IndexError)."""
    m = pkmkit.machine("verne")
    data = simulate(m, m, "ballbar", 5, np.random.default_rng(0), noise="none")
    path = tmp_path / "ballbar.csv"
    write_measurements(path, data, m, units="m", comment="a test\nsecond line")
    lines = path.read_text().splitlines()
    column = lines[3].split(",").index("length")
    cells = lines[6].split(",")
    cells[column] = "-0.5"
    lines[6] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"ballbar\.csv:7: column 'length' must be > 0"):
        read_measurements(path, m, "ballbar")
