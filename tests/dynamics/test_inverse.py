import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics import (
    default_masses,
    inverse_dynamics,
    load_masses,
    mass_properties,
    mechanical_energy,
    rod_section_mass,
)
from pkmkit.errors import InputError
from pkmkit.motion import circle, helix, joint_trajectory, plan
from tests.conftest import random_poses


def static(machine, masses, x, wrench=None):
    q = machine.ik(x)
    zeros = np.zeros_like(x)
    return inverse_dynamics(machine, masses, x, zeros, zeros, q, np.zeros_like(q),
                            np.zeros_like(q), wrench=wrench).force


@pytest.fixture(scope="module")
def delta_b():
    return pkmkit.machine("linear-delta-table-iv1")


def test_static_equilibrium_of_the_vertical_slides(delta_b):
    """Vertical slides carry the whole weight: Σ f = total mass × g at any static pose."""
    masses = default_masses(delta_b)
    x = random_poses(delta_b, 50, seed=1)
    np.testing.assert_allclose(static(delta_b, masses, x).sum(axis=1), masses.total_mass * 9.81,
                               rtol=1e-12)


def test_static_forces_are_the_gradient_of_the_potential(preset):
    """At rest f = ∂V/∂q (virtual work), for any machine and gravity direction."""
    masses = mass_properties(preset, carriage=3.0, rod=0.7, rod_radius=0.01, platform=4.0,
                             gravity=(0.3, -2.0, -9.81))
    x = random_poses(preset, 5, seed=2)
    q = preset.ik(x)
    f = static(preset, masses, x)
    h = 1e-6
    for k in range(preset.n_actuators):
        dq = np.zeros(preset.n_actuators)
        dq[k] = h
        xp, xm = preset.fk(q + dq), preset.fk(q - dq)
        zeros = np.zeros_like(q)
        vp = mechanical_energy(preset, masses, xp, np.zeros_like(xp), q + dq, zeros)
        vm = mechanical_energy(preset, masses, xm, np.zeros_like(xm), q - dq, zeros)
        np.testing.assert_allclose(f[:, k], (vp - vm) / (2 * h), rtol=1e-6, atol=1e-6)


def test_power_balance_along_a_helix(delta_b):
    """Σ f_k q̇_k + F·ẋ = dE/dt (kinetic + potential energy of every body)."""
    mass, radius = rod_section_mass(delta_b, 0.04, 7700.0)
    masses = mass_properties(delta_b, carriage=8.0, rod=mass, rod_radius=radius, platform=15.0)
    tr = plan(helix([0, 0, 0.1], 0.12, pitch=0.05, turns=1.0), feed=0.4, accel=3.0, jerk=40.0,
              period=2e-4)
    jt = joint_trajectory(delta_b, tr)
    force = np.array([30.0, -20.0, 50.0])
    res = inverse_dynamics(delta_b, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd,
                           wrench=force)
    energy = mechanical_energy(delta_b, masses, jt.x, jt.xd, jt.q, jt.qd)
    d_energy = np.gradient(energy, jt.t)
    power = res.power.sum(axis=1) + jt.xd @ force
    scale = np.abs(res.power).max()
    np.testing.assert_allclose(power[3:-3], d_energy[3:-3], atol=2e-4 * scale)
    parts = sum(res.parts.values())
    np.testing.assert_allclose(parts, res.force, atol=1e-9)


def test_external_force_only(delta_b):
    """No masses, no gravity: f = −Jᵀ F (the cutting force is reacted by the actuators)."""
    masses = mass_properties(delta_b, gravity=(0, 0, 0))
    x = random_poses(delta_b, 10, seed=3)
    force = np.array([100.0, -50.0, 300.0])
    f = static(delta_b, masses, x, wrench=np.concatenate([force, [1.0, 2.0, 3.0]]))
    jac = delta_b.jacobian(x)
    np.testing.assert_allclose(f, -np.einsum("kji,j->ki", jac.J, force), atol=1e-9)


def test_leg_axial_forces_balance_the_weight(delta_b):
    """Massless rods, static: the legs' tensions hold the platform up, Σ T_i d̂_i = M g (d̂ from
    carriage to platform, tension > 0)."""
    masses = mass_properties(delta_b, carriage=5.0, platform=20.0)
    x = random_poses(delta_b, 5, seed=4)
    q = delta_b.ik(x)
    zeros = np.zeros_like(x)
    res = inverse_dynamics(delta_b, masses, x, zeros, zeros, q, np.zeros_like(q),
                           np.zeros_like(q))
    a = delta_b.jacobian(x, q=q).A
    unit = a / np.linalg.norm(a, axis=2, keepdims=True)  # carriage → platform
    total = np.einsum("ki,kid->kd", res.leg_axial, unit)
    np.testing.assert_allclose(total, np.tile([0, 0, -20.0 * 9.81], (5, 1)), atol=1e-9)
    assert (res.leg_axial > 0).all()  # the platform hangs from the legs


def test_masses_file_and_errors(tmp_path, delta_b):
    path = tmp_path / "m.toml"
    path.write_text("[masses]\nunits = 'mm'\ncarriage = [8, 8, 9]\nrod_diameter = 40\n"
                    "rod_density = 1000\nplatform = 15\n[wrench]\nforce = [0, 0, 100]\n")
    masses, wrench = load_masses(path, delta_b)
    assert masses.carriage_mass.tolist() == [8, 8, 9]
    np.testing.assert_allclose(masses.rod_mass, 1000 * np.pi / 4 * 0.04**2 * 1.04)
    assert wrench.tolist() == [0, 0, 100, 0, 0, 0]
    for text, message in [("[masses]\ncarriage = -1\n", ">= 0"),
                          ("[masses]\nwheels = 4\n", "unknown key"),
                          ("[mass]\n", "expected a \\[masses\\] table"),
                          ("[masses]\ncarriage = [1, 2]\n", "1 or 3 values"),
                          ("[masses]\nrod = 1\nrod_diameter = 0.04\n", "either")]:
        path.write_text(text)
        with pytest.raises(InputError, match=message):
            load_masses(path, delta_b)


def test_struts_are_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n'
                    + "".join(f'[[legs]]\ntype = "strut"\nbase = [{np.cos(a):.6f}, '
                              f'{np.sin(a):.6f}, 0]\nplatform = [0, 0, 0]\nlength = 1.2\n'
                              for a in np.radians([0.0, 120.0, 240.0])))
    m = pkmkit.load(path)
    with pytest.raises(InputError, match="strut"):
        static(m, default_masses(m), m.home_pose[None])


def test_forces_along_the_seed_circle(delta_b):
    """Table IV.1 machine, Ø300 mm at 120 mm/s: with the illustrative masses, gravity dominates;
    at constant speed the inertial part is a few newtons."""
    masses = default_masses(delta_b)
    jt = joint_trajectory(delta_b, plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0,
                                        jerk=10.0, period=0.005))
    res = inverse_dynamics(delta_b, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    no_gravity = mass_properties(delta_b, carriage=masses.carriage_mass, rod=masses.rod_mass,
                                 rod_radius=masses.rod_radius, platform=masses.platform_mass,
                                 gravity=(0, 0, 0))
    inertial = inverse_dynamics(delta_b, no_gravity, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    cruise = (jt.t > 2.0) & (jt.t < 6.0)
    assert np.abs(inertial.force[cruise]).max() < 0.05 * np.abs(res.force).min()
