"""Extreme but finite values on the command line (issue 18 §5, §7): each was answered with exit
status 0 (NaN, a 1e-302 m grid step, a 10 m deflection) or a traceback, and is now refused with
a one-line error naming the option and the value, or judged doubtful (exit 3)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


@pytest.mark.parametrize("args, words", [
    # every singularity measure is a ratio in [0, 1]: --tol 1e300 flagged every pose singular
    # and printed a Jacobian of NaN with exit 0
    (["jacobian", "orthoglide", "--pose", "0,0,0", "--tol", "1e300"], "must lie in (0, 1)"),
    (["jacobian", "orthoglide", "--pose", "0,0,0", "--tol", "1"], "must lie in (0, 1)"),
    # grids and regions thinner than 1 nm: a workspace of 0 m³ with a NaN GCI, a map over
    # 2e-300 m, a "feasible" cube of 1e-300 m
    (["workspace", "orthoglide", "--box", "-1e-300,1e-300,-1e-300,1e-300,-1e-300,1e-300"],
     "the x range [-1e-300, 1e-300] (--units) is narrower than 1 nm"),
    (["map", "orthoglide", "--index", "condition", "--slice", "z=0", "--range",
      "-1,1,-1e-301,1e-301", "--out", "m.png"], "the y range"),
    # the workspace study runs before the cube is judged: 1.6 s, marked ci (.ci/run)
    pytest.param(["workspace", "orthoglide", "--cube", "1e-300", "--center", "0,0,0"],
                 "the side = 1e-300 m is below 1e-09 m", marks=pytest.mark.ci),
    # arm materials: a density of 1e300 kg/m³ raised NumPy's ValueError (a traceback), one of
    # 1e-300 sized an arm of 5.6e-305 kg; a safety factor below 1 sizes an arm that fails
    (["arm-sizing", "--length", "1", "--force", "100", "--density", "1e300"],
     "material density = 1e+300 kg/m³ is outside [1, 100000]"),
    (["arm-sizing", "--length", "1", "--force", "100", "--density", "1e-300"],
     "material density = 1e-300"),
    (["arm-sizing", "--length", "1", "--force", "100", "--young", "1e300"],
     "--young 1e+300 Pa is outside the plausible range [1e+06, 1e+13] Pa"),
    (["arm-sizing", "--length", "1", "--force", "100", "--yield", "1e300"],
     "material yield_strength = 1e+300 Pa"),
    (["arm-sizing", "--length", "1", "--force", "100", "--stress-safety", "1e-300"],
     "the stress safety = 1e-300 is below 1"),
    # defect sizes of a first-order sensitivity: 1e300 printed inf displacements, 1e-300 an
    # exact model rounded to 0, both with exit 0
    (["errors", "linear-delta", "--sensitivity", "--length-size", "1e300", "--points", "5"],
     "--length-size 1e+300 m is outside [1e-09, 0.13] m"),
    (["errors", "linear-delta", "--sensitivity", "--length-size", "1e-300", "--points", "5",
      "--units", "mm"], "--length-size 1e-300 mm is outside [1e-06, 130] mm"),
    (["errors", "linear-delta", "--sensitivity", "--angle-size", "1e300", "--points", "5"],
     "--angle-size 1e+300° is outside"),
    # a rank tolerance below double precision: "rank 30 of 30" at a condition of 1.8e18,
    # every defect called identifiable (with the default 1e-9: rank 24, six combinations)
    (["identifiability", "orthoglide", "--measure", "point", "--poses", "20", "--rtol",
      "1e-300"], "--rtol 1e-300 is outside [1e-14, 1)"),
    (["errors", "gough-stewart", "--compatibility", "--rtol", "1e-300"], "--rtol 1e-300"),
    # a billion sampled configurations hung (killed after 120 s); a pivot of 1e300 m
    # overflowed into an error blaming the rank
    (["identifiability", "orthoglide", "--measure", "point", "--poses", "1000000000"],
     "1e+09 configurations to sample (--poses/--candidates N), above the limit of 1e+05"),
    (["select-poses", "orthoglide", "--measure", "point", "--n", "5", "--candidates",
      "1000000000", "--out", "sel.csv"], "above the limit of 1e+05"),
    (["identifiability", "orthoglide", "--measure", "ballbar", "--poses", "20", "--pivot",
      "1e300,0,0"], "--pivot 1e300,0,0: beyond 1e+06 m from the origin"),
    # numbers inside text options (issue 18 §5, second pass): a work offset ignored without a
    # program, a part turned by 1e300°, transmission-factor bounds of [1e-300, 1e300] (no
    # bound) were accepted with exit 0
    (["path", "orthoglide", "--line", "0,0,0:0.05,0,0", "--feed", "0.05", "--accel", "1",
      "--origin", "1e300,0,0"], "--origin is the work offset of a G-code program"),
    (["machined-part", "simulate", "verne", "--gcode", EXAMPLES / "pocket.nc", "--out",
      "cmm.csv", "--placement", "0,0,0,1e300"], "--placement: PHI = 1e+300° is outside"),
    (["machined-part", "simulate", "verne", "--gcode", EXAMPLES / "pocket.nc", "--out",
      "cmm.csv", "--placement", "1e300,0,0,0"], "--placement 1e+300 mm is outside the plausible"),
    (["machined-part", "ballbar-plan", "verne", "--out", "plan.csv", "--table-points",
      "1e300,0,0"], "--table-points 1e+300 mm is outside the plausible range"),
    (["machined-part", "ballbar-plan", "verne", "--out", "plan.csv", "--tool-lengths",
      "0,1e300"], "--tool-lengths: 1e+300 mm is beyond"),
    (["useful-workspace", "orthoglide", "--bounds", "1e-300,1e300"],
     "--bounds 1e-300 is outside the plausible range [1e-06, 1e+06]"),
])
def test_extreme_values_are_refused(run, tmp_path, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code in (1, 2), result.output
    assert words in result.output
    assert result.output.strip().splitlines()[-1].startswith("Error:")
    assert not list(tmp_path.iterdir())  # no figure of a degenerate grid


def test_analyze_deflection_beyond_the_linear_model_exits_3(run):
    """1e9 N on the Orthoglide printed a 10 m deflection with exit 0."""
    args = ["analyze", "orthoglide", "--stiffness", "--wrench", "1e9,1e9,1e9", "--units", "mm"]
    result = run(*args)
    assert result.exit_code == 3, result.output
    assert "deflection under" in result.stdout
    assert "doubtful: the deflection is beyond the range of the linear" in result.stderr
    assert "a translation beyond 3.1 mm" in result.stderr
    out = json.loads(run(*args, "--json").stdout)
    assert "small-displacement" in out["stiffness"]["beyond_linear_range"]
    fine = run("analyze", "orthoglide", "--stiffness", "--wrench", "100,0,0")
    assert fine.exit_code == 0 and "doubtful" not in fine.output


@pytest.mark.ci
def test_map_of_deflections_beyond_the_linear_model_exits_3(run, tmp_path):
    """A map of 0.86 km deflections under 1e9 N was drawn with exit 0."""
    args = ["map", "orthoglide", "--index", "deflection", "--slice", "z=0", "--resolution",
            "11", "--units", "mm"]
    result = run(*args, "--wrench", "1e9,0,0", "--out", tmp_path / "d.png")
    assert result.exit_code == 3, result.output
    assert "doubtful: the deflection is beyond the range of the linear" in result.stderr
    fine = run(*args, "--wrench", "100,0,0", "--out", tmp_path / "e.png")
    assert fine.exit_code == 0 and "doubtful" not in fine.output
