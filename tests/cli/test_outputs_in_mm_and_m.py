"""Command outputs in mm and in m: the same physical values (issue 18 §9, plausible bugs).

A unit factor dropped or inverted at the command line's boundary passed the tests of these
commands, which run in one unit only: the corrected program's tolerance, step, bound and
deviation in ``compensate --json``, the step named in the refusal of a program cut into too
many pieces, and the tool lengths of ``machined-part ballbar-plan``. Each test compares a
command's output in mm with its output in m (×1000) and with a value known beforehand (the
option as given, the program's length read by the G-code reader, the documented default).
"""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


@pytest.fixture(scope="module")
def truth(tmp_path_factory):
    """A linear Delta with random defects (the 'calibrated' machine file)."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    d = tmp_path_factory.mktemp("truth")
    res = CliRunner().invoke(cli, ["simulate-measurements", "linear-delta", "--measure", "point",
                                   "--poses", "10", "--defects", "random", "--out",
                                   str(d / "m.csv")], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    return d / "m.truth.toml"


def _compensate(run, as_json, truth, tmp_path, units, tolerance, step):
    return as_json(run("compensate", "linear-delta", "--calibrated", truth, "--gcode",
                       EXAMPLES / "pocket.nc", "--units", units, "--tolerance", tolerance,
                       "--step", step, "--out", tmp_path / f"fixed-{units}.nc", "--json"))


def test_corrected_program_summary_is_the_same_in_mm_and_m(run, as_json, truth, tmp_path):
    mm = _compensate(run, as_json, truth, tmp_path, "mm", "0.05", "2")["program"]
    m = _compensate(run, as_json, truth, tmp_path, "m", "5e-5", "0.002")["program"]
    # the options as given, in the command's unit
    assert mm["tolerance"] == pytest.approx(0.05, rel=1e-12)
    assert m["tolerance"] == pytest.approx(5e-5, rel=1e-12)
    assert mm["step"] == pytest.approx(2.0, rel=1e-12)
    assert m["step"] == pytest.approx(0.002, rel=1e-12)
    # what the command works out: the same physical value
    for key in ("max_correction", "deviation_max"):
        assert m[key] > 0
        assert mm[key] == pytest.approx(1000 * m[key], rel=1e-9), key
    assert (mm["blocks"], mm["moves"]) == (m["blocks"], m["moves"])


@pytest.mark.parametrize("units, step, scale", [("mm", "0.0001", 1e3), ("m", "1e-7", 1.0)])
def test_step_refusal_states_the_step_and_the_program_length_in_the_command_unit(
        run, truth, tmp_path, units, step, scale):
    """10⁻⁴ mm pieces over the 0.36 m pocket: 3.6 million, over the limit of 2 million."""
    from pkmkit.motion.gcode import read_gcode

    length = read_gcode(EXAMPLES / "pocket.nc").length * scale
    res = run("compensate", "linear-delta", "--calibrated", truth, "--gcode",
              EXAMPLES / "pocket.nc", "--units", units, "--step", step, "--out",
              tmp_path / "f.nc")
    assert res.exit_code == 1, res.output
    last = res.output.strip().splitlines()[-1]
    assert f"pieces of {float(step):g} {units} (--step) over the program's {length:.6g} " \
           f"{units}" in last, last
    assert not (tmp_path / "f.nc").exists()


def _plan(path: Path) -> tuple[list[str], list[list[str]]]:
    lines = path.read_text().splitlines()
    body = [line for line in lines if not line.startswith("#")]
    rows = list(csv.reader(body))
    return rows[0], rows[1:]


def test_ballbar_plan_tool_lengths_in_mm_and_m_short_plan(run, tmp_path, monkeypatch):
    """The ordinary run's version of the test below (4 points per circle, 0.1 s): tools of 0
    and 50 mm given in mm or as 0 and 0.05 m give the same plan, whose second tool's rows
    carry 50 mm."""
    monkeypatch.chdir(tmp_path)
    for args, name in ((["--tool-lengths", "0,50"], "mm.csv"),
                       (["--tool-lengths", "0,0.05", "--units", "m"], "m.csv")):
        res = run("machined-part", "ballbar-plan", "verne", "--points", 4, "--out", name, *args)
        assert res.exit_code == 0, res.output
    header, mm = _plan(Path("mm.csv"))
    _, m = _plan(Path("m.csv"))
    tool = header.index("tool_length")
    assert {row[tool] for row in mm} == {"0", "50"} and {row[tool] for row in m} == {"0", "0.05"}
    assert len(m) == len(mm) == 24
    for a, b in zip(mm, m, strict=True):
        for k in range(header.index("id")):
            if header[k] != "tool":
                assert float(a[k]) == pytest.approx(1000 * float(b[k]), rel=1e-8, abs=1e-9)


@pytest.mark.ci
def test_ballbar_plan_tool_lengths_in_mm_and_m(run, tmp_path, monkeypatch):
    """The documented default tools are 0 and 100 mm: given explicitly in mm or in m, the same
    plan; other tools change only the second tool's rows."""
    monkeypatch.chdir(tmp_path)
    for args, name in (([], "default.csv"), (["--tool-lengths", "0,100"], "mm.csv"),
                       (["--tool-lengths", "0,0.1", "--units", "m"], "m.csv")):
        res = run("machined-part", "ballbar-plan", "verne", "--out", name, *args)
        assert res.exit_code == 0, res.output
    assert Path("mm.csv").read_text() == Path("default.csv").read_text()
    header, mm = _plan(Path("mm.csv"))
    _, m = _plan(Path("m.csv"))
    tool = header.index("tool_length")
    assert {row[tool] for row in mm} == {"0", "100"}
    assert len(m) == len(mm)
    for a, b in zip(mm, m, strict=True):
        for k in range(header.index("id")):
            if header[k] != "tool":
                assert float(a[k]) == pytest.approx(1000 * float(b[k]), rel=1e-8, abs=1e-9)


def _cmm(path: Path) -> tuple[list[str], list[list[str]]]:
    return _plan(path)


@pytest.mark.ci
def test_machined_part_origin_in_mm_and_m(run, tmp_path, monkeypatch):
    """``--origin`` is in the command's unit: 10 mm or 0.01 m cut and probe the same part (the
    same machine: random defects of seed 0), and the part moves by 10 mm along x against the
    program run without an offset (to 0.5 mm: the machine's defects differ 10 mm away, by
    up to 0.1 mm on this part)."""
    monkeypatch.chdir(tmp_path)
    gcode = EXAMPLES / "pocket.nc"
    for args, name in ((["--origin", "10,0,0"], "mm.csv"),
                       (["--origin", "0.01,0,0", "--units", "m"], "m.csv"),
                       ([], "none.csv")):
        res = run("machined-part", "simulate", "verne", "--gcode", gcode, "--defects",
                  "random", "--out", name, *args)
        assert res.exit_code == 0, res.output
    header, mm = _cmm(Path("mm.csv"))
    _, m = _cmm(Path("m.csv"))
    _, none = _cmm(Path("none.csv"))
    xyz = [header.index(c) for c in ("x", "y", "z")]
    assert len(mm) == len(m) == len(none) > 100
    for a, b, c in zip(mm, m, none, strict=True):
        assert [float(a[k]) for k in xyz] == pytest.approx(
            [1000 * float(b[k]) for k in xyz], abs=1e-6)
        assert [float(a[k]) for k in xyz] == pytest.approx(
            [float(c[xyz[0]]) + 10, float(c[xyz[1]]), float(c[xyz[2]])], abs=0.5)
