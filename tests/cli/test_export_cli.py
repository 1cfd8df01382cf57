"""``pkmkit export``: built-ins, machine files and calibrated machine files to each format; what a
format cannot express is refused and nothing is written; a written file that would not reproduce
pkmkit's model is caught by the command's own check."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.io.machine_defects import write_machine_with_defects
from pkmkit.machines.registry import preset_path
from pkmkit.model.defects_table import defect_index


def test_linuxcnc_module_of_a_builtin(run, tmp_path):
    out = tmp_path / "orthokins.c"
    res = run("export", "orthoglide", "--to", "linuxcnc", "--out", out)
    assert res.exit_code == 0, res.output
    assert "module orthokins (3 joints, mm)" in res.output
    assert "check: its rods close" in res.output
    text = out.read_text()
    assert 'hal_init("orthokins")' in text and "halcompile --install orthokins.c" in text


def test_a_calibrated_machine_file_carries_its_defects(run, tmp_path):
    nominal = pkmkit.machine("gough-stewart")
    index = defect_index(nominal)
    delta = np.zeros(len(index.names))
    delta[index.names.index("dA1x")] = 2e-4  # 0.2 mm
    calibrated = tmp_path / "hexapod-calibrated.toml"
    write_machine_with_defects(calibrated, preset_path("gough-stewart"), nominal, delta)
    res = run("export", calibrated, "--to", "linuxcnc", "--out", tmp_path / "hexkins.c")
    assert res.exit_code == 0, res.output
    cal = (tmp_path / "hexkins.c").read_text()
    run("export", "gough-stewart", "--to", "linuxcnc", "--out", tmp_path / "nomkins.c")
    nom = (tmp_path / "nomkins.c").read_text()
    def first_base_x(text):  # mm
        return float(re.search(r"rod_base\[N_RODS\]\[3\] = \{\s*\{([^,]+),", text).group(1))

    assert first_base_x(nom) == pytest.approx(nominal.model.rod_base[0, 0] * 1e3, abs=1e-9)
    assert first_base_x(cal) - first_base_x(nom) == pytest.approx(0.2, abs=1e-9)


def test_klipper_and_mjcf(run, tmp_path):
    res = run("export", "linear-delta-table-iv1", "--to", "klipper", "--out", tmp_path / "d.cfg",
              "--endstops", "1650,1650,1650")
    assert res.exit_code == 0, res.output
    assert "position_endstop" in (tmp_path / "d.cfg").read_text()
    pytest.importorskip("mujoco")
    res = run("export", "gough-stewart", "--to", "mjcf", "--out", tmp_path / "h.xml")
    assert res.exit_code == 0, res.output
    assert "loaded in MuJoCo" in res.output


@pytest.mark.parametrize("name, fmt, words", [
    ("tripteor-x7", "klipper", "three vertical slides"),  # linuxcnc: test_linuxcnc_chains
    ("orthoglide", "klipper", "not vertical"),
    ("delta", "klipper", "crank"),  # (MuJoCo now takes the Delta robot: docs/export.md)
])
def test_refusals_write_nothing(run, tmp_path, name, fmt, words):
    out = tmp_path / ("outkins.c" if fmt == "linuxcnc" else "out.txt")
    res = run("export", name, "--to", fmt, "--out", out)
    assert res.exit_code == 1
    assert f"cannot export {name!r} to {fmt}" in res.output and words in res.output
    assert not out.exists()


def test_a_linuxcnc_file_must_be_named_as_its_module(run, tmp_path):
    res = run("export", "orthoglide", "--to", "linuxcnc", "--out", tmp_path / "ortho-kins.c")
    assert res.exit_code == 2 and "C identifier" in res.output


@pytest.mark.parametrize("fmt, module, function, out", [
    ("linuxcnc", "pkmkit.export.linuxcnc", "linuxcnc_source", "kins.c"),
    ("klipper", "pkmkit.export.klipper", "klipper_config", "d.cfg"),
])
def test_the_command_checks_what_it_writes(run, tmp_path, monkeypatch, fmt, module, function,
                                           out):
    """A generator that writes a wrong number (here: one arm 1 µm longer) is caught."""
    import importlib

    mod = importlib.import_module(module)
    original = getattr(mod, function)

    def wrong(*args, **kwargs):
        text = original(*args, **kwargs)
        if fmt == "linuxcnc":
            return text.replace("rod_length[N_RODS] = {1040.0", "rod_length[N_RODS] = {1040.001")
        return text.replace("arm_length: 1040\n", "arm_length: 1040.001\n", 1)

    monkeypatch.setattr(mod, function, wrong)
    res = run("export", "linear-delta-table-iv1", "--to", fmt, "--out", tmp_path / out)
    assert res.exit_code == 1 and "not written" in res.output
    assert not (tmp_path / out).exists()


def test_mjcf_with_a_masses_file(run, tmp_path):
    """The masses file's steel arms (Ø40 mm, 7700 kg/m³, 1.04 m: 10.06 kg each) reach the model."""
    mujoco = pytest.importorskip("mujoco")
    out = tmp_path / "delta.xml"
    res = run("export", "linear-delta-table-iv1", "--to", "mjcf", "--out", out, "--masses",
              Path(__file__).parents[2] / "docs" / "examples" / "delta-masses.toml")
    assert res.exit_code == 0, res.output
    model = mujoco.MjModel.from_xml_path(str(out))
    arm = 7700 * np.pi / 4 * 0.04**2 * 1.04
    assert model.body("rod0").mass[0] == pytest.approx(arm, rel=1e-12)
    assert model.body("platform").mass[0] == pytest.approx(15.0)


def test_format_options_go_with_their_format(run, tmp_path):
    res = run("export", "orthoglide", "--to", "linuxcnc", "--out", tmp_path / "okins.c",
              "--endstops", "1,2,3")
    assert res.exit_code == 2 and "--endstops goes with --to klipper" in res.output


@pytest.mark.parametrize("extra", [["--endstops", "1e300,1e300,1e300"],
                                   ["--endstops", "1650,5,1650"],
                                   ["--set", "q_max=2e5,2e5,2e5", "--units", "m"]])
def test_klipper_endstops_beyond_the_machine_write_nothing(run, tmp_path, extra):
    out = tmp_path / "printer.cfg"
    res = run("export", "linear-delta-table-iv1", "--to", "klipper", "--out", out, *extra)
    assert res.exit_code == 1, res.output
    assert res.output.startswith("Error:") and "endstop" in res.output
    assert not out.exists()
