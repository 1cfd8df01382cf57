"""Masses of a masses file in the MuJoCo models of joint-chain machines (body by body,
:mod:`pkmkit.export.chain_masses`) and of the Delta robot's cranks (its carriage masses), and
in the joint chains' URDF."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import pkmkit
from pkmkit.cli.main import cli
from pkmkit.exceptions import InputError, UnsupportedExportError
from pkmkit.export.chain_masses import PLACEHOLDER_KG, load_chain_masses, read_masses
from pkmkit.export.mjcf_chains import chain_mjcf
from pkmkit.export.mjcf_writer import check_mjcf
from pkmkit.export.urdf_chains import joint_values, sample_configurations
from pkmkit.spatial.rotation import rotvec_to_matrix

from .test_mjcf_chains import _within_strokes, set_joint_values

mujoco = pytest.importorskip("mujoco")

TRIPTEOR = """[masses]
units = "mm"
gravity = [3.0, -4.0, -9.81]
[bodies.platform]
mass = 60.0
com = [20, -10, -40]
inertia = [[2.1, 0.1, 0.0], [0.1, 2.5, 0.2], [0.0, 0.2, 3.4]]
[bodies.Q1]
mass = 30
com = [0, 0, 350]
inertia = [3.0, 3.0, 0.1]
[bodies.Q5]
mass = 80
com = [0, 0, 100]
"""


def _file(tmp_path, text: str, name: str = "masses.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _body_inertia(model, name: str) -> np.ndarray:
    """A body's inertia (3, 3) in its frame, from MuJoCo's principal moments and axes."""
    body = model.body(name)
    w, x, y, z = body.iquat
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_quat([x, y, z, w]).as_matrix()
    return rot @ np.diag(body.inertia) @ rot.T


def test_the_bodies_weigh_what_the_file_says(tmp_path):
    """Mass, centre of mass and inertia of every named body, read back from MuJoCo; every
    other body a placeholder, named in the file; the file's gravity."""
    m = pkmkit.machine("tripteor-x7")
    masses = load_chain_masses(_file(tmp_path, TRIPTEOR), m)
    export = chain_mjcf(m, masses)
    assert "masses from masses.toml (3 bodies, 170 kg)" in export.xml
    assert "Q4, R7_T: 0.01 kg placeholder spheres" in export.xml
    assert check_mjcf(m, export) <= 1e-9
    model = mujoco.MjModel.from_xml_string(export.xml)
    assert model.body("platform").mass[0] == pytest.approx(60.0)
    assert model.body("platform").ipos == pytest.approx([0.02, -0.01, -0.04])
    np.testing.assert_allclose(_body_inertia(model, "platform"),
                               [[2.1, 0.1, 0.0], [0.1, 2.5, 0.2], [0.0, 0.2, 3.4]], atol=1e-12)
    assert model.body("Q1_body").mass[0] == pytest.approx(30.0)
    assert model.body("Q1_body").ipos == pytest.approx([0.0, 0.0, 0.35])
    np.testing.assert_allclose(_body_inertia(model, "Q1_body"), np.diag([3.0, 3.0, 0.1]),
                               atol=1e-12)
    q5 = model.body("Q5_body")  # no inertia given: a solid sphere of 20 mm
    np.testing.assert_allclose(q5.inertia, [0.4 * 80 * 0.02**2] * 3, rtol=1e-12)
    assert model.body("psi1_body").mass[0] == pytest.approx(PLACEHOLDER_KG)
    assert model.body_mass.sum() == pytest.approx(170 + 17 * PLACEHOLDER_KG)
    assert model.opt.gravity == pytest.approx([3.0, -4.0, -9.81])


def test_the_platform_weight_loads_the_actuators_as_pkmkit_says(tmp_path, monkeypatch):
    """MuJoCo's static actuator forces of a 60 kg platform whose centre of mass is off its
    frame (every other body nearly massless) — its generalized gravity balanced by the motors
    and the welds — are the virtual work of that weight at pkmkit's platform pose (central
    differences of pkmkit's direct model): the file's centre of mass is where pkmkit puts it."""
    monkeypatch.setattr("pkmkit.export.chain_masses.PLACEHOLDER_KG", 1e-9)
    text = TRIPTEOR.split("[bodies.Q1]")[0]
    m = pkmkit.machine("tripteor-x7")
    model = mujoco.MjModel.from_xml_string(chain_mjcf(m, load_chain_masses(
        _file(tmp_path, text), m)).xml)
    data = mujoco.MjData(model)
    gravity, com = np.array([3.0, -4.0, -9.81]), np.array([0.02, -0.01, -0.04])

    def potential(q: np.ndarray) -> float:
        res = m.fk(q, full_output=True, strokes="ignore")
        plat = np.ravel(res.platform)
        return -60.0 * gravity @ (plat[:3] + rotvec_to_matrix(plat[None, 3:])[0] @ com)

    act = [model.jnt_dofadr[model.joint(a).id] for a in m.actuator_names]
    select = np.zeros((model.nv, len(act)))
    select[act, np.arange(len(act))] = 1.0
    for q in _within_strokes(m, sample_configurations(m, 6, seed=4)[1:])[:2]:
        set_joint_values(model, data, joint_values(m, q))
        mujoco.mj_forward(model, data)
        system = np.hstack([select, data.efc_J.reshape(data.nefc, model.nv).T])
        solution = np.linalg.lstsq(system, data.qfrc_bias, rcond=None)[0]
        assert np.abs(system @ solution - data.qfrc_bias).max() < 1e-9
        h = 1e-6
        expected = np.array([(potential(q + h * e) - potential(q - h * e)) / (2 * h)
                             for e in np.eye(len(q))])
        assert np.abs(expected).max() > 10.0
        np.testing.assert_allclose(solution[:len(act)], expected,
                                   atol=1e-7 * np.abs(expected).max(), rtol=0)


@pytest.mark.parametrize(("text", "message"), [
    ("[bodies.nope]\nmass = 1\n", "has no body 'nope'; its bodies: platform, psi1"),
    ("[bodies.Q1]\nmass = -1\n", "mass must be one number > 0"),
    ("[bodies.Q1]\nmass = 1\ninertia = [1, 1, 3]\n", ":3: .*principal moments"),
    ("[bodies.Q1]\nmass = 1\ncom = [0, 0]\n", ":3: .*com must be 3 numbers"),
    ("[bodies.Q1]\nmass = 1\nspin = 2\n", r"\[bodies.Q1\] needs mass"),
    ("[masses]\nplatform = 1.0\n", r"a \[bodies.NAME\] table per body"),
])
def test_bad_files_are_refused_with_what_and_where(tmp_path, text, message):
    m = pkmkit.machine("tripteor-x7")
    with pytest.raises(InputError, match=message):
        read_masses(_file(tmp_path, text), m)


def test_rod_leg_masses_are_refused_for_a_chain():
    from pkmkit.dynamics.masses import mass_properties

    delta = pkmkit.machine("linear-delta-ch3")
    rods = mass_properties(delta, carriage=1.0, rod=0.5, platform=2.0)
    with pytest.raises(UnsupportedExportError, match="bodies' masses"):
        chain_mjcf(pkmkit.machine("tripteor-x7"), rods)


def test_command_line_chain_and_crank_masses(tmp_path):
    runner = CliRunner()
    out = tmp_path / "t.xml"
    done = runner.invoke(cli, ["export", "trimule-600", "--to", "mjcf", "--masses",
                               str(_file(tmp_path, "[bodies.platform]\nmass = 40\n")),
                               "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert "masses from masses.toml (1 bodies, 40 kg)" in done.output and out.exists()
    crank = _file(tmp_path, "[masses]\ncarriage = 1.2\nrod = 0.3\nrod_radius = 0.008\n"
                  "platform = 2.0\n", "delta.toml")
    done = runner.invoke(cli, ["export", "delta", "--to", "mjcf", "--masses", str(crank),
                               "--out", str(tmp_path / "d.xml")])
    assert done.exit_code == 0, done.output
    assert "masses of the masses file" in done.output and "carriage masses" in done.output


@pytest.mark.parametrize("ident", ["tripteor-x7", "trimule-600"])
def test_pinocchio_and_mujoco_weigh_the_same_bodies(ident, tmp_path, monkeypatch):
    """The same masses file through both exports: Pinocchio's generalized gravity of the URDF
    tree equals MuJoCo's of the MJCF tree, joint by joint, at pkmkit's configurations (the
    MJCF's placeholders made negligible; the URDF's unnamed links carry nothing)."""
    pin = pytest.importorskip("pinocchio")
    from pkmkit.export.urdf_check import pinocchio_configuration
    from pkmkit.export.urdf_writer import write_urdf

    monkeypatch.setattr("pkmkit.export.chain_masses.PLACEHOLDER_KG", 1e-9)
    m = pkmkit.machine(ident)
    names = {"tripteor-x7": ("Q1", "Q2", "Q5"), "trimule-600": ("Q1", "theta4", "Q5")}[ident]
    text = TRIPTEOR.split("[bodies.Q1]")[0] + "".join(
        f"[bodies.{n}]\nmass = {10 + k}\ncom = [{k * 10}, -20, 150]\n"
        f"inertia = [[0.5, 0.01, 0.0], [0.01, 0.6, 0.02], [0.0, 0.02, 0.3]]\n"
        for k, n in enumerate(names))
    masses = read_masses(_file(tmp_path, text), m)
    export = write_urdf(m, masses)
    assert export.inertial and "masses from masses.toml (4 bodies" in export.urdf
    robot = pin.buildModelFromXML(export.urdf)
    robot.gravity.linear[:] = masses.gravity
    pin_data = robot.createData()
    model = mujoco.MjModel.from_xml_string(chain_mjcf(m, masses).xml)
    data = mujoco.MjData(model)
    assert sum(robot.inertias[i].mass for i in range(robot.njoints)) == pytest.approx(
        60 + 10 + 11 + 12)
    for q in sample_configurations(m, 4, seed=2):
        values = joint_values(m, q)
        g_pin = pin.computeGeneralizedGravity(robot, pin_data,
                                              pinocchio_configuration(pin, robot, values))
        set_joint_values(model, data, values)
        mujoco.mj_forward(model, data)
        for jid in range(1, robot.njoints):
            name = robot.names[jid]
            dof = model.jnt_dofadr[model.joint(name).id]
            assert g_pin[robot.joints[jid].idx_v] == pytest.approx(
                data.qfrc_bias[dof], abs=1e-9 * np.abs(g_pin).max())
