"""URDF export of planar machines (export/urdf_planar.py): a tree that stays in the x-y plane
(carriages, rods on hinges about z, the platform on rod 1's tip), read back by Pinocchio and the
pure-Python reader, closes its loops and carries the platform at pkmkit's configurations;
Pinocchio's closure Jacobian has pkmkit's mobility; planted errors are caught."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

import pkmkit
from pkmkit.cli.main import cli
from pkmkit.export.base import ExportCheckError, UnsupportedExportError, sample_poses
from pkmkit.export.urdf import configuration
from pkmkit.export.urdf_check import check_urdf_export, pinocchio_configuration
from pkmkit.export.urdf_planar import planar_urdf_export
from pkmkit.export.urdf_writer import write_urdf
from pkmkit.model.defect_rule import defect_index

from .planar_files import TWO_RODS

pin = pytest.importorskip("pinocchio")

PLANAR = ["five-bar-biglide", "five-bar-isotropic"]


def _calibrated(machine, seed: int):
    """Random calibration-sized defects (0.2 mm, 1 mrad)."""
    index = defect_index(machine)
    rng = np.random.default_rng(seed)
    delta = np.where(np.asarray(index.units) == "m", 2e-4, 1e-3) * rng.standard_normal(
        len(index.names))
    return machine.with_defects(delta)


@pytest.mark.parametrize("name", PLANAR)
@pytest.mark.parametrize("calibrated", [False, True], ids=["nominal", "calibrated"])
@pytest.mark.parametrize("use_pinocchio", [True, False], ids=["pinocchio", "python"])
def test_the_loops_close_at_pkmkits_configurations(name, calibrated, use_pinocchio):
    m = pkmkit.machine(name)
    if calibrated:
        m = _calibrated(m, seed=len(name))
    export = write_urdf(m, name=name)
    worst, reader = check_urdf_export(m, export, use_pinocchio=use_pinocchio)
    assert worst < 1e-12 and reader == ("pinocchio" if use_pinocchio else "python")
    closures = yaml.safe_load(export.closures)
    assert closures["type"] == ["3D"] * 3 and closures["constrained"] == [["x", "y"]] * 3
    assert closures["name_mot"] == list(m.actuator_names)


@pytest.mark.parametrize("name", PLANAR)
def test_the_tree_stays_in_the_plane_with_pkmkits_mobility(name):
    """At a solved configuration: every frame at z = 0 with its z axis vertical; the closures'
    z rows vanish; nv − rank(J) = 2 (pkmkit's actuators) and the passive joints' columns have
    full rank (the actuators fix every passive joint)."""
    m = pkmkit.machine(name)
    export = planar_urdf_export(m)
    model = pin.buildModelFromXML(export.urdf)
    data = model.createData()
    poses, qs = sample_poses(m, 4, seed=2)
    x, q = poses[-1], qs[-1]
    values = configuration(m, export, x, q)
    pin.computeJointJacobians(model, data, pinocchio_configuration(pin, model, values))
    pin.updateFramePlacements(model, data)
    for frame in data.oMf:
        assert abs(frame.translation[2]) < 1e-15
        assert np.allclose(frame.rotation[:, 2], [0, 0, 1], atol=1e-15)
    rows = [pin.getFrameJacobian(model, data, model.getFrameId(a), pin.LOCAL_WORLD_ALIGNED)[:3]
            - pin.getFrameJacobian(model, data, model.getFrameId(b), pin.LOCAL_WORLD_ALIGNED)[:3]
            for a, b in export.closure_frames]
    jac = np.vstack(rows)
    assert np.abs(jac[2::3]).max() == 0.0  # the z rows
    rank = np.linalg.matrix_rank(jac, tol=1e-9 * np.abs(jac).max())
    assert model.nv - rank == m.n_actuators
    passive = [model.joints[model.getJointId(j.name)].idx_v for j in export.joints
               if j.role != "actuator"]
    assert np.linalg.matrix_rank(jac[:, passive], tol=1e-9 * np.abs(jac).max()) == len(passive)
    platform = data.oMf[model.getFrameId("platform")]
    np.testing.assert_allclose(platform.translation[:2], x, atol=1e-12)
    np.testing.assert_allclose(platform.rotation, np.eye(3), atol=1e-12)


@pytest.mark.parametrize("use_pinocchio", [True, False], ids=["pinocchio", "python"])
def test_planted_errors_are_caught(use_pinocchio):
    m = pkmkit.machine("five-bar-isotropic")
    export = planar_urdf_export(m)
    key = ('<joint name="rod3_tip_frame" type="fixed"><parent link="rod3"/>'
           '<child link="rod3_tip"/><origin xyz="')
    start = export.urdf.index(key) + len(key)
    first = export.urdf[start:].split()[0]
    wrong = export.urdf[:start] + repr(float(first) + 1e-6) + export.urdf[start + len(first):]
    with pytest.raises(ExportCheckError, match="not written"):
        check_urdf_export(m, replace(export, urdf=wrong), use_pinocchio=use_pinocchio)


def test_masses_are_the_dynamics_model():
    from pkmkit.dynamics.defaults import default_masses

    m = pkmkit.machine("five-bar-biglide")
    model = pin.buildModelFromXML(planar_urdf_export(m).urdf)
    masses = default_masses(m)
    assert sum(i.mass for i in model.inertias) == pytest.approx(masses.total_mass, rel=1e-12)


def test_struts_are_refused():
    """The planar tree holds slides (the five-bars): a strut leg is refused, not written."""
    from types import SimpleNamespace

    from pkmkit.model.rods import STRUT

    m = pkmkit.machine("five-bar-isotropic")
    kind = m.model.leg_kind.copy()
    kind[0] = STRUT
    strut = SimpleNamespace(model=replace(m.model, leg_kind=kind), id=m.id)
    with pytest.raises(UnsupportedExportError, match="slides are"):
        planar_urdf_export(strut)


def test_the_command(tmp_path):
    out = tmp_path / "five-bar.urdf"
    res = CliRunner().invoke(cli, ["export", "five-bar-isotropic", "--to", "urdf", "--out",
                                   str(out)])
    assert res.exit_code == 0, res.output
    assert "3 loop closures (3D)" in res.output and "Pinocchio" in res.output
    assert (tmp_path / "five-bar.closures.yaml").exists()


def test_a_planar_platform_on_two_rods_is_refused(tmp_path):
    path = tmp_path / "five.toml"
    path.write_text(TWO_RODS)
    with pytest.raises(UnsupportedExportError, match="planar platform on 2 rods"):
        write_urdf(pkmkit.load(path))


def _in_plane_forces(model, export, machine, x, q, qd, qdd) -> np.ndarray:
    """Actuator forces (n,) of the tree and its closures (their x, y rows) at pkmkit's
    configuration, speeds and accelerations: the passive joints' rates from the closures
    (J v = 0, J a + γ = 0, consistent least squares), RNEA on the tree, then τ = S f + Jᵀ λ
    (λ not unique: the parallelograms are redundant in rotation; f is)."""
    data = model.createData()
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    frames = [(model.getFrameId(a), model.getFrameId(b)) for a, b in export.closure_frames]
    q_pin = pinocchio_configuration(pin, model, configuration(machine, export, x, q))
    act = [model.joints[model.getJointId(a)].idx_v for a in machine.model.actuator_names]
    passive = np.setdiff1d(np.arange(model.nv), act)
    pin.computeJointJacobians(model, data, q_pin)
    pin.updateFramePlacements(model, data)
    jac = np.vstack([pin.getFrameJacobian(model, data, a, world)[:2]
                     - pin.getFrameJacobian(model, data, b, world)[:2] for a, b in frames])
    v, a = np.zeros(model.nv), np.zeros(model.nv)
    v[act], a[act] = qd, qdd
    v[passive] = np.linalg.lstsq(jac[:, passive], -jac[:, act] @ qd, rcond=None)[0]
    pin.forwardKinematics(model, data, q_pin, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    gamma = np.concatenate([pin.getFrameClassicalAcceleration(model, data, f1, world).linear[:2]
                            - pin.getFrameClassicalAcceleration(model, data, f2, world).linear[:2]
                            for f1, f2 in frames])
    a[passive] = np.linalg.lstsq(jac[:, passive], -jac[:, act] @ qdd - gamma, rcond=None)[0]
    assert np.abs(jac @ a + gamma).max() < 1e-9  # the closures hold in acceleration
    tau = pin.rnea(model, data, q_pin, v, a)
    select = np.zeros((model.nv, len(act)))
    select[act, np.arange(len(act))] = 1.0
    system = np.hstack([select, jac.T])
    solution = np.linalg.lstsq(system, tau, rcond=None)[0]
    assert np.abs(system @ solution - tau).max() < 1e-9 * max(1.0, np.abs(tau).max())
    return solution[:len(act)]


@pytest.mark.parametrize("name", PLANAR)
def test_pinocchio_inverse_dynamics_is_pkmkits(name):
    """The written masses and inertias are the dynamics model's: Pinocchio's inverse dynamics of
    the planar tree, its closures enforced, gives pkmkit's actuator forces along a circle."""
    from pkmkit.dynamics import inverse_dynamics
    from pkmkit.dynamics.defaults import default_masses
    from pkmkit.motion import circle, joint_trajectory, plan

    m = pkmkit.machine(name)
    masses = default_masses(m)
    export = planar_urdf_export(m, masses)
    model = pin.buildModelFromXML(export.urdf)
    jt = joint_trajectory(m, plan(circle(m.home_pose, 0.1), feed=0.3, accel=2.0, jerk=20.0,
                                  period=0.01))
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    assert np.abs(res.force).max() > 0.5  # the move loads the actuators
    for k in range(0, len(jt.t), 25):
        f = _in_plane_forces(model, export, m, jt.x[k], jt.q[k], jt.qd[k], jt.qdd[k])
        np.testing.assert_allclose(f, res.force[k], rtol=1e-9, atol=1e-9)
