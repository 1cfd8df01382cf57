"""``ik``, ``fk`` and ``jacobian`` on the command line flag configurations beyond the strokes for
every family: a single pose prints its values, names the joint, its leg and the excess on
standard error and exits with status 3; a batch labels the row ``out-of-stroke``, keeps its
values and exits with status 3 (pkmkit.cli.stroke_flags)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pkmkit.boundary.coordinates import pose_columns, pose_to_cli
from pkmkit.machines.registry import machine
from tests.cli.conftest import table_lines
from tests.machines.test_strokes import (
    _crank_slider_with_strokes,
    _dietmaier_with_strokes,
    _quiet_fk,
    beyond,
)

BUILT_IN = ["gough-stewart", "verne", "delta", "linear-delta", "orthoglide", "five-bar",
            "tripteor-x7", "trimule-600"]
FILES = ["crank-slider-file", "dietmaier-file"]


def _case(ident, tmp_path):
    """``(machine, CLI name, q beyond, pose beyond)``."""
    if ident == "crank-slider-file":
        m, path = _crank_slider_with_strokes(tmp_path)
        q, pose, _ = beyond(m)
        return m, path, q, pose
    if ident == "dietmaier-file":
        m, path, pose, _ = _dietmaier_with_strokes(tmp_path)
        return m, path, m.ik(pose, strokes="ignore"), pose
    m = machine(ident)
    q, pose, _ = beyond(m)
    return m, ident, q, pose


def _cli_pose(m, pose) -> np.ndarray:
    if getattr(m, "position_controlled", False):
        return np.asarray(pose)[:3]
    return pose_to_cli(pose, m, "m", "xyz")[0]


def _columns(m) -> list[str]:
    return ["x", "y", "z"] if getattr(m, "position_controlled", False) else pose_columns(m)


def _text(values) -> str:
    return ",".join(repr(float(v)) for v in values)


@pytest.mark.parametrize("ident", BUILT_IN + FILES)
def test_single_ik_and_fk_beyond_a_stroke_exit_3(run, tmp_path, ident):
    m, name, q, pose = _case(ident, tmp_path)
    result = run("ik", name, "--pose", _text(_cli_pose(m, pose)), "--json")
    assert result.exit_code == 3, result.output
    data = json.loads(result.stdout)
    assert data["status"] == "out-of-stroke"
    first = data["out_of_stroke"][0]
    assert first["joint"] in m.actuator_names + tuple(getattr(m, "passive_names", ()))
    assert first["leg"] and first["excess"] != 0
    np.testing.assert_allclose(data["q"], _q_cli(m, q), atol=1e-6)  # the values are printed
    text = run("ik", name, "--pose", _text(_cli_pose(m, pose)))
    assert text.exit_code == 3 and "out of stroke: " in text.output
    assert "its stroke [" in text.output
    fk = run("fk", name, "--q", _text(_q_cli(m, q)))
    assert fk.exit_code == 3 and "out of stroke: " in fk.output


def _q_cli(m, q):
    from pkmkit.boundary.coordinates import actuator_scales

    return np.asarray(q) / actuator_scales(m, "m")


@pytest.mark.parametrize("ident", BUILT_IN + FILES)
def test_batch_ik_and_fk_flag_the_row_beyond_a_stroke(run, tmp_path, ident):
    m, name, q, pose = _case(ident, tmp_path)
    home_pose = np.asarray(_quiet_fk(m, m.home_q).pose)
    poses = tmp_path / "poses.csv"
    poses.write_text(",".join(_columns(m)) + "\n" + "\n".join(
        _text(_cli_pose(m, p)) for p in (home_pose, pose)) + "\n")
    out = tmp_path / "q.csv"
    result = run("ik", name, "--input", poses, "--output", out)
    assert result.exit_code == 3, result.output
    lines = table_lines(out.read_text())
    assert lines[1].endswith(",ok") and lines[2].endswith(",out-of-stroke")
    assert "nan" not in lines[2]  # the values are kept
    assert "row 1: out of stroke: " in result.output
    qs = tmp_path / "qs.csv"
    qs.write_text(",".join(m.actuator_names) + "\n" + "\n".join(
        _text(_q_cli(m, v)) for v in (m.home_q, q)) + "\n")
    result = run("fk", name, "--input", qs, "--output", out)
    assert result.exit_code == 3, result.output
    lines = table_lines(out.read_text())
    assert lines[1].endswith(",ok") and lines[2].endswith(",out-of-stroke")


def test_units_and_magnitude_hint(run):
    """Every number of the message in --units; q read in metres 1000× beyond: the hint."""
    result = run("fk", "gough-stewart", "--q", "866,866,866,866,866,866")
    assert result.exit_code == 3
    assert "did you mean --units mm?" in result.output
    result = run("ik", "gough-stewart", "--pose", "0,0,1400,0,0,0", "--units", "mm")
    assert result.exit_code == 3
    assert "q1 (leg 1) = 1438.81 mm, 338.814 mm beyond its stroke [650, 1100] mm" in (
        result.output)
    assert "did you mean" not in result.output


def test_jacobian_single_flags_the_stroke(run):
    result = run("jacobian", "gough-stewart", "--pose", "0,0,1.4,0,0,0")
    assert result.exit_code == 3 and "out of stroke: q1 (leg 1)" in result.output


@pytest.mark.ci
def test_select_measure_calibrate_pipeline_stays_within_strokes(run, tmp_path):
    """docs/errors.md's select → simulate → calibrate: the linear Delta's default region
    reaches beyond its 0.7–2 m slides; the selected poses are all within, so the calibration
    runs (it refused 17 rows out of stroke)."""
    from pkmkit.machines.strokes import stroke_excess

    poses, meas = tmp_path / "poses.csv", tmp_path / "meas.csv"
    assert run("select-poses", "linear-delta", "--measure", "point", "--n", "12", "--out",
               poses).exit_code == 0
    rows = np.loadtxt(poses, delimiter=",", skiprows=2)  # the units line, the header
    assert rows.shape == (12, 3)
    assert not stroke_excess(machine("linear-delta"), rows).out_of_stroke.any()
    assert run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", poses,
               "--defects", "random", "--seed", "1", "--out", meas).exit_code == 0
    result = run("calibrate", "linear-delta", "--measure", "point", "--measurements", meas,
                 "--out", tmp_path / "cal")
    assert "out of stroke" not in result.output and result.exit_code in (0, 3), result.output


def test_simulate_measurements_refuses_given_configurations_beyond_strokes(run, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_text("q1,q2,q3\n1.2,1.2,1.2\n2.5,1.2,1.2\n")
    result = run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", poses,
                 "--out", tmp_path / "m.csv")
    assert result.exit_code == 1
    assert "configuration 2: q1 (leg 1) = 2.5 m, 0.5 m beyond its stroke [0.7, 2] m" in (
        result.output)
    assert not (tmp_path / "m.csv").exists()


def test_passive_prismatic_joints_are_printed_in_the_units_asked(run, tmp_path):
    """The TriMule's L4 and the crank-slider's x4 (passive prismatic joints) were printed in
    metres under --units mm; single and batch now give the same physical value in m and mm."""
    for ident, name in (("trimule-600", "L4"), ("crank-slider", "x4")):
        m = machine(ident)
        angle = np.array([qty == "angle" for qty in m.actuator_quantities])
        home = np.where(angle, np.degrees(m.home_q), m.home_q)  # angles in degrees
        q_m = ",".join(repr(float(v)) for v in home)
        q_mm = ",".join(repr(float(v)) for v in np.where(angle, home, 1e3 * home))
        in_m = json.loads(run("fk", ident, "--q", q_m, "--json").stdout)["passive"]
        in_mm = json.loads(run("fk", ident, "--q", q_mm, "--units", "mm",
                               "--json").stdout)["passive"]
        assert in_mm[name] == pytest.approx(1e3 * in_m[name], rel=1e-9)
        assert in_m[name] == pytest.approx(float(m.home_passive[m.passive_names.index(name)]))
        table = tmp_path / "q.csv"
        table.write_text(",".join(m.actuator_names) + "\n" + q_mm + "\n")
        result = run("fk", ident, "--input", table, "--output", "-", "--units", "mm")
        header, row = table_lines(result.stdout, "mm")[:2]
        value = float(row.split(",")[header.split(",").index(f"passive_{name}")])
        assert value == pytest.approx(in_mm[name], rel=1e-9)
