"""``pkmkit path`` and ``pkmkit arm-sizing`` end to end."""

import json

import numpy as np
import pytest


@pytest.mark.ci
def test_path_circle_summary_and_files(run, tmp_path, as_json):
    out = tmp_path / "circle"
    data = as_json(run("path", "linear-delta-table-iv1", "--circle", "0,0,200,150", "--units",
                       "mm", "--feed", "120", "--accel", "1000", "--jerk", "10000",
                       "--json", "--out", out))
    for key in ("duration", "q_min", "q_max", "qd_max", "qdd_max", "force_max", "violations"):
        assert key in data
    np.testing.assert_allclose(data["stroke"], 190.84, atol=0.02)
    np.testing.assert_allclose(data["qd_max"], 76.34, atol=0.02)
    assert data["violations"] == [] and data["duration"] > np.pi * 300 / 120
    for name in ("motion.png", "path.png", "trajectory.csv"):
        assert (out / name).stat().st_size > 1000
    units, header = (out / "trajectory.csv").read_text().splitlines()[:2]
    assert units == "# units: mm"
    assert header.startswith("t,x,y,z,q1,q2,q3,q1_dot")


@pytest.mark.ci
def test_path_gcode_with_violations(run, tmp_path):
    program = tmp_path / "facing.nc"
    program.write_text("G21 G90 G17\nG0 X-100 Y-50 Z0\nG1 X100 F3000\nG1 Y50\nG1 X-100\n")
    result = run("path", "linear-delta-table-iv1", "--gcode", program, "--origin", "0,0,0.2",
                 "--feed", "0.05", "--accel", "2", "--jerk", "20", "--speed-limit", "0.01")
    assert result.exit_code == 3  # the limit is reported, the results written
    assert "LIMIT speed" in result.output and "worst excess" in result.output


@pytest.mark.ci
def test_path_reports_every_actuator_over_a_limit_with_spans_and_lines(run, as_json, tmp_path):
    """The issue's case: with a 60 mm/s limit, q1 (−143 mm/s) and q3 (+192 mm/s) both exceed
    it during the rapid of line 3; before, only q3's first excursion was reported. The figure
    draws the limits and marks the violations."""
    program = tmp_path / "start.nc"
    program.write_text("G21 G90 G17\n(rapid first)\nG0 X-50 Y-40 Z5\nG1 Z0 F600\n")
    args = ["path", "linear-delta-table-iv1", "--gcode", program, "--origin", "0,0,200",
            "--units", "mm", "--accel", "3000", "--jerk", "30000", "--rapid-feed", "3000",
            "--speed-limit", "60"]
    text = run(*args, "--out", tmp_path / "out")
    assert text.exit_code == 3
    lines = [ln for ln in text.output.splitlines() if "LIMIT speed" in ln]
    assert len(lines) == 2 and "q1" in lines[0] and "q3" in lines[1]
    assert all("line 3 'G0 X-50 Y-40 Z5'" in ln and "1 excursion(s)" in ln for ln in lines)
    assert "worst excess 83.02" in lines[0] and "mm/s" in lines[0]
    res = run(*args, "--json")
    assert res.exit_code == 3
    data = json.loads(res.stdout)
    speed = {v["actuator"]: v for v in data["violations"] if v["limit"] == "speed"}
    assert set(speed) == {"q1", "q3"}
    assert speed["q1"]["excess"] == pytest.approx(83.02, abs=0.01)
    assert speed["q3"]["excess"] == pytest.approx(131.86, abs=0.01)
    for v in speed.values():
        assert v["line"] == 3 and v["upper"] == pytest.approx(60.0)
        (span,) = v["spans"]
        assert 0.05 < span["start"] < v["t_peak"] < span["end"] < 0.4
    assert (tmp_path / "out" / "motion.png").stat().st_size > 1000


@pytest.mark.ci
def test_joint_figure_draws_limits_and_marks_violations():
    import pkmkit
    from pkmkit.dynamics.trajectory import simulate_path
    from pkmkit.motion import Limits, circle
    from pkmkit.motion.limits import limit_bounds
    from pkmkit.plot.motion_figures import plot_joint_motion

    m = pkmkit.machine("linear-delta-table-iv1")
    limits = Limits(speed=0.05)
    r = simulate_path(m, circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0,
                      period=0.05, limits=limits)
    fig = plot_joint_motion(r.motion, m.actuator_names, forces=r.forces.force,
                            limits={k: (lo, hi) for k, _, lo, hi in limit_bounds(m, limits)},
                            violations=r.violations)
    speed_axis = fig.axes[1]
    levels = {round(float(ln.get_ydata()[0]), 9) for ln in speed_axis.lines
              if ln.get_linestyle() == "--"}
    assert levels == {-0.05, 0.05}
    shaded = [p for p in speed_axis.patches]
    assert len(shaded) == sum(len(v.excursions) for v in r.violations) > 0
    marks = [ln for ln in speed_axis.lines if ln.get_marker() == "x"]
    assert len(marks) == len(m.actuator_names)


@pytest.mark.ci
def test_path_raster_and_wrench(run, as_json):
    data = as_json(run("path", "linear-delta-table-iv1", "--raster", "-0.1,-0.05,0.2,0.2,0.1,3,"
                       "one-way", "--feed", "0.05", "--accel", "1", "--jerk", "10", "--wrench",
                       "0,0,-500", "--json"))
    # a 500 N downward force on the tool adds about a third of it to each vertical motor
    assert 300 < min(data["force_max"]) and data["total_mass"] * 9.81 / 3 < 160


def test_arm_sizing(run, as_json):
    seed = as_json(run("arm-sizing", "--seed-tables", "--json"))
    assert len(seed["rows"]) == 14
    sized = as_json(run("arm-sizing", "--force", "1000", "--length", "1.04", "--json"))
    assert sized["feasible"] and sized["buckling_safety"] == pytest.approx(3.0, rel=1e-4)
    analysed = as_json(run("arm-sizing", "--length", "1040", "--diameter", "40", "--units", "mm",
                           "--json"))
    assert analysed["mode"] == "analysis" and analysed["mass"] == pytest.approx(
        7700 * np.pi / 4 * 0.04**2 * 1.04)


def test_arm_sizing_for_a_machine_stiffness(run, as_json):
    """The Orthoglide about its isotropic point (a 1 mm cube): 50 N/µm needs EA ≈ 1.55e7 N
    (by hand at the point, test_arm_sizing.py), the sized arm at least EA/ℓ."""
    data = as_json(run("arm-sizing", "--length", "310", "--units", "mm", "--machine",
                       "orthoglide", "--machine-stiffness", "50", "--region", "1", "--json"))
    need = data["machine_stiffness"]
    assert need["axial_rigidity"] == pytest.approx(1.55e7, rel=0.02)
    assert data["feasible"] and data["axial_stiffness"] >= need["axial_rigidity"] / 0.31 * 0.999999


@pytest.mark.parametrize(
    "args, message",
    [
        (["path", "linear-delta", "--feed", "0.1", "--accel", "1", "--jerk", "1"],
         "exactly one of"),
        (["path", "linear-delta", "--circle", "0,0,0.2", "--feed", "0.1", "--accel", "1",
          "--jerk", "1"], "needs 4 numbers"),
        (["path", "linear-delta", "--circle", "0,0,0.2,0.1", "--feed", "-1", "--accel", "1",
          "--jerk", "1"], "must be a finite number > 0"),
        (["path", "linear-delta", "--circle", "0,0,0.2,0.1", "--feed", "0.1", "--accel", "1",
          "--jerk", "-2"], "--jerk must be a finite number > 0"),
        (["path", "linear-delta", "--circle", "0,0,0.2,0.1", "--accel", "1"],
         "--feed is required"),
        (["path", "linear-delta", "--line", "0,0,0:3,0,0", "--feed", "0.1", "--accel", "1",
          "--jerk", "10"], "leaves the workspace"),
        (["path", "five-bar", "--helix", "1,0,0,0.1,0.01,2", "--feed", "0.1", "--accel", "1",
          "--jerk", "10"], "spatial machine"),
        # sizes over the whole diameter range before refusing: 1.5 s, marked ci (.ci/run)
        pytest.param(["arm-sizing", "--force", "1e7", "--length", "1.0"], "buckling",
                     marks=pytest.mark.ci),
        (["arm-sizing"], "--length"),
        (["arm-sizing", "--length", "1", "--machine", "linear-delta", "--machine-stiffness",
          "40", "--region", "0.15"], "no arm meets"),
        (["arm-sizing", "--length", "1", "--machine", "linear-delta"], "go together"),
    ],
)
def test_bad_input(run, args, message):
    result = run(*args)
    assert result.exit_code in (1, 2), result.output
    assert message in result.output and "Traceback" not in result.output


def test_bad_gcode_and_masses(run, tmp_path):
    program = tmp_path / "bad.nc"
    program.write_text("G21\nG1 X1 F100\nG41 D1\n")
    result = run("path", "linear-delta", "--gcode", program, "--feed", "0.1", "--accel", "1",
                 "--jerk", "10")
    assert result.exit_code == 1 and "bad.nc:3:" in result.output
    masses = tmp_path / "m.toml"
    masses.write_text("[masses]\nplatform = -3\n")
    result = run("path", "linear-delta", "--circle", "0,0,0.2,0.1", "--feed", "0.1", "--accel",
                 "1", "--jerk", "10", "--masses", masses)
    assert result.exit_code == 1 and ">= 0" in result.output


@pytest.mark.ci
def test_shipped_examples_run(run, as_json):
    """The G-code program and the masses file of docs/examples/ work as documented."""
    from pathlib import Path

    examples = Path(__file__).parents[2] / "docs" / "examples"
    plain = as_json(run("path", "linear-delta-table-iv1", "--gcode", examples / "pocket.nc",
                        "--origin", "0,0,0.2", "--feed", "0.05", "--accel", "1", "--jerk", "10",
                        "--json"))
    assert plain["violations"] == [] and 21 < plain["duration"] < 22.5
    heavy = as_json(run("path", "linear-delta-table-iv1", "--gcode", examples / "pocket.nc",
                        "--origin", "0,0,0.2", "--feed", "0.05", "--accel", "1", "--jerk", "10",
                        "--masses", examples / "delta-masses.toml", "--json"))
    tripod = as_json(run("path", examples / "strut-tripod.toml", "--circle", "0,0,-800,100",
                         "--units", "mm", "--feed", "200", "--accel", "2000", "--jerk", "20000",
                         "--json"))
    assert tripod["violations"] == [] and max(tripod["force_range"][1]) < 0  # hanging: tension
    # Ø40 mm steel arms weigh 10.1 kg each instead of 1.31 kg at 1000 kg/m³: +52 kg in all
    assert heavy["total_mass"] - plain["total_mass"] == pytest.approx(6 * (10.06 - 1.307), abs=0.05)


def test_path_on_a_strut_machine(run, as_json, tmp_path):
    """A user's machine of three actuated struts: the platform hangs from them (tension)."""
    lines = ['[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n']
    for a in np.radians([0.0, 120.0, 240.0]):
        lines.append(f'[[legs]]\ntype = "strut"\nbase = [{np.cos(a):.6f}, {np.sin(a):.6f}, 0]\n'
                     'platform = [0, 0, 0]\nlength = 1.2\n')
    machine = tmp_path / "tripod.toml"
    machine.write_text("".join(lines))
    data = as_json(run("path", machine, "--circle", "0,0,-0.8,0.1", "--feed", "0.2", "--accel",
                       "2", "--jerk", "20", "--json"))
    assert data["violations"] == [] and max(data["force_range"][1]) < 0
    np.testing.assert_allclose(data["leg_axial_max"], data["force_max"])


@pytest.mark.ci
def test_cli_stroke_independent_of_period(run, as_json):
    args = ("path", "linear-delta-table-iv1", "--circle", "0,0,200,150", "--units", "mm",
            "--feed", "120", "--accel", "1000", "--jerk", "10000", "--json")
    fine = as_json(run(*args))
    coarse = as_json(run(*args, "--period", "10"))
    assert coarse["samples"] == 2
    np.testing.assert_allclose(coarse["stroke"], fine["stroke"], rtol=1e-4)
    np.testing.assert_allclose(coarse["qd_max"], fine["qd_max"], rtol=1e-4)
    np.testing.assert_allclose(coarse["stroke"], 190.845, atol=1e-3)
    text = run(*args[:-1], "--period", "10", "--speed-limit", "20").output
    assert "LIMIT speed" in text and "every checked limit holds" not in text


@pytest.mark.ci
def test_gcode_feeds_and_default_jerk(run, as_json, tmp_path):
    """A G-code program with F words runs with no --feed and no --jerk; the defaults used
    are printed and reported in JSON, and match giving them explicitly."""
    program = tmp_path / "p.nc"
    program.write_text("G21 G90 G94 G54\nM3 S1000\nG0 X0 Y0 Z0\nG1 X20 F600\n"
                       "G2 X30 Y10 I0 J10 F300\nM30\n")
    base = ["path", "linear-delta-table-iv1", "--gcode", program, "--origin", "0,0,200",
            "--units", "mm", "--accel", "1000"]
    result = run(*base)
    assert result.exit_code == 0, result.output
    assert "default --jerk 10000 mm/s³" in result.output
    assert "default --rapid-feed 50 mm/s" in result.output
    implicit = as_json(run(*base, "--json"))
    explicit = as_json(run(*base, "--jerk", "10000", "--feed", "10", "--json"))
    assert [d["option"] for d in implicit["defaults"]] == ["--rapid-feed", "--jerk"]
    assert explicit["defaults"] == []
    assert implicit["duration"] == explicit["duration"]
