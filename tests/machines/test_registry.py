"""The machine library: ids, overrides, shipped machine files, user files and their errors."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import MachineFileError, ParameterError, UnknownMachineError
from pkmkit.machines.registry import preset_path


def test_ids_and_aliases():
    ids = pkmkit.machines()
    for required in ("orthoglide", "linear-delta", "five-bar", "five-bar-biglide",
                     "linear-delta-table-iv1"):
        assert required in ids
    np.testing.assert_array_equal(pkmkit.machine("linear-delta").ik([0.1, 0, 0]),
                                  pkmkit.machine("linear-delta-ch3").ik([0.1, 0, 0]))


def test_unknown_machine_lists_valid_ids():
    with pytest.raises(UnknownMachineError,
                       match="valid ids: crank-slider, delta, dietmaier-hexapod, five-bar, ",
                       ) as info:
        pkmkit.machine("tripteor-x8")
    assert "orthoglide" in info.value.valid


def test_unknown_parameter_lists_valid_ones():
    with pytest.raises(pkmkit.UnknownParameterError, match="valid parameters: L, R, angles"):
        pkmkit.machine("linear-delta", length=1.0)


def test_override_errors_are_not_blamed_on_the_file():
    with pytest.raises(ParameterError) as info:
        pkmkit.machine("linear-delta", L=0.4)
    assert not isinstance(info.value, MachineFileError)


#: The seed machines' dimensions (m, degrees) and home configurations, written from the seeds
#: (000 Table IV.1 and Ch. III, 001 §3, 004 §2), independently of the shipped files.
_S = 0.5 / np.sqrt(2.0)
SEED_PRESETS = {
    "orthoglide": ({"L": 0.31, "q_min": [0.1265] * 3, "q_max": [0.3831] * 3},
                   [0.0, 0.0, 0.0], [0.31] * 3),
    "linear-delta-ch3": ({"R": 0.7, "r": 0.15, "L": 1.3, "angles": [0.0, 120.0, 240.0]},
                         [0.0, 0.0, 0.0], [np.sqrt(1.3**2 - 0.55**2)] * 3),
    "linear-delta-table-iv1": ({"R": 0.7, "r": 0.15, "L": 1.04, "angles": [0.0, 120.0, 240.0],
                                "q_min": [0.4] * 3, "q_max": [1.7] * 3},
                               [0.0, 0.0, 0.0], [np.sqrt(1.04**2 - 0.55**2)] * 3),
    "five-bar-isotropic": ({"A": [0.0, 0.0], "B": [1.0, -1.0], "alpha1": 0.0, "alpha2": 90.0,
                            "L": 0.5}, [1.0, 0.0], [0.5, 0.5]),
    "five-bar-biglide": ({"A": [0.0, 0.0], "B": [np.sqrt(2.0), 0.0], "alpha1": 0.0,
                          "alpha2": 0.0, "L": 0.5}, [np.sqrt(2.0) / 2, -_S], [_S, -_S]),
}


@pytest.mark.parametrize("ident", sorted(SEED_PRESETS))
def test_presets_carry_the_seed_dimensions(ident):
    """Each shipped file, loaded as a user file and by id, has the seed's dimensions and home
    configuration (and the inverse model closes there)."""
    values, home_pose, home_q = SEED_PRESETS[ident]
    for m in (pkmkit.machine(ident), pkmkit.load(preset_path(ident))):
        for name, value in values.items():
            expected = np.radians(value) if name.startswith(("angles", "alpha")) else value
            np.testing.assert_allclose(m.params[name], expected, rtol=1e-15, atol=1e-15,
                                       err_msg=f"{ident}: {name}")
        np.testing.assert_allclose(m.home_pose, home_pose, atol=1e-15)
        np.testing.assert_allclose(m.home_q, home_q, rtol=1e-15, atol=1e-15)
        np.testing.assert_allclose(m.ik(m.home_pose), home_q, rtol=1e-14, atol=1e-15)
    assert set(SEED_PRESETS) <= set(pkmkit.machines())


def test_yaml_and_toml_give_the_same_machine(tmp_path):
    toml = tmp_path / "d.toml"
    toml.write_text('[machine]\nkind = "linear-delta"\nunits = "mm"\n[parameters]\n'
                    'R = 700\nr = 150\nL = 1040\nangles = [90, 210, 330]\n')
    yaml_path = tmp_path / "d.yaml"
    yaml_path.write_text("machine:\n  kind: linear-delta\n  units: mm\nparameters:\n"
                         "  R: 700\n  r: 150\n  L: 1040\n  angles: [90, 210, 330]\n")
    a, b = pkmkit.load(toml), pkmkit.load(yaml_path)
    assert a.params == b.params and a.params["L"] == pytest.approx(1.04)
    assert a.params["angles"] == pytest.approx(np.radians([90, 210, 330]))
    np.testing.assert_allclose(a.ik([0.1, 0.0, 0.0]), b.ik([0.1, 0.0, 0.0]))
    assert a.id == "d"


def test_user_planar_rod_legs_machine(tmp_path):
    """The isotropic five-bar written leg by leg equals the built-in one."""
    path = tmp_path / "five.yaml"
    path.write_text(
        """
machine:
  kind: rod-legs
  name: my five-bar
  dims: 2
  home: [1.0, 0.0]
  mode_names: [right, left]
legs:
  - actuator: rho1
    base: [0, 0]
    axis: [1, 0]
    platform: [0, 0]
    length: 0.5
    branch: -1
    parallelogram: {width: 0.05, direction: [0, 1]}
  - actuator: rho2
    base: [1, -1]
    axis: [0, 1]
    platform: [0, 0]
    length: 0.5
    branch: -1
poses:
  corner: [1.1, 0.1]
"""
    )
    user, builtin = pkmkit.load(path), pkmkit.machine("five-bar")
    assert user.actuator_names == ("rho1", "rho2") and user.model.n_rods == 3
    x = np.array([[1.05, -0.03], [0.95, 0.08]])
    np.testing.assert_allclose(user.ik(x), builtin.ik(x), atol=1e-15)
    np.testing.assert_allclose(user.jacobian(x).J, builtin.jacobian(x).J, atol=1e-14)
    np.testing.assert_allclose(user.fk(user.ik(x), method="numeric"), x, atol=1e-12)
    assert user.mode_labels == ("left", "right")
    assert "corner" in user.reference_poses()
    with pytest.raises(ParameterError, match="leg by leg"):
        user.with_params(L=1.0)


ROD = ('[machine]\nkind = "rod-legs"\n\n[[legs]]\nbase = [0.5, 0, 0]\n'
       "platform = [0, 0, 0]\nlength = 1\naxis = [0, 0, 1]\n")

BAD_FILES = [
    ('[machine]\nkind = "deltoid"\n', 2, "kind must be one of"),
    ('[machine]\nkind = "linear-delta"\nunits = "inch"\n', 3, "unknown length unit"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nR = 0.7\nRR = 1\n', 5,
     "unknown parameter 'RR'"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nR = 0.7\nL = -1\n', 5, "must be > 0"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nL = 0.3\n', 4, "smaller than L"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nangles = [0, 1]\n', 4, "vector of 3"),
    ('[machine]\nkind = "five-bar"\ncolour = "red"\n', 3, "unknown key 'colour'"),
    ('[machine]\nkind = "five-bar"\n[extras]\na = 1\n', 3, "unknown key 'extras'"),
    ("[parameters]\nL = 1\n", None, "missing \\[machine\\]"),
    ('[machine]\nkind = "rod-legs"\ndims = 3\n\n[[legs]]\nbase = [0, 0, 0]\n'
     "platform = [0, 0, 0]\nlength = 1\naxis = [0, 0]\n", 9, "axis must be 3"),
    ('[machine]\nkind = "rod-legs"\n\n[[legs]]\nbase = [0, 0, 0]\nlength = 1\n', 4,
     "needs 'platform'"),
    ('[machine]\nkind = "rod-legs"\n\n[[legs]]\nbase = [0, 0, 0]\nplatform = [0, 0, 0]\n'
     "length = 1\naxis = [0, 0, 1]\nwheel = 3\n", 9, "unknown key 'wheel'"),
    ('[machine]\nkind = "orthoglide"\n[poses]\np = [0, 0]\n', 4, "3 coordinates"),
    ('[machine]\nkind = "linear-delta"\nunits = []\n', 3, "units must be a string"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nL = true\n', 4, "numeric"),
    ('[machine]\nkind = "linear-delta"\n[parameters]\nL = "1.3"\n', 4, "numeric"),
    ('[machine]\nkind = "rod-legs"\ndims = 2.0\n', 3, "integer 2, 3 or 6"),
    (ROD + 'type = ["slide"]\n', 9, "type must be 'slide', 'strut' or 'crank'"),
    (ROD + 'parallelogram = { width = "abc", direction = [1, 0, 0] }\n', 9,
     "width must be a finite number"),
    (ROD + "parallelogram = { width = 0.05 }\n", 9, "needs a 'direction'"),
    (ROD + "branch = 0.5\n", 9, "branch must be 1 or -1"),
    (ROD.replace("\n\n", "\nhome = [1, 0]\n", 1), 3, "home must be 3"),
    (ROD.replace("\n\n", '\nmode_names = ["a"]\n', 1), 3, "mode_names"),
    ('[machine]\nkind = "linear-delta"\ndescription = """\n[parameters]\nL = 1\n"""\n'
     "[parameters]\nR = 0.7\nL = -1\n", 9, "must be > 0"),
    # issue 18 §7 fuzz: magnitudes of 1e307 gave overflow warnings and an error at line 2
    # ('does not assemble', 'a parallel singularity'); strokes of 1e308 loaded silently
    (ROD.replace("base = [0.5, 0, 0]", "base = [1e308, 0, 0]"), 5, "legs.0.base: magnitude "
     "beyond 1e.06"),
    (ROD.replace("platform = [0, 0, 0]", "platform = [0, 0, 1e307]"), 6, "magnitude beyond"),
    (ROD + "stroke = [0, 1e308]\n", 9, "legs.0.stroke: magnitude beyond"),
    (ROD.replace("length = 1", "length = 1e308"), 7, "legs.0.length: magnitude beyond"),
    (ROD.replace("\n\n", "\nhome = [0, 0, 1e300]\n", 1), 3, "machine.home: magnitude beyond"),
]


@pytest.mark.parametrize("text, line, message", BAD_FILES)
def test_malformed_files_report_the_line(tmp_path, text, line, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(MachineFileError, match=message) as info:
        pkmkit.load(path)
    assert info.value.line == line, str(info.value)


def test_documented_machine_files_load(tmp_path):
    """Every TOML and YAML example of docs/machine-files.md is a valid machine file."""
    import re
    from pathlib import Path

    text = (Path(__file__).parents[2] / "docs" / "machine-files.md").read_text()
    blocks = re.findall(r"```(toml|yaml)\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 3
    for k, (fmt, body) in enumerate(blocks):
        path = tmp_path / f"example{k}.{fmt}"
        path.write_text(body)
        m = pkmkit.load(path)
        np.testing.assert_allclose(m.fk(m.ik(m.home_pose)), m.home_pose, atol=1e-12)


@pytest.mark.parametrize(
    "text, line, message",
    [
        ("machine: &m {kind: orthoglide, self: *m}\n", 1, "anchors and aliases"),
        ("a0: &a0 [1, 1]\na1: [*a0, *a0]\nmachine: {kind: orthoglide}\n", 1,
         "anchors and aliases"),
        ("machine:\nparameters: {L: 0.3}\n", 1, "is empty"),
        ("machine: {kind: linear-delta}\nparameters:\n  L: yes\n", 3, "numeric"),
        ("machine: {kind: orthoglide}\nparameters: {L: 0.3\n", 3,
         "YAML syntax error: expected ',' or '}'"),  # the parser's own words
    ],
)
def test_malformed_yaml_files(tmp_path, text, line, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(MachineFileError, match=message) as info:
        pkmkit.load(path)
    assert info.value.line == line, str(info.value)


def test_rods_that_do_not_fix_the_orientation_are_reported(tmp_path):
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    path = tmp_path / "tripod.toml"
    path.write_text(
        '[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n'
        + "".join(f'[[legs]]\ntype = "strut"\nbase = [{np.cos(a):.6f}, {np.sin(a):.6f}, 0]\n'
                  "platform = [0, 0, 0]\nlength = 1.2\n"
                  for a in np.radians([0.0, 120.0, 240.0]))
    )
    m = pkmkit.load(path)
    assert m.mobility()["instantaneous"].platform_freedom_locked == 3
    result = CliRunner().invoke(cli, ["show", str(path)])
    assert result.exit_code == 0 and "warning:" in result.output
    assert "orientation" in result.output
