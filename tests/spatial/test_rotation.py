import numpy as np

from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix, skew


def test_skew_is_cross_product():
    rng = np.random.default_rng(0)
    v, w = rng.normal(size=(2, 10, 3))
    np.testing.assert_allclose(np.einsum("kij,kj->ki", skew(v), w), np.cross(v, w), atol=1e-15)


def test_rotvec_matrices_are_rotations_and_compose():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, 20, 3))
    ra, rb = rotvec_to_matrix(a), rotvec_to_matrix(b)
    np.testing.assert_allclose(ra @ ra.transpose(0, 2, 1), np.broadcast_to(np.eye(3), ra.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(ra), 1.0, atol=1e-12)
    np.testing.assert_allclose(rotvec_to_matrix(compose_rotvec(a, b)), ra @ rb, atol=1e-12)


def test_small_rotation_is_identity_plus_skew():
    d = np.array([[1e-7, -2e-7, 3e-7]])
    np.testing.assert_allclose(rotvec_to_matrix(d)[0], np.eye(3) + skew(d[0]), atol=1e-13)


def test_matrix_to_rotvec_keeps_good_rows_of_a_batch_with_failed_ones():
    """A batch whose failed rows are NaN (a direct model that did not close) converts its good
    rows and leaves NaN rows NaN — SciPy alone may raise on them (SVD did not converge)."""
    from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

    phi = np.array([[0.1, -0.2, 0.3], [0.0, 0.0, 0.0], [1.0, 2.0, -0.5]])
    mats = rotvec_to_matrix(phi)
    mats[1] = np.nan
    mats[2, 0, 1] = np.inf
    out = matrix_to_rotvec(mats)
    np.testing.assert_allclose(out[0], phi[0], atol=1e-14)
    assert np.isnan(out[1:]).all()


def test_left_jacobians_against_the_exponential_map():
    """One SO(3) left Jacobian for the whole package: exp(φ + dφ) = exp(J_l dφ) exp(φ) to
    first order, checked by central differences of scipy's exponential map, across the
    series/closed-form switch; the inverse is the matrix inverse."""
    from scipy.spatial.transform import Rotation

    from pkmkit.spatial.rotation import inverse_left_jacobian, left_jacobian

    rng = np.random.default_rng(7)
    directions = rng.normal(size=(6, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    for theta in (0.0, 3e-7, 2e-6, 9e-4, 1.1e-3, 0.3, 2.5):
        for u in directions:
            phi = theta * u
            h = 1e-6
            numeric = np.empty((3, 3))
            base = Rotation.from_rotvec(phi)
            for k in range(3):
                step = np.zeros(3)
                step[k] = h
                plus = (Rotation.from_rotvec(phi + step) * base.inv()).as_rotvec()
                minus = (Rotation.from_rotvec(phi - step) * base.inv()).as_rotvec()
                numeric[:, k] = (plus - minus) / (2 * h)
            np.testing.assert_allclose(left_jacobian(phi), numeric, atol=1e-8)
            np.testing.assert_allclose(inverse_left_jacobian(phi[None])[0] @ left_jacobian(phi),
                                       np.eye(3), atol=1e-12)
