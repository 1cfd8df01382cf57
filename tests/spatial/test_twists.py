"""Twists, adjoints and small displacements against independent formulations (scipy.linalg.expm
of the 4×4 hat matrix, explicit conjugation, finite motions)."""

import numpy as np
import pytest
from scipy.linalg import expm

from pkmkit.spatial import (
    adjoint,
    adjoint_inverse,
    hat,
    move_reduction_point,
    point_displacement,
    se3_exp,
    se3_log,
)

RNG = np.random.default_rng(20261123)


def _random_transform():
    xi = RNG.normal(size=6) * np.array([0.3, 0.3, 0.3, 1.0, 1.0, 1.0])
    return expm(hat(xi))


def test_exp_matches_matrix_exponential_of_the_hat():
    xis = RNG.normal(size=(20, 6)) * 0.8
    for xi, mat in zip(xis, se3_exp(xis), strict=True):
        np.testing.assert_allclose(mat, expm(hat(xi)), atol=1e-13)
    # the linear part comes first: a pure (v, 0) twist is a translation by v
    np.testing.assert_allclose(se3_exp([1.0, 2.0, 3.0, 0, 0, 0])[:3, 3], [1, 2, 3])


def test_log_inverts_exp_and_single_shapes():
    xis = RNG.normal(size=(50, 6)) * 0.9
    np.testing.assert_allclose(se3_log(se3_exp(xis)), xis, atol=1e-12)
    assert se3_exp(xis[0]).shape == (4, 4) and se3_log(se3_exp(xis[0])).shape == (6,)


def test_adjoint_conjugates_twists():
    for _ in range(10):
        t = _random_transform()
        xi = RNG.normal(size=6)
        ad = adjoint(t[:3, :3], t[:3, 3])
        # T exp(ξ̂) T⁻¹ = exp((Ad_T ξ)^)
        np.testing.assert_allclose(t @ hat(xi) @ np.linalg.inv(t), hat(ad @ xi), atol=1e-12)
        np.testing.assert_allclose(adjoint_inverse(t[:3, :3], t[:3, 3]) @ ad, np.eye(6),
                                   atol=1e-12)


def test_small_displacement_of_points_matches_a_small_finite_motion():
    xi = RNG.normal(size=6)
    eps = 1e-7
    points = RNG.normal(size=(5, 3))
    moved = (se3_exp(eps * xi) @ np.c_[points, np.ones(5)].T).T[:, :3]
    np.testing.assert_allclose((moved - points) / eps, point_displacement(xi, points), atol=1e-6)


def test_moving_the_reduction_point():
    torsor = RNG.normal(size=6)
    a, x = RNG.normal(size=(2, 3))
    moved = move_reduction_point(torsor, a)
    # displacement of x computed from either reduction point is the same
    np.testing.assert_allclose(point_displacement(moved, x - a), point_displacement(torsor, x),
                               atol=1e-14)
    np.testing.assert_array_equal(moved[3:], torsor[3:])


@pytest.mark.parametrize("angle", [1e-9, 1e-4, np.pi - 1e-6])
def test_exp_log_near_zero_and_pi(angle):
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    xi = np.r_[0.2, -0.1, 0.3, angle * axis]
    np.testing.assert_allclose(se3_log(se3_exp(xi)), xi, atol=1e-10)
