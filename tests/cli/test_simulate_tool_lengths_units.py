"""``simulate-measurements --tool-lengths`` is read in ``--units``: the same simulation written
in mm and in m gives the same physical readings (every length 1000× in the mm file, the tool
lengths as given)."""

import csv

import numpy as np


def _table(path):
    rows = [r for r in csv.reader(path.read_text().splitlines()) if not r[0].startswith("#")]
    header, body = rows[0], rows[1:]
    return {name: np.array([float(r[k]) for r in body]) for k, name in enumerate(header)
            if name != "tool"}


def test_tool_lengths_in_mm_and_in_m_give_the_same_readings(run, tmp_path):
    args = ["simulate-measurements", "tripteor-x7", "--measure", "point", "--poses", "3",
            "--noise", "none"]
    mm, m = tmp_path / "mm.csv", tmp_path / "m.csv"
    assert run(*args, "--tool-lengths", "100,200", "--units", "mm", "--out", mm).exit_code == 0
    assert run(*args, "--tool-lengths", "0.1,0.2", "--units", "m", "--out", m).exit_code == 0
    a, b = _table(mm), _table(m)
    np.testing.assert_allclose(a["tool_length"], [100.0, 200.0, 100.0])
    for name in ("Q1", "Q2", "Q3", "x", "y", "z", "tool_length"):
        np.testing.assert_allclose(a[name], 1000.0 * b[name], rtol=1e-9, err_msg=name)
