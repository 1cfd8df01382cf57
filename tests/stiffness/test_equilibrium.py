"""The loaded equilibrium (:mod:`pkmkit.stiffness.equilibrium`) against independent solutions:
the force and moment balance of a cubic hexapod's struts solved here, and the minimum of the
drives' energy minus the work of a force through the machine's direct model (rigid rods)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import ConvergenceError, InputError
from pkmkit.machines.registry import machine
from pkmkit.status import Status
from pkmkit.stiffness import Section, default_data
from pkmkit.stiffness.equilibrium import loaded_equilibrium

from .helpers import cubic_hexapod

A, K_A = 0.5, 5e7
X0 = np.array([0.01, -0.02, 0.015, 0.02, 0.01, -0.03])
WRENCH = np.array([300.0, -200.0, 800.0, 20.0, -15.0, 10.0])


def _hexapod():
    m = cubic_hexapod(A)
    section = Section.circle(0.02)
    data = dataclasses.replace(default_data(m), actuator_stiffness=np.full(6, K_A),
                               rod_section=section)
    return m, data, 210e9 * section.area


def _balance(m, x0, k_a, ea, wrench, r):
    """The reference point's displacement and the platform rotation under ``wrench`` at the
    platform point ``r``: struts (drive k_a in series with a rod EA/ℓ₀), unknowns δp, the
    rotation vector of R R0ᵀ and the drives' deflections; forces and moments about p."""
    model = m.model
    q0 = m.ik(x0)
    k_r = ea / q0
    r0 = Rotation.from_rotvec(x0[3:]).as_matrix()

    def residual(u):
        p = x0[:3] + u[:3]
        rot = Rotation.from_rotvec(u[3:6]).as_matrix() @ r0
        out = np.zeros(12)
        total_f = wrench[:3].copy()
        total_m = wrench[3:] + np.cross(rot @ r, wrench[:3])
        for j in range(6):
            b = rot @ model.rod_platform[j]
            d = p + b - model.rod_base[j]
            tension = k_r[j] * (np.linalg.norm(d) - q0[j] - u[6 + j])
            total_f -= tension * d / np.linalg.norm(d)
            total_m -= np.cross(b, tension * d / np.linalg.norm(d))
            out[6 + j] = (k_a * u[6 + j] - tension) / k_a
        out[:3], out[3:6] = total_f / k_a, total_m / k_a
        return out

    u = least_squares(residual, np.zeros(12), xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    rot = Rotation.from_rotvec(u[3:6]).as_matrix() @ r0
    return np.concatenate([u[:3] + rot @ r - r0 @ r, u[3:6]])


@pytest.mark.parametrize("r", [None, [0.02, -0.05, -0.15]])
def test_cubic_hexapod_equilibrium_and_the_square_law(r):
    m, data, ea = _hexapod()
    offset = np.zeros(3) if r is None else np.asarray(r)
    gaps = []
    for scale in (1.0, 2.0, 4.0):
        w = WRENCH * scale
        got = loaded_equilibrium(m, X0, w, data=data, reference=r)
        exact = _balance(m, X0, K_A, ea, w, offset)
        assert got.status == Status.OK
        gap = np.abs(exact - got.linear).max()
        # the loaded equilibrium is the exact one to a millionth of the geometric term
        np.testing.assert_allclose(got.loaded, exact, rtol=0, atol=1e-5 * gap)
        np.testing.assert_allclose(got.difference, got.loaded - got.linear, rtol=1e-15)
        gaps.append(np.abs(got.difference).max())
    # second order in the load: four times larger at twice the load
    assert 3.9 < gaps[1] / gaps[0] < 4.1 and 3.9 < gaps[2] / gaps[1] < 4.1
    assert 0 < got.share < 1e-3


def _drive_energy_minimum(m, x0, force, h=1e-7):
    """Rigid rods: δq minimising ½ δqᵀ K_q δq − F·(fk(q0 + δq) − x0), the platform by the
    machine's own direct model; stationarity K_q δq = J(q)ᵀ F with J by central differences."""
    k = default_data(m).actuator_stiffness
    q0 = np.asarray(m.ik(x0), dtype=float)

    def jac(q):
        cols = [(m.fk(q + h * e) - m.fk(q - h * e)) / (2 * h) for e in np.eye(len(q))]
        return np.array(cols).T

    def residual(dq):
        return (k * dq - jac(q0 + dq).T @ force) / k

    dq = least_squares(residual, np.zeros(len(q0)), xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    return m.fk(q0 + dq) - x0


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta", "five-bar"])
def test_rigid_rods_against_the_direct_model(name):
    m = machine(name)
    data = dataclasses.replace(default_data(m), rod_section=None)
    x0 = m.home_pose + 0.03 * np.arange(1, m.dims + 1) / m.dims
    force = np.array([40000.0, -30000.0, 50000.0])[:m.dims]  # shares of 1e-4 to 1e-3
    got = loaded_equilibrium(m, x0, force, data=data)
    exact = _drive_energy_minimum(m, x0, force)
    gap = np.abs(exact - got.linear).max()
    assert gap > 1e-4 * np.abs(exact).max()  # a geometric term worth resolving
    np.testing.assert_allclose(got.loaded, exact, rtol=0, atol=1e-4 * gap)


def test_rigid_rod_hexapod_and_verne_converge_and_batches_match():
    for name, pose in (("gough-stewart", np.array([0.01, 0.02, 0.8, 0.05, -0.03, 0.02])),
                       ("verne", np.array([0.01, -0.02, 0.01]))):
        m = machine(name)
        w = np.array([500.0, -300.0, -1000.0, 30.0, -20.0, 10.0])
        one = loaded_equilibrium(m, pose, w)
        assert one.status == Status.OK and 0 < one.share < 1e-2
        batch = loaded_equilibrium(m, np.array([pose, pose * 0.5]), w)
        np.testing.assert_allclose(batch.loaded[0], one.loaded, rtol=1e-9, atol=1e-18)


def test_no_equilibrium_is_flagged_not_converged():
    """A load that buckles the machine far beyond the small-displacement range: the Newton
    steps from the linear solution find no equilibrium (the flag, not a number)."""
    m, data, _ = _hexapod()
    got = loaded_equilibrium(m, np.array([X0, X0]), np.array([WRENCH, WRENCH * 1e6]), data=data)
    assert got.status.tolist() == [Status.OK, Status.NOT_CONVERGED]
    assert np.isnan(got.loaded[1]).all() and np.isfinite(got.linear[1]).all()
    with pytest.raises(ConvergenceError, match="no loaded equilibrium"):
        loaded_equilibrium(m, X0, WRENCH * 1e6, data=data)  # one pose: a typed error


def test_joint_chains_and_cranks_are_refused():
    with pytest.raises(InputError, match="joint-chain"):
        m = machine("tripteor-x7")
        loaded_equilibrium(m, m.home_pose, np.zeros(6))
    with pytest.raises(InputError, match="crank"):
        m = machine("delta")
        loaded_equilibrium(m, m.home_pose, np.zeros(3))


def test_rows_converging_at_different_steps_match_single_calls():
    """A batch whose rows need different numbers of Newton steps (a zero load is done at once):
    each row is its single-pose equilibrium."""
    m, data, _ = _hexapod()
    poses = np.array([X0, X0 * 0.5, X0])
    loads = np.array([WRENCH * 0.0, WRENCH, WRENCH * 50.0])
    batch = loaded_equilibrium(m, poses, loads, data=data)
    assert len(set(batch.iterations.tolist())) > 1
    for k in range(3):
        one = loaded_equilibrium(m, poses[k], loads[k], data=data)
        np.testing.assert_allclose(batch.loaded[k], one.loaded, rtol=1e-12, atol=0)
    np.testing.assert_array_equal(batch.loaded[0], 0.0)
