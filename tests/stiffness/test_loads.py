"""Deflection under gravity and a tool force against independent oracles: the static actuator
forces of the inverse dynamics (rigid rods) and the Hessian of the elastic energy of the rod
geometry by finite differences (compliant rods)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.inverse import inverse_dynamics
from pkmkit.exceptions import InputError
from pkmkit.machines.registry import machine
from pkmkit.stiffness import Material, Section, default_data
from pkmkit.stiffness.loads import load_deflection


def _poses(m, count=5, seed=3):
    rng = np.random.default_rng(seed)
    return m.home_pose + 0.04 * rng.uniform(-1, 1, (count, m.dims))


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta-table-iv1", "five-bar"])
def test_rigid_rods_deflect_as_the_static_actuator_forces_load_the_drives(name):
    m = machine(name)
    data = dataclasses.replace(default_data(m), rod_section=None,
                               actuator_stiffness=np.array([8e7, 1e8, 1.3e8][:m.n_actuators]))
    masses = default_masses(m)
    x = _poses(m)
    q = m.ik(x)
    zeros = np.zeros_like(x)
    force = np.array([120.0, -80.0, -300.0])
    f_static = inverse_dynamics(m, masses, x, zeros, zeros, q, np.zeros_like(q),
                                np.zeros_like(q), wrench=force).force
    jac = m.jacobian(x).J
    expected = -np.einsum("nia,na->ni", jac, f_static / data.actuator_stiffness)
    got = load_deflection(m, x, masses, force=force, data=data)
    scale = np.abs(expected).max()
    assert scale > 1e-7  # the loads do deflect the machine
    np.testing.assert_allclose(got.total, expected, rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_allclose(got.gravity + got.force, got.total, rtol=0, atol=1e-15)


def _energy_deflection(m, x0, q0, kq, k_leg, platform_force, carriage_force, h=1e-5):
    """Deflection ``(δx, δq)`` minimising ½ Σ k_a δq² + ½ Σ k_leg (|d_j| − ℓ_j)² − W·δx − f·δq,
    the Hessian of the elastic energy from central differences of the leg geometry alone."""
    model = m.model
    base, axis, plat = model.leg_base, model.leg_axis, model.leg_platform
    d = len(x0)

    def legs(u):
        p = np.zeros(3)
        p[:d] = x0 + u[:d]
        q = q0 + u[d:]
        return np.array([np.linalg.norm(p + plat[j] - base[j] - q[j] * axis[j])
                         for j in range(len(base))])

    rest = legs(np.zeros(d + len(q0)))

    def energy(u):
        return 0.5 * np.sum(kq * u[d:] ** 2) + 0.5 * np.sum(k_leg * (legs(u) - rest) ** 2)

    n = d + len(q0)
    eye = np.eye(n) * h
    hess = np.array([[(energy(eye[i] + eye[j]) - energy(eye[i] - eye[j])
                       - energy(-eye[i] + eye[j]) + energy(-eye[i] - eye[j])) / (4 * h * h)
                      for j in range(n)] for i in range(n)])
    return np.linalg.solve(hess, np.concatenate([platform_force, carriage_force]))[:d]


@pytest.mark.parametrize("name", ["linear-delta-table-iv1", "orthoglide"])
def test_compliant_rods_against_the_energy_hessian(name):
    m = machine(name)
    section = Section.circle(0.008)
    data = dataclasses.replace(default_data(m), rod_section=section, rod_material=Material())
    masses = default_masses(m)
    x0 = _poses(m, 1, seed=7)[0]
    q0 = m.ik(x0)
    force = np.array([200.0, 50.0, -400.0])
    counts = np.bincount(m.model.rod_leg)
    k_leg = section.area * 210e9 * counts / m.model.leg_length
    g = masses.gravity
    half = 0.5 * masses.rod_mass
    w = (masses.platform_mass + half.sum()) * g + force
    carriage = masses.carriage_mass + np.bincount(m.model.rod_actuator, weights=half)
    f_c = carriage * (m.model.leg_axis @ g)
    expected = _energy_deflection(m, x0, q0, data.actuator_stiffness, k_leg, w, f_c)
    got = load_deflection(m, x0[None], masses, force=force, data=data).total[0]
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-6 * np.abs(expected).max())
    rigid = load_deflection(m, x0[None], masses, force=force,
                            data=dataclasses.replace(data, rod_section=None)).total[0]
    assert np.linalg.norm(got) > np.linalg.norm(rigid) * 1.01  # the rods add compliance


def test_batch_matches_single_rows_and_flags_unreachable():
    m = machine("orthoglide")
    masses = default_masses(m)
    x = _poses(m, 4)
    x[2] = [5.0, 5.0, 5.0]
    batch = load_deflection(m, x, masses, force=[0.0, 0.0, -100.0])
    assert np.isnan(batch.total[2]).all() and batch.status[2] != 0
    for k in (0, 1, 3):
        one = load_deflection(m, x[k:k + 1], masses, force=[0.0, 0.0, -100.0])
        np.testing.assert_allclose(batch.total[k], one.total[0], rtol=1e-13)


def test_refusals():
    m = machine("orthoglide")
    with pytest.raises(InputError, match="tool force"):
        load_deflection(m, m.home_pose[None], None, force=[1.0, 2.0])
    with pytest.raises(InputError, match="translating platform"):
        from pkmkit.stiffness.loads import gravity_loads

        gravity_loads(machine("gough-stewart"), default_masses(m))
