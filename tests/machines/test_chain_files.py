"""Machine files describing joint-chain machines element by element (``kind =
"joint-chain"``): the shipped crank-slider example against the built-in kind, round trips of
every built-in joint-chain machine through a file, YAML, defects, and malformed files — each
error naming its line."""

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

import pkmkit
from pkmkit.exceptions import MachineFileError, ParameterError
from pkmkit.machines.chain_file import machine_file_text

EXAMPLE = Path(__file__).parents[2] / "docs" / "examples" / "crank-slider.toml"
CHAIN_PRESETS = ["crank-slider", "tripteor-x7", "trimule-600"]


def line_of(text: str, needle: str, occurrence: int = 1) -> int:
    """1-based line of the ``occurrence``-th line containing ``needle``."""
    hits = [i + 1 for i, line in enumerate(text.splitlines()) if needle in line]
    return hits[occurrence - 1]


def load_text(tmp_path, text: str, name: str = "machine.toml"):
    path = tmp_path / name
    path.write_text(text)
    return pkmkit.load(path)


def assert_same_kinematics(a, b, q, tol=1e-12):
    assert a.actuator_names == b.actuator_names and a.passive_names == b.passive_names
    assert a.model.leg_names == b.model.leg_names
    assert a.model.parameter_names() == b.model.parameter_names()
    assert a.model.defect_index.names == b.model.defect_index.names
    assert np.abs(a.model.frames - b.model.frames).max() <= tol
    assert a.tool_length == pytest.approx(b.tool_length, abs=tol)
    assert a.hyperstatism() == b.hyperstatism()
    ra, rb = a.fk(q, full_output=True), b.fk(q, full_output=True)
    assert np.array_equal(ra.status, rb.status)
    assert np.abs(ra.pose - rb.pose).max() <= tol
    assert np.abs(ra.passive - rb.passive).max() <= tol
    ja, jb = a.jacobian(q), b.jacobian(q)
    assert np.abs(ja.J - jb.J).max() <= 1e3 * tol


def test_example_is_the_builtin_crank_slider():
    example = pkmkit.load(EXAMPLE)
    builtin = pkmkit.machine("crank-slider")
    assert example.name.startswith("Crank-slider, element by element")
    q = np.radians(np.arange(-180.0, 181.0, 7.5))[:, None]
    assert_same_kinematics(example, builtin, q, tol=1e-15)
    assert np.array_equal(example.model.frames, builtin.model.frames)
    assert example.home_q == pytest.approx(builtin.home_q, abs=0)
    assert example.home_closure_residual < 1e-15
    poses = example.reference_poses()
    assert {k: v.tolist() for k, v in poses.items()} == {
        k: v.tolist() for k, v in builtin.reference_poses().items()}
    assert [e.display for e in example.model.elements[:3]] == ["θ1", "θ2", "θ3"]


def test_the_same_file_in_yaml(tmp_path):
    import tomllib

    data = tomllib.loads(EXAMPLE.read_text())
    path = tmp_path / "crank-slider.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True))
    q = np.radians(np.arange(-180.0, 181.0, 30.0))[:, None]
    assert_same_kinematics(pkmkit.load(path), pkmkit.machine("crank-slider"), q, tol=1e-15)
    # and its errors have lines too
    data["elements"][2]["type"] = "S"
    path.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True))
    text = path.read_text()
    with pytest.raises(MachineFileError) as info:
        pkmkit.load(path)
    assert info.value.line == line_of(text, "type: S")


@pytest.mark.parametrize("machine_id", CHAIN_PRESETS)
def test_every_builtin_chain_machine_round_trips_through_a_file(tmp_path, machine_id):
    """Shared joints (the TriMule's ψ1 in three legs), fixed frames given by axis and spin or by
    a rotation, strokes, heads and reference configurations survive the file."""
    builtin = pkmkit.machine(machine_id)
    loaded = load_text(tmp_path, machine_file_text(builtin), f"{machine_id}.toml")
    q = np.array(list(builtin.reference_poses().values()))
    assert_same_kinematics(loaded, builtin, q, tol=1e-14)
    assert np.array_equal(loaded.model.q_min, builtin.model.q_min)
    assert np.abs(loaded.home_q - builtin.home_q).max() < 1e-14
    assert np.abs(loaded.home_passive - builtin.home_passive).max() < 1e-14
    in_mm = load_text(tmp_path, machine_file_text(builtin, "mm"), f"{machine_id}-mm.toml")
    assert_same_kinematics(in_mm, builtin, q, tol=1e-12)


def test_shared_joint_is_one_joint(tmp_path):
    text = machine_file_text(pkmkit.machine("trimule-600"))
    loaded = load_text(tmp_path, text)
    assert text.count('name = "psi1"') == 1 and text.count('"psi1"') == 4
    assert loaded.hyperstatism().joints == 19
    assert loaded.passive_names.count("psi1") == 1


def test_defects_table(tmp_path):
    """Defects in the file: dimensionless orientation components, spins in degrees, positions in
    the file's unit."""
    text = EXAMPLE.read_text() + "\n[defects]\ndK4 = 0.002\nda2 = 0.5\ndS3F = 0.1\n"
    loaded = load_text(tmp_path, text)
    reference = pkmkit.machine("crank-slider").with_defects(
        {"dK4": 0.002, "da2": 0.5e-3, "dS3F": math.radians(0.1)})
    assert np.abs(loaded.model.defects - reference.model.defects).max() < 1e-18
    q = np.radians(np.arange(-180.0, 181.0, 45.0))[:, None]
    assert np.abs(loaded.fk(q) - reference.fk(q)).max() < 1e-12
    # and a machine with defects writes them back
    again = load_text(tmp_path, machine_file_text(reference), "again.toml")
    assert np.abs(again.model.defects - reference.model.defects).max() < 1e-18


# ----------------------------------------------------------------------------- malformed files
def edited(replacements, append=""):
    text = EXAMPLE.read_text()
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text + append


def assert_file_error(tmp_path, text, needle, match, occurrence=1):
    with pytest.raises(MachineFileError, match=match) as info:
        load_text(tmp_path, text)
    assert info.value.line == line_of(text, needle, occurrence), str(info.value)
    assert str(info.value).startswith(f"{tmp_path / 'machine.toml'}:{info.value.line}: ")
    return info.value


def test_unknown_joint_type(tmp_path):
    text = edited([('type = "P"', 'type = "C"')])
    err = assert_file_error(tmp_path, text, 'type = "C"', "unknown joint type 'C'")
    assert "R (revolute), P (prismatic), F (fixed frame)" in str(err)


def test_axis_of_zero_length(tmp_path):
    text = edited([("axis = [0, 0, 1]", "axis = [0, 0, 0]")])
    assert_file_error(tmp_path, text, "axis = [0, 0, 0]", r"element 'theta2': the axis .* has "
                      "zero length")


def test_leg_naming_an_unknown_element(tmp_path):
    text = edited([('elements = ["x4", "R4_RF"]', 'elements = ["x4", "R4_FR"]')])
    assert_file_error(tmp_path, text, '"R4_FR"', "slider names an unknown element 'R4_FR'")


def test_element_used_by_nothing(tmp_path):
    text = edited([('elements = ["theta1", "theta2", "theta3", "R3_RF"]',
                    'elements = ["theta1", "theta2", "theta3"]')])
    # R3_RF (the 4th [[elements]] table) is now orphaned
    assert_file_error(tmp_path, text, "[[elements]]", "'R3_RF' is used by no leg", 4)


def test_no_actuated_joint(tmp_path):
    text = edited([("actuated = true", "actuated = false")])
    assert_file_error(tmp_path, text, "[[elements]]", "no element is actuated")


def test_home_that_does_not_close(tmp_path):
    """The slider 500 mm off the crank's plane: no platform pose closes both legs; the error
    names a leg, by how much it misses, and points at it."""
    text = edited([("point = [200, 0, 0]", "point = [200, 500, 0]")])
    with pytest.raises(MachineFileError, match=r"do not close at the home joint values: "
                       r"(slider|crank and rod) misses the platform by \d") as info:
        load_text(tmp_path, text)
    leg = "slider" if "slider misses" in str(info.value) else "crank and rod"
    assert info.value.line == line_of(text, f'name = "{leg}"') - 1  # its [[legs]] header
    assert "largest closure residual" in str(info.value) and " mm" in str(info.value)


def test_actuated_joints_must_match_the_mobility(tmp_path):
    text = edited([('label = "2"', 'label = "2"\nactuated = true')])
    assert_file_error(tmp_path, text, "actuated = true", r"1 degree\(s\) of freedom at home "
                      r"but 2 actuated joint\(s\) \(theta1, theta2\)")


def test_actuators_that_leave_the_legs_free(tmp_path):
    """Driving the slider with the crank at a dead centre (θ1 = 0): the slider does not fix the
    crank there."""
    text = edited([("actuated = true\nhome = 30", "home = 0"),
                   ('label = "4"', 'label = "4"\nactuated = true'),
                   ("home = -39.59406822686046", "home = 0"),
                   ("home = 9.59406822686046", "home = 0"),
                   ("home = 232.40652953342465", "home = 250")])
    assert_file_error(tmp_path, text, "actuated = true", "do not fix the legs at home")


@pytest.mark.parametrize("replacements, append, needle, match", [
    ([('label = "1"', 'label = "1"\ncolour = "red"')], "", "colour", "unknown key 'colour'"),
    ([('name = "theta2"', 'name = "theta1"')], "", ('name = "theta1"', 2),
     "'theta1' is defined twice"),
    ([("axis = [0, -1, 0]", "axis = [0, -1]")], "", "axis = [0, -1]", "must be 3 numbers"),
    ([("axis = [0, -1, 0]", 'axis = [0, "-1", 0]')], "", "axis = [0,", "must be 3 numbers"),
    ([("point = [100, 0, 0]", "point = [100, 0, nan]")], "", "nan", "3 finite numbers"),
    ([("home = 30", 'home = "30"')], "", 'home = "30"', "must be a finite number"),
    ([("home = 30", "home = 30\nstroke = [90, 10]")], "", "stroke = [90, 10]", "min < max"),
    ([("home = 30", "home = 30\nstroke = [40, 90]")], "", "home = 30", "outside the stroke"),
    ([("rotation = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]",
       "rotation = [[1, 0, 0], [0, 1, 1], [0, -1, 0]]")], "", "[0, 1, 1]", "rotation matrix"),
    ([('label = "3F"', 'label = "3F"\nactuated = true')], "", ("actuated = true", 2),
     "cannot be actuated"),
    ([('label = "3F"', 'label = "3F"\nhome = 3.5')], "", "home = 3.5", "has no home"),
    ([('axis = [0, 0, 1]\npoint = [100', 'rotation = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n'
       'point = [100')], "", "rotation = [[1, 0, 0], [0, 1, 0]", "places fixed frames"),
    ([("actuated = true", 'actuated = "yes"')], "", 'actuated = "yes"', "true or false"),
    ([('name = "slider"', 'name = "crank and rod"')], "", ('name = "crank and rod"', 2),
     "two legs are named"),
    ([('elements = ["x4", "R4_RF"]', 'elements = ["x4", "x4", "R4_RF"]')], "",
     'elements = ["x4", "x4"', "names x4 twice"),
    ([('elements = ["x4", "R4_RF"]', "elements = []")], "", "elements = []", "has no element"),
    ([('units = "mm"', 'units = "inch"')], "", 'units = "inch"', "inch"),
    ([("characteristic_length = 300", "characteristic_length = -3")], "",
     "characteristic_length = -3", "must be > 0"),
    ([], "\n[defects]\ndK9 = 0.1\n", "dK9", "unknown defect 'dK9'"),
    ([], "\n[defects]\ndK4 = true\n", "dK4 = true", "must be a finite number"),
    ([("crank-90 = [90]", "crank-90 = [90, 0]")], "", "crank-90", r"one value per actuator"),
    ([], "\n[tools]\nlength = 3\n", "[tools]", "unknown key 'tools'"),
    ([], "\n[head]\nelements = [\"theta1\"]\n", "[\"theta1\"]", "is in a leg and in the head"),
    # issue 18 §7 fuzz: 400-digit literals (TypeError, OverflowError), 1e308 (overflow
    # warnings in the closure; a zero axis), a rotation entry of 1e308 (overflow in R^T R)
    ([("home = 30", "home = " + "7" * 400)], "", "home = 777", "must be a finite number"),
    ([("point = [100, 0, 0]", "point = [100, 0, " + "7" * 400 + "]")], "", "point = [100, 0, 7",
     "must be 3 numbers"),
    ([("characteristic_length = 300", "characteristic_length = " + "7" * 400)], "",
     "characteristic_length = 777", "must be a finite number"),
    ([("point = [100, 0, 0]", "point = [1e308, 0, 0]")], "", "point = [1e308",
     "magnitude beyond 1e.06"),
    ([("axis = [0, -1, 0]", "axis = [0, -1e308, 1e308]")], "", "axis = [0, -1e308",
     "magnitude beyond 1e.06"),
    ([("home = 30", "home = 1e308")], "", "home = 1e308", "magnitude beyond 1e.06"),
    ([("rotation = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]",
       "rotation = [[1, 0, 0], [0, 0, 1], [0, -1e308, 0]]")], "", "[0, -1e308", "rotation matrix"),
])
def test_malformed_files(tmp_path, replacements, append, needle, match):
    needle, occurrence = needle if isinstance(needle, tuple) else (needle, 1)
    assert_file_error(tmp_path, edited(replacements, append), needle, match, occurrence)


def test_missing_tables(tmp_path):
    head = EXAMPLE.read_text().split("[[elements]]")[0]
    with pytest.raises(MachineFileError, match=r"needs \[\[elements\]\]"):
        load_text(tmp_path, head)
    no_legs = EXAMPLE.read_text().split("[[legs]]")[0]
    with pytest.raises(MachineFileError, match=r"needs \[\[legs\]\]"):
        load_text(tmp_path, no_legs)


def test_overrides_are_refused(tmp_path):
    from pkmkit.machines.registry import load

    with pytest.raises(ParameterError, match="element by element"):
        load(EXAMPLE, _overrides={"L1": 0.2})


def test_kind_list_names_joint_chain(tmp_path):
    with pytest.raises(MachineFileError, match="joint-chain"):
        load_text(tmp_path, '[machine]\nkind = "joint-chains"\n')
