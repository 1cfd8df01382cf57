import numpy as np

from pkmkit.numerics.linalg import batched_det, condition_number, singular_values


def test_batched_det_matches_lapack():
    rng = np.random.default_rng(0)
    for n in (2, 3, 4):
        m = rng.normal(size=(50, n, n))
        np.testing.assert_allclose(batched_det(m), np.linalg.det(m), rtol=1e-12, atol=1e-12)


def test_singular_values_sorted_and_nan_rows():
    rng = np.random.default_rng(1)
    m = rng.normal(size=(20, 3, 3))
    m[3] = np.nan
    sv = singular_values(m)
    assert np.isnan(sv[3]).all()
    ok = np.delete(np.arange(20), 3)
    np.testing.assert_allclose(sv[ok], np.linalg.svd(m[ok], compute_uv=False), rtol=1e-12)
    assert (np.diff(sv[ok], axis=1) <= 0).all()


def test_condition_number_edge_cases():
    sv = np.array([[2.0, 1.0], [3.0, 0.0], [np.nan, np.nan]])
    kappa = condition_number(sv)
    assert kappa[0] == 2.0 and np.isinf(kappa[1]) and np.isnan(kappa[2])
