"""The linear deflection against the loaded equilibrium of the rod geometry (small loads)."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from pkmkit.stiffness import Section, default_data, stiffness
from pkmkit.stiffness.equilibrium import loaded_equilibrium

from .helpers import cubic_hexapod


def _equilibrium(m, x0, q0, k_a, k_r, wrench):
    """Platform pose under ``wrench`` solved from the exact rod geometry: each strut is its drive
    (spring k_a on the actuator coordinate) in series with its rod (spring k_r); unknowns the
    platform displacement (δp, rotation vector of R R0ᵀ) and the drives' deflections δq."""
    model = m.model
    r0 = Rotation.from_rotvec(x0[3:]).as_matrix()
    force, moment = wrench[:3], wrench[3:]

    def residual(u):
        p = x0[:3] + u[:3]
        rot = Rotation.from_rotvec(u[3:6]).as_matrix() @ r0
        dq = u[6:]
        out = np.zeros(12)
        total_f, total_m = force.copy(), moment.copy()
        for j in range(6):
            b = rot @ model.rod_platform[j]
            d = p + b - model.rod_base[j]
            length = np.linalg.norm(d)
            unit = d / length
            rest = q0[j] + dq[j]  # strut: the drive sets the rod's rest length
            tension = k_r[j] * (length - rest)
            total_f -= tension * unit
            total_m -= np.cross(b, tension * unit)
            out[6 + j] = (k_a * dq[j] - tension) / k_a
        # moments about the displaced reference point p; forces in N, scaled like the rest
        out[:3] = total_f / k_a
        out[3:6] = total_m / k_a
        return out

    sol = least_squares(residual, np.zeros(12), xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return sol.x[:6]


def test_linear_deflection_is_the_small_load_limit_of_the_equilibrium():
    a, k_a = 0.5, 5e7
    m = cubic_hexapod(a)
    section = Section.circle(0.02)
    data = dataclasses.replace(default_data(m), actuator_stiffness=np.full(6, k_a),
                               rod_section=section)
    x0 = np.array([0.01, -0.02, 0.015, 0.02, 0.01, -0.03])
    q0 = m.ik(x0)
    k_r = 210e9 * section.area / q0  # each strut's rod at its length
    base_wrench = np.array([300.0, -200.0, 800.0, 20.0, -15.0, 10.0])
    gaps = []
    for scale in (1.0, 2.0):
        w = base_wrench * scale
        linear = stiffness(m, x0, data=data, wrench=w).deflection
        exact = _equilibrium(m, x0, q0, k_a, k_r, w)
        np.testing.assert_allclose(exact, linear, rtol=1e-3, atol=1e-4 * np.abs(linear).max())
        gaps.append(np.abs(exact - linear).max())
        # pkmkit's own loaded equilibrium is this one, to a millionth of the gap
        loaded = loaded_equilibrium(m, x0, w, data=data)
        np.testing.assert_allclose(loaded.loaded, exact, rtol=0, atol=1e-5 * gaps[-1])
        np.testing.assert_allclose(loaded.linear, linear, rtol=1e-12)
    # the gap is the second-order (geometric stiffness) term: four times larger at twice the load
    assert 3.5 < gaps[1] / gaps[0] < 4.5
