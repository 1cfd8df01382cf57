"""Weight deflection of full-pose rod machines against the minimum of the elastic plus potential
energy of the exact rod geometry (Hessian and gradient by central differences, no Jacobian and no
load formula of the library)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.dynamics.defaults import default_masses
from pkmkit.exceptions import InputError
from pkmkit.machines.registry import machine
from pkmkit.model.rods import SLIDE, STRUT
from pkmkit.stiffness import Material, Section, default_data
from pkmkit.stiffness.platform_gravity import platform_gravity_deflection


def _energy_deflection(m, x0, masses, kq, ea, h=1e-6):
    """δ (6,) of the platform (δp, rotation vector) minimising E + V to first order: E the
    springs of the drives and rods, V the weights of platform, rods (struts: cylinder and piston
    tubes), carriages; u = (δp, θ, δq), R = exp(θ) R0."""
    model = m.model
    g = np.asarray(masses.gravity)
    q0 = np.asarray(m.ik(x0), dtype=float)
    r0 = Rotation.from_rotvec(x0[3:]).as_matrix()
    piston, l1, l2 = masses.strut_parts(model.n_rods)

    def geometry(u):
        p = x0[:3] + u[:3]
        rot = Rotation.from_rotvec(u[3:6]).as_matrix() @ r0
        q = q0 + u[6:]
        ends = []
        for j in range(model.n_rods):
            qa = q[model.rod_actuator[j]]
            a = model.rod_base[j] + (qa * model.rod_axis[j] if model.rod_kind[j] == SLIDE
                                     else 0.0)
            ends.append((a, p + rot @ model.rod_platform[j]))
        return p, rot, q, ends

    _, _, _, ends0 = geometry(np.zeros(6 + m.n_actuators))
    len0 = np.array([np.linalg.norm(b - a) for a, b in ends0])
    k_rod = ea / len0

    def energy(u):
        p, rot, q, ends = geometry(u)
        e = 0.5 * np.sum(kq * (q - q0) ** 2)
        v = -masses.platform_mass * g @ (p + rot @ masses.platform_com)
        for j, (a, b) in enumerate(ends):
            length = np.linalg.norm(b - a)
            rest = len0[j] + ((q - q0)[model.rod_actuator[j]] if model.rod_kind[j] == STRUT
                              else 0.0)
            e += 0.5 * k_rod[j] * (length - rest) ** 2
            if model.rod_kind[j] == STRUT:
                unit = (b - a) / length
                v -= g @ (masses.rod_mass[j] * (a + 0.5 * l1[j] * unit)
                          + piston[j] * (b - 0.5 * l2[j] * unit))
            else:
                v -= masses.rod_mass[j] * g @ (0.5 * (a + b))
        for k in range(m.n_actuators):
            slide = (model.rod_actuator == k) & (model.rod_kind == SLIDE)
            if slide.any():
                axis = model.rod_axis[np.flatnonzero(slide)[0]]
                v -= masses.carriage_mass[k] * g @ (q[k] * axis)
        return e, v

    n = 6 + m.n_actuators
    eye = np.eye(n) * h
    hess = np.zeros((n, n))
    grad = np.zeros(n)
    for i in range(n):
        grad[i] = (energy(eye[i])[1] - energy(-eye[i])[1]) / (2 * h)
        for j in range(n):
            hess[i, j] = (energy(eye[i] + eye[j])[0] - energy(eye[i] - eye[j])[0]
                          - energy(-eye[i] + eye[j])[0] + energy(-eye[i] - eye[j])[0]
                          ) / (4 * h * h)
    return -np.linalg.solve(hess, grad)[:6]


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod", "verne"])
def test_weight_deflection_is_the_energy_minimum(name):
    m = machine(name)
    section = Section.circle(0.03)
    data = dataclasses.replace(default_data(m), rod_section=section, rod_material=Material())
    masses = default_masses(m, tubes_at_home=True)
    masses = dataclasses.replace(masses, platform_com=np.array([0.02, -0.01, -0.05]))
    x0 = np.asarray(m.fk(m.home_q), dtype=float)
    if name != "verne":  # a tilted, shifted pose: every moment arm non-zero
        x0 = x0 + np.array([0.01, -0.02, 0.015, 0.02, -0.01, 0.03])
    arg = x0[:3] if name == "verne" else x0
    got, status = platform_gravity_deflection(m, arg[None], masses, data=data)
    assert status[0] == 0
    expected = _energy_deflection(m, x0, masses, data.actuator_stiffness,
                                  section.area * 210e9)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(got[0], expected, rtol=1e-4, atol=1e-5 * scale)
    # the tool tip 0.2 m below the platform: the rotation carries it
    tip, _ = platform_gravity_deflection(m, arg[None], masses, data=data,
                                         point=[0.0, 0.0, -0.2])
    r = Rotation.from_rotvec(x0[3:]).as_matrix() @ [0.0, 0.0, -0.2]
    np.testing.assert_allclose(tip[0, :3], expected[:3] + np.cross(expected[3:], r),
                               rtol=1e-4, atol=1e-5 * scale)


def test_doubling_the_drives_halves_a_rigid_rod_hexapods_sag():
    m = machine("gough-stewart")
    x = m.home_pose + np.array([0.0, 0.0, 0.0, 0.05, 0.0, 0.0])
    one, _ = platform_gravity_deflection(m, x[None])
    data = dataclasses.replace(default_data(m), actuator_stiffness=2 * default_data(
        m).actuator_stiffness)
    two, _ = platform_gravity_deflection(m, x[None], data=data)
    np.testing.assert_allclose(two, one / 2, rtol=1e-12, atol=1e-20)
    assert one[0, 2] < 0  # it sags


def test_cranks_have_no_weight_model():
    from pkmkit.calibration.gravity import gravity_deflection

    m = machine("delta")  # the Delta robot's cranks
    with pytest.raises(InputError, match="crank"):
        gravity_deflection(m, m.home_q[None])


def test_calibration_gravity_of_a_hexapod_is_its_platform_sag_at_the_tool_tip():
    from pkmkit.calibration.gravity import gravity_deflection

    m = machine("dietmaier-hexapod")
    q = np.atleast_2d(m.ik(m.home_pose + np.array([0.01, 0.0, 0.02, 0.0, 0.03, 0.0])))
    sag = gravity_deflection(m, q, tool_length=0.15)
    expected, _ = platform_gravity_deflection(m, np.atleast_2d(m.fk(q)), point=[0, 0, -0.15])
    np.testing.assert_allclose(sag.deflection, expected, rtol=1e-12)
    assert "illustrative" in sag.note
