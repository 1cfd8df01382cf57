"""``pkmkit machined-part``: the chain from G-code to identified parameters on the command line,
and a user's CMM file with an error."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import parse_json


@pytest.mark.ci
def test_gcode_to_identified_parameters(run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = run("machined-part", "program", "verne", "--out", "part.nc")
    assert out.exit_code == 0 and "12 straight passes" in out.output
    out = run("machined-part", "simulate", "verne", "--gcode", "part.nc", "--defects", "random",
              "--seed", 2, "--sections", 100, "--out", "cmm.csv")
    assert out.exit_code == 0, out.output
    assert (tmp_path / "cmm.truth.toml").exists()
    out = run("machined-part", "reconstruct", "cmm.csv", "--gcode", "part.nc", "--out",
              "centres.csv", "--json")
    assert out.exit_code == 0, out.output
    info = parse_json(out)
    assert info["units"] == "mm" and info["passes"] == 12
    out = run("calibrate", "verne", "--measure", "part", "--measurements", "centres.csv",
              "--json")
    assert out.exit_code == 0, out.output
    result = parse_json(out)
    assert result["rms_after"] < 0.01 * result["rms_before"]
    assert {"part_x", "part_y", "part_z", "part_phi"} == set(result["setup"])


def test_a_bad_cmm_file_names_its_line(run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run("machined-part", "program", "verne", "--out", "part.nc")
    (tmp_path / "cmm.csv").write_text("# units: mm\nsection,label,x,y,z,path,direction\n"
                                      "1,Q,0,0,0,6,x\n1,K,0,10,5,6,x\n")
    out = run("machined-part", "reconstruct", "cmm.csv", "--gcode", "part.nc", "--out", "c.csv")
    assert out.exit_code == 1
    assert "cmm.csv:4: column 'label': 'K' is not Q or M or N" in out.output
    assert not (tmp_path / "c.csv").exists()


@pytest.mark.ci
def test_demo_writes_the_chain(tmp_path, monkeypatch):
    from pkmkit.demos import machining as demo_machining
    from pkmkit.machining import study

    monkeypatch.setattr(demo_machining, "machined_part_study",
                        lambda: study.machined_part_study(sections=60))
    lines = []
    summary = demo_machining.run_machining_demo(tmp_path, lines.append)
    files = {p.name for p in (tmp_path / "calibration-verne-cmm").iterdir()}
    assert {"part.nc", "cmm.csv", "centres.csv", "report.html"} <= files
    assert "(seed 003, real Verne: < 20 and < 40 µm)" in lines[0]
    assert "illustrative" in lines[0] and "illustrative" in summary["machine"]
    assert summary["seed"] == pytest.approx({"along_x": 20.0, "along_y": 40.0})


@pytest.mark.ci
def test_ballbar_plan_feeds_simulate_measurements(run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    out = run("machined-part", "ballbar-plan", "verne", "--points", 40, "--out", "plan.csv")
    assert out.exit_code == 0, out.output
    assert "40 points × 3 table points × 2 tools = 240 ball-bar readings" in out.output
    out = run("simulate-measurements", "verne", "--measure", "ballbar", "--poses", "plan.csv",
              "--defects", "random", "--units", "mm", "--out", "bb.csv")
    assert out.exit_code == 0, out.output
    assert "240 ballbar measurements" in out.output
    out = run("calibrate", "verne", "--measure", "ballbar", "--measurements", "bb.csv", "--out",
              "cal", "--json")
    assert out.exit_code == 0, out.output
    out = run("machined-part", "check", "verne", "--calibrated", "cal/verne-calibrated.toml",
              "--truth", "bb.truth.toml", "--json")
    assert out.exit_code == 0, out.output
    result = parse_json(out)
    assert result["compensated"]["along_x"] < 20 and result["compensated"]["along_y"] < 40
    assert result["nominal"]["along_x"] > 100 and not result["compensation_worse"]
    # a machine without defects "compensated" by a wrong geometry: worse, exit status 3
    from pkmkit.machines.registry import preset_path

    out = run("machined-part", "check", "verne", "--calibrated", "bb.truth.toml", "--truth",
              preset_path("verne"))
    assert out.exit_code == 3
    assert "seed 003 (real Verne)      < 20      < 40" in out.output
    assert "do not use this calibration" in out.output


def test_part_file_refuses_a_plan(run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run("machined-part", "ballbar-plan", "verne", "--points", 10, "--out", "plan.csv")
    out = run("simulate-measurements", "verne", "--measure", "part", "--poses", "plan.csv",
              "--out", "p.csv")
    assert out.exit_code == 1 and "pkmkit machined-part simulate" in out.output


def test_a_leaning_wall_flags_its_section(run, tmp_path, monkeypatch):
    """A cutter that was not vertical: that section is left out, named, and the exit status is
    3; the others are written."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "part.nc").write_text("G21 G90\nG0 X-60 Y-20 Z-50\nG1 X60 F1000\nM30\n")
    rows = "".join(f"{k},Q,{x},-20,-58,3,x\n{k},M,{x},-10,-47,3,x\n{k},N,{x},-10,-43,3,x\n"
                   for k, x in enumerate((0, 10, 20), start=1))
    rows = rows.replace("2,N,10,-10,", "2,N,10,-9.9,")
    (tmp_path / "cmm.csv").write_text("# units: mm\nsection,label,x,y,z,path,direction\n" + rows)
    out = run("machined-part", "reconstruct", "cmm.csv", "--gcode", "part.nc", "--out", "c.csv")
    assert out.exit_code == 3
    assert "1 section(s) with a wall leaning by more than 5 mrad, the worst 25 mrad at " \
           "cmm.csv:6" in out.output
    assert "3 sections of 1 passes → 2 tool centres" in out.output
    assert len((tmp_path / "c.csv").read_text().splitlines()) == 3 + 2


def test_check_of_a_part_calibration_says_when_it_helps(run, tmp_path, monkeypatch):
    """``machined-part check`` in the ordinary run (its end-to-end examples, with a calibration
    in between, are ``ci``: the documentation's machined-part session and the ball-bar test
    above): the defects of a simulated part's true machine, "compensated" by that same true
    geometry, leave nothing; a machine without defects "compensated" by that geometry is made
    worse (exit status 3)."""
    from pkmkit.machines.registry import preset_path

    monkeypatch.chdir(tmp_path)
    run("machined-part", "program", "verne", "--out", "part.nc")
    out = run("machined-part", "simulate", "verne", "--gcode", "part.nc", "--defects", "random",
              "--seed", 3, "--sections", 12, "--out", "cmm.csv")
    assert out.exit_code == 0, out.output
    out = run("machined-part", "check", "verne", "--calibrated", "cmm.truth.toml", "--truth",
              "cmm.truth.toml", "--json")
    result = parse_json(out)
    assert result["compensated"]["along_x"] < 1e-6 and result["compensated"]["along_y"] < 1e-6
    assert result["nominal"]["along_x"] > 1 and not result["compensation_worse"]
    # the library's figures, in metres, printed in µm
    import pkmkit
    from pkmkit.calibration.studies import machined_errors

    truth = pkmkit.load(str(tmp_path / "cmm.truth.toml"))
    errors = machined_errors(truth, pkmkit.machine("verne"), truth)
    assert result["units"] == "µm"
    for axis in ("along_x", "along_y"):
        assert result["nominal"][axis] == pytest.approx(errors["nominal"][axis] * 1e6, rel=1e-12)
    out = run("machined-part", "check", "verne", "--calibrated", "cmm.truth.toml", "--truth",
              preset_path("verne"))
    assert out.exit_code == 3 and "do not use this calibration" in out.output


def test_ballbar_plan_bar_length_is_read_in_the_units_given(run, tmp_path, monkeypatch):
    """``--bar-length`` in mm and in m: every reading's ball is that far from its table pivot
    (the bar's definition, from the written coordinates), and the two plans are the same in SI
    (a value taken as metres in mm, or the reverse, moves every ball)."""
    monkeypatch.chdir(tmp_path)
    plans = {}
    for unit, length, scale in (("mm", 120, 1e-3), ("m", 0.12, 1.0)):
        out = run("machined-part", "ballbar-plan", "verne", "--points", 4, "--bar-length",
                  length, "--units", unit, "--out", f"{unit}.csv")
        assert out.exit_code == 0, out.output
        assert f"bar {length:g} {unit})" in out.output
        lines = (tmp_path / f"{unit}.csv").read_text().splitlines()
        assert f"# bar length: {length:g} {unit}" in lines
        rows = np.array([[float(v) for v in line.split(",")[:6]]
                         for line in lines if line[:1] not in "#x"])
        np.testing.assert_allclose(np.linalg.norm(rows[:, :3] - rows[:, 3:], axis=1), length,
                                   rtol=1e-8)
        plans[unit] = rows * scale
    np.testing.assert_allclose(plans["mm"], plans["m"], rtol=0, atol=1e-9)


def test_simulate_placement_is_read_in_the_units_given(run, tmp_path, monkeypatch):
    """``--placement`` in mm and in m, on a machine with defects (where the placement changes
    what is cut): the CMM points are the same in SI, and the default placement's (the default
    box's lower corner, 0.3°: −0.2 m each way for the Verne) when given as it."""
    from pathlib import Path

    monkeypatch.chdir(tmp_path)
    gcode = Path(__file__).resolve().parents[2] / "docs" / "examples" / "pocket.nc"
    points = {}
    for name, unit, placement, scale in (("mm", "mm", "-200,-200,-200,0.3", 1e-3),
                                         ("m", "m", "-0.2,-0.2,-0.2,0.3", 1.0),
                                         ("default", "m", None, 1.0)):
        args = ["machined-part", "simulate", "verne", "--gcode", gcode, "--sections", 6,
                "--defects", "random", "--seed", 2, "--units", unit, "--out", f"{name}.csv",
                "--json"]
        out = run(*args, *(() if placement is None else (f"--placement={placement}",)))
        assert out.exit_code == 0, out.output
        echoed = parse_json(out)["placement"]
        assert [echoed[k] for k in ("dx", "dy", "dz")] == pytest.approx([-0.2 / scale] * 3)
        lines = (tmp_path / f"{name}.csv").read_text().splitlines()
        points[name] = np.array([[float(v) for v in line.split(",")[2:5]]
                                 for line in lines if line[:1].isdigit()]) * scale
    np.testing.assert_allclose(points["mm"], points["m"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(points["m"], points["default"], rtol=0, atol=1e-12)
