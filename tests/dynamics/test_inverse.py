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
from pkmkit.exceptions import InputError
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


def test_static_forces_are_the_gradient_of_the_potential(linear_preset):
    preset = linear_preset
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
    mass, radius, _ = rod_section_mass(delta_b, 0.04, 7700.0)
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


def test_mass_properties_keep_what_they_are_given(delta_b):
    inertia = np.array([[0.2, 0.01, 0.0], [0.01, 0.3, 0.0], [0.0, 0.0, 0.4]])
    masses = mass_properties(delta_b, carriage=2.0, platform=5.0, platform_inertia=inertia,
                             platform_com=(0.0, 0.0, 0.1), gravity=(0.0, 1.0, -9.0))
    np.testing.assert_array_equal(masses.platform_inertia, inertia)
    np.testing.assert_array_equal(masses.gravity, [0.0, 1.0, -9.0])
    np.testing.assert_array_equal(masses.platform_com, [0.0, 0.0, 0.1])
    with pytest.raises(InputError, match="gravity"):
        mass_properties(delta_b, gravity=(0.0, -9.81))
    with pytest.raises(InputError, match="symmetric"):  # an inertia tensor is symmetric
        mass_properties(delta_b, platform_inertia=inertia + np.triu(np.full((3, 3), 0.05), 1))


@pytest.mark.parametrize("which", ["xd", "xdd", "q", "qd", "qdd"])
def test_mis_shaped_motion_names_the_argument(delta_b, which):
    x = np.array([[0.0, 0.0, 0.2], [0.01, 0.0, 0.2]])
    args = {"x": x, "xd": np.zeros((2, 3)), "xdd": np.zeros((2, 3)), "q": delta_b.ik(x),
            "qd": np.zeros((2, 3)), "qdd": np.zeros((2, 3))}
    args[which] = args[which][:1]
    with pytest.raises(InputError, match=rf"^{which} must have shape \(2, 3\)"):
        inverse_dynamics(delta_b, default_masses(delta_b), *args.values())


def test_masses_file_and_errors(tmp_path, delta_b):
    path = tmp_path / "m.toml"
    path.write_text("[masses]\nunits = 'mm'\ncarriage = [8, 8, 9]\nrod_diameter = 40\n"
                    "rod_density = 1000\nplatform = 15\nplatform_com = [0, 0, 50]\n"
                    "[wrench]\nforce = [0, 0, 100]\n")
    masses, wrench = load_masses(path, delta_b)
    np.testing.assert_allclose(masses.platform_com, [0.0, 0.0, 0.05])  # mm in the file
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


@pytest.mark.parametrize("text, message", [
    ("[masses]\ncarriage = 8\nrod = 1e308\n", r"m.toml:3: rod = 1e\+308 kg is beyond 1e\+06 kg"),
    ("[masses]\nplatform = 2e6\n", r"m.toml:2: platform = 2e\+06 kg is beyond"),
    ("[masses]\ncarriage = [8, 1e300, 8]\n", r"m.toml:2: carriage 2 = 1e\+300 kg"),
    ("[masses]\nrod_diameter = 1e300\n", r"m.toml:2: rod_diameter = 1e\+300 m is beyond"),
    ("[masses]\nrod_diameter = 0.04\nrod_density = 1e200\n", r"m.toml:3: rod_density"),
    ("[masses]\nunits = 'mm'\nplatform_com = [0, 0, 1e300]\n",
     r"m.toml:3: platform_com 3 = 1e\+300 mm is beyond 1e\+09 mm"),
    ("[masses]\ngravity = [0, 0, -1e300]\n", r"m.toml:2: gravity 3 = -1e\+300 m/s²"),
    ("[masses]\nplatform_inertia = [[1e300, 0, 0], [0, 1, 0], [0, 0, 1]]\n",
     "m.toml:2: platform_inertia 1"),
    ("[masses]\nplatform_inertia = [[nan, 0, 0], [0, 1, 0], [0, 0, 1]]\n",
     "platform_inertia 1 must be a finite number, got nan"),
    # ragged (a ValueError from NumPy escaped the line check: found by the fuzz profile)
    ("[masses]\nplatform_inertia = [[1, 0], [0]]\n", r"m.toml: setting an array element"),
    ("[masses]\nrod = 1\n[wrench]\nforce = [0, 0, 1]\nmoment = [0, 1e200, 0]\n",
     r"m.toml:5: \[wrench\] moment component 2 = 1e\+200 N·m is beyond 1e\+09"),
])
def test_absurd_masses_and_loads_name_their_line(tmp_path, delta_b, text, message):
    """Masses of 1e308 kg (and the like) gave inf/nan actuator forces, overflow warnings, or
    forces of 1e201 N printed with exit 0; the line and the value are named now."""
    path = tmp_path / "m.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        load_masses(path, delta_b)


@pytest.mark.parametrize("kwargs, message", [
    ({"carriage": 1e308}, r"carriage mass 1 = 1e\+308 kg"),
    ({"rod": 1e7}, r"rod mass 1 = 1e\+07 kg is beyond 1e\+06 kg"),
    ({"platform": 1e200}, "platform mass = 1e"),
    ({"gravity": (0.0, 0.0, -1e300)}, "gravity component 3"),
    ({"platform_com": (0.0, 0.0, 1e300)}, "platform_com component 3"),
])
def test_mass_properties_refuse_absurd_magnitudes(delta_b, kwargs, message):
    with pytest.raises(InputError, match=message):
        mass_properties(delta_b, **kwargs)


def test_inverse_dynamics_refuses_an_absurd_wrench(delta_b):
    """A finite wrench of 1e308 N overflowed into inf forces."""
    x = np.array([[0.0, 0.0, 0.2]])
    with pytest.raises(InputError, match=r"wrench component 3 = 1e\+308"):
        static(delta_b, default_masses(delta_b), x, wrench=[0.0, 0.0, 1e308])


STRUT_TRIPOD = "".join(
    f'[[legs]]\ntype = "strut"\nbase = [{np.cos(a):.6f}, {np.sin(a):.6f}, 0]\n'
    f'platform = [0, 0, 0]\nlength = 1.2\n' for a in np.radians([0.0, 120.0, 240.0]))

#: A planar machine with one slide leg and one strut leg meeting at the tool point.
MIXED_PLANAR = """[machine]
kind = "rod-legs"
dims = 2
home = [0.5, -0.6]
[[legs]]
type = "slide"
base = [0, 0]
axis = [1, 0]
platform = [0, 0]
length = 0.8
branch = -1
[[legs]]
type = "strut"
base = [1.2, 0]
platform = [0, 0]
length = 0.7
"""


@pytest.fixture(scope="module", params=["tripod", "mixed", "delta"])
def strut_machine(request, tmp_path_factory):
    """A point-platform tripod of three struts, a planar slide + strut machine and the linear
    Delta, with masses on every body (gravity in the plane of the planar one)."""
    path = tmp_path_factory.mktemp("struts") / f"{request.param}.toml"
    if request.param == "delta":
        m = pkmkit.machine("linear-delta-table-iv1")
        mass, radius, _ = rod_section_mass(m, 0.04, 7700.0)
        masses = mass_properties(m, carriage=8.0, rod=mass, rod_radius=radius, platform=15.0,
                                 gravity=(1.0, 0.5, -9.81))
        tr = plan(helix([0.02, 0.01, 0.1], 0.12, pitch=0.05, turns=1.0), feed=0.4, accel=3.0,
                  jerk=40.0, period=2e-4)
    elif request.param == "tripod":
        path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n' + STRUT_TRIPOD)
        m = pkmkit.load(path)
        masses = mass_properties(m, carriage=0.3, rod=2.0, rod_radius=0.03, platform=4.0,
                                 piston=1.5, cylinder_length=0.7, piston_length=0.8,
                                 gravity=(0.5, -1.0, -9.81))
        tr = plan(helix([0.05, -0.03, -0.85], 0.1, pitch=0.05, turns=1.0), feed=0.4,
                  accel=3.0, jerk=40.0, period=2e-4)
    else:
        path.write_text(MIXED_PLANAR)
        m = pkmkit.load(path)
        masses = mass_properties(m, carriage=[3.0, 0.2], rod=[1.0, 2.5], rod_radius=0.02,
                                 platform=4.0, piston=[0.0, 1.2], cylinder_length=0.5,
                                 piston_length=0.45, gravity=(0.0, -9.81, 0.0))
        tr = plan(circle([0.55, -0.55, 0.0], 0.08), feed=0.4, accel=3.0, jerk=40.0,
                  period=2e-4)
    return m, masses, joint_trajectory(m, tr)


def test_power_balance_with_struts(strut_machine):
    """Σ f_k q̇_k = dE/dt along the move, E the energy of every body (cylinders and pistons
    turning with their struts)."""
    m, masses, jt = strut_machine
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    energy = mechanical_energy(m, masses, jt.x, jt.xd, jt.q, jt.qd)
    d_energy = np.gradient(energy, jt.t)
    scale = np.abs(res.power).max()
    assert scale > 1.0
    np.testing.assert_allclose(res.power.sum(axis=1)[3:-3], d_energy[3:-3], atol=2e-4 * scale)


def test_forces_satisfy_lagrange_equations(strut_machine):
    """Every component, not only the power: f = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q, with T and V
    from the energy as a function of (q, q̇) through the direct model and J, differentiated
    numerically (an independent route to the same forces)."""
    m, masses, jt = strut_machine
    res = inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)

    def energy(q, qd):
        x = m.fk(q)
        xd = m.jacobian(x).J @ qd
        return float(mechanical_energy(m, masses, x[None], xd[None], q[None], qd[None])[0])

    def kinetic(q, qd):
        return energy(q, qd) - energy(q, np.zeros_like(qd))

    def grad(fun, v, h):
        out = np.zeros_like(v)
        for i in range(v.size):
            e = np.zeros_like(v)
            e[i] = h
            out[i] = (fun(v + e) - fun(v - e)) / (2 * h)
        return out

    def momentum(k):
        return grad(lambda w: kinetic(jt.q[k], w), jt.qd[k], 1e-3)

    n = m.n_actuators
    dt = jt.t[1] - jt.t[0]
    for k in np.linspace(50, len(jt.t) - 50, 5).astype(int):
        rate = (momentum(k + 1) - momentum(k - 1)) / (2 * dt)
        dT = grad(lambda v, k=k: kinetic(v, jt.qd[k]), jt.q[k], 1e-6)
        dV = grad(lambda v: energy(v, np.zeros(n)), jt.q[k], 1e-6)
        expected = rate - dT + dV
        np.testing.assert_allclose(res.force[k], expected, rtol=2e-4,
                                   atol=2e-4 * np.abs(expected).max())


def test_strut_axial_force_and_masses_file(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, -0.8]\n' + STRUT_TRIPOD)
    m = pkmkit.load(path)
    masses = default_masses(m)  # Ø20 mm aluminium tubes, 0.6 × 1.2 m each
    tube = 2700 * np.pi / 4 * 0.02**2 * 0.72
    np.testing.assert_allclose(masses.rod_mass, tube)
    np.testing.assert_allclose(masses.piston_mass, tube)
    x = m.home_pose[None]
    zeros = np.zeros_like(x)
    q = m.ik(x)
    res = inverse_dynamics(m, masses, x, zeros, zeros, q, np.zeros_like(q), np.zeros_like(q))
    # the platform hangs from the struts: each one pulls (f < 0, tension > 0) and carries at
    # least a third of the platform's weight along its own direction (cos = 0.8 / 1.28)
    assert np.allclose(res.leg_axial, -res.force)
    assert (res.leg_axial > 5.0 * 9.81 / 3 / (0.8 / 1.28)).all()
    spec = tmp_path / "masses.toml"
    spec.write_text("[masses]\nunits = 'mm'\nrod_diameter = 30\nrod_density = 7800\n"
                    "cylinder_length = 600\npiston_length = 500\nplatform = 10\n")
    props, _ = load_masses(spec, m)
    area = np.pi / 4 * 0.03**2
    np.testing.assert_allclose(props.rod_mass, 7800 * area * 0.6)
    np.testing.assert_allclose(props.piston_mass, 7800 * area * 0.5)
    delta = pkmkit.machine("linear-delta")
    with pytest.raises(InputError, match="strut legs only"):
        mass_properties(delta, piston=[1.0] * 6)
    with pytest.raises(InputError, match="cylinder length"):
        mass_properties(m, rod=1.0, cylinder_length=0.0)


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
    # gravity and inertia add up, the inertial part is small but there: 0.1 N to 5 % of the
    # forces (a model without inertia must fail) ...
    np.testing.assert_allclose(res.force - inertial.force,
                               static(delta_b, masses, jt.x), rtol=1e-12, atol=1e-9)
    assert 0.1 < np.abs(inertial.force[cruise]).max() < 0.05 * np.abs(res.force).min()
    # ... and equals MuJoCo's (exact closures, no gravity) at samples along the cruise
    mujoco_rods = pytest.importorskip("tests.dynamics.mujoco_rods")
    oracle = mujoco_rods.MujocoRodMachine(delta_b, no_gravity)
    for k in np.flatnonzero(cruise)[::100]:
        f, residual, _ = oracle.hard_constraint_forces(jt.x[k], jt.xd[k], jt.xdd[k], jt.q[k],
                                                       jt.qd[k], jt.qdd[k])
        assert residual < 1e-10
        np.testing.assert_allclose(inertial.force[k], f, rtol=1e-9)


def test_leg_axial_force_against_newton_euler_statics(tmp_path):
    """Three single heavy rods on vertical slides meeting at a point platform: the rod end
    forces from each body's own equilibrium (rods: forces and moments about A; platform:
    forces), solved here independently; pkmkit reports the larger end tension of each rod and
    the actuator forces that balance the carriages."""
    angles = np.radians([0.0, 120.0, 240.0])
    path = tmp_path / "single.toml"
    path.write_text('[machine]\nkind = "rod-legs"\nhome = [0, 0, 0]\n' + "".join(
        f'[[legs]]\ntype = "slide"\nbase = [{0.55 * np.cos(a):.9f}, {0.55 * np.sin(a):.9f}, 0]'
        f'\naxis = [0, 0, 1]\nplatform = [0, 0, 0]\nlength = 1.04\n' for a in angles))
    m = pkmkit.load(path)
    g = np.array([0.4, -0.3, -9.81])
    masses = mass_properties(m, carriage=6.0, rod=10.0, rod_radius=0.02, platform=20.0,
                             gravity=g)
    x = np.array([0.1, -0.05, 0.0])
    q = m.ik(x)
    res = inverse_dynamics(m, masses, x[None], np.zeros((1, 3)), np.zeros((1, 3)), q[None],
                           np.zeros((1, 3)), np.zeros((1, 3)))
    base = m.model.leg_base + q[:, None] * m.model.leg_axis
    d = x[None] - base
    unit = d / np.linalg.norm(d, axis=1, keepdims=True)
    # R_P = −m g/2 + λ d̂ on each rod; platform: Σ λ_i d̂_i = M g + Σ m g/2
    lam = np.linalg.solve(unit.T, 20.0 * g + 3 * 10.0 * g / 2)
    n_platform_end = lam - 10.0 * (unit @ g) / 2
    n_carriage_end = lam + 10.0 * (unit @ g) / 2
    larger = np.where(np.abs(n_platform_end) > np.abs(n_carriage_end), n_platform_end,
                      n_carriage_end)
    np.testing.assert_allclose(res.leg_axial[0], larger, rtol=1e-10)
    # carriage along its slide: actuator + weight + force from the rod (−R_A) balance
    r_a = -(-10.0 * g / 2 + lam[:, None] * unit) - 10.0 * g
    actuator = -(6.0 * g[2]) + r_a[:, 2]
    np.testing.assert_allclose(res.force[0], actuator, rtol=1e-10)


def test_first_speed_excursion_is_the_earliest_along_the_path():
    """Seed 000's circle with a 70 mm/s speed limit (the slides peak at 76.3 mm/s, twice
    each): the reported first excursion starts between the last sample (10 ms apart) under the
    limit and the first over it, and names that actuator."""
    from pkmkit.dynamics.trajectory import simulate_path
    from pkmkit.motion.joints import Limits

    m = pkmkit.machine("linear-delta-table-iv1")
    r = simulate_path(m, circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0,
                      period=0.01, limits=Limits(speed=0.07))
    first = r.limits["speed"]["first"]
    over = np.abs(r.motion.qd) > 0.07
    k = np.flatnonzero(over.any(axis=1))[0]
    assert r.motion.t[k - 1] <= first["t"] <= r.motion.t[k]
    assert first["actuator"] == m.actuator_names[np.flatnonzero(over[k])[0]]
    assert 0.07 < first["value"] < 0.0764
