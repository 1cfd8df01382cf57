"""Calibrated machine files: the [defects] table is written, read back by pkmkit.load with the
defects included, and errors in it name the line."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.exceptions import MachineFileError
from pkmkit.io.machine_defects import machine_text_with_defects, write_machine_with_defects
from pkmkit.machines.registry import preset_path
from pkmkit.model.defects_table import apply_defect_vector


@pytest.mark.parametrize("name", ["tripteor-x7", "verne", "linear-delta", "gough-stewart"])
def test_defects_round_trip(tmp_path, name):
    m = pkmkit.machine(name)
    delta = random_defects(m, np.random.default_rng(1))
    true = apply_defect_vector(m, delta)
    path = tmp_path / f"{name}.toml"
    write_machine_with_defects(path, preset_path(name), m, delta, note="test")
    back = pkmkit.load(path)
    q = np.atleast_2d(m.home_q)
    np.testing.assert_allclose(back.fk(q), true.fk(q), atol=1e-11)
    assert np.abs(back.fk(q) - m.fk(q)).max() > 1e-6
    assert "[defects]" in path.read_text()


def test_recalibration_adds_to_the_file_defects(tmp_path):
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(2)
    first, second = random_defects(m, rng), random_defects(m, rng)
    one = tmp_path / "one.toml"
    write_machine_with_defects(one, preset_path("tripteor-x7"), m, first)
    loaded = pkmkit.load(one)
    two = tmp_path / "two.toml"
    write_machine_with_defects(two, one, loaded, second)
    assert two.read_text().count("[defects]") == 1
    q = np.atleast_2d(m.home_q)
    np.testing.assert_allclose(pkmkit.load(two).fk(q),
                               apply_defect_vector(m, first + second).fk(q), atol=1e-11)


def test_yaml_machine_files(tmp_path):
    source = tmp_path / "delta.yaml"
    source.write_text("machine:\n  kind: linear-delta\n  units: mm\nparameters:\n  R: 700\n"
                      "  r: 150\n  L: 1300\n")
    m = pkmkit.load(source)
    delta = np.zeros(30)
    delta[0] = 1e-4
    text = machine_text_with_defects(source, m, delta)
    assert "defects:\n  dA1x: 0.1" in text
    out = tmp_path / "cal.yaml"
    out.write_text(text)
    assert pkmkit.load(out).model.leg_base[0, 0] == pytest.approx(m.model.leg_base[0, 0] + 1e-4)


def test_bad_defects_tables_name_the_line(tmp_path):
    path = tmp_path / "bad.toml"
    text = preset_path("linear-delta")
    base = open(text).read()
    path.write_text(base + "\n[defects]\ndA1x = 0.1\ndZZ9 = 0.2\n")
    with pytest.raises(MachineFileError, match=r"bad\.toml:\d+: unknown defect 'dZZ9'") as err:
        pkmkit.load(path)
    assert err.value.line == len(base.splitlines()) + 4
    path.write_text(base + "\n[defects]\ndA1x = \"x\"\n")
    with pytest.raises(MachineFileError, match="must be a finite number"):
        pkmkit.load(path)


def test_a_defect_too_large_for_a_float_names_its_line(tmp_path):
    """A 400-digit integer in [defects] (issue 18 §7 fuzz: a TypeError from np.isfinite)."""
    path = tmp_path / "huge.toml"
    base = open(preset_path("linear-delta")).read()
    path.write_text(base + "\n[defects]\ndA1x = 0.1\ndL1 = " + "9" * 400 + "\n")
    with pytest.raises(MachineFileError, match=r"huge\.toml:\d+: defect 'dL1' must be a finite "
                                               "number") as err:
        pkmkit.load(path)
    assert err.value.line == len(base.splitlines()) + 4
