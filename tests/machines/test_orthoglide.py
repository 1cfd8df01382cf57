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


@pytest.mark.parametrize("length", [0.31, 0.45])
def test_isotropy_conditions_eq_3_to_5(length):
    """Seed 001 eq. (3)–(5) on the library's own A and B (A ẋ = B ρ̇, rows of A the legs
    (p − b_i)ᵀ, B = diag((p − b_i)·e_i)) at the isotropic point: (4) the legs are mutually
    orthogonal (A Aᵀ = L² I), (3) the ratios ‖A_i‖ / B_ii are equal and (5) of magnitude 1;
    hence J = I. Off the isotropic point they fail, as they must."""
    ortho = pkmkit.machine("orthoglide", L=length)
    jac = ortho.jacobian([0.0, 0.0, 0.0])
    np.testing.assert_allclose(jac.A @ jac.A.T, length**2 * np.eye(3), atol=1e-15)
    ratios = np.linalg.norm(jac.A, axis=1) / np.diag(jac.B)
    np.testing.assert_allclose(np.abs(ratios), 1.0, rtol=1e-15)
    np.testing.assert_allclose(ratios, ratios[0], rtol=1e-15)
    np.testing.assert_allclose(np.abs(np.diag(jac.B)), length, rtol=1e-15)
    np.testing.assert_allclose(jac.J, np.eye(3), atol=1e-15)
    off = ortho.jacobian([0.03, -0.05, 0.02])
    gram = off.A @ off.A.T
    assert np.abs(gram - np.diag(np.diag(gram))).max() > 1e-4 * length**2
    assert np.ptp(np.linalg.norm(off.A, axis=1) / np.abs(np.diag(off.B))) > 1e-3


def test_inverse_jacobian_is_seed_eq_2(ortho):
    """Eq. 2 written from the carriage points ρ_i e_i and the tool point equals the library's
    J⁻¹ = B⁻¹A, at the isotropic point and elsewhere."""
    a = np.zeros((3, 3))  # slide origins; the slides run from A_i along e_i
    for x in ([0.0, 0.0, 0.0], [0.03, -0.05, 0.02], [-0.08, 0.06, 0.1]):
        x = np.asarray(x)
        rho = np.array([x[i] + np.sqrt(0.31**2 - x @ x + x[i] ** 2) for i in range(3)])
        b = np.eye(3) * rho[:, None]  # carriage points B_i, from the closed form of the docs
        c = np.tile(x, (3, 1))  # leg end points C_i on the tool
        np.testing.assert_allclose(seed_inverse_jacobian(a, b, c), ortho.jacobian(x).J_inv,
                                   atol=1e-14)


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
