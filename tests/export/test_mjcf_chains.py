"""MJCF export of joint-chain machines (export/mjcf_chains.py), loaded in MuJoCo: at pkmkit's
configurations the welds hold and the tool frame is pkmkit's; the motors, driven to pkmkit's
actuator values, settle the machine (MuJoCo closing the loops by its weld constraints) where
pkmkit's direct model puts the tool; planted errors are caught; what the model cannot hold is
refused."""

from __future__ import annotations

import re

import numpy as np
import pytest
from click.testing import CliRunner

import pkmkit
from pkmkit.cli.main import cli
from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.mjcf_chains import (
    LINK_MASS,
    ChainMjcf,
    chain_mjcf,
    check_chain_mjcf,
    set_joint_values,
    tool_transform,
)
from pkmkit.export.mjcf_writer import check_mjcf, write_mjcf
from pkmkit.export.urdf_chains import (
    chain_urdf_export,
    expected_tool,
    frame_error,
    joint_assembly,
    joint_values,
    sample_configurations,
)
from pkmkit.stiffness.chain_gravity import illustrative_masses

mujoco = pytest.importorskip("mujoco")

CHAINS = ["tripteor-x7", "trimule-600", "crank-slider"]
TOL = 1e-8  # m (issue 23 §3)


def _within_strokes(machine, qs: np.ndarray) -> np.ndarray:
    """The actuator vectors whose every joint (passive ones too) is within its stroke: MuJoCo's
    joint ranges then stay inactive."""
    model = machine.model
    keep = []
    for q in qs:
        v = np.array(list(joint_values(machine, q).values()))
        keep.append(bool(((v >= model.q_min) & (v <= model.q_max)).all()))
    return qs[np.array(keep)]


#: Servo gains (kp, kv) and damping of every degree of freedom that settle each machine: the
#: illustrative masses (a 80 kg head, 0.01 kg placeholder links) make a stiff system whose
#: gains are tuned per machine, as a real servo's.
GAINS = {"tripteor-x7": (2e5, 4e3, 1e3), "trimule-600": (1e6, 1e5, 0.0),
         "crank-slider": (1e6, 1e5, 0.0)}


class Settle:
    """Drive the joints to q, gravity off: the motors turned into MuJoCo position servos in
    memory (force kp (q − qpos) − kv q̇, the velocity term implicit), every degree of freedom
    damped as :data:`GAINS` says, 30 000 steps (3 s). At rest the damping and the velocity
    terms vanish and the equilibrium is the kinematics'."""

    def __init__(self, machine, ident: str):
        self.machine = machine
        self.export = chain_mjcf(machine)
        model = self.model = mujoco.MjModel.from_xml_string(self.export.xml)
        kp, kv, damping = GAINS[ident]
        model.opt.gravity[:] = 0.0
        model.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        model.dof_damping[:] = damping
        model.actuator_gaintype[:] = mujoco.mjtGain.mjGAIN_FIXED
        model.actuator_biastype[:] = mujoco.mjtBias.mjBIAS_AFFINE
        model.actuator_gainprm[:, 0] = kp
        model.actuator_biasprm[:, 1:3] = -kp, -kv
        self.data = mujoco.MjData(model)
        ids = [model.joint(j).id for j in self.export.actuator_joints]
        self.qadr = model.jnt_qposadr[ids]

    def run(self, q: np.ndarray, steps: int = 30_000) -> np.ndarray:
        self.data.ctrl[:] = q
        mujoco.mj_step(self.model, self.data, steps)
        return self.data.qpos[self.qadr].copy()


@pytest.mark.parametrize("ident", CHAINS)
def test_the_welds_hold_and_the_tool_is_pkmkit_at_its_configurations(ident):
    m = pkmkit.machine(ident)
    export = write_mjcf(m)
    assert isinstance(export, ChainMjcf)
    assert check_mjcf(m, export) < 1e-12
    model = mujoco.MjModel.from_xml_string(export.xml)
    # a joint per pkmkit variable, named as it; a motor per actuator on its joint
    assert sorted(model.joint(i).name for i in range(model.njnt)) == sorted(m.model.variables)
    assert [model.actuator(i).name for i in range(model.nu)] == list(m.actuator_names)
    assert [model.joint(model.actuator_trnid[i, 0]).name for i in range(model.nu)] == list(
        m.actuator_names)
    assert model.neq == len(m.model.legs) - 1
    assert (model.eq_type == mujoco.mjtEq.mjEQ_WELD).all()
    # the reference configuration is pkmkit's home, assembled
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    assert np.abs(data.efc_pos[: data.nefc]).max() < 1e-12
    values = joint_values(m, m.home_q)
    assert np.allclose([data.qpos[model.jnt_qposadr[model.joint(k).id]] for k in values],
                       list(values.values()), atol=0, rtol=0)


@pytest.mark.parametrize("ident", CHAINS)
def test_driven_motors_settle_the_tool_where_pkmkit_puts_it(ident):
    m = pkmkit.machine(ident)
    sim = Settle(m, ident)
    qs = _within_strokes(m, sample_configurations(m, 6, seed=1)[1:])
    q = qs[0]
    assert np.abs(q - m.home_q).max() > 1e-3  # the machine moves
    settled = sim.run(q)
    assert np.abs(settled - q).max() <= TOL
    tool = tool_transform(sim.data)  # the tool frame: position, orientation × 1 m
    _, at_settled = joint_assembly(m, settled)
    assert frame_error(np.linalg.inv(expected_tool(at_settled)) @ tool, 1.0) <= TOL
    values, res = joint_assembly(m, q)
    assert frame_error(np.linalg.inv(expected_tool(res)) @ tool, 1.0) <= 10 * TOL
    point = sim.data.site("tool_point").xpos
    np.testing.assert_allclose(point, m.fk(settled)[:3], atol=TOL, rtol=0)
    # every passive joint settled at pkmkit's direct model
    got = np.array([sim.data.qpos[sim.model.jnt_qposadr[sim.model.joint(k).id]] for k in values])
    assert np.abs(got - np.array(list(values.values()))).max() <= 1e-6


def test_the_tree_is_the_urdf_one():
    """One spanning tree (urdf_chains.chain_tree) for both formats: the same bodies in the same
    parent links."""
    m = pkmkit.machine("trimule-600")
    export = chain_mjcf(m)
    urdf = chain_urdf_export(m)
    parents = {child: parent for parent, child in re.findall(
        r'<parent link="(\w+)"/><child link="(\w+)"/>', urdf.urdf)}
    model = mujoco.MjModel.from_xml_string(export.xml)
    bodies = [model.body(i).name for i in range(1, model.nbody)]
    assert sorted(bodies) == sorted(b for b in parents if b.endswith("_body") or b == "platform")
    for body in bodies:
        parent = model.body(model.body_parentid[model.body(body).id]).name
        assert parents[body] == ("base" if parent == "world" else parent)
    for name in ("psi1",):  # the TriMule's shared ψ1: one body, legs 1, 3, 4 branch after it
        body = model.body(f"{name}_body").id
        assert sum(model.body_parentid[i] == body for i in range(model.nbody)) == 3


def test_masses_are_the_illustrative_lumped_ones():
    m = pkmkit.machine("tripteor-x7")
    model = mujoco.MjModel.from_xml_string(chain_mjcf(m).xml)
    lumped = illustrative_masses(m)
    platform = lumped.platform + 0.5 * lumped.legs.sum()
    assert model.body("platform").mass[0] == pytest.approx(platform, rel=1e-12)
    tool_body = model.site_bodyid[model.site("tool").id]
    assert model.body_mass[tool_body] == pytest.approx(lumped.head, rel=1e-12)
    others = model.nbody - 3  # world, platform, the head's last body
    assert model.body_mass.sum() == pytest.approx(platform + lumped.head + others * LINK_MASS,
                                                  rel=1e-12)
    assert np.allclose(model.opt.gravity, lumped.gravity)


def test_planted_errors_are_caught():
    m = pkmkit.machine("tripteor-x7")
    export = chain_mjcf(m)
    # θ3's body 1 µm off
    moved = re.sub(r'(<body name="theta3_body" pos=")([-0-9.e]+)',
                   lambda g: g.group(1) + repr(float(g.group(2)) + 1e-6), export.xml, count=1)
    assert moved != export.xml
    with pytest.raises(ExportCheckError, match="does not close"):
        check_chain_mjcf(m, ChainMjcf(**{**export.__dict__, "xml": moved}))
    # a weld's relative pose turned: the check reads the bodies, MuJoCo's residual sees it too
    turned = export.xml.replace('relpose="0 0 0 1 0 0 0"', 'relpose="0 0 0 1 0 0 0.001"', 1)
    with pytest.raises(ExportCheckError, match="does not close"):
        check_chain_mjcf(m, ChainMjcf(**{**export.__dict__, "xml": turned}))
    # a joint whose ref is not pkmkit's home value: qpos would not be pkmkit's joint value
    shifted = re.sub(r'(<joint name="Q2" type="slide" axis="0 0 1" ref=")([-0-9.e]+)',
                     lambda g: g.group(1) + repr(float(g.group(2)) + 1e-6), export.xml, count=1)
    assert shifted != export.xml
    with pytest.raises(ExportCheckError, match="does not close"):
        check_chain_mjcf(m, ChainMjcf(**{**export.__dict__, "xml": shifted}))


@pytest.mark.ci
def test_compatible_defects_are_exported_incompatible_ones_refused():
    m = pkmkit.machine("tripteor-x7")
    bent = m.with_defects({"dJ21": 2e-3, "db21": 1e-4, "dK12": 1e-3})
    misfit = float(np.max(bent.fk(bent.home_q, full_output=True).closure_residual))
    export = chain_mjcf(bent)
    assert export.xml != chain_mjcf(m).xml
    assert check_chain_mjcf(bent, export) <= 2 * misfit + 1e-9
    # driven, the soft welds share pkmkit's misfit: the tool settles within 2 × misfit + 1e-8 m
    sim = Settle(bent, "tripteor-x7")
    q = _within_strokes(bent, sample_configurations(bent, 6, seed=1)[1:])[0]
    settled = sim.run(q)
    assert np.abs(settled - q).max() <= TOL
    _, res = joint_assembly(bent, q)
    local = 2 * float(np.max(res.closure_residual))
    error = frame_error(np.linalg.inv(expected_tool(res)) @ tool_transform(sim.data), 1.0)
    assert error <= local + TOL
    with pytest.raises(UnsupportedExportError, match="least squares"):
        chain_mjcf(m.with_defects({"dK21": 1e-3}))


def test_joint_ranges_are_the_strokes():
    m = pkmkit.machine("trimule-600")
    model = mujoco.MjModel.from_xml_string(chain_mjcf(m).xml)
    for k, name in enumerate(m.model.variables):
        j = model.joint(name).id
        finite = bool(np.isfinite([m.model.q_min[k], m.model.q_max[k]]).all())
        assert bool(model.jnt_limited[j]) == finite
        if finite:
            assert tuple(model.jnt_range[j]) == (m.model.q_min[k], m.model.q_max[k])


def test_set_joint_values_puts_pkmkit_configuration():
    m = pkmkit.machine("crank-slider")
    export = chain_mjcf(m)
    model = mujoco.MjModel.from_xml_string(export.xml)
    data = mujoco.MjData(model)
    q = sample_configurations(m, 3)[2]
    values, res = joint_assembly(m, q)
    set_joint_values(model, data, values)
    mujoco.mj_forward(model, data)
    assert frame_error(np.linalg.inv(expected_tool(res)) @ tool_transform(data), 1.0) < 1e-12


def test_command_line(tmp_path):
    runner = CliRunner()
    out = tmp_path / "tripteor.xml"
    done = runner.invoke(cli, ["export", "tripteor-x7", "--to", "mjcf", "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert "illustrative lumped masses" in done.output and out.exists()
    masses = tmp_path / "m.toml"
    masses.write_text("[masses]\nplatform = 1.0\n")
    done = runner.invoke(cli, ["export", "tripteor-x7", "--to", "mjcf", "--masses", str(masses),
                               "--out", str(tmp_path / "t2.xml")])
    assert done.exit_code == 1 and not (tmp_path / "t2.xml").exists()
    assert "joint-chain" in done.output


@pytest.mark.parametrize("ident", CHAINS)
def test_the_weights_are_the_gravity_models(ident, monkeypatch):
    """MuJoCo's static actuator forces — at rest at pkmkit's configuration, its generalized
    gravity (``qfrc_bias``) = S τ + Jᵀ λ over the weld rows — are the virtual work of pkmkit's
    lumped masses (platform with half the legs at the platform frame, head at the tool frame,
    central differences of pkmkit's direct model), with the placeholder links made negligible
    (1e-9 kg) and gravity in a direction that loads every actuator."""
    monkeypatch.setattr("pkmkit.export.mjcf_chains.LINK_MASS", 1e-9)
    m = pkmkit.machine(ident)
    model = mujoco.MjModel.from_xml_string(chain_mjcf(m).xml)
    gravity = np.array([3.0, -4.0, -9.81])
    model.opt.gravity[:] = gravity
    data = mujoco.MjData(model)
    lumped = illustrative_masses(m)
    platform, head = lumped.platform + 0.5 * lumped.legs.sum(), lumped.head

    def potential(q: np.ndarray) -> float:
        res = m.fk(q, full_output=True, strokes="ignore")
        return -gravity @ (platform * np.ravel(res.platform)[:3]
                           + head * np.ravel(res.tool_frame)[:3])

    act = [model.jnt_dofadr[model.joint(a).id] for a in m.actuator_names]
    select = np.zeros((model.nv, len(act)))
    select[act, np.arange(len(act))] = 1.0
    for q in _within_strokes(m, sample_configurations(m, 6, seed=4)[1:])[:2]:
        set_joint_values(model, data, joint_values(m, q))
        mujoco.mj_forward(model, data)
        welds = data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY
        assert welds.all()  # no joint range active
        system = np.hstack([select, data.efc_J.reshape(data.nefc, model.nv).T])
        solution = np.linalg.lstsq(system, data.qfrc_bias, rcond=None)[0]
        assert np.abs(system @ solution - data.qfrc_bias).max() < 1e-9
        h = 1e-6
        expected = np.array([(potential(q + h * e) - potential(q - h * e)) / (2 * h)
                             for e in np.eye(len(q))])
        assert np.abs(expected).max() > 10.0  # the weights load the actuators
        np.testing.assert_allclose(solution[:len(act)], expected,
                                   atol=1e-8 * np.abs(expected).max(), rtol=0)
