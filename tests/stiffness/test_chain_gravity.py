"""Weight-induced deflection of joint-chain machines against independent oracles."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.machines.registry import machine
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix
from pkmkit.stiffness import Section, default_data, stiffness
from pkmkit.stiffness.chain_gravity import (
    ChainMasses,
    chain_gravity_deflection,
    generalized_gravity,
    illustrative_masses,
)
from pkmkit.stiffness.joint_chains import assemble

G = np.array([0.0, 0.0, -9.81])


def _configurations(m, count=3, seed=1):
    rng = np.random.default_rng(seed)
    q = np.tile(m.home_q, (count, 1))
    q[1:] += rng.uniform(-0.01, 0.01, (count - 1, m.n_actuators))
    return q


def _frames(m, q):
    """Tool point, tool rotation, platform origin and spindle nose from ``fk`` alone."""
    r = m.fk(q, full_output=True, strokes="ignore")
    tool_frame = np.asarray(r.tool_frame)
    return (np.asarray(r.pose)[:3], rotvec_to_matrix(tool_frame[3:])[0],
            np.asarray(r.platform)[:3], tool_frame[:3])


def _kinematic_oracle(m, q, masses, h=1e-6):
    """Rigid links: the drives are the only springs. The weights' generalized forces on the
    actuators are −∂V/∂q (V the potential energy of the lumped masses, central differences of
    fk), each drive yields by Q_j/k_j, and the tool follows by its Jacobian (central
    differences of fk): an independent model from the kinematics alone."""
    n = m.n_actuators
    k_a = default_data(m).actuator_stiffness
    f_p = (masses.platform + 0.5 * masses.legs.sum()) * masses.gravity
    f_h = masses.head * masses.gravity
    jac = np.zeros((6, n))
    load = np.zeros(n)
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        tp, rp, pp, np_ = _frames(m, q + dq)
        tm, rm, pm, nm = _frames(m, q - dq)
        jac[:3, j] = (tp - tm) / (2 * h)
        jac[3:, j] = matrix_to_rotvec(rp @ rm.T)[0] / (2 * h)
        load[j] = (f_p @ (pp - pm) + f_h @ (np_ - nm)) / (2 * h)  # −∂V/∂q_j
    return jac @ (load / k_a)


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_rigid_links_match_the_kinematics(name):
    m = machine(name)
    masses = illustrative_masses(m)
    q = _configurations(m)
    defl, status = chain_gravity_deflection(m, q, masses)
    assert (status == 0).all()
    for i in range(len(q)):
        oracle = _kinematic_oracle(m, q[i], masses)
        np.testing.assert_allclose(defl[i], oracle, rtol=1e-6,
                                   atol=1e-6 * np.abs(oracle).max())


def test_head_weight_alone_is_the_compliance_times_its_wrench():
    """Compliant links, only the head's weight: the load is a wrench on the tool's body, so the
    deflection is the public stiffness() compliance times that wrench moved to the tool
    point."""
    m = machine("tripteor-x7")
    data = dataclasses.replace(default_data(m), link_section=Section.tube(0.12, 0.10))
    masses = ChainMasses(0.0, 80.0, np.zeros(3), G)
    q = _configurations(m)
    defl, _ = chain_gravity_deflection(m, q, masses, data=data)
    r = stiffness(m, q=q, data=data)
    for i in range(len(q)):
        point, _, _, nose = _frames(m, q[i])
        f = 80.0 * G
        w = np.concatenate([f, np.cross(nose - point, f)])
        np.testing.assert_allclose(defl[i], r.compliance[i] @ w, rtol=1e-9,
                                   atol=1e-9 * np.abs(defl[i]).max())


def test_compliant_links_match_a_lagrange_multiplier_solution():
    """Compliant links, all weights: min ½zᵀHz − Qᵀz subject to Gz = 0 solved with Lagrange
    multipliers (least squares of the full KKT system, the redundant rows kept) — not the
    null-space basis of the module."""
    m = machine("tripteor-x7")
    data = dataclasses.replace(default_data(m), link_section=Section.tube(0.12, 0.10))
    masses = illustrative_masses(m)
    q = _configurations(m)
    defl, _ = chain_gravity_deflection(m, q, masses, data=data)
    system = assemble(m, q, data)
    load = generalized_gravity(system, masses, m.tool_length)
    for i in range(len(q)):
        g, h = system.G[i], system.H[i]
        r, nz = g.shape
        scale = np.abs(h).max()  # multipliers in the units of H: a balanced matrix
        kkt = np.block([[h, scale * g.T], [scale * g, np.zeros((r, r))]])
        sol = np.linalg.lstsq(kkt, np.concatenate([load[i], np.zeros(r)]), rcond=1e-14)[0]
        np.testing.assert_allclose(defl[i], system.T[i] @ sol[:nz], rtol=1e-7,
                                   atol=1e-7 * np.abs(defl[i]).max())


def test_stiffer_drives_deflect_less_and_zero_mass_does_not_deflect():
    m = machine("tripteor-x7")
    masses = illustrative_masses(m)
    base, _ = chain_gravity_deflection(m, m.home_q, masses)
    stiff = dataclasses.replace(default_data(m),
                                actuator_stiffness=default_data(m).actuator_stiffness * 2)
    half, _ = chain_gravity_deflection(m, m.home_q, masses, data=stiff)
    np.testing.assert_allclose(half, base / 2, rtol=1e-9)
    none, _ = chain_gravity_deflection(m, m.home_q, ChainMasses(0.0, 0.0, np.zeros(3), G))
    np.testing.assert_array_equal(none, 0.0)


def test_bad_masses_are_refused():
    m = machine("tripteor-x7")
    with pytest.raises(InputError, match="leg masses"):
        chain_gravity_deflection(m, m.home_q, ChainMasses(1.0, 1.0, np.zeros(2), G))
    with pytest.raises(InputError, match="head mass"):
        chain_gravity_deflection(m, m.home_q, ChainMasses(1.0, -1.0, np.zeros(3), G))
    # finite but absurd: 1e308 kg gave inf/nan deflections with overflow warnings
    with pytest.raises(InputError, match=r"platform mass = 1e\+308 kg is beyond 1e\+06 kg"):
        chain_gravity_deflection(m, m.home_q, ChainMasses(1e308, 1.0, np.zeros(3), G))
    with pytest.raises(InputError, match=r"leg mass 2 = 1e\+200 kg"):
        chain_gravity_deflection(m, m.home_q, ChainMasses(1.0, 1.0, np.array([0, 1e200, 0]),
                                                          G))
    with pytest.raises(InputError, match="gravity component 3"):
        chain_gravity_deflection(m, m.home_q, ChainMasses(1.0, 1.0, np.zeros(3),
                                                          np.array([0.0, 0.0, -1e300])))


def test_illustrative_leg_masses_are_the_tube_mass_per_metre_times_the_leg_length():
    """Ø 120/100 mm steel tube: 7850 kg/m³ × π/4 × (0.12² − 0.10²) m² = 27.128 kg/m (by
    hand); each leg weighs that times the length of its links at home."""
    from pkmkit.stiffness.joint_chains import _links

    m = machine("tripteor-x7")
    lengths = np.zeros(len(m.model.legs))
    for link in _links(m):
        if link.chain == "leg":
            lengths[link.index] += link.home_length
    assert (lengths > 0.1).all()
    np.testing.assert_allclose(illustrative_masses(m).legs, 27.1276 * lengths, rtol=1e-5)
