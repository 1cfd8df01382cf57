"""``pkmkit simulate-measurements``, ``register``, ``calibrate`` and ``compensate`` end to end,
the report's content, and bad input (exit 1, the file line named, nothing written)."""

from __future__ import annotations

import base64
import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

import pkmkit


@pytest.fixture(scope="module")
def delta_run(tmp_path_factory):
    """Simulated Delta measurements (identification + validation) and their calibration."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d = tmp_path_factory.mktemp("delta")
    runner = CliRunner()

    def run(*args):
        res = runner.invoke(cli, [str(a) for a in args], catch_exceptions=False)
        assert res.exit_code == 0, res.output
        return res

    run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 60,
        "--defects", "random", "--seed", 3, "--units", "mm", "--out", d / "ident.csv")
    run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 25,
        "--defects", d / "ident.truth.toml", "--seed", 4, "--units", "mm",
        "--out", d / "valid.csv")
    out = run("calibrate", "linear-delta", "--measure", "point", "--measurements",
              d / "ident.csv", "--validate", d / "valid.csv", "--out", d / "cal", "--json")
    return d, json.loads(out.stdout)


@pytest.mark.ci
def test_simulate_writes_measurements_and_truth(delta_run):
    d, _ = delta_run
    text = (d / "ident.csv").read_text()
    assert "# units: mm" in text and "q1,q2,q3,x,y,z" in text
    truth = pkmkit.load(d / "ident.truth.toml")
    nominal = pkmkit.machine("linear-delta")
    q = np.atleast_2d(nominal.home_q)
    assert 1e-6 < np.abs(truth.fk(q) - nominal.fk(q)).max() < 2e-2


def test_calibrate_json_and_outputs(delta_run):
    d, payload = delta_run
    for key in ("parameters", "std", "rms_before", "rms_after", "max_before", "max_after",
                "validation", "rank", "condition", "unidentifiable"):
        assert key in payload
    assert payload["units"] == "mm"
    assert payload["rms_after"] < 0.05 < payload["rms_before"]
    assert payload["validation"]["rms_after"] < 0.06
    assert set(payload["std"]) == set(payload["parameters"])
    files = {p.name for p in (d / "cal").iterdir()}
    assert {"report.html", "calibration.json", "residuals.csv", "residuals.png",
            "histograms.png", "parameters.png", "identifiability.png",
            "linear-delta-calibrated.toml"} <= files
    # the calibrated machine file reads back and is closer to the truth than the nominal
    calibrated = pkmkit.load(d / "cal" / "linear-delta-calibrated.toml")
    truth = pkmkit.load(d / "ident.truth.toml")
    nominal = pkmkit.machine("linear-delta")
    q = nominal.ik(np.array([[0.1, -0.1, 0.2], [-0.2, 0.1, 0.3], [0.0, 0.2, 0.1]]))
    err_cal = np.abs(calibrated.fk(q) - truth.fk(q)).max()
    err_nom = np.abs(nominal.fk(q) - truth.fk(q)).max()
    assert err_cal < 0.2 * err_nom


def test_report_content(delta_run):
    d, payload = delta_run
    page = (d / "cal" / "report.html").read_text()
    assert page.startswith("<!DOCTYPE html>")
    # self-contained: every figure embedded as a PNG data URI, no external resource
    images = re.findall(r"src='data:image/png;base64,([A-Za-z0-9+/=]+)'", page)
    assert len(images) == 5  # residuals, histograms, parameters, identifiability, maps
    assert all(base64.b64decode(img)[:8] == b"\x89PNG\r\n\x1a\n" for img in images)
    # nothing fetched: no script, image or style sheet from elsewhere (the inlined Plotly
    # library of the 3-D view names web addresses in its own code, never loaded)
    assert not re.search(r"<script[^>]+src=", page)
    markup = re.sub(r"<script[^>]*>.*?</script>", "", page, flags=re.S)
    assert "http://" not in markup and "https://" not in markup
    text = html.unescape(page)
    for name in payload["parameters"]:
        assert f"<code>{name}</code>" in text
    for name in payload["unidentifiable"]:
        assert f"<code>{name}</code>" in text
    # the residual table shows before/after for both sets, as in the JSON
    assert "identification" in text and "validation" in text
    assert f"{payload['rms_after']:.4g}" in text
    assert f"{payload['validation']['rms_after']:.4g}" in text
    assert "Parameters left at their nominal value" in text
    residuals = (d / "cal" / "residuals.csv").read_text().splitlines()
    assert residuals[1] == "row,set,before,after,weight"
    assert len(residuals) == 2 + 60 + 25


@pytest.mark.ci
def test_report_embeds_the_3d_view_of_the_correction(delta_run):
    """Issue 23 §5: report.html embeds the 3-D view (``pkmkit view --calibration``): the
    machine with a slider per actuator, and the tool error of the identified machine against
    the nominal one as vectors, whose largest value is the view's own computation."""
    from pkmkit.export.view import view_figure
    from pkmkit.plot.calibration_report import REPORT_VIEW_STEPS

    d, _ = delta_run
    page = (d / "cal" / "report.html").read_text()
    assert "<h2 id='view'>3-D view</h2>" in page and "id=\"pkmkit-view\"" in page
    assert "pkmkitReport" in page and page.count("Plotly.newPlot") == 1
    calibrated = pkmkit.load(d / "cal" / "linear-delta-calibrated.toml")
    nominal = pkmkit.machine("linear-delta")
    _, content = view_figure(nominal, calibrated=calibrated, steps=REPORT_VIEW_STEPS)
    shown = re.search(r"(\d+) vectors\. Largest tool error shown: ([0-9.e+-]+) mm", page)
    assert int(shown.group(1)) == content.error_vectors > 0
    assert float(shown.group(2)) == pytest.approx(content.error_max * 1e3, rel=1e-3)
    # the error the calibration corrects is what the identified machine moves the tool by
    q = nominal.ik(np.array([[0.0, 0.0, 0.2], [0.1, 0.05, 0.25]]))
    moved = np.linalg.norm(calibrated.fk(q) - nominal.fk(q), axis=1).max()
    assert 0.2 * content.error_max < moved < 2 * content.error_max


@pytest.mark.skipif(not (shutil.which("chromium") or shutil.which("chromium-browser")),
                    reason="headless Chromium is not installed")
@pytest.mark.ci
def test_report_with_its_view_loads_in_a_browser(delta_run):
    """The report opens in headless Chromium without script errors and its view is drawn:
    the page script reports the tool point shown (the nominal machine at home, mm)."""
    d, _ = delta_run
    page = d / "cal" / "report.html"
    done = subprocess.run(
        [shutil.which("chromium") or shutil.which("chromium-browser"), "--headless",
         "--no-sandbox", "--disable-gpu", "--enable-logging=stderr",
         "--virtual-time-budget=8000", "--dump-dom", f"file://{page}"],
        capture_output=True, text=True, timeout=120)
    assert "Uncaught" not in done.stderr and "ReferenceError" not in done.stderr
    shown = np.array(json.loads(re.search(r'data-tool="([^"]*)"', done.stdout).group(1)))
    m = pkmkit.machine("linear-delta")
    np.testing.assert_allclose(shown, np.asarray(m.fk(m.home_q)) * 1000, atol=1e-6)


@pytest.mark.ci
def test_report_without_the_view(tmp_path, delta_run):
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d, _ = delta_run
    done = CliRunner().invoke(cli, ["calibrate", "linear-delta", "--measure", "point",
                                    "--measurements", str(d / "ident.csv"), "--no-view",
                                    "--out", str(tmp_path / "cal")])
    assert done.exit_code == 0, done.output
    page = (tmp_path / "cal" / "report.html").read_text()
    assert "pkmkit-view" not in page and "Plotly" not in page
    assert len(page) < 0.5 * len((d / "cal" / "report.html").read_text())


def test_calibrate_text_output(run, delta_run):
    d, _ = delta_run
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements",
              d / "ident.csv", "--robust")
    assert res.exit_code == 0, res.output
    assert "residual before" in res.output and "identified (value ± std)" in res.output
    assert "verdict: PASSED" in res.output
    # six of the defects cannot explain millimetre errors: a red verdict, exit status 3
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements",
              d / "ident.csv", "--robust", "--parameters", "dL1,dL2,dL3,dq1,dq2,dq3")
    assert res.exit_code == 3, res.output
    assert "dL1" in res.output and "verdict: FAILED (noise)" in res.output
    assert "likely cause (noise-or-model)" in res.output


@pytest.mark.ci
def test_register_reproduces_table_5_4_and_feeds_calibrate(run, as_json, tmp_path):
    lts = tmp_path / "lts.csv"
    bcs = tmp_path / "bcs.csv"
    lts.write_text("# units: mm\nx,y,z,i,j,k\n-331.205,2567.607,389.687,-5.357,42.349,41.987\n"
                   "-809.819,2774.647,423.530,59.375,7.779,-0.283\n"
                   "-330.062,2558.758,383.845,-5.382,42.412,41.934\n"
                   "-808.695,2765.857,417.398,59.378,7.778,-0.286\n")
    bcs.write_text("# units: mm\nx,y,z,i,j,k\n794.963,415.758,-59.545,-0.001,0.709,0.705\n"
                   "1242.534,450.304,207.671,-0.999,0,0\n794.958,409.808,-68.367,-0.001,0.708,"
                   "0.706\n1242.53,444.061,198.884,-0.999,0,0\n")
    out = as_json(run("register", "--measured", lts, "--nominal", bcs, "--json"))
    assert out["directions"] == 4 and out["units"] == "mm"
    assert max(out["direction_residuals_deg"]) < 0.07
    # points only: 0.085 mm, pkmkit's fit of Table 5.4 (the thesis prints no residual)
    lts.write_text("\n".join(line.rsplit(",", 3)[0] if "," in line else line
                             for line in lts.read_text().splitlines()) + "\n")
    bcs.write_text("\n".join(line.rsplit(",", 3)[0] if "," in line else line
                             for line in bcs.read_text().splitlines()) + "\n")
    frame = tmp_path / "frame.json"
    res = run("register", "--measured", lts, "--nominal", bcs, "--out", frame)
    assert res.exit_code == 0, res.output
    assert "rms 0.085 mm" in res.output
    # a tracker frame: simulate in it, calibrate through it
    meas = tmp_path / "m.csv"
    assert run("simulate-measurements", "verne", "--measure", "point", "--poses", 40,
               "--defects", "random", "--frame", frame, "--out", meas).exit_code == 0
    good = as_json(run("calibrate", "verne", "--measure", "point", "--measurements", meas,
                       "--frame", frame, "--json"))
    res = run("calibrate", "verne", "--measure", "point", "--measurements", meas,
              "--parameters", "dL1,dL2", "--json")
    assert res.exit_code == 3  # readings in the tracker frame, no --frame: a failed verdict
    bad = json.loads(res.stdout)
    assert good["rms_after"] < 1e-4 < bad["rms_after"]
    assert good["verdict"]["passed"] and not bad["verdict"]["passed"]
    assert [c["cause"] for c in bad["verdict"]["causes"]] == ["frame"]
    res = run("calibrate", "verne", "--measure", "point", "--measurements", meas,
              "--frame", "identify", "--json", "--parameters", "dL1,dL2,dL3,dL4,dL5,dL6")
    assert res.exit_code == 3  # six rod lengths cannot explain the machine's defects
    joint = json.loads(res.stdout)
    assert set(joint["setup"]) == {"frame_rx", "frame_ry", "frame_rz", "frame_x", "frame_y",
                                   "frame_z"}


def test_compensate_grid_gcode_and_truth(run, as_json, delta_run, tmp_path):
    d, _ = delta_run
    cal = d / "cal" / "linear-delta-calibrated.toml"
    out = as_json(run("compensate", "linear-delta", "--calibrated", cal, "--grid",
                      "-200,-200,0:200,200,300:3,3,2", "--units", "mm",
                      "--truth", d / "ident.truth.toml", "--out", tmp_path / "grid.csv",
                      "--json"))
    assert out["targets"] == 18
    assert out["check"]["rms_after"] < 0.2 * out["check"]["rms_before"]
    rows = (tmp_path / "grid.csv").read_text().splitlines()
    assert rows[2] == "x,y,z,cx,cy,cz,dx,dy,dz,status"
    assert all(r.endswith(",ok") for r in rows[3:])
    program = tmp_path / "part.nc"
    program.write_text("G21 G90\nG0 X0 Y0 Z100\nG1 X50 Y0 Z100 F300\nG2 X50 Y50 I0 J25\n")
    res = run("compensate", "linear-delta", "--calibrated", cal, "--gcode", program,
              "--step", 5, "--units", "mm", "--out", tmp_path / "fixed.nc")
    assert res.exit_code == 0, res.output
    from pkmkit.motion.gcode import read_gcode

    fixed = read_gcode(tmp_path / "fixed.nc")
    assert len(fixed.segments) >= 3  # the three blocks, halved only where needed
    res = run("compensate", "tripteor-x7", "--calibrated", cal, "--grid", "0,0,0:1,1,1:1,1,1",
              "--out", tmp_path / "x.csv")
    assert res.exit_code == 1 and "not a calibration of" in res.output


def test_bad_input_exits_1_naming_the_line_and_writes_nothing(run, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("# units: mm\nq1,q2,q3,x,y\n1000,1000,1000,0,0\n")
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements", bad,
              "--out", tmp_path / "out")
    assert res.exit_code == 1
    assert f"{bad}:2: missing column(s) z" in res.output
    assert not (tmp_path / "out").exists()
    bad.write_text("# units: mm\nq1,q2,q3,x,y,z\n1000,1000,1000,0,0,0\n")
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements", bad,
              "--units", "m")
    assert res.exit_code == 1 and "units mismatch" in res.output
    bad.write_text("q1,q2,q3,x,y,z\n" + "".join(f"{5 + k},1,1,0,0,{k}\n" for k in range(8)))
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements", bad)
    assert res.exit_code == 1 and "outside the stroke" in res.output and "bad.csv:2" in res.output
    res = run("simulate-measurements", "verne", "--measure", "ballbar", "--poses", bad,
              "--out", tmp_path / "b.csv")
    # a ball-bar --poses FILE is a plan (pkmkit machined-part ballbar-plan), not actuators
    assert res.exit_code == 1 and f"{bad}:1: missing column(s) px, py, pz" in res.output
    assert "(a ball-bar plan)" in res.output
    assert not (tmp_path / "b.csv").exists()
    res = run("compensate", "linear-delta", "--calibrated", tmp_path / "none.toml", "--out",
              tmp_path / "c.csv")
    assert res.exit_code == 2


def test_defects_table_file(run, as_json, tmp_path):
    table = tmp_path / "d.toml"
    table.write_text('units = "mm"\n[defects]\ndL1 = 0.2\ndq2 = -0.1\n')
    out = as_json(run("simulate-measurements", "linear-delta", "--measure", "point", "--poses",
                      20, "--defects", table, "--noise", "none", "--out", tmp_path / "m.csv",
                      "--json"))
    assert out["truth"] is None and out["defects"] == str(table)
    res = as_json(run("calibrate", "linear-delta", "--measure", "point", "--measurements",
                      tmp_path / "m.csv", "--parameters", "dL1,dq2", "--units", "m", "--json"))
    assert res["parameters"]["dL1"] == pytest.approx(2e-4, rel=1e-6)
    assert res["parameters"]["dq2"] == pytest.approx(-1e-4, rel=1e-6)
    table.write_text("[defects]\ndZ1 = 1\n")
    res = run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 5,
              "--defects", table, "--out", tmp_path / "n.csv")
    assert res.exit_code == 1 and "d.toml:2: unknown defect 'dZ1'" in res.output


def test_tolerances_and_correlations(run, as_json, delta_run):
    d, _ = delta_run
    out = as_json(run("calibrate", "linear-delta", "--measure", "point", "--measurements",
                      d / "ident.csv", "--prior", "--tolerance", "dL1=0.001", "--json"))
    names = out["correlation"]["names"]
    corr = np.array(out["correlation"]["matrix"])
    assert corr.shape == (len(names), len(names))
    np.testing.assert_allclose(np.diag(corr), 1.0)
    assert abs(out["parameters"]["dL1"]) < 0.005  # mm: held near zero by its tight prior
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements",
              d / "ident.csv", "--tolerance", "dQ9=1")
    assert res.exit_code == 1 and "unknown defect 'dQ9'" in res.output


@pytest.fixture(scope="module")
def delta_truth(tmp_path_factory):
    """A linear Delta with random defects (the simulated 'calibrated' machine file)."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d = tmp_path_factory.mktemp("truth")
    res = CliRunner().invoke(cli, ["simulate-measurements", "linear-delta", "--measure", "point",
                                   "--poses", "10", "--defects", "random", "--out",
                                   str(d / "m.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return d / "m.truth.toml"


POCKET = "docs/examples/pocket.nc"


def _pocket(tmp_path):
    from pathlib import Path

    source = Path(__file__).resolve().parents[2] / POCKET
    target = tmp_path / "pocket.nc"
    target.write_text(source.read_text())
    return target


def test_corrected_program_has_the_original_moves(run, as_json, delta_truth, tmp_path):
    """The issue's case: the old program began with ~65 rapids from the work origin at cutting
    height and cut every rapid into 1 mm pieces. Now: the original's moves, in order, with
    their types; the first one is the original's first target, corrected."""
    from pkmkit.calibration.controller import corrected_targets
    from pkmkit.motion.gcode import read_gcode

    program = _pocket(tmp_path)
    out = as_json(run("compensate", "linear-delta", "--calibrated", delta_truth, "--gcode",
                      program, "--units", "mm", "--tolerance", "0.05", "--out",
                      tmp_path / "fixed.nc", "--json"))
    original = read_gcode(program)
    fixed = read_gcode(tmp_path / "fixed.nc")
    assert out["program"] == {**out["program"], "blocks": 11, "moves": 11,
                              "subdivided_blocks": 0}
    assert len(fixed.segments) == len(original.segments)
    assert [type(s).__name__ for s in fixed.segments] == \
        [type(s).__name__ for s in original.segments]
    assert [s.rapid for s in fixed.segments] == [s.rapid for s in original.segments]
    nominal, true = pkmkit.machine("linear-delta"), pkmkit.load(delta_truth)
    first = corrected_targets(nominal, true, original.segments[0].end)[0]
    np.testing.assert_allclose(fixed.segments[0].end, first, atol=1e-7)  # 4 decimals in mm
    text = (tmp_path / "fixed.nc").read_text().splitlines()
    assert sum(line.startswith("G0") for line in text) == 2


def test_compensate_refuses_blocks_beyond_the_bound_and_writes_nothing(run, delta_truth,
                                                                       tmp_path):
    program = _pocket(tmp_path)
    res = run("compensate", "linear-delta", "--calibrated", delta_truth, "--gcode", program,
              "--units", "mm", "--max-correction", "0.001", "--out", tmp_path / "fixed.nc")
    assert res.exit_code == 3
    assert "pocket.nc:3: G0 X-50 Y-40 Z5: correction" in res.output
    assert "no program written" in res.output and res.output.startswith("Refused: ")
    assert not (tmp_path / "fixed.nc").exists()


@pytest.mark.parametrize("option", ["--step", "--tolerance", "--max-correction"])
@pytest.mark.parametrize("value", ["0", "-1", "nan"])
def test_compensate_refuses_a_zero_step(run, delta_truth, tmp_path, option, value):
    """--step 0 fell back to the 1 mm default."""
    res = run("compensate", "linear-delta", "--calibrated", delta_truth, "--gcode",
              _pocket(tmp_path), "--units", "mm", option, value, "--out", tmp_path / "f.nc")
    assert res.exit_code == 1 and f"{option} must be a finite number > 0" in res.output
    assert not (tmp_path / "f.nc").exists()


@pytest.mark.parametrize("value", ["nan", "-1", "inf"])
def test_compensate_refuses_a_tool_length_that_is_not_a_length(run, delta_truth, tmp_path,
                                                                value):
    """--tool-length nan was blamed on the calibrated file ('places the tool inf m from the
    nominal machine's tool point', issue 18 §7 fuzz)."""
    res = run("compensate", "linear-delta", "--calibrated", delta_truth, "--grid",
              "0,0,0.1:0.01,0.01,0.1:2,2,1", "--tool-length", value, "--out", tmp_path / "t.csv")
    assert res.exit_code == 1 and "--tool-length must be a finite number ≥ 0" in res.output
    assert "not a calibration" not in res.output and not (tmp_path / "t.csv").exists()


def test_compensate_refuses_a_machine_of_other_dimensions(run, tmp_path):
    """A nominal Table IV.1 Delta (L = 1.04 m) passed as the calibration of the Ch. III one
    (L = 1.3 m) was accepted and its huge 'corrections' written."""
    other = tmp_path / "other.toml"
    other.write_text('[machine]\nkind = "linear-delta"\nname = "other"\nunits = "m"\n'
                     "[parameters]\nR = 0.7\nr = 0.15\nL = 1.04\n")
    assert pkmkit.load(other).n_actuators == 3
    res = run("compensate", "linear-delta", "--calibrated", other, "--grid",
              "0,0,0:0.01,0.01,0:2,2,1", "--out", tmp_path / "t.csv")
    assert res.exit_code == 1 and "is not a calibration of 'linear-delta'" in res.output
    assert not (tmp_path / "t.csv").exists()


def test_compensate_targets_honour_units_and_flag_rows(run, as_json, delta_truth, tmp_path):
    """The file's '# units: mm' sets the output unit; a target out of stroke and one out of
    reach are flagged on their own rows (exit 3), the others kept."""
    targets = tmp_path / "t.csv"
    targets.write_text("# units: mm\nx,y,z\n0,0,0\n10,0,0\n0,0,-900\n5000,0,0\n")
    res = run("compensate", "linear-delta", "--calibrated", delta_truth, "--targets", targets,
              "--truth", delta_truth, "--out", tmp_path / "o.csv")
    assert res.exit_code == 3
    rows = (tmp_path / "o.csv").read_text().splitlines()
    assert "# units: mm" in rows
    body = rows[rows.index("x,y,z,cx,cy,cz,dx,dy,dz,status") + 1:]
    assert body[0].startswith("0,0,0,") and body[0].endswith(",ok")
    assert abs(float(body[1].split(",")[3]) - 10) < 5  # mm, not 0.01
    assert body[2].startswith("0,0,-900,,,") and "out-of-stroke q" in body[2]
    assert body[3].endswith("out-of-reach")
    assert "t.csv:5: out-of-stroke" in res.output and "t.csv:6: out-of-reach" in res.output
    assert "with the workpiece set-up (a rigid motion) removed" in res.output
    assert " mm" in res.output.splitlines()[0]


@pytest.mark.ci
def test_an_identified_frame_is_written_as_a_reusable_registration(run, as_json, tmp_path):
    """--frame identify: the frame found with the machine is written beside the report in
    register's format, and reads back (before: only inside calibration.json)."""
    from pkmkit.calibration.registration import load_registration

    res = run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 20,
              "--defects", "random", "--out", tmp_path / "m.csv")
    assert res.exit_code == 0, res.output
    out = as_json(run("calibrate", "linear-delta", "--measure", "point", "--measurements",
                      tmp_path / "m.csv", "--frame", "identify", "--out", tmp_path / "cal",
                      "--json"))
    assert out["files"]["frame.json"] == str(tmp_path / "cal" / "frame.json")
    frame = load_registration(tmp_path / "cal" / "frame.json")
    np.testing.assert_allclose(frame.rotation, out["frame"]["rotation"], atol=1e-15)
    np.testing.assert_allclose(frame.translation, out["frame"]["translation"], atol=1e-15)
    again = run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 5,
                "--frame", tmp_path / "cal" / "frame.json", "--out", tmp_path / "n.csv")
    assert again.exit_code == 0, again.output


@pytest.mark.parametrize(("value", "std", "text"), [
    (0.0258488, 0.025, "+0.026 ± 0.025"),
    (-2.81269e-05, 0.0012, "-0.0000 ± 0.0012"),
    (-0.00190212, 0.00042, "-0.00190 ± 0.00042"),
    (1000.6254, 0.0021, "+1000.6254 ± 0.0021"),
    (7.77, 0.996, "+7.8 ± 1.0"),          # std rounds up to a new decade: one decimal, not two
    (7.77, 0.994, "+7.77 ± 0.99"),
    (123456.7, 250.0, "+123460 ± 250"),
    (1.234e-12, 3.1e-14, "+1.234e-12 ± 3.1e-14"),
    (0.32050026, 0.015, "+0.321 ± 0.015"),
    (5.0, float("inf"), "+5 ± inf"),        # undetermined: the value's own digits
    (5.0, 0.0, "+5 ± 0"),
])
def test_identified_values_printed_to_their_uncertainty(value, std, text):
    from pkmkit.cli.calibration_cmds import with_std
    assert with_std(value, std) == text
