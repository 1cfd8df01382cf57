"""Orthoglide against seed 001 (Wenger, Chablat & Majou 2002)."""

import numpy as np
import pytest

import pkmkit
from tests.conftest import random_poses


@pytest.fixture(scope="module")
def ortho():
    return pkmkit.machine("orthoglide")


def seed_inverse_jacobian(a, b, c):
    """Eq. 2: rows (c_i − b_i)ᵀ/η_i with η_i = (c_i − b_i)ᵀ (b_i − a_i)/‖b_i − a_i‖."""
    rows = []
    for ai, bi, ci in zip(a, b, c, strict=True):
        u = (bi - ai) / np.linalg.norm(bi - ai)
        rows.append((ci - bi) / np.dot(ci - bi, u))
    return np.array(rows)


def test_isotropic_point(ortho):
    assert ortho.params["L"] == pytest.approx(0.31)
    np.testing.assert_allclose(ortho.ik([0, 0, 0]), [0.31] * 3, atol=1e-15)
    jac = ortho.jacobian([0, 0, 0])
    np.testing.assert_allclose(jac.J, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(jac.singular_values, [1, 1, 1], atol=1e-15)
    assert jac.condition == pytest.approx(1.0) and jac.status == "regular"


def test_isotropy_conditions_eq_3_to_5(ortho):
    p = np.zeros(3)
    rho = ortho.ik(p)
    a = np.zeros((3, 3))  # slide origins; the slides run from A_i along e_i
    b = np.eye(3) * rho[:, None]  # carriage points B_i
    c = np.tile(p, (3, 1))  # leg end points C_i on the tool
    legs = c - b
    eta = [np.dot(legs[i], np.eye(3)[i]) for i in range(3)]
    ratios = [np.linalg.norm(legs[i]) / eta[i] for i in range(3)]
    # (3): equal ratios, (5): equal to 1 in magnitude; (4): orthogonal legs
    assert np.allclose(np.abs(ratios), 1.0)
    for i in range(3):
        assert abs(np.dot(legs[i], legs[(i + 1) % 3])) < 1e-15
    # eq. 2 written independently equals the library's J^-1 = B^-1 A, here and elsewhere
    np.testing.assert_allclose(seed_inverse_jacobian(a, b, c), ortho.jacobian(p).J_inv, atol=1e-15)
    x = np.array([0.03, -0.05, 0.02])
    rho = ortho.ik(x)
    b = np.eye(3) * rho[:, None]
    c = np.tile(x, (3, 1))
    np.testing.assert_allclose(seed_inverse_jacobian(a, b, c), ortho.jacobian(x).J_inv, atol=1e-14)


def test_working_mode_sign_test_holds_in_the_workspace(ortho):
    x = random_poses(ortho, 500, seed=5)
    rho = ortho.ik(x)
    assert (rho > x).all()
    np.testing.assert_allclose(rho, x + np.sqrt(0.31**2 - (x**2).sum(1, keepdims=True) + x**2),
                               atol=1e-15)


def test_mode_not_sign_test_selects_the_root(ortho):
    """At ρ = (L, L, L) both roots satisfy ρ_i > p_i; only the assembly mode tells them apart."""
    modes = ortho.fk_all([0.31] * 3)
    np.testing.assert_allclose(modes.poses[0], 0.0, atol=1e-15)
    np.testing.assert_allclose(modes.poses[1], [2 * 0.31 / 3] * 3, atol=1e-15)
    assert (0.31 > modes.poses[1]).all()  # the mirror root passes the sign test too
    assert modes.branches.tolist() == [[1, 1, 1], [1, 1, 1]]
    assert modes.labels == ("origin-side", "far-side")
    np.testing.assert_allclose(ortho.fk([0.31] * 3), 0.0, atol=1e-15)


def test_parallel_singularity_where_the_modes_merge(ortho):
    """For ρ = (s, s, s) the roots p = t(1, 1, 1) solve 3t² − 2st + s² = L²; they merge at
    s = L·sqrt(3/2), where the tool lies in the plane of the three carriages (det A = 0)."""
    length = ortho.params["L"]
    s = length * np.sqrt(1.5)
    q = np.full(3, s)
    modes = ortho.fk_all(q)
    assert modes.count == 1
    np.testing.assert_allclose(modes.poses[0], np.full(3, s / 3), atol=1e-7)
    jac = ortho.jacobian(np.full(3, s / 3), q=q)
    assert jac.status == "parallel" and np.isnan(jac.condition) and np.isnan(jac.J).all()
    assert jac.parallel_measure < 1e-12
    rates = ortho.jacobian_dot(np.full(3, s / 3), np.ones(3), q=q)
    assert np.isnan(rates.J_dot).all()


def test_serial_singularity_when_a_leg_is_perpendicular_to_its_slide(ortho):
    """Leg 1 perpendicular to slide 1: ρ1 = p_x and p_y² + p_z² = L²."""
    length = ortho.params["L"]
    p_x, p_y = 0.05, 0.25
    p_z = np.sqrt(length**2 - p_y**2)
    p = np.array([p_x, p_y, p_z])
    q = np.array([p_x, p_y + np.sqrt(p_y**2 - p_x**2), p_z + np.sqrt(p_z**2 - p_x**2)])
    jac = ortho.jacobian(p, q=q)
    np.testing.assert_allclose(np.linalg.norm(jac.A, axis=1), length, atol=1e-15)
    assert jac.status == "serial"
    assert jac.serial_measure < 1e-15 and np.isinf(jac.condition)
