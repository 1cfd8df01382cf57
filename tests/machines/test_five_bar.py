"""Five-bar with prismatic actuators against seed 004 (Chablat, Wenger & Angeles 2000)."""

import numpy as np
import pytest

import pkmkit
from tests.conftest import random_poses


@pytest.fixture(scope="module", params=["five-bar-isotropic", "five-bar-biglide"])
def five(request):
    return pkmkit.machine(request.param)


def leg_angles(m, x, q):
    """θ1, θ2: directions of the legs C→P and D→P, from the parameters and positions."""
    c, d = slide_points(m, q)
    return np.stack([np.arctan2(*(x - c).T[::-1]), np.arctan2(*(x - d).T[::-1])], axis=1)


def test_kappa_a_closed_form(five):
    x = random_poses(five, 300, seed=6)
    q = five.ik(x)
    theta = leg_angles(five, x, q)
    jac = five.jacobian(x)
    sv = np.linalg.svd(jac.A, compute_uv=False)
    expected = 1 / np.abs(np.tan((theta[:, 1] - theta[:, 0]) / 2))
    # seed: κ(A) = σmax/σmin = 1/|tan((θ2 − θ1)/2)| when ≥ 1, its inverse otherwise
    kappa = sv[:, 0] / sv[:, 1]
    np.testing.assert_allclose(kappa, np.maximum(expected, 1 / expected), rtol=1e-10)
    # A Aᵀ = L² [[1, cos(θ1 − θ2)], [cos(θ1 − θ2), 1]]
    aat = jac.A @ np.swapaxes(jac.A, 1, 2)
    length = five.params["L"]
    np.testing.assert_allclose(aat[:, 0, 1], length**2 * np.cos(theta[:, 0] - theta[:, 1]),
                               atol=1e-12)


def test_kappa_b_closed_form(five):
    x = random_poses(five, 300, seed=7)
    q = five.ik(x)
    theta = leg_angles(five, x, q)
    alpha = np.array([five.params["alpha1"], five.params["alpha2"]])
    c = np.abs(np.cos(theta - alpha))
    jac = five.jacobian(x)
    length = five.params["L"]
    np.testing.assert_allclose(np.abs(np.diagonal(jac.B, axis1=1, axis2=2)), length * c,
                               atol=1e-12)
    sv = np.abs(np.diagonal(jac.B, axis1=1, axis2=2))
    np.testing.assert_allclose(sv.max(1) / sv.min(1), c.max(1) / c.min(1), rtol=1e-12)


def test_isotropic_configuration():
    m = pkmkit.machine("five-bar-isotropic")
    big_m = m.params["B"][0]
    assert m.params["B"] == (big_m, -big_m) and m.params["A"] == (0.0, 0.0)
    length = m.params["L"]
    np.testing.assert_allclose(m.home_q, [big_m - length] * 2, atol=1e-15)  # ρ1 = ρ2
    jac = m.jacobian(m.home_pose)
    np.testing.assert_allclose(jac.J_inv, np.eye(2), atol=1e-15)
    np.testing.assert_allclose(jac.J, np.eye(2), atol=1e-15)
    # moving ρ1 moves P along x, ρ2 along y, like a PP table
    for step in ([1e-4, 0.0], [0.0, 1e-4]):
        moved = m.fk(m.home_q + np.array(step)) - m.home_pose
        np.testing.assert_allclose(moved, step, atol=1e-7)


def slide_points(m, q):
    """Carriage points C, D ``(N, 2)`` from the parameters (independent of the library)."""
    u = np.array([[np.cos(m.params["alpha1"]), np.sin(m.params["alpha1"])],
                  [np.cos(m.params["alpha2"]), np.sin(m.params["alpha2"])]])
    return np.asarray(m.params["A"]) + q[:, :1] * u[0], np.asarray(m.params["B"]) + q[:, 1:] * u[1]


def test_parallel_singularity_when_c_d_p_aligned():
    """Isotropic design: for any direction e, P = (M − L e_x, L e_y) has C = P − L e on slide 1
    and D = P + L e on slide 2, aligned with P; the inverse model reaches it and it is flagged
    parallel, with both assembly modes merged and J undefined."""
    m = pkmkit.machine("five-bar-isotropic")
    big_m, length = m.params["B"][0], m.params["L"]
    for phi in np.radians([10.0, 35.0, 60.0, 80.0]):
        e = np.array([np.cos(phi), np.sin(phi)])
        p = np.array([big_m - length * e[0], length * e[1]])
        q = np.array([big_m - 2 * length * e[0], 2 * length * e[1] + big_m])
        jac = m.jacobian(p, q=q)
        assert jac.status == "parallel"
        assert np.isnan(jac.J).all() and np.isnan(jac.condition)
        modes = m.fk_all(q)
        assert modes.count == 1
        np.testing.assert_allclose(modes.poses[0], p, atol=1e-6)


def test_det_a_is_the_cross_product_of_c_d_p(five):
    """det A = (D − C) × (P − C): zero exactly when C, D and P are aligned."""
    x = random_poses(five, 200, seed=9)
    q = five.ik(x)
    c, d = slide_points(five, q)
    cross = (d - c)[:, 0] * (x - c)[:, 1] - (d - c)[:, 1] * (x - c)[:, 0]
    np.testing.assert_allclose(five.jacobian(x).det_A, cross, atol=1e-12)


def test_parallel_singularity_flagged_at_double_root():
    m = pkmkit.machine("five-bar-biglide")
    # carriages exactly 2L apart on the rail: P at their midpoint, C, D, P aligned
    length = m.params["L"]
    base_b = m.model.leg_base[1, 0]
    q = np.array([0.2, 0.2 + 2 * length - base_b])
    modes = m.fk_all(q)
    assert modes.count == 1
    p = modes.poses[0]
    jac = m.jacobian(p)  # through the inverse model
    np.testing.assert_allclose(jac.q, q, atol=1e-6)
    assert jac.status == "parallel" and np.isnan(jac.condition) and np.isnan(jac.J).all()


def test_serial_singularity_at_workspace_boundary():
    m = pkmkit.machine("five-bar-isotropic")
    # leg 1 perpendicular to slide 1 (θ1 − α1 = 90°): P straight above C
    q1 = 0.6
    p = np.array([q1, m.params["L"]])
    q = m.ik(p)
    assert q[0] == pytest.approx(q1)
    jac = m.jacobian(p)
    assert "serial" in jac.status and jac.serial_measure < 1e-12


def test_biglide_shares_ab_distance_and_legs():
    iso, big = pkmkit.machine("five-bar-isotropic"), pkmkit.machine("five-bar-biglide")
    ab = lambda m: np.linalg.norm(np.subtract(m.params["B"], m.params["A"]))  # noqa: E731
    assert ab(iso) == pytest.approx(ab(big)) and iso.params["L"] == big.params["L"]
    assert big.jacobian(big.home_pose).condition == pytest.approx(1.0)  # legs at 90°


def five_bar_cross(m, q, p):
    """(D − C) × (P − C) for carriages C = A + ρ1 u1, D = B + ρ2 u2 from the parameters."""
    a, b = np.asarray(m.params["A"]), np.asarray(m.params["B"])
    u1 = np.array([np.cos(m.params["alpha1"]), np.sin(m.params["alpha1"])])
    u2 = np.array([np.cos(m.params["alpha2"]), np.sin(m.params["alpha2"])])
    c, d = a + q[0] * u1, b + q[1] * u2
    return (d - c)[0] * (p - c)[1] - (d - c)[1] * (p - c)[0]


@pytest.mark.parametrize("ident", ["five-bar-isotropic", "five-bar-biglide"])
def test_mode_labels_follow_the_side_of_cd(ident):
    """Each assembly mode's name says on which side of the directed line C→D the tool point
    lies, computed here from the carriage positions: swapped names must fail."""
    m = pkmkit.machine(ident)
    x = random_poses(m, 30, seed=17)
    q = m.ik(x)
    modes = m.fk_all(q)
    assert modes.valid.all()
    for k in range(len(q)):
        for col in range(2):
            side = five_bar_cross(m, q[k], modes.poses[k, col])
            assert abs(side) > 1e-6
            assert modes.labels[col] == ("left-of-CD" if side > 0 else "right-of-CD")
            assert np.sign(np.linalg.det(m.jacobian(modes.poses[k, col], q=q[k]).A)) == \
                modes.mode_signs[col]
    # the working mode is the home configuration's side
    home_side = five_bar_cross(m, m.home_q, m.home_pose)
    assert m.mode_labels[0] == ("left-of-CD" if home_side > 0 else "right-of-CD")
