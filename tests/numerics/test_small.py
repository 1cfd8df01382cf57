import numpy as np
import pytest

from pkmkit.numerics import small


def batch_last(m):
    return np.ascontiguousarray(m.transpose(1, 2, 0))


@pytest.mark.parametrize("n", [2, 3])
def test_singular_values_match_lapack_on_random_matrices(n):
    m = np.random.default_rng(n).normal(size=(5000, n, n))
    got = small.singular_values(batch_last(m)).T
    np.testing.assert_allclose(got, np.linalg.svd(m, compute_uv=False), rtol=1e-12)


@pytest.mark.parametrize("n", [2, 3])
def test_ill_conditioned_and_isotropic(n):
    """σ_min keeps its relative accuracy when only one singular value is small."""
    rng = np.random.default_rng(10 + n)
    k = np.logspace(0, -10, 400)
    u = np.linalg.qr(rng.normal(size=(400, n, n)))[0]
    v = np.linalg.qr(rng.normal(size=(400, n, n)))[0]
    s = np.zeros((400, n, n))
    s[:, 0, 0] = 1.0
    if n == 3:
        s[:, 1, 1] = 0.5
    s[:, -1, -1] = k
    m = u @ s @ v.transpose(0, 2, 1)
    got = small.singular_values(batch_last(m)).T
    ref = np.linalg.svd(m, compute_uv=False)
    # both methods carry an error of order eps·σ_max/σ_min relative to σ_min
    assert (np.abs(got - ref) / ref <= 1e-15 / k[:, None] * 50 + 1e-14).all()
    eye = batch_last(np.stack([np.eye(n), 3 * np.eye(n)]))
    np.testing.assert_array_equal(small.singular_values(eye).T, [[1.0] * n, [3.0] * n])


def test_singular_and_nan_matrices():
    m = np.array([[[1.0, 2, 3], [2, 4, 6], [0, 1, 0]], [[np.nan, 0, 0], [0, 1, 0], [0, 0, 1]]])
    sv = small.singular_values(batch_last(m)).T
    np.testing.assert_allclose(sv[0], np.linalg.svd(m[0], compute_uv=False), atol=1e-14)
    assert sv[0, 2] == 0.0 and np.isnan(sv[1]).all()


@pytest.mark.parametrize("n", [2, 3])
def test_det_and_cofactors(n):
    m = np.random.default_rng(n).normal(size=(100, n, n))
    mt = batch_last(m)
    np.testing.assert_allclose(small.det(mt), np.linalg.det(m), rtol=1e-12, atol=1e-12)
    adj = small.cofactors(mt).transpose(2, 1, 0)  # adj = Cᵀ, batch first
    np.testing.assert_allclose(adj / np.linalg.det(m)[:, None, None], np.linalg.inv(m),
                               rtol=1e-9, atol=1e-9)


def test_2x2_nan_and_inf_entries_give_nan_not_zero():
    """A NaN (unreachable pose) must not become σ_min = 0, i.e. κ = inf and 1/κ = 0."""
    m = np.array([[[np.nan, 0.0], [0.0, 1.0]],
                  [[1.0, 2.0], [2.0, 4.0]],      # singular but finite: σ = (5, 0)
                  [[np.inf, 0.0], [0.0, 1.0]],
                  [[0.0, 0.0], [0.0, 0.0]]])
    sv = small.singular_values(batch_last(m)).T
    assert np.isnan(sv[0]).all() and np.isnan(sv[2]).all()
    np.testing.assert_allclose(sv[1], [5.0, 0.0], atol=1e-15)
    np.testing.assert_array_equal(sv[3], [0.0, 0.0])
    # through the public wrappers: κ is NaN (undefined), not inf
    from pkmkit.numerics import condition_number, singular_values

    kappa = condition_number(singular_values(m))
    assert np.isnan(kappa[0]) and np.isnan(kappa[2]) and np.isinf(kappa[1])


@pytest.mark.parametrize("pattern", [(3.0, 1.2, 1.2), (2.0, 2.0, 0.5), (1.5, 1.5, 1.5),
                                     (2.0, 1.0 + 1e-7, 1.0), (5.0, 1.0, 1.0 - 1e-9)])
def test_3x3_coinciding_singular_values_are_accurate(pattern):
    """Matrices U diag(σ) Vᵀ with two (or three) equal or nearly equal singular values: the
    closed forms alone lose about √eps there; the result must match LAPACK to ~1e-13."""
    rng = np.random.default_rng(3)
    n = 200
    u = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    v = np.linalg.qr(rng.normal(size=(n, 3, 3)))[0]
    m = u @ (np.array(pattern)[None, :, None] * np.swapaxes(v, 1, 2))
    got = small.singular_values(np.ascontiguousarray(m.transpose(1, 2, 0)))
    expected = np.linalg.svd(m, compute_uv=False).T
    np.testing.assert_allclose(got, expected, rtol=1e-12)
