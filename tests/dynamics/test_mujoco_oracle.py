"""Inverse dynamics against MuJoCo (used only as a test oracle) on the linear Delta."""

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics import inverse_dynamics, mass_properties, rod_section_mass
from pkmkit.motion import circle, joint_trajectory, plan

from .mujoco_delta import MujocoDelta


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
