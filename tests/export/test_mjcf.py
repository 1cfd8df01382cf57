"""The MJCF export loaded in MuJoCo: the actuators, driven to pkmkit's inverse model of a pose,
settle the platform where pkmkit's direct model puts it (MuJoCo closing the loops itself, by its
equality constraints); masses as the dynamics model gives them. The inverse dynamics through
the same writer: tests/dynamics/test_mujoco_oracle.py."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.dynamics.defaults import default_masses
from pkmkit.export.base import ExportCheckError, UnsupportedExportError
from pkmkit.export.mjcf import check_mjcf_model, mjcf_layout, mjcf_model
from pkmkit.export.mjcf_writer import write_mjcf
from pkmkit.machines.registry import ALIASES
from pkmkit.model.defects_table import apply_defect_vector, defect_index
from pkmkit.model.rods import CRANK

mujoco = pytest.importorskip("mujoco")

SUPPORTED = ["delta", "dietmaier-hexapod", "gough-stewart", "linear-delta-ch3",
             "linear-delta-table-iv1", "orthoglide", "verne"]
#: Planar machines (tests/export/test_mjcf_planar.py).
PLANAR = ["five-bar-biglide", "five-bar-isotropic"]
#: Written by export/mjcf_chains.py (tests/export/test_mjcf_chains.py).
CHAINS = ["crank-slider", "trimule-600", "tripteor-x7"]
TOL = 1e-8  # m


def _calibrated(machine, seed: int):
    """Random calibration-sized defects (0.2 mm, 1 mrad); a crank's axis kept (a tilted one is
    refused: :func:`test_a_tilted_crank_axis_is_refused`)."""
    index = defect_index(machine)
    rng = np.random.default_rng(seed)
    delta = np.where(np.asarray(index.units) == "m", 2e-4, 1e-3) * rng.standard_normal(
        len(index.names))
    if (machine.model.leg_kind == CRANK).any():
        delta = np.where(np.asarray(index.kind) == "axis", 0.0, delta)
    return apply_defect_vector(machine, delta)


def _points(machine, pose: np.ndarray) -> np.ndarray:
    """Platform joint centres (rods, 3) of a pose (m): one metric for every machine."""
    rot = (Rotation.from_rotvec(np.array(pose[3:])).as_matrix() if len(pose) == 6 else np.eye(3))
    return pose[:3] + machine.model.rod_platform @ rot.T


class Simulation:
    def __init__(self, machine):
        self.machine = machine
        self.layout = mjcf_layout(machine)
        self.model = mujoco.MjModel.from_xml_string(self.layout.xml)
        self.data = mujoco.MjData(self.model)
        joints = [self.model.joint(j).id for j in self.layout.actuator_joints]
        self.qadr = self.model.jnt_qposadr[joints]
        self.dadr = self.model.jnt_dofadr[joints]
        free = self.model.body("platform").jntadr[0]
        self.padr = self.model.jnt_qposadr[free]

    def settle(self, q: np.ndarray, steps: int = 20_000) -> tuple[np.ndarray, np.ndarray]:
        """Drive the motors to q (a stiff PD loop), let everything settle, gravity off: the
        settled actuator coordinates and platform pose (pkmkit's form)."""
        self.model.opt.gravity[:] = 0.0
        d = self.data
        for _ in range(steps):
            d.ctrl[:] = 2e5 * (q - d.qpos[self.qadr]) - 4e3 * d.qvel[self.dadr]
            mujoco.mj_step(self.model, d)
        a = self.padr
        w, x, y, z = d.qpos[a + 3:a + 7]
        pose = d.qpos[a:a + 3].copy()
        if self.machine.dims == 6:
            pose = np.concatenate([pose, Rotation.from_quat([x, y, z, w]).as_rotvec()])
        return d.qpos[self.qadr].copy(), pose

    def violation(self) -> float:
        mujoco.mj_forward(self.model, self.data)
        return float(np.abs(self.data.efc_pos[: self.data.nefc]).max())


def test_the_supported_presets_are_exactly_these():
    exported = []
    for name in pkmkit.machines():
        if name in ALIASES:
            continue
        try:
            write_mjcf(pkmkit.machine(name))
        except UnsupportedExportError as exc:
            assert exc.format == "mjcf" and exc.reason
            continue
        exported.append(name)
    assert exported == sorted(SUPPORTED + CHAINS + PLANAR)


# the first machine in the ordinary run, the others marked ci (.ci/run): 0.35 s each
@pytest.mark.parametrize("name", [pytest.param(n, marks=[pytest.mark.ci] if k else [])
                                  for k, n in enumerate(SUPPORTED)])
@pytest.mark.parametrize("calibrated", [False, True], ids=["nominal", "calibrated"])
def test_driven_actuators_settle_the_platform_where_pkmkit_puts_it(name, calibrated):
    m = pkmkit.machine(name)
    if calibrated:
        m = _calibrated(m, seed=len(name))
    sim = Simulation(m)
    assert sim.violation() < 1e-12  # the reference configuration is assembled
    rng = np.random.default_rng(len(name))
    target = m.home_pose[:3] + rng.uniform(-0.03, 0.03, 3)
    if m.dims == 6 and not m.position_controlled:
        turn = Rotation.from_rotvec(rng.uniform(-1, 1, 3) * np.radians(2))
        target = np.concatenate([target, (turn * Rotation.from_rotvec(m.home_pose[3:]))
                                 .as_rotvec()])
    res = m.ik(target, full_output=True)
    q = np.asarray(res.q)
    q_settled, pose = sim.settle(q)
    assert np.abs(q_settled - q).max() <= TOL
    expected = (m.fk(q_settled) if m.dims == 3 else m.fk(q_settled, x0=pose))
    assert np.abs(_points(m, pose) - _points(m, expected)).max() <= TOL
    full = target if len(target) == m.dims else np.asarray(res.pose)
    assert np.abs(_points(m, pose) - _points(m, full)).max() <= TOL
    assert sim.violation() <= TOL


@pytest.mark.parametrize("name", ["linear-delta-table-iv1", "gough-stewart"])
def test_masses_are_the_dynamics_model(name):
    m = pkmkit.machine(name)
    masses = default_masses(m, tubes_at_home=name == "gough-stewart")
    sim = Simulation(m)
    model = sim.model
    armature = masses.carriage_mass.sum() if name == "gough-stewart" else 0.0
    assert model.body_mass.sum() == pytest.approx(masses.total_mass - armature, rel=1e-12)
    assert model.body("platform").mass[0] == pytest.approx(masses.platform_mass, rel=1e-12)
    if name == "gough-stewart":  # the motor's translating inertia is the piston joint's armature
        dof = model.jnt_dofadr[model.joint("act0").id]
        assert model.dof_armature[dof] == pytest.approx(masses.carriage_mass[0])
    else:
        assert model.body("carriage0").mass[0] == pytest.approx(masses.carriage_mass[0])


def test_the_delta_robot_has_arms_with_illustrative_masses():
    """The cranks are arm bodies on hinges (qpos pkmkit's crank angle); the masses are the
    illustrative ones of export/mjcf_cranks.py, and the file says so."""
    from pkmkit.export.mjcf_cranks import DENSITY, DIAMETER, PLATFORM_KG, arm_length

    m = pkmkit.machine("delta")
    xml = mjcf_model(m)
    assert "illustrative masses" in xml and "no mass model of crank" in xml
    assert check_mjcf_model(m, xml) < 1e-12  # rods closed with the arms turned (samples)
    model = mujoco.MjModel.from_xml_string(xml)
    area = np.pi / 4 * DIAMETER**2
    for k in range(3):
        assert model.joint(f"act{k}").type[0] == mujoco.mjtJoint.mjJNT_HINGE
        arm = model.body(f"arm{k}")
        assert arm.mass[0] == pytest.approx(DENSITY * area * arm_length(m, k), rel=1e-12)
        assert model.qpos0[model.jnt_qposadr[model.joint(f"act{k}").id]] == m.home_q[k]
    rods = DENSITY * area * m.model.rod_length.sum()
    assert model.body_mass.sum() == pytest.approx(
        rods + PLATFORM_KG + sum(model.body(f"arm{k}").mass[0] for k in range(3)), rel=1e-12)


def test_the_delta_robot_takes_given_masses_and_refuses_a_tilted_crank_axis(tmp_path):
    """Given masses (a masses file's): the arms weigh its carriage masses, the rods and the
    platform its own, and the file says what was assumed of the arms."""
    from pkmkit.dynamics.masses import mass_properties

    m = pkmkit.machine("delta")
    masses = mass_properties(m, carriage=[1.0, 1.5, 2.0], rod=0.5, rod_radius=0.01,
                             platform=2.0)
    xml = mjcf_model(m, masses)
    assert "masses of the masses file" in xml and "illustrative masses" not in xml
    model = mujoco.MjModel.from_xml_string(xml)
    assert [model.body(f"arm{k}").mass[0] for k in range(3)] == pytest.approx([1.0, 1.5, 2.0])
    assert [model.body(f"rod{j}").mass[0] for j in range(6)] == pytest.approx([0.5] * 6)
    assert model.body("platform").mass[0] == pytest.approx(2.0)
    assert check_mjcf_model(m, xml) < 1e-12
    with pytest.raises(UnsupportedExportError, match="misses its length"):
        mjcf_model(m.with_defects({"dw1y": 1e-3}))


def test_a_platform_on_three_single_rods_is_refused(tmp_path):
    path = tmp_path / "tripod.toml"
    angles = np.radians([0.0, 120.0, 240.0])
    path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, 0]\n' + "".join(
        f'[[legs]]\ntype = "slide"\nbase = [{0.55 * np.cos(a):.9f}, {0.55 * np.sin(a):.9f}, 0]'
        f'\naxis = [0, 0, 1]\nplatform = [0, 0, 0]\nlength = 1.04\n' for a in angles))
    with pytest.raises(UnsupportedExportError, match="3 rods"):
        mjcf_model(pkmkit.load(path))


def test_the_self_check_catches_a_model_off_pkmkit():
    """:func:`check_mjcf_model` (what ``pkmkit export --to mjcf`` runs before writing): a rod tip
    moved by 1 µm leaves the home configuration unassembled."""
    m = pkmkit.machine("linear-delta-table-iv1")
    xml = mjcf_model(m)
    assert check_mjcf_model(m, xml) <= 1e-9
    start = xml.index('<connect body1="rod0" body2="platform" anchor="') + len(
        '<connect body1="rod0" body2="platform" anchor="')
    first = xml[start:].split()[0]
    wrong = xml[:start] + repr(float(first) + 1e-6) + xml[start + len(first):]
    with pytest.raises(ExportCheckError, match="not written"):
        check_mjcf_model(m, wrong)


@pytest.mark.ci
def test_a_six_slide_hexapod_settles_where_pkmkit_puts_it(tmp_path):
    from .six_slides import six_slide_machine

    m = six_slide_machine(tmp_path)
    sim = Simulation(m)
    target = m.home_pose + np.array([0.02, -0.01, 0.015, 0.02, -0.01, 0.03])
    q = m.ik(target)
    q_settled, pose = sim.settle(q)
    assert np.abs(q_settled - q).max() <= TOL
    assert np.abs(_points(m, pose) - _points(m, target)).max() <= TOL


def test_mujocos_refusal_is_one_line(tmp_path):
    """A masses file whose platform inertia breaks the triangle inequality: MuJoCo's two-line
    message ended the output without 'Error:' on its last line (issue 18 §7 fuzz)."""
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    masses = tmp_path / "m.toml"
    masses.write_text("[masses]\ncarriage = [1, 2, 3]\nrod = 0.5\nplatform = 3\n"
                      "platform_inertia = [[10, 0, 0], [0, 1, 0], [0, 0, 1]]\n")
    out = tmp_path / "model.xml"
    res = CliRunner().invoke(cli, ["export", "linear-delta", "--to", "mjcf", "--masses",
                                   str(masses), "--out", str(out)])
    assert res.exit_code == 1 and not out.exists()
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: MuJoCo refuses the generated model")
    assert "A + B >= C" in lines[0] and "Element name 'platform'" in lines[0]


def test_the_command_says_the_delta_masses_are_illustrative(tmp_path):
    from click.testing import CliRunner

    from pkmkit.cli.main import cli

    out = tmp_path / "delta.xml"
    res = CliRunner().invoke(cli, ["export", "delta", "--to", "mjcf", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "illustrative masses: pkmkit has no mass model of crank actuators" in res.output
    assert "loaded in MuJoCo" in res.output and out.exists()
