"""Study-coordinate rod equations: against the rod geometry and by finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.solve.study_rods import (
    RodParameters,
    StudyHomotopy,
    pose_to_study,
    rod_quadrics,
    study_to_pose,
)

RNG = np.random.default_rng(11)


def _crandn(*shape):
    return (RNG.normal(size=shape) + 1j * RNG.normal(size=shape)) / np.sqrt(2)


def _quat_scalar_first(rot: Rotation) -> np.ndarray:
    return rot.as_quat()[:, [3, 0, 1, 2]]


def test_pose_round_trip_and_study_quadric():
    rot = Rotation.random(20, random_state=1)
    p = RNG.normal(size=(20, 3))
    scale = RNG.uniform(0.2, 3.0, size=(20, 1)) * RNG.choice([-1, 1], size=(20, 1))
    x = pose_to_study(p, scale * _quat_scalar_first(rot))
    assert np.abs(np.einsum("pk,pk->p", x[:, :4], x[:, 4:])).max() < 1e-14
    p_back, q_back = study_to_pose(x)
    np.testing.assert_allclose(p_back, p, atol=1e-13)
    back = Rotation.from_quat(q_back[:, [1, 2, 3, 0]])
    assert (back.inv() * rot).magnitude().max() < 1e-12


def test_rod_quadrics_equal_scaled_squared_rod_equations():
    """f_j(e, g) = (e·e) (|p + R b_j − a_j|² − ℓ_j²) for any pose and any quaternion scale."""
    n = 15
    a, b = RNG.normal(size=(n, 6, 3)), RNG.normal(size=(n, 6, 3))
    ell = RNG.uniform(0.5, 2.0, size=(n, 6))
    rot = Rotation.random(n, random_state=2)
    p = RNG.normal(size=(n, 3))
    scale = RNG.uniform(0.5, 2.0, size=(n, 1))
    x = pose_to_study(p, scale * _quat_scalar_first(rot))
    d = p[:, None] + np.einsum("nij,nkj->nki", rot.as_matrix(), b) - a
    expected = scale**2 * ((d**2).sum(axis=2) - ell**2)
    got = rod_quadrics(x.T, RodParameters.from_geometry(a, b, ell)).T
    np.testing.assert_allclose(got, expected, atol=1e-12)


def _reference(start, target, patch, x, t, col):
    """H by the quaternion formula at the interpolated parameters (no coefficient expansion)."""
    par = RodParameters(
        target.base[:, :, [col]] + t * (start.base - target.base[:, :, [col]]),
        target.platform[:, :, [col]] + t * (start.platform - target.platform[:, :, [col]]),
        target.offset[:, [col]] + t * (start.offset - target.offset[:, [col]]),
    )
    rods = rod_quadrics(x[:, None], par)[:, 0]
    return np.r_[rods, x[:4] @ x[4:], patch @ x - 1.0]


@pytest.mark.parametrize("n_conf", [1, 3])
def test_homotopy_value_and_derivatives(n_conf):
    start = RodParameters(_crandn(3, 6, 1), _crandn(3, 6, 1), _crandn(6, 1))
    target = RodParameters(_crandn(3, 6, n_conf), _crandn(3, 6, n_conf), _crandn(6, n_conf))
    patch = _crandn(8)
    hom = StudyHomotopy.between(start, target, patch)
    n_pts = 6
    x = _crandn(n_pts, 8)
    t = RNG.uniform(0, 1, n_pts)
    cols = RNG.integers(0, n_conf, n_pts)
    res, jac, d_t = hom.evaluate(x, t, None if n_conf == 1 else cols)
    h = 1e-6
    for k in range(n_pts):
        c = 0 if n_conf == 1 else cols[k]
        ref = _reference(start, target, patch, x[k], t[k], c)
        np.testing.assert_allclose(res[k], ref, atol=1e-12)
        # holomorphic: a real finite difference along each coordinate gives the column
        fd = np.array([(_reference(start, target, patch, x[k] + h * e, t[k], c)
                        - _reference(start, target, patch, x[k] - h * e, t[k], c)) / (2 * h)
                       for e in np.eye(8)]).T
        np.testing.assert_allclose(jac[k], fd, atol=1e-7)
        fd_t = (_reference(start, target, patch, x[k], t[k] + h, c)
                - _reference(start, target, patch, x[k], t[k] - h, c)) / (2 * h)
        np.testing.assert_allclose(d_t[k], fd_t, atol=1e-7)
