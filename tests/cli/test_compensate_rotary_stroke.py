"""``compensate --gcode`` refuses a block whose corrected target puts a crank beyond its
stroke, stating the excess in degrees (issue 18 §9, plausible bugs: the excess of a rotary
actuator printed in radians as degrees passed every test, which used slides only). Oracle: the
calibrated machine's own inverse model at the block's target, against the −40° limit."""

from __future__ import annotations

import re

import numpy as np
import pytest

import pkmkit


@pytest.fixture(scope="module")
def delta_truth(tmp_path_factory):
    """A Delta robot (cranks, strokes [−40, 95]°) with random defects."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d = tmp_path_factory.mktemp("delta")
    res = CliRunner().invoke(cli, ["simulate-measurements", "delta", "--measure", "point",
                                   "--poses", "10", "--defects", "random", "--out",
                                   str(d / "m.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return d / "m.truth.toml"


@pytest.mark.parametrize("units", ["mm", "m"])
def test_crank_beyond_its_stroke_is_refused_in_degrees(run, delta_truth, tmp_path, units):
    program = tmp_path / "high.nc"
    program.write_text("G21 G90\nG0 X0 Y0 Z-830\nG1 X0 Y0 Z-700 F600\nG1 X0 Y0 Z-450\n")
    res = run("compensate", "delta", "--calibrated", delta_truth, "--gcode", program,
              "--units", units, "--out", tmp_path / "fixed.nc")
    assert res.exit_code == 3, res.output
    assert not (tmp_path / "fixed.nc").exists()
    line = next(x for x in res.output.splitlines() if "high.nc:4:" in x)
    m = re.search(r"(q\d) out of stroke by ([0-9.e+-]+) deg", line)
    assert m, line
    q = np.degrees(pkmkit.load(delta_truth).ik(np.array([[0.0, 0.0, -0.45]]),
                                               strokes="ignore")[0])
    k = int(m.group(1)[1:]) - 1
    assert q[k] < -40.0
    assert float(m.group(2)) == pytest.approx(-40.0 - q[k], abs=2e-3)
