"""Elastic data from machine files: values, defaults, typed errors with their line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pkmkit.exceptions import MachineFileError
from pkmkit.machines.registry import load, machine
from pkmkit.stiffness import default_data, stiffness
from pkmkit.stiffness.file_data import file_data

DOCS = Path(__file__).resolve().parents[2] / "docs" / "examples"

KIND_FILE = """[machine]
kind = "orthoglide"
units = "mm"
[parameters]
L = 310
parallelogram_width = 60
[stiffness]
{body}
"""

ROD_LEGS = (DOCS / "hexapod-6-6.toml").read_text()


def _write(tmp_path, text, name="m.toml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_kind_file_values(tmp_path):
    path = _write(tmp_path, KIND_FILE.format(body='actuator_stiffness = [1e8, 2e8, 3e8]\n'
                                                  'rod_section = "tube:20,16"\n'
                                                  'rod_material = [70e9, 26e9]'))
    m = load(path)
    data = file_data(path, m)
    np.testing.assert_array_equal(data.actuator_stiffness, [1e8, 2e8, 3e8])
    assert data.rod_section.area == pytest.approx(np.pi * (0.02**2 - 0.016**2) / 4)
    assert data.rod_material.E == 70e9
    assert not data.assumed
    result = stiffness(m, m.home_pose, data=data)
    assert np.isfinite(result.stiffness).all()


@pytest.mark.parametrize("body, line, match", [
    ("actuator_stiffness = -1e8", 8, r"actuator_stiffness\[0\]"),
    ("actuator_stiffness = 0", 8, r"actuator_stiffness\[0\]"),
    ("actuator_stiffness = nan", 8, r"actuator_stiffness\[0\]"),
    ("actuator_stiffness = [1e8, 1e8]", 8, "needs 1 or 3"),
    ('rod_section = "hexagon:3"', 8, "shape"),
    ("rod_material = [-1, 2]", 8, "material E"),
    ("stiffnes = 3", 8, "unknown key"),
])
def test_kind_file_errors_name_the_line(tmp_path, body, line, match):
    path = _write(tmp_path, KIND_FILE.format(body=body))
    m = load(path)
    with pytest.raises(MachineFileError, match=match) as info:
        file_data(path, m)
    assert info.value.line == line


def test_per_leg_actuator_stiffness(tmp_path):
    text = ROD_LEGS.replace('type = "strut"', 'type = "strut"\nactuator_stiffness = 5e7')
    path = _write(tmp_path, text)
    m = load(path)
    data = file_data(path, m)
    np.testing.assert_array_equal(data.actuator_stiffness, np.full(6, 5e7))
    bad = text.replace("actuator_stiffness = 5e7", "actuator_stiffness = -5e7", 1)
    path = _write(tmp_path, bad, "bad.toml")
    with pytest.raises(MachineFileError, match=r"actuator_stiffness\[0\]") as info:
        file_data(path, load(path))
    assert info.value.line is not None
    assert "actuator_stiffness = -5e7" in bad.splitlines()[info.value.line - 1]


def test_joint_chain_file_link_sections(tmp_path):
    text = (DOCS / "crank-slider.toml").read_text() + (
        '\n[stiffness]\nlink_section = "circle:20"\n[stiffness.links]\ntheta3 = "circle:30"\n')
    path = _write(tmp_path, text)
    m = load(path)
    data = file_data(path, m)
    assert set(data.link_sections) == {"theta3"}
    assert data.link_sections["theta3"].size == pytest.approx(0.03)
    soft = stiffness(m, q=m.home_q, data=data)
    assert np.isfinite(soft.compliance).all()
    wrong = text.replace('theta3 = "circle:30"', 'nothere = "circle:30"')
    path = _write(tmp_path, wrong, "wrong.toml")
    with pytest.raises(MachineFileError, match="not an element"):
        file_data(path, load(path))


def test_user_file_of_a_kind_does_not_take_the_presets_sections():
    built_in = default_data(machine("linear-delta"))
    user = default_data(load(str(DOCS / "my-machine.toml")))
    assert built_in.rod_section is not None and user.rod_section is None
