"""``pkmkit compensate --gravity``: the corrected table aims the calibrated machine's loaded
tool point at the targets (:mod:`pkmkit.calibration.gravity`), the G-code program too."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.compensation import correct_table
from pkmkit.calibration.gravity import aim_loaded


@pytest.fixture(scope="module")
def truth(tmp_path_factory):
    """A linear Delta with random defects (the simulations' 'calibrated' machine file)."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d = tmp_path_factory.mktemp("gravity")
    res = CliRunner().invoke(cli, ["simulate-measurements", "linear-delta", "--measure", "point",
                                   "--poses", "10", "--defects", "random", "--out",
                                   str(d / "m.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return d / "m.truth.toml"


def _corrected(path) -> np.ndarray:
    """The corrected targets (columns cx, cy, cz) of a correction table."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    header = lines[0].split(",")
    cols = [header.index(c) for c in ("cx", "cy", "cz")]
    return np.array([[float(line.split(",")[c]) for c in cols] for line in lines[1:]])


def test_gravity_moves_the_corrected_targets_by_the_sag(run, as_json, truth, tmp_path):
    grid = "-0.1,-0.1,0.1:0.1,0.1,0.2:2,2,2"
    plain = as_json(run("compensate", "linear-delta", "--calibrated", truth, "--grid", grid,
                        "--out", tmp_path / "plain.csv", "--json"))
    loaded = as_json(run("compensate", "linear-delta", "--calibrated", truth, "--grid", grid,
                         "--gravity", "--out", tmp_path / "loaded.csv", "--json"))
    assert plain["gravity"] is None
    assert loaded["gravity"]["deflection_max"] > 1e-7 and "illustrative" in (
        loaded["gravity"]["masses"])
    nominal, identified = pkmkit.machine("linear-delta"), pkmkit.load(truth)
    from pkmkit.calibration.compensation import grid_targets

    targets = grid_targets([-0.1, -0.1, 0.1], [0.1, 0.1, 0.2], [2, 2, 2])
    aimed, sag = aim_loaded(identified, targets, masses_of=nominal)
    expected, _ = correct_table(nominal, identified, aimed, max_correction=1.0)
    got = _corrected(tmp_path / "loaded.csv")
    assert np.allclose(got, expected, atol=1e-10, rtol=0)  # the file keeps 10 digits
    moved = got - _corrected(tmp_path / "plain.csv")
    assert np.allclose(np.linalg.norm(moved, axis=1), np.linalg.norm(sag.deflection[:, :3],
                                                                     axis=1), rtol=0.05)


def test_gravity_corrects_a_gcode_program(run, as_json, truth, tmp_path):
    """The program's corrected end points are the library's (correct_path with LoadedAim), the
    JSON says how large the sag was; a bound below the sag refuses blocks by their line."""
    from pkmkit.calibration.corrected_program import correct_path
    from pkmkit.calibration.gravity import LoadedAim
    from pkmkit.motion.gcode import read_gcode

    program = tmp_path / "p.nc"
    program.write_text("G21 G90\nG0 X0 Y0 Z100\nG1 X10 Y0 Z100 F300\nG1 X10 Y10 Z100\n")
    out = as_json(run("compensate", "linear-delta", "--calibrated", truth, "--gcode", program,
                      "--gravity", "--units", "mm", "--out", tmp_path / "fixed.nc", "--json"))
    assert 1e-4 < out["gravity"]["deflection_max"] < 1e-2  # mm
    # the linear Delta's masses, though the calibrated file has no kind of its own
    assert "carriages 8 kg, platform 15 kg" in out["gravity"]["masses"]
    nominal, identified = pkmkit.machine("linear-delta"), pkmkit.load(truth)
    path = read_gcode(program.read_text())
    expected = correct_path(nominal, identified, path,
                            aim=LoadedAim(identified, masses_of=nominal))
    back = read_gcode((tmp_path / "fixed.nc").read_text())
    assert [s.rapid for s in back.segments] == expected.rapid.tolist()
    ends = np.array([s.end for s in back.segments])
    np.testing.assert_allclose(ends, expected.corrected, atol=6e-8)  # 4 decimals in mm
    plain = correct_path(nominal, identified, path)
    assert np.linalg.norm(ends - plain.corrected, axis=1).min() > 1e-7  # moved by the sag
    refused = run("compensate", "linear-delta", "--calibrated", truth, "--gcode", program,
                  "--gravity", "--units", "mm",
                  "--max-correction", "1e-4", "--out", tmp_path / "no.nc")
    assert refused.exit_code == 3 and "p.nc:2:" in refused.output
    assert not (tmp_path / "no.nc").exists()
