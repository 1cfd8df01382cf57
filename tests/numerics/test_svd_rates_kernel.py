"""Singular values with their rates (:func:`pkmkit.numerics.linalg.singular_value_rates`): the
compiled one-sided Jacobi kernel against LAPACK's SVD with vectors (σ̇_i = u_iᵀ Ṁ v_i), and
both against central differences of the singular values."""

import numpy as np
import pytest

from pkmkit.numerics.linalg import singular_value_rates

pytest.importorskip("numba")


@pytest.mark.parametrize("shape", [(6, 6), (6, 3), (3, 6), (8, 6)])
def test_rates_agree_with_lapack_and_differences(shape, monkeypatch):
    rng = np.random.default_rng(11)
    m = rng.normal(size=(200, *shape))
    dm = rng.normal(size=(200, *shape, 2))
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    sigma, rates = singular_value_rates(m, dm)
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    sigma_ref, rates_ref = singular_value_rates(m, dm)
    k = min(shape)
    assert sigma.shape == (200, k) and rates.shape == (200, k, 2)
    np.testing.assert_allclose(sigma, np.linalg.svd(m, compute_uv=False), rtol=1e-13)
    np.testing.assert_allclose(sigma, sigma_ref, rtol=1e-13)
    np.testing.assert_allclose(rates, rates_ref, atol=1e-10 * np.abs(rates_ref).max())
    h = 1e-6
    for e in range(2):
        central = (np.linalg.svd(m + h * dm[..., e], compute_uv=False)
                   - np.linalg.svd(m - h * dm[..., e], compute_uv=False)) / (2 * h)
        np.testing.assert_allclose(rates[:, :, e], central, atol=1e-6)


def test_non_finite_rows_give_nan(monkeypatch):
    m = np.random.default_rng(2).normal(size=(40, 6, 6))
    dm = np.ones((40, 6, 6, 1))
    m[3, 1, 1] = np.nan
    dm[5, 0, 0, 0] = np.inf
    for mode in ("1", "0"):
        monkeypatch.setenv("PKMKIT_COMPILED", mode)
        sigma, rates = singular_value_rates(m, dm)
        assert np.isnan(rates[[3, 5]]).all() and np.isfinite(np.delete(rates, [3, 5], 0)).all()
        assert np.isnan(sigma[3]).all()
