"""Stiffness in ``map``, ``analyze``, ``workspace``, ``path`` and ``optimize``: the command line
against the library (units N/µm and µm at the boundary, SI inside), refusals, verdicts."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pkmkit.cli.main import cli
from pkmkit.dynamics.defaults import default_masses
from pkmkit.machines.registry import machine
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.timelaw import plan
from pkmkit.stiffness import stiffness
from pkmkit.stiffness.along_path import path_deflection
from pkmkit.stiffness.indices import stiffness_index

POCKET = Path(__file__).resolve().parents[2] / "docs" / "examples" / "pocket.nc"


def run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args], catch_exceptions=False)


def as_json(result):
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.mark.ci
def test_map_stiffness_is_the_library_index_in_n_per_um(tmp_path):
    out = as_json(run("map", "orthoglide", "--index", "stiffness", "--slice", "z=0",
                      "--range", "-100,100,-100,100", "--resolution", "21", "--units", "mm",
                      "--out", tmp_path / "k.png", "--json"))
    assert out["index_unit"] == "N/µm" and (tmp_path / "k.png").exists()
    m = machine("orthoglide")
    at_min = np.array(out["at_min"]) * 1e-3
    assert out["min"] == pytest.approx(stiffness_index(m, at_min[None], "stiffness")[0] / 1e6,
                                       rel=1e-12)
    doubled = as_json(run("map", "orthoglide", "--index", "stiffness", "--slice", "z=0",
                          "--range", "-100,100,-100,100", "--resolution", "21", "--units", "mm",
                          "--set", "actuator_stiffness=2e8", "--out", tmp_path / "k2.png",
                          "--json"))
    assert doubled["min"] == pytest.approx(2 * out["min"], rel=1e-12)


def test_map_deflection_needs_a_wrench(tmp_path):
    result = CliRunner().invoke(cli, ["map", "orthoglide", "--index", "deflection", "--slice",
                                      "z=0", "--out", str(tmp_path / "d.png")])
    assert result.exit_code != 0 and "--wrench" in result.output
    result = CliRunner().invoke(cli, ["map", "orthoglide", "--index", "condition", "--slice",
                                      "z=0", "--wrench", "0,0,-100", "--out",
                                      str(tmp_path / "c.png")])
    assert result.exit_code != 0 and "go together" in result.output


def test_analyze_stiffness_and_deflection_agree_with_the_library():
    out = as_json(run("analyze", "orthoglide", "--pose", "80,-40,60", "--units", "mm",
                      "--wrench", "0,0,-500", "--json"))
    ref = stiffness(machine("orthoglide"), np.array([0.08, -0.04, 0.06]), wrench=[0, 0, -500])
    np.testing.assert_allclose(out["stiffness"]["translational_eigenvalues"], ref.translational,
                               rtol=1e-12)
    np.testing.assert_allclose(out["stiffness"]["deflection"], ref.deflection, rtol=1e-12)
    text = run("analyze", "orthoglide", "--pose", "80,-40,60", "--units", "mm",
               "--stiffness").output
    assert "translational stiffness (pure force): [61.349, 111.34, 153.73] N/µm" in text
    assert "deflection" not in text


@pytest.mark.ci
def test_workspace_with_a_stiffness_criterion():
    base = ("workspace", "orthoglide", "--slice", "z=0", "--box", "-150,150,-150,150",
            "--resolution", "31", "--units", "mm", "--json")
    plain = as_json(run(*base, "--stiffness"))
    bounded = as_json(run(*base, "--min-stiffness", "50", "--wrench", "0,0,-500",
                          "--max-deflection", "9"))
    assert bounded["criteria"]["min_stiffness"] == 50
    assert bounded["criteria"]["max_deflection"] == 9
    assert bounded["feasible_points"] < plain["feasible_points"]
    assert bounded["points_per_criterion"]["stiffness"] < bounded["points_per_criterion"]["mode"]
    s = bounded["stiffness"]
    assert s["min"] >= 50 * (1 - 1e-9) and s["deflection_max"] <= 9 * (1 + 1e-9)
    assert plain["stiffness"]["min"] < 50
    assert "stiffness" not in plain["points_per_criterion"]
    m = machine("orthoglide")
    at = np.array([*s["at_min"], 0.0])[:3] * 1e-3
    assert s["min"] == pytest.approx(stiffness_index(m, at[None], "stiffness")[0] / 1e6,
                                     rel=1e-10)


def test_workspace_refuses_a_deflection_bound_without_a_wrench():
    result = CliRunner().invoke(cli, ["workspace", "orthoglide", "--max-deflection", "5"])
    assert result.exit_code != 0 and "--wrench" in result.output


@pytest.mark.ci
def test_path_deflection_is_the_library_figure(tmp_path):
    out = as_json(run("path", "linear-delta-table-iv1", "--gcode", POCKET, "--origin",
                      "0,0,200", "--units", "mm", "--feed", "20", "--accel", "1000", "--jerk",
                      "10000", "--rapid-feed", "100", "--period", "0.05", "--wrench",
                      "100,0,-200", "--deflection", "--out", tmp_path / "run", "--json"))
    m = machine("linear-delta-table-iv1")
    traj = plan(read_gcode(POCKET, origin=(0.0, 0.0, 0.2)), feed=0.02, accel=1.0, jerk=10.0,
                rapid_feed=0.1, period=0.05)
    ref = path_deflection(m, traj, default_masses(m), force=[100.0, 0.0, -200.0])
    d = out["deflection"]
    assert d["max"] == pytest.approx(ref.peak["value"] * 1e6, rel=1e-9)
    assert d["line"] == ref.peak["line"] and d["unit"] == "µm"
    assert len(d["blocks"]) == len(ref.blocks)
    assert "deflection.png" in out["files"] and (tmp_path / "run" / "deflection.png").exists()
    with open(tmp_path / "run" / "trajectory.csv") as f:
        assert f.readline().strip() == "# units: mm"      # the outputs record their unit
        rows = list(csv.DictReader(f))
    norms = np.array([float(r["defl"]) for r in rows])
    np.testing.assert_allclose(norms, np.linalg.norm(ref.total, axis=1) * 1e6, rtol=1e-9)


@pytest.mark.ci
def test_path_deflection_limit_exits_3():
    args = ("path", "orthoglide", "--line", "-50,0,0:50,0,0", "--units", "mm", "--feed", "50",
            "--accel", "1000", "--wrench", "0,0,-800")
    peak = as_json(run(*args, "--deflection", "--json"))["deflection"]["max"]
    limited = run(*args, "--max-deflection", f"{0.9 * peak:.6g}")
    assert limited.exit_code == 3 and "EXCEEDED" in limited.output
    assert run(*args, "--max-deflection", f"{1.1 * peak:.6g}").exit_code == 0


@pytest.mark.ci
def test_optimize_with_a_stiffness_constraint(tmp_path):
    out = as_json(run("optimize", "linear-delta", "--vary", "r=150:300", "--objective",
                      "min:stroke", "--constraint", "min_stiffness>=20", "--region", "150",
                      "--units", "mm", "--generations", "4", "--population", "8",
                      "--no-progress", "--out", tmp_path, "--json"))
    assert out["column_units"]["min_stiffness"] == "N/µm"
    best = out["best"]
    assert best["min_stiffness"] >= 20
    with open(tmp_path / "results.csv") as f:
        rows = list(csv.DictReader(f))
    values = [float(r["min_stiffness [N/µm]"]) for r in rows]
    assert min(values) < 20 < max(values)  # the constraint binds somewhere in the range
