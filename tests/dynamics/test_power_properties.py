"""Power balance over random machines of every kind with random masses, gravity and tool force:
the actuators' power plus the tool force's equals the rate of the mechanical energy,
Σ f_k q̇_k + F·ẋ = dE/dt, along a smooth motion through a random pose (dE/dt by a five-point
stencil of the exact energy: an independent route, accurate to ~1e-9 here)."""

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from pkmkit.dynamics import inverse_dynamics, mass_properties, mechanical_energy
from pkmkit.model.rods import STRUT
from tests.strategies import FAMILIES, near_home, well_posed


def _motion(x0, a, b, omega, t):
    """x(t) = x0 + a sin ωt + b (1 − cos ωt) and its first two derivatives."""
    s, c = np.sin(omega * t), np.cos(omega * t)
    return (x0 + a * s + b * (1 - c), omega * (a * c + b * s), omega**2 * (-a * s + b * c))


@pytest.mark.parametrize("family", sorted(FAMILIES))
@given(data=st.data())
def test_power_balance_on_random_machines(family, data):
    m = data.draw(FAMILIES[family])
    dims = m.dims
    scale = float(m.model.leg_length.max())
    x0 = near_home(data.draw, m, 0.1)
    assume(well_posed(m, x0, kappa_max=200.0))
    floats = st.floats(-1.0, 1.0)
    a = np.array([data.draw(floats) for _ in range(dims)]) * 0.05 * scale
    b = np.array([data.draw(floats) for _ in range(dims)]) * 0.05 * scale
    assume(np.linalg.norm(a) > 0.005 * scale)
    omega = data.draw(st.floats(0.5, 5.0))
    strut = m.model.rod_kind == STRUT
    masses = mass_properties(
        m, carriage=data.draw(st.floats(0.0, 10.0)), rod=data.draw(st.floats(0.1, 5.0)),
        rod_radius=data.draw(st.floats(0.0, 0.05)) * scale,
        platform=data.draw(st.floats(0.0, 20.0)),
        piston=np.where(strut, data.draw(st.floats(0.1, 3.0)), 0.0),
        gravity=[data.draw(st.floats(-10.0, 10.0)) for _ in range(2)] + [-9.81])
    if dims == 2:
        masses = mass_properties(m, carriage=masses.carriage_mass, rod=masses.rod_mass,
                                 rod_radius=masses.rod_radius, platform=masses.platform_mass,
                                 piston=masses.piston_mass, gravity=(*masses.gravity[:2], 0.0))
    force = np.array([data.draw(st.floats(-100.0, 100.0)) for _ in range(3)])
    if dims == 2:
        force[2] = 0.0

    def state(t):
        x, xd, xdd = (v[None] for v in _motion(x0, a, b, omega, t))
        q = m.ik(x)
        jac = m.jacobian(x, q=q)
        qd = np.einsum("kij,kj->ki", jac.J_inv, xd)
        j_dot = m.jacobian_dot(x, xd, q=q).J_dot
        qdd = np.einsum("kij,kj->ki", jac.J_inv, xdd - np.einsum("kij,kj->ki", j_dot, qd))
        return x, xd, xdd, q, qd, qdd

    x, xd, xdd, q, qd, qdd = state(0.0)
    assume(np.isfinite(q).all() and np.isfinite(qdd).all())
    res = inverse_dynamics(m, masses, x, xd, xdd, q, qd, qdd, wrench=force)
    power = float(res.power.sum()) + float(force[:dims] @ xd[0])
    h = 1e-3 / omega

    def energy(t):
        x, xd, _, q, qd, _ = state(t)
        return float(mechanical_energy(m, masses, x, xd, q, qd)[0])

    rate = (-energy(2 * h) + 8 * energy(h) - 8 * energy(-h) + energy(-2 * h)) / (12 * h)
    magnitude = float(np.abs(res.power).sum() + abs(force[:dims] @ xd[0]) + abs(rate))
    assert magnitude > 1e-6
    assert abs(power - rate) <= 1e-7 * magnitude, (power, rate)
