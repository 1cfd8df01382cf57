"""MJCF export of planar rod-leg machines (the five-bars): the platform on a planar joint (two
slides and a hinge about z), each rod on a hinge about z, the loops closed by ``connect``
constraints; loaded in MuJoCo, the motors driven to pkmkit's inverse model settle the platform
where pkmkit's direct model puts it."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.mjcf import check_mjcf_model, mjcf_layout, mjcf_model
from pkmkit.model.defect_rule import defect_index

from .planar_files import TWO_RODS

mujoco = pytest.importorskip("mujoco")

PLANAR = ["five-bar-biglide", "five-bar-isotropic"]
TOL = 1e-8  # m


def _qpos(model, data, joint: str) -> float:
    return float(data.qpos[model.jnt_qposadr[model.joint(joint).id]])


def _calibrated(machine, seed: int):
    """Random calibration-sized defects (0.2 mm, 1 mrad)."""
    index = defect_index(machine)
    rng = np.random.default_rng(seed)
    delta = np.where(np.asarray(index.units) == "m", 2e-4, 1e-3) * rng.standard_normal(
        len(index.names))
    return machine.with_defects(delta)


@pytest.mark.parametrize("name", PLANAR)
@pytest.mark.parametrize("calibrated", [False, True], ids=["nominal", "calibrated"])
def test_driven_actuators_settle_the_platform_where_pkmkit_puts_it(name, calibrated):
    m = pkmkit.machine(name)
    if calibrated:
        m = _calibrated(m, seed=len(name))
    layout = mjcf_layout(m)
    assert check_mjcf_model(m, layout.xml) < 1e-12
    model = mujoco.MjModel.from_xml_string(layout.xml)
    model.opt.gravity[:] = 0.0
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert np.abs(data.efc_pos[: data.nefc]).max() < 1e-12  # home is assembled
    assert (_qpos(model, data, "platform_x"), _qpos(model, data, "platform_y")) == tuple(
        m.model.pad(m.home_pose[None])[0][:2])
    joints = [model.joint(j).id for j in layout.actuator_joints]
    qadr, dadr = model.jnt_qposadr[joints], model.jnt_dofadr[joints]
    target = m.home_pose + np.array([0.03, -0.02])
    q = m.ik(target)
    for _ in range(20_000):
        data.ctrl[:] = 2e5 * (q - data.qpos[qadr]) - 4e3 * data.qvel[dadr]
        mujoco.mj_step(model, data)
    pose = np.array([_qpos(model, data, "platform_x"), _qpos(model, data, "platform_y")])
    assert np.abs(data.qpos[qadr] - q).max() <= TOL
    assert np.abs(pose - target).max() <= TOL
    assert np.abs(pose - m.fk(data.qpos[qadr])).max() <= TOL
    assert abs(_qpos(model, data, "platform_rz")) <= TOL  # the parallelograms hold it
    assert np.abs(data.xpos[:, 2]).max() <= 1e-12  # nothing leaves the plane


def test_the_self_check_catches_a_rod_off_pkmkit():
    m = pkmkit.machine("five-bar-isotropic")
    xml = mjcf_model(m)
    key = '<connect body1="rod2" body2="platform" anchor="'
    start = xml.index(key) + len(key)
    first = xml[start:].split()[0]
    wrong = xml[:start] + repr(float(first) + 1e-6) + xml[start + len(first):]
    with pytest.raises(ExportCheckError, match="not written"):
        check_mjcf_model(m, wrong)


def test_a_planar_platform_on_two_rods_is_refused(tmp_path):
    """Two single rods leave MuJoCo's platform free to turn (pkmkit takes it as translating)."""
    path = tmp_path / "five.toml"
    path.write_text(TWO_RODS)
    m = pkmkit.load(path)
    assert m.export_layout == "planar" and m.model.n_rods == 2
    with pytest.raises(UnsupportedExportError, match="planar platform on 2 rods"):
        mjcf_model(m)
