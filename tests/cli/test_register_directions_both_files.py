"""``pkmkit register``: directions (columns i, j, k) are used only when both files give them;
a file with directions beside one without is refused naming the columns, whichever of the two
has them (issue 18 §9, plausible bugs: the check compared the nominal file with itself)."""

from __future__ import annotations

import pytest

POINTS = [(0.0, 0.0, 0.0), (0.1, 0.0, 0.0), (0.0, 0.2, 0.0), (0.0, 0.0, 0.3)]


def _write(path, with_directions: bool):
    rows = ["# units: m", "id,x,y,z" + (",i,j,k" if with_directions else "")]
    for k, p in enumerate(POINTS):
        rows.append(f"{k + 1},{p[0]},{p[1]},{p[2]}" + (",0,0,1" if with_directions else ""))
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("measured_dirs, nominal_dirs", [(True, False), (False, True)])
def test_directions_in_one_file_only_are_refused(run, tmp_path, measured_dirs, nominal_dirs):
    measured = _write(tmp_path / "measured.csv", measured_dirs)
    nominal = _write(tmp_path / "nominal.csv", nominal_dirs)
    res = run("register", "--measured", measured, "--nominal", nominal)
    assert res.exit_code == 1, res.output
    assert res.output.strip().splitlines()[-1] == \
        "Error: give directions (i, j, k) in both files or in neither"


def test_directions_in_both_files_register(run, tmp_path):
    measured = _write(tmp_path / "measured.csv", True)
    nominal = _write(tmp_path / "nominal.csv", True)
    res = run("register", "--measured", measured, "--nominal", nominal)
    assert res.exit_code == 0, res.output
