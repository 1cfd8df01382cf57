"""Inverse dynamics against MuJoCo (used only as a test oracle) on the linear Delta."""

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics import inverse_dynamics, mass_properties, rod_section_mass
from pkmkit.motion import circle, helix, joint_trajectory, plan

from .mujoco_delta import MujocoDelta
from .mujoco_rods import MujocoRodMachine
from .test_inverse import MIXED_PLANAR, STRUT_TRIPOD


@pytest.fixture(scope="module")
def setup():
    m = pkmkit.machine("linear-delta-table-iv1")
    mass, radius, _ = rod_section_mass(m, 0.04, 1000.0)
    masses = mass_properties(m, carriage=8.0, rod=mass, rod_radius=radius, platform=15.0)
    tr = plan(circle([0, 0, 0.2], 0.15), feed=0.3, accel=2.0, jerk=20.0, period=0.01)
    jt = joint_trajectory(m, tr)
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    return m, masses, jt, res, MujocoDelta(m, masses)


def test_hard_constraint_dynamics_agree(setup):
    """MuJoCo's mass matrix, bias forces and loop-closure Jacobian, closures enforced exactly:
    the actuator forces agree to rounding along the whole circle."""
    _m, _masses, jt, res, mj = setup
    for k in range(0, len(jt.t), 20):
        f, residual = mj.hard_constraint_forces(jt.x[k], jt.xd[k], jt.xdd[k], jt.q[k],
                                                jt.qd[k], jt.qdd[k])
        assert residual < 1e-10
        np.testing.assert_allclose(f, res.force[k], rtol=1e-9)


def test_forward_simulation_agrees_within_one_percent(setup):
    """MuJoCo's own (soft-constraint) forward dynamics: the forces that produce the prescribed
    carriage accelerations agree within 1 % along the circle."""
    _m, _masses, jt, res, mj = setup
    for k in range(0, len(jt.t), 40):
        mj.set_state(jt.x[k], jt.xd[k], jt.q[k], jt.qd[k])
        assert mj.constraint_violation() < 1e-12
        f = mj.forces_for(jt.qdd[k])
        assert np.abs(f - res.force[k]).max() <= 0.01 * np.abs(res.force[k]).max()


@pytest.fixture(scope="module", params=["tripod", "mixed"])
def strut_setup(request, tmp_path_factory):
    """Machines with actuated struts (cylinder + piston tubes, motor inertia): a tripod of three
    struts with gravity off the vertical, and a planar slide + strut machine."""
    path = tmp_path_factory.mktemp("mj") / f"{request.param}.toml"
    if request.param == "tripod":
        path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n' + STRUT_TRIPOD)
        m = pkmkit.load(path)
        masses = mass_properties(m, carriage=0.3, rod=2.0, rod_radius=0.03, platform=4.0,
                                 piston=1.5, cylinder_length=0.7, piston_length=0.8,
                                 gravity=(0.5, -1.0, -9.81))
        tr = plan(helix([0.05, -0.03, -0.85], 0.1, pitch=0.05, turns=1.0), feed=0.4,
                  accel=3.0, jerk=40.0, period=2e-3)
    else:
        path.write_text(MIXED_PLANAR)
        m = pkmkit.load(path)
        masses = mass_properties(m, carriage=[3.0, 0.2], rod=[1.0, 2.5], rod_radius=0.02,
                                 platform=4.0, piston=[0.0, 1.2], cylinder_length=0.5,
                                 piston_length=0.45, gravity=(0.0, -9.81, 0.0))
        tr = plan(circle([0.55, -0.55, 0.0], 0.08), feed=0.4, accel=3.0, jerk=40.0,
                  period=2e-3)
    jt = joint_trajectory(m, tr)
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    return m, jt, res, MujocoRodMachine(m, masses)


def test_strut_machines_against_hard_constraint_mujoco(strut_setup):
    """Struts (cylinder hinged at the base, piston at the platform, both turning with the strut)
    against MuJoCo's mass matrix, bias forces and closure Jacobian: every actuator force agrees
    to 1e-9 relative along the move — tight enough for a 1e-5 error in any inertia."""
    _m, jt, res, mj = strut_setup
    scale = np.abs(res.force).max()
    for k in range(0, len(jt.t), max(len(jt.t) // 25, 1)):
        f, residual, violation = mj.hard_constraint_forces(
            jt.x[k], jt.xd[k], jt.xdd[k], jt.q[k], jt.qd[k], jt.qdd[k])
        assert residual < 1e-10 and violation < 1e-12
        np.testing.assert_allclose(f, res.force[k], rtol=0, atol=1e-9 * scale)
