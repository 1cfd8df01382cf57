"""The URDF export read back by Pinocchio (and by the pure-Python reader): at pkmkit's solved
configurations — actuators at its inverse model, passive joints from its geometry — every loop
of the closures YAML closes and the platform frame is pkmkit's pose (≤ 1e-9 m), on every
supported built-in, nominal and with random calibration-sized defects; the tree and closures
have exactly pkmkit's mobility; masses are the dynamics model's."""

from __future__ import annotations

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

import pkmkit
from pkmkit.dynamics.defaults import default_masses
from pkmkit.export.base import (
    ExportCheckError,
    UnsupportedExportError,
    platform_points,
    sample_poses,
)
from pkmkit.export.urdf import configuration, urdf_export
from pkmkit.export.urdf_check import check_urdf_export
from pkmkit.machines.registry import ALIASES
from pkmkit.model.defect_rule import defect_index

pin = pytest.importorskip("pinocchio")

SUPPORTED = ["delta", "dietmaier-hexapod", "gough-stewart", "linear-delta-ch3",
             "linear-delta-table-iv1", "orthoglide", "verne"]
TOL = 1e-9  # m


def _calibrated(machine, seed: int):
    """Random calibration-sized defects (0.2 mm, 1 mrad); a crank's axis kept (see
    :func:`test_a_tilted_crank_axis_is_refused`)."""
    index = defect_index(machine)
    rng = np.random.default_rng(seed)
    delta = np.where(np.asarray(index.units) == "m", 2e-4, 1e-3) * rng.standard_normal(
        len(index.names))
    if (machine.model.leg_kind == 2).any():
        delta = np.where(np.asarray(index.kind) == "axis", 0.0, delta)
    return machine.with_defects(delta)


def _load(export):
    model = pin.buildModelFromXML(export.urdf)
    pairs = yaml.safe_load(export.closures)["closed_loop"]
    return model, [tuple(model.getFrameId(n) for n in pair) for pair in pairs]


def _q(model, values: dict) -> np.ndarray:
    q = pin.neutral(model)
    for jid in range(1, model.njoints):
        joint, v = model.joints[jid], values[model.names[jid]]
        q[joint.idx_q:joint.idx_q + joint.nq] = [np.cos(v), np.sin(v)] if joint.nq == 2 else v
    return q


def test_the_supported_presets_are_exactly_these():
    exported = []
    for name in pkmkit.machines():
        if name in ALIASES:
            continue
        try:
            urdf_export(pkmkit.machine(name))
        except UnsupportedExportError as exc:
            assert exc.format == "urdf" and exc.reason
            continue
        exported.append(name)
    assert exported == SUPPORTED


@pytest.mark.parametrize("name", SUPPORTED)
@pytest.mark.parametrize("calibrated", [False, True], ids=["nominal", "calibrated"])
def test_pinocchio_closes_the_loops_at_pkmkits_configurations(name, calibrated):
    m = pkmkit.machine(name)
    if calibrated:
        m = _calibrated(m, seed=len(name))
    export = urdf_export(m)
    model, frames = _load(export)
    data = model.createData()
    assert {model.names[i] for i in range(1, model.njoints)} >= set(m.model.actuator_names)
    poses, q = sample_poses(m)
    assert len(poses) >= 10
    worst = 0.0
    for x, qk in zip(poses, q, strict=True):
        values = configuration(m, export, x, qk)
        assert [values[a] for a in m.model.actuator_names] == list(qk)
        pin.framesForwardKinematics(model, data, _q(model, values))
        for f1, f2 in frames:
            worst = max(worst, np.linalg.norm(data.oMf[f1].translation
                                              - data.oMf[f2].translation))
        p, rot, tips = platform_points(m, x)
        placement = data.oMf[model.getFrameId("platform")]
        assert np.abs(placement.translation - p).max() <= TOL
        assert np.abs(placement.rotation - rot).max() <= TOL
        for j in range(1, m.model.n_rods):  # the platform's joints where pkmkit puts them
            frame = data.oMf[model.getFrameId(f"platform_b{j + 1}")]
            assert np.abs(frame.translation - tips[j]).max() <= TOL
    assert worst <= TOL
    # the exporter's own check, through both readers, says the same
    assert check_urdf_export(m, export, use_pinocchio=True)[0] <= TOL
    assert check_urdf_export(m, export, use_pinocchio=False)[0] <= TOL


@pytest.mark.parametrize("name", SUPPORTED)
def test_the_tree_with_its_closures_has_pkmkits_mobility(name):
    """At a solved configuration the closures' Jacobian leaves exactly the actuators free: its
    passive columns are square and invertible (the actuators fix every other joint)."""
    m = pkmkit.machine(name)
    export = urdf_export(m)
    model, frames = _load(export)
    data = model.createData()
    poses, q = sample_poses(m)
    q_pin = _q(model, configuration(m, export, poses[-1], q[-1]))
    pin.computeJointJacobians(model, data, q_pin)
    pin.updateFramePlacements(model, data)
    frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    jac = np.vstack([pin.getFrameJacobian(model, data, f1, frame)[:3]
                     - pin.getFrameJacobian(model, data, f2, frame)[:3] for f1, f2 in frames])
    actuated = [model.joints[model.getJointId(a)].idx_v for a in m.model.actuator_names]
    passive = np.setdiff1d(np.arange(model.nv), actuated)
    assert jac.shape == (len(passive), model.nv)
    s = np.linalg.svd(jac[:, passive], compute_uv=False)
    assert s.min() > 1e-6 * s.max()


@pytest.mark.parametrize("name", ["linear-delta-table-iv1", "gough-stewart"])
def test_masses_are_the_dynamics_model(name):
    m = pkmkit.machine(name)
    masses = default_masses(m, tubes_at_home=name == "gough-stewart")
    model, _ = _load(urdf_export(m))
    armature = masses.carriage_mass.sum() if name == "gough-stewart" else 0.0
    total = sum(inertia.mass for inertia in model.inertias)
    assert total == pytest.approx(masses.total_mass - armature, rel=1e-12)
    closures = yaml.safe_load(urdf_export(m).closures)
    if name == "gough-stewart":  # the strut motors' inertia, which URDF cannot hold
        assert closures["armature"] == dict.fromkeys(m.model.actuator_names, 5.0)
    else:
        assert "armature" not in closures


def test_a_crank_delta_is_kinematic():
    export = urdf_export(pkmkit.machine("delta"))
    assert not export.inertial and "<inertial>" not in export.urdf
    model, _ = _load(export)
    assert sum(inertia.mass for inertia in model.inertias) == 0.0
    assert model.lowerPositionLimit[model.joints[model.getJointId("q1")].idx_q] == (
        pytest.approx(pkmkit.machine("delta").model.q_min[0]))


@pytest.mark.parametrize("name, words", [
    ("tripteor-x7", "joint-chain"), ("crank-slider", "joint-chain"),
    ("five-bar-isotropic", "urdf_planar")])
def test_machines_it_cannot_express_are_refused(name, words):
    with pytest.raises(UnsupportedExportError, match=words):
        urdf_export(pkmkit.machine(name))


def test_a_tilted_crank_axis_is_refused():
    """pkmkit's translational Delta keeps its platform translating (the legs' midlines); a
    tilted crank axis leaves a parallelogram's two rods unable to close so: not exported."""
    m = pkmkit.machine("delta")
    tilted = m.with_defects({"dw1y": 1e-3})
    with pytest.raises(UnsupportedExportError, match="misses its length"):
        urdf_export(tilted)


@pytest.mark.parametrize("use_pinocchio", [True, False], ids=["pinocchio", "python"])
def test_the_self_check_catches_a_tree_off_pkmkit(use_pinocchio):
    """:func:`check_urdf_export` (what ``pkmkit export --to urdf`` runs before writing): a
    platform joint moved by 1 µm opens its loop."""
    m = pkmkit.machine("gough-stewart")
    export = urdf_export(m)
    assert check_urdf_export(m, export, use_pinocchio=use_pinocchio)[0] <= TOL
    key = '<joint name="platform_b3_frame" type="fixed"><parent link="platform"/>' \
          '<child link="platform_b3"/><origin xyz="'
    start = export.urdf.index(key) + len(key)
    first = export.urdf[start:].split()[0]
    wrong = export.urdf[:start] + repr(float(first) + 1e-6) + export.urdf[start + len(first):]
    from dataclasses import replace

    with pytest.raises(ExportCheckError, match="not written"):
        check_urdf_export(m, replace(export, urdf=wrong), use_pinocchio=use_pinocchio)


def test_the_command_writes_the_tree_and_its_closures(tmp_path):
    from pkmkit.cli.main import cli

    out = tmp_path / "hexapod.urdf"
    res = CliRunner().invoke(cli, ["export", "gough-stewart", "--to", "urdf", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "read back with Pinocchio" in res.output
    closures = yaml.safe_load((tmp_path / "hexapod.closures.yaml").read_text())
    assert closures["name_mot"] == ["q1", "q2", "q3", "q4", "q5", "q6"]
    assert len(closures["closed_loop"]) == 5 and closures["type"] == ["3D"] * 5
    model = pin.buildModelFromUrdf(str(out))
    assert model.nq == 6 + 2 * (6 * 2 + 3)  # 6 prismatic, 15 continuous (cos, sin)
    masses = tmp_path / "m.toml"  # a refusal: pkmkit has no masses of joint chains
    masses.write_text("[masses]\nplatform = 1.0\n")
    res = CliRunner().invoke(cli, ["export", "tripteor-x7", "--to", "urdf", "--masses",
                                   str(masses), "--out", str(tmp_path / "t.urdf")])
    assert res.exit_code == 1 and not (tmp_path / "t.urdf").exists()
    assert not (tmp_path / "t.closures.yaml").exists()


def test_a_six_slide_hexapod_closes_its_loops(tmp_path):
    from .six_slides import six_slide_machine

    m = six_slide_machine(tmp_path)
    export = urdf_export(m)
    assert "carriage6" in export.urdf
    assert check_urdf_export(m, export, use_pinocchio=True)[0] <= TOL


def test_a_platform_turned_at_home_is_carried_turned(tmp_path):
    """The spherical joint's zero is the platform's home orientation (here turned 0.05 rad
    about z and 0.03 about x)."""
    from .six_slides import six_slide_machine

    six_slide_machine(tmp_path)
    path = tmp_path / "six-slides.toml"
    path.write_text(path.read_text().replace("home = [0, 0, -0.5, 0, 0, 0]",
                                             "home = [0, 0, -0.5, 0.03, 0, 0.05]"))
    m = pkmkit.load(path)
    assert np.abs(m.home_pose[3:] - [0.03, 0, 0.05]).max() == 0
    export = urdf_export(m)
    assert yaml.safe_load(export.closures)["home"]["rod1_sz"] == pytest.approx(0.0, abs=1e-12)
    assert check_urdf_export(m, export, use_pinocchio=True)[0] <= TOL


def test_masses_for_cranks_and_a_wrong_suffix_are_refused(tmp_path):
    from pkmkit.cli.main import cli

    m = pkmkit.machine("linear-delta-table-iv1")
    with pytest.raises(UnsupportedExportError, match="no mass model of crank"):
        urdf_export(pkmkit.machine("delta"), default_masses(m))
    res = CliRunner().invoke(cli, ["export", "orthoglide", "--to", "urdf", "--out",
                                   str(tmp_path / "o.xml")])
    assert res.exit_code == 2 and "NAME.urdf" in res.output
    assert not list(tmp_path.iterdir())


def _pinocchio_forces(model, frames, machine, export, x, q, qd, qdd) -> np.ndarray:
    """Actuator forces (n,) of the tree and its closures at pkmkit's configuration, speeds and
    accelerations: the passive joints' rates from the closures (J v = 0, J a + γ = 0), RNEA on
    the tree, then τ = S f + Jᵀ λ solved for (f, λ)."""
    data = model.createData()
    world = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    q_pin = _q(model, configuration(machine, export, x, q))
    act = [model.joints[model.getJointId(a)].idx_v for a in machine.model.actuator_names]
    passive = np.setdiff1d(np.arange(model.nv), act)
    pin.computeJointJacobians(model, data, q_pin)
    pin.updateFramePlacements(model, data)
    jac = np.vstack([pin.getFrameJacobian(model, data, a, world)[:3]
                     - pin.getFrameJacobian(model, data, b, world)[:3] for a, b in frames])
    v, a = np.zeros(model.nv), np.zeros(model.nv)
    v[act], a[act] = qd, qdd
    v[passive] = np.linalg.solve(jac[:, passive], -jac[:, act] @ qd)
    pin.forwardKinematics(model, data, q_pin, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    gamma = np.concatenate([pin.getFrameClassicalAcceleration(model, data, f1, world).linear
                            - pin.getFrameClassicalAcceleration(model, data, f2, world).linear
                            for f1, f2 in frames])
    a[passive] = np.linalg.solve(jac[:, passive], -jac[:, act] @ qdd - gamma)
    tau = pin.rnea(model, data, q_pin, v, a)
    select = np.zeros((model.nv, len(act)))
    select[act, np.arange(len(act))] = 1.0
    return np.linalg.solve(np.hstack([select, jac.T]), tau)[:len(act)]


@pytest.mark.parametrize("name", ["linear-delta-table-iv1", "orthoglide"])
def test_pinocchio_inverse_dynamics_is_pkmkits(name):
    """The written masses and inertias are the dynamics model's: Pinocchio's inverse dynamics of
    the tree, its closures enforced, gives pkmkit's actuator forces along a circle (gravity
    included)."""
    from pkmkit.dynamics import inverse_dynamics
    from pkmkit.motion import circle, joint_trajectory, plan

    m = pkmkit.machine(name)
    masses = default_masses(m)
    export = urdf_export(m, masses)
    model, frames = _load(export)
    radius = 0.05 if name == "orthoglide" else 0.15
    jt = joint_trajectory(m, plan(circle(m.home_pose, radius), feed=0.3, accel=2.0, jerk=20.0,
                                  period=0.01))
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    for k in range(0, len(jt.t), 25):
        f = _pinocchio_forces(model, frames, m, export, jt.x[k], jt.q[k], jt.qd[k], jt.qdd[k])
        np.testing.assert_allclose(f, res.force[k], rtol=1e-9, atol=1e-9)


def test_a_calibrated_machine_file_carries_its_defects(tmp_path):
    from pkmkit.cli.main import cli
    from pkmkit.io.machine_defects import write_machine_with_defects
    from pkmkit.machines.registry import preset_path

    nominal = pkmkit.machine("gough-stewart")
    delta = dict.fromkeys(defect_index(nominal).names, 0.0) | {"dA1x": 2e-4}
    path = tmp_path / "hexapod-calibrated.toml"
    write_machine_with_defects(path, preset_path("gough-stewart"), nominal,
                               np.array(list(delta.values())))
    res = CliRunner().invoke(cli, ["export", str(path), "--to", "urdf", "--out",
                                   str(tmp_path / "cal.urdf")])
    assert res.exit_code == 0, res.output
    model = pin.buildModelFromUrdf(str(tmp_path / "cal.urdf"))
    joint = model.getJointId("rod1_ux")
    np.testing.assert_allclose(model.jointPlacements[joint].translation,
                               nominal.model.rod_base[0] + [2e-4, 0, 0], atol=1e-15)
