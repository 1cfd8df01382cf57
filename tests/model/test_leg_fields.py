"""Leg fields of rod-legs machines as scalar parameters (pkmkit.machines.registry.leg_parameters
and with_leg_values), used by the design layer to vary machines described leg by leg."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ParameterError
from pkmkit.machines.registry import leg_parameters, with_leg_values

TRIPOD = """
[machine]
kind = "rod-legs"
units = "mm"
home = [0, 0, -800]
[[legs]]
base = [500, 0, 0]
axis = [0, 0, 1]
platform = [100, 0, 0]
length = 900
parallelogram = {{ width = 60, direction = [0, 1, 0] }}
stroke = [-200, 400]
[[legs]]
type = "strut"
base = [-250, 433, 0]
platform = [-50, 86.6, 0]
length = {strut}
[[legs]]
base = [-250, -433, 0]
axis = [0, 0, 1]
platform = [-50, -86.6, 0]
length = 900
"""

PLANAR = """
[machine]
kind = "rod-legs"
dims = 2
home = [1.0, 0.0]
[[legs]]
base = [0, 0]
axis = [1, 0]
platform = [0, 0]
length = 0.5
branch = -1
[[legs]]
base = [1, -1]
axis = [0, 1]
platform = [0, 0]
length = {length}
branch = -1
"""


@pytest.fixture
def tripod(tmp_path):
    path = tmp_path / "tripod.toml"
    path.write_text(TRIPOD.format(strut=700))
    return pkmkit.load(path)


def test_names_values_and_quantities(tripod):
    fields = leg_parameters(tripod)
    assert fields["legs[0].length"] == (pytest.approx(0.9), "length")
    assert fields["legs[2].base[0]"] == (pytest.approx(-0.25), "length")
    assert fields["legs[0].axis[2]"] == (pytest.approx(1.0), "number")
    assert fields["legs[0].parallelogram_width"] == (pytest.approx(0.06), "length")
    assert fields["legs[0].stroke[1]"] == (pytest.approx(0.4), "length")
    # a strut has no axis, a single rod no width, an unlimited stroke no limit
    assert "legs[1].axis[0]" not in fields and "legs[1].parallelogram_width" not in fields
    assert "legs[2].stroke[0]" not in fields


def test_unchanged_fields_rebuild_the_same_machine(tripod):
    same = with_leg_values(tripod, {})
    for name in ("leg_base", "leg_axis", "leg_platform", "leg_length", "q_min", "q_max",
                 "rod_base", "rod_platform", "rod_length", "leg_branch", "leg_kind"):
        np.testing.assert_array_equal(getattr(same.model, name), getattr(tripod.model, name))


def test_changed_field_equals_the_file_written_with_it(tripod, tmp_path):
    """legs[1].length = 0.75 m gives the machine of the file with 750 mm, and the original
    machine is unchanged."""
    changed = with_leg_values(tripod, {"legs[1].length": 0.75, "legs[0].parallelogram_width":
                                       0.08})
    path = tmp_path / "direct.toml"
    path.write_text(TRIPOD.format(strut=750).replace("width = 60", "width = 80"))
    direct = pkmkit.load(path)
    np.testing.assert_allclose(changed.model.rod_base, direct.model.rod_base, atol=1e-15)
    pts = np.array([[0.0, 0.0, -0.8], [0.05, -0.03, -0.75]])
    np.testing.assert_allclose(changed.ik(pts), direct.ik(pts), atol=1e-12)
    assert tripod.model.leg_length[1] == pytest.approx(0.7)
    assert not np.allclose(changed.ik(pts), tripod.ik(pts))


def test_planar_machine_exposes_two_components(tmp_path):
    path = tmp_path / "planar.toml"
    path.write_text(PLANAR.format(length=0.5))
    m = pkmkit.load(path)
    fields = leg_parameters(m)
    assert "legs[1].base[1]" in fields and "legs[1].base[2]" not in fields
    moved = with_leg_values(m, {"legs[1].length": 0.6})
    path.write_text(PLANAR.format(length=0.6))
    x = np.array([[1.05, -0.03]])
    np.testing.assert_allclose(moved.ik(x), pkmkit.load(path).ik(x), atol=1e-14)


def test_errors(tripod):
    with pytest.raises(ParameterError, match=r"unknown leg field 'legs\[5\]\.length'"):
        with_leg_values(tripod, {"legs[5].length": 1.0})
    with pytest.raises(ParameterError, match=r"legs\.0\.length must be > 0"):
        with_leg_values(tripod, {"legs[0].length": -1.0})
    with pytest.raises(ParameterError, match="too short"):
        with_leg_values(tripod, {"legs[0].length": 0.1})  # home out of reach
    with pytest.raises(ParameterError, match="named parameters"):
        leg_parameters(pkmkit.machine("linear-delta"))
