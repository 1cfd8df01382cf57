"""Absurd magnitudes and sizes are refused up front with a typed error naming the limit
(issue 18 §5), where they gave inf/nan with exit status 0, a NaN residual, or ran for hours."""

import pytest

from pkmkit.cli.limits import MAX_FORCE, MAX_NOISE, MAX_TOOL_LENGTH
from pkmkit.machines.registry import preset_path


def test_a_wrench_of_1e300_is_refused(run):
    result = run("stiffness", "orthoglide", "--pose", "0,0,0", "--wrench", "1e300,0,0")
    assert result.exit_code == 1
    assert f"--wrench: component 1 = 1e+300 is beyond {MAX_FORCE:g} N" in result.output
    assert run("stiffness", "orthoglide", "--pose", "0,0,0", "--wrench",
               "1e4,0,0").exit_code == 0
    result = run("path", "orthoglide", "--line", "0,0,0,0.01,0,0", "--feed", "0.1", "--accel",
                 "1", "--wrench", "0,0,-1e300")
    assert result.exit_code == 1 and "component 3 = -1e+300" in result.output


@pytest.mark.parametrize("value, units, hint", [("1e300", "m", False), ("169.9", "m", True),
                                                ("inf", "m", False), ("1e6", "mm", False)])
def test_tool_lengths_beyond_100_m_are_refused(run, value, units, hint):
    result = run("ik", "tripteor-x7", "--pose", "0,0,0.3,0,0,1", "--tool-length", value,
                 "--units", units)
    assert result.exit_code == 2
    assert "--tool-length" in result.output
    if value != "inf":
        assert f"is beyond {MAX_TOOL_LENGTH * (1e3 if units == 'mm' else 1):g} {units}" in (
            result.output)
    assert ("did you mean --units mm?" in result.output) == hint


def test_a_tool_length_in_mm_is_read_with_units_mm(run, as_json):
    import numpy as np

    import pkmkit

    m = pkmkit.machine("tripteor-x7")
    home = np.where(m.angular_actuators, np.degrees(m.home_q), 1e3 * np.asarray(m.home_q))
    q = ",".join(repr(float(v)) for v in home)
    res = as_json(run("fk", "tripteor-x7", "--q", q, "--units", "mm", "--tool-length",
                      "169.889", "--json"))
    np.testing.assert_allclose(res["pose"], 1e3 * np.asarray(m.home_pose[:3]), atol=1e-6)


def test_simulated_measurements_refuse_absurd_noise_tool_lengths_and_sizes(run, tmp_path):
    out = tmp_path / "s.csv"
    args = ["simulate-measurements", "tripteor-x7", "--measure", "point", "--out", out]
    result = run(*args, "--poses", "100000000")
    assert result.exit_code == 1 and "1e+08 simulated measurements" in result.output
    assert "above the limit of 1e+06" in result.output
    result = run(*args, "--poses", "5", "--noise", "1e300")
    assert result.exit_code == 1 and f"is beyond {MAX_NOISE:g} m" in result.output
    result = run(*args, "--poses", "5", "--noise", "15")
    assert "did you mean --units mm?" in result.output
    result = run(*args, "--poses", "5", "--tool-lengths", "0.1,1e300")
    assert result.exit_code == 1 and "--tool-lengths: 1e+300 m is beyond 100 m" in result.output
    assert not any(tmp_path.iterdir())
    result = run(*args, "--poses", "5", "--noise", "0.015")  # a large but possible noise
    assert result.exit_code == 0


def test_monte_carlo_and_compensation_sizes_are_refused_before_work(run, tmp_path):
    tol = tmp_path / "tol.toml"
    tol.write_text('units = "mm"\n[classes]\nlength = 0.01\n')
    result = run("errors", "gough-stewart", "--tolerance", tol, "--monte-carlo", "10000000")
    assert result.exit_code == 1
    assert "2.25e+09 sampled machines (10000000 --monte-carlo samples at each of 15² map " \
           "points), above the limit of 5e+07" in result.output
    program = tmp_path / "part.nc"
    program.write_text("G21 G90\nG0 X0 Y0 Z100\nG1 X50 Y0 Z100 F300\n")
    out = tmp_path / "fixed.nc"
    result = run("compensate", "linear-delta", "--calibrated", preset_path("linear-delta"),
                 "--gcode", program, "--step", "1e-5", "--units", "mm", "--out", out)
    assert result.exit_code == 1 and not out.exists()
    assert "pieces of 1e-05 mm (--step) over the program's 150 mm" in result.output
    # below 1 nm the step is refused as a unit slip before counting (the sweep's range)
    result = run("compensate", "linear-delta", "--calibrated", preset_path("linear-delta"),
                 "--gcode", program, "--step", "1e-9", "--units", "mm", "--out", out)
    assert result.exit_code == 1
    assert "--step 1e-09 mm is outside the plausible range" in result.output


@pytest.mark.parametrize("text, message", [
    ("[classes]\nlength = 1e300\n", "tol.toml:2: classes.length: a half-width of 1e+300 m is "
                                    "beyond 0.1 m, the largest tolerance of a length-like"),
    ("[classes]\nlength = 10\n", 'did you mean units = "mm"?'),
])
def test_absurd_tolerances_are_refused(run, tmp_path, text, message):
    """A tolerance of 1e300 m gave a NaN accuracy map with exit status 0."""
    tol = tmp_path / "tol.toml"
    tol.write_text(text)
    result = run("errors", "gough-stewart", "--tolerance", tol, "--monte-carlo", "5",
                 "--resolution", "3")
    assert result.exit_code == 1 and message in result.output


def test_a_machine_file_in_mm_without_units_is_refused(run, tmp_path):
    """Every length of docs/examples/my-machine.toml in mm, strokes included, without
    `units = "mm"`: a consistent machine 1000× too large, which loaded and answered."""
    from pathlib import Path

    source = Path(__file__).parents[2] / "docs" / "examples" / "my-machine.toml"
    text = source.read_text()
    assert 'units = "mm"' in text
    path = tmp_path / "no-units.toml"
    path.write_text(text.replace('units = "mm"\n', ""))
    result = run("ik", path, "--pose", "0,0,0")
    assert result.exit_code == 1
    assert "no-units.toml: at its home the machine reaches 882.7 m from its origin" in (
        result.output)
    assert 'without `units = "mm"`' in result.output
    assert run("ik", source, "--pose", "0,0,0").exit_code == 0


@pytest.mark.ci
def test_an_absurd_feed_the_path_never_reaches_is_refused(run):
    """--feed 120 meant in mm/s, read as 120 m/s: the run went at a few cm/s, exit 0."""
    result = run("path", "orthoglide", "--line", "0,0,0,0.1,0,0", "--feed", "120", "--accel",
                 "1")
    assert result.exit_code == 1
    assert "--feed 120 m/s is never reached: the tool peaks at" in result.output
    assert "did you mean --units mm?" in result.output
    ok = run("path", "orthoglide", "--line", "0,0,0,50,0,0", "--feed", "120", "--accel", "1000",
             "--units", "mm")
    assert ok.exit_code == 0, ok.output
