"""``pkmkit stiffness``: JSON keys, units, elastic settings, refusals, batches."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pkmkit.machines.registry import machine
from pkmkit.stiffness import stiffness


def test_orthoglide_json_at_home_is_ka_identity(run, as_json):
    out = as_json(run("stiffness", "orthoglide", "--pose", "0,0,0", "--json",
                      "--set", "actuator_stiffness=2e7"))
    for key in ("stiffness", "compliance", "eigenvalues", "translational_eigenvalues"):
        assert key in out
    np.testing.assert_allclose(out["stiffness"], 2e7 * np.eye(3), atol=1e-3)
    np.testing.assert_allclose(out["compliance"], np.eye(3) / 2e7, rtol=1e-10)
    assert out["elastic_data"]["assumed"] is False or "given" in " ".join(
        out["elastic_data"]["notes"])


def test_default_values_are_said_to_be_assumed(run, as_json):
    out = as_json(run("stiffness", "gough-stewart", "--pose", "0,0,0.8,0,0,0", "--json"))
    assert out["elastic_data"]["assumed"] is True
    text = run("stiffness", "gough-stewart", "--pose", "0,0,0.8,0,0,0").output
    assert "assumed" in text


def test_deflection_json_and_mm_units_agree_with_the_library(run, as_json):
    m = machine("gough-stewart")
    x = np.array([0.01, 0.0, 0.8, 0.0, 0.0, 0.0])
    w = [10.0, -20.0, 300.0, 1.0, 2.0, -3.0]
    out = as_json(run("stiffness", "gough-stewart", "--pose", "10,0,800,0,0,0", "--units", "mm",
                      "--wrench", ",".join(map(str, w)), "--json"))
    ref = stiffness(m, x, wrench=w)
    np.testing.assert_allclose(out["deflection"], ref.deflection, rtol=1e-9)
    np.testing.assert_allclose(out["stiffness"], ref.stiffness, rtol=1e-9)


def test_joint_chain_with_link_sections(run, as_json):
    q = "0.983186,1.064076,0.988005,0,0"
    rigid = as_json(run("stiffness", "tripteor-x7", "--q", q, "--json"))
    soft = as_json(run("stiffness", "tripteor-x7", "--q", "983.186,1064.076,988.005,0,0", "--json",
                       "--set", "link_section=tube:80,60", "--units", "mm"))
    assert rigid["rigid_directions"] == 1 and rigid["stiffness"][0][0] is None
    assert soft["rigid_directions"] == 0
    assert np.isfinite(np.array(soft["stiffness"], dtype=float)).all()


@pytest.mark.parametrize("value", ["0", "-1e8", "inf", "nan", "1e8,1e8"])
def test_bad_actuator_stiffness_exits_1(run, value):
    result = run("stiffness", "orthoglide", "--pose", "0,0,0", "--set",
                 f"actuator_stiffness={value}")
    assert result.exit_code == 1
    assert "actuator_stiffness" in result.output


def test_bad_section_and_wrench_exit_1(run):
    assert run("stiffness", "orthoglide", "--pose", "0,0,0", "--set",
               "rod_section=hexagon:3").exit_code == 1
    result = run("stiffness", "orthoglide", "--pose", "0,0,0", "--wrench", "1,2")
    assert result.exit_code == 1 and "--wrench" in result.output


@pytest.mark.parametrize("args, exceeded", [
    (["linear-delta", "--pose", "0,0,0", "--units", "mm", "--wrench", "1e9,1e9,1e9"], True),
    (["gough-stewart", "--pose", "0,0,0.8,0,0,0", "--wrench", "0,0,0,1e6,0,0"], True),
    (["linear-delta", "--pose", "0,0,0", "--wrench", "1000,1000,1000"], False),
])
def test_a_deflection_beyond_the_linear_model_exits_3(run, args, exceeded):
    """1e9 N on a linear Delta printed a 40 m deflection, 1e6 N·m on the hexapod a 0.046 rad
    rotation, with exit 0: the linear model does not hold there (exit 3, said on stderr)."""
    result = run("stiffness", *args)
    assert result.exit_code == (3 if exceeded else 0), result.output
    assert ("beyond the range of the linear (small-displacement) model" in result.stderr) \
        == exceeded
    if exceeded:
        assert "deflection under" in result.stdout
        out = json.loads(run("stiffness", *args, "--json").stdout)
        assert "small-displacement" in out["beyond_linear_range"]


def test_unreachable_single_pose_exits_1(run):
    assert run("stiffness", "orthoglide", "--pose", "5,5,5").exit_code == 1


def test_batch_flags_bad_rows_with_exit_3(run, tmp_path):
    src = tmp_path / "poses.csv"
    src.write_text("x,y,z\n0,0,0\n5,5,5\n0.05,0,0\n")
    dst = tmp_path / "out.csv"
    result = run("stiffness", "orthoglide", "--input", src, "--output", dst, "--wrench",
                 "100,0,0")
    assert result.exit_code == 3
    import csv

    rows = list(csv.DictReader(line for line in dst.open() if not line.startswith("#")))
    assert [r["status"] for r in rows] == ["ok", "unreachable", "ok"]
    assert float(rows[0]["kt1"]) == pytest.approx(100.0)
    m = machine("orthoglide")
    ref = stiffness(m, np.array([0.05, 0.0, 0.0]), wrench=[100.0, 0.0, 0.0])
    assert float(rows[2]["dx"]) == pytest.approx(ref.deflection[0] * 1e6, rel=1e-9)
    # the loaded equilibrium beside it (the library's), empty where the pose is unreachable
    from pkmkit.stiffness.equilibrium import loaded_equilibrium

    lib = loaded_equilibrium(m, np.array([0.05, 0.0, 0.0]), np.array([100.0, 0.0, 0.0]))
    assert float(rows[2]["dx_loaded"]) == pytest.approx(lib.loaded[0] * 1e6, rel=1e-12)
    assert float(rows[2]["geometric_share"]) == pytest.approx(lib.share, rel=1e-9)
    assert rows[1]["dx_loaded"] in ("", "nan", "NaN")


def test_machine_file_error_exits_1_with_the_line(run, tmp_path):
    path = tmp_path / "m.toml"
    path.write_text('[machine]\nkind = "orthoglide"\n[stiffness]\nactuator_stiffness = -3\n')
    result = run("stiffness", path, "--pose", "0,0,0")
    assert result.exit_code == 1
    assert "m.toml:4:" in result.output and "actuator_stiffness" in result.output


def test_show_says_which_values_are_assumed(run):
    text = run("show", "orthoglide").output
    assert "elastic data (pkmkit stiffness)" in text and "assumed" in text


def test_a_section_for_the_other_family_is_refused(run):
    result = run("stiffness", "orthoglide", "--pose", "0,0,0", "--set", "link_section=circle:0.02")
    assert result.exit_code == 1 and "rod_section" in result.output
    result = run("stiffness", "tripteor-x7", "--q", "0.983186,1.064076,0.988005,0,0", "--set",
                 "rod_section=circle:0.02")
    assert result.exit_code == 1 and "link_section" in result.output


@pytest.mark.parametrize(("machine", "pose"), [("gough-stewart", "0,0,3,0,0,0"),
                                               ("linear-delta", "0,0,1.0")])
def test_a_pose_beyond_the_strokes_is_flagged_with_exit_3(machine, pose):
    """The one stroke check of every command (issue 18 §4): a stiffness at a pose the machine
    cannot reach within its strokes is reported as such, with exit status 3."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    result = CliRunner().invoke(cli, ["stiffness", machine, "--pose", pose, "--json"])
    assert result.exit_code == 3, result.output
    payload = json.loads(result.stdout)
    assert payload["out_of_stroke"], payload


def test_gravity_deflection_of_a_joint_chain_machine(run, as_json):
    """--gravity prints the library's chain_gravity_deflection (JSON: m, rad) and the masses'
    note."""
    import numpy as np

    from pkmkit.machines.registry import machine
    from pkmkit.stiffness.chain_gravity import chain_gravity_deflection

    m = machine("tripteor-x7")
    q = "983.186,1064.076,988.005,0,0"
    data = as_json(run("stiffness", "tripteor-x7", "--q", q, "--units", "mm", "--gravity",
                       "--json"))
    expected, _ = chain_gravity_deflection(m, np.array([0.983186, 1.064076, 0.988005, 0, 0]))
    np.testing.assert_allclose(data["gravity_deflection"], expected[0], rtol=1e-12)
    assert "illustrative masses" in data["masses"]
    loaded = as_json(run("stiffness", "tripteor-x7", "--q", q, "--units", "mm", "--wrench",
                         "0,0,-1000,0,0,0", "--json"))
    assert loaded["deflection_loaded"] is None and "linear" in loaded["loaded_note"]
    text = run("stiffness", "tripteor-x7", "--q", q, "--units", "mm", "--gravity").output
    assert "deflection under its own weight: [16.833, 9.2813, -7.681] µm" in text


def test_gravity_deflection_of_rod_machines(run, as_json):
    """--gravity on a hexapod (at a moved reference point: the tool tip) and a translating
    machine prints the library's weight deflections; a batch is refused."""
    from pkmkit.dynamics.defaults import default_masses
    from pkmkit.stiffness.loads import load_deflection
    from pkmkit.stiffness.platform_gravity import platform_gravity_deflection

    m = machine("dietmaier-hexapod")
    pose = m.home_pose + np.array([0.01, 0.0, 0.02, 0.0, 0.05, 0.0])
    from scipy.spatial.transform import Rotation

    angles = Rotation.from_rotvec(pose[3:]).as_euler("xyz", degrees=True)  # --angles xyz
    text = ",".join(f"{v:.17g}" for v in np.concatenate([pose[:3], angles]))
    data = as_json(run("stiffness", "dietmaier-hexapod", "--pose", text, "--gravity",
                       "--reference", "0,0,-0.15", "--units", "m", "--json"))
    expected, _ = platform_gravity_deflection(m, pose[None], point=[0, 0, -0.15])
    np.testing.assert_allclose(data["gravity_deflection"], expected[0], rtol=1e-9)
    assert np.abs(expected[0, 3:]).max() > 0 and "illustrative masses" in data["masses"]
    o = machine("orthoglide")
    data = as_json(run("stiffness", "orthoglide", "--pose", "0.02,0,0", "--gravity", "--units",
                       "m", "--json"))
    sag = load_deflection(o, np.array([[0.02, 0.0, 0.0]]), default_masses(o)).gravity[0]
    np.testing.assert_allclose(data["gravity_deflection"], sag, rtol=1e-12)
    assert "rotation" not in run("stiffness", "orthoglide", "--pose", "0,0,0",
                                 "--gravity").output


def test_loaded_equilibrium_beside_the_linear_deflection(run, as_json):
    """--wrench on a rod machine: the library's loaded equilibrium, its difference from the
    linear deflection and the geometric-stiffness share (JSON, SI); text lines in µm."""
    from pkmkit.stiffness.equilibrium import loaded_equilibrium

    m = machine("gough-stewart")
    args = ("stiffness", "gough-stewart", "--pose", "0,0,0.8,0,0,0", "--units", "m",
            "--wrench", "500,0,-1000,0,0,0", "--reference", "0,0,-0.15")
    out = as_json(run(*args, "--json"))
    lib = loaded_equilibrium(m, np.array([0, 0, 0.8, 0, 0, 0]),
                             np.array([500.0, 0, -1000, 0, 0, 0]), reference=[0, 0, -0.15])
    np.testing.assert_allclose(out["deflection_loaded"], lib.loaded, rtol=1e-12)
    np.testing.assert_allclose(out["deflection_difference"], lib.difference, rtol=1e-12)
    assert out["geometric_stiffness_share"] == pytest.approx(lib.share, rel=1e-12)
    assert out["loaded_status"] == "ok" and 0 < lib.share < 1e-3
    assert np.abs(lib.difference).max() > 0
    text = run(*args).output
    assert "loaded equilibrium: [13.882, 0, -1.9537] µm" in text
    assert "geometric-stiffness share: 2.82e-05" in text


def test_no_loaded_equilibrium_is_doubtful(run, monkeypatch):
    """An equilibrium Newton does not find: said on standard error, exit status 3."""
    import dataclasses

    import pkmkit.stiffness.equilibrium as equilibrium
    from pkmkit.status import Status

    real = equilibrium.loaded_equilibrium

    def failing(*args, **kwargs):
        got = real(*args, **kwargs)
        return dataclasses.replace(got, loaded=got.loaded * np.nan,
                                   status=np.full(len(got.status), Status.NOT_CONVERGED))

    monkeypatch.setattr(equilibrium, "loaded_equilibrium", failing)
    res = run("stiffness", "orthoglide", "--pose", "0,0,0", "--wrench", "0,0,-500")
    assert res.exit_code == 3
    assert "not found" in res.output and "no loaded equilibrium found" in res.output
