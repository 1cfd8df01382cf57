"""The compiled one-sided Jacobi singular values against LAPACK (np.linalg.svd)."""

import numpy as np
import pytest

from pkmkit.numerics.linalg import small_singular_values

pytest.importorskip("numba")



@pytest.mark.parametrize("shape", [(6, 6), (6, 3), (3, 6), (8, 6), (2, 2)])
def test_jacobi_singular_values_agree_with_lapack(shape, monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    rng = np.random.default_rng(7)
    m = rng.normal(size=(300, *shape))
    # graded and rank-deficient matrices: the small singular values are where methods differ
    k = min(shape)
    m[100:200] = m[100:200] @ np.diag(np.logspace(0, -9, shape[1]))
    m[200:250, :, -1] = m[200:250, :, 0]  # two equal columns: σ_min = 0
    out = small_singular_values(m)
    ref = np.linalg.svd(m, compute_uv=False)
    assert out.shape == (300, k)
    assert np.all(np.diff(out, axis=1) <= 0)
    # absolute accuracy relative to σ_max, as LAPACK's own
    assert np.max(np.abs(out - ref) / ref[:, :1]) < 1e-14
    # well-conditioned rows: relative accuracy of every singular value
    assert np.max(np.abs(out[:100] - ref[:100]) / ref[:100]) < 1e-13


def test_jacobi_and_lapack_paths_agree_and_flag_non_finite_rows(monkeypatch):
    m = np.random.default_rng(3).normal(size=(50, 6, 6))
    m[4, 2, 3] = np.nan
    m[9, 0, 0] = np.inf
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    compiled = small_singular_values(m)
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    lapack = small_singular_values(m)
    for out in (compiled, lapack):
        assert np.isnan(out[[4, 9]]).all() and np.isfinite(np.delete(out, [4, 9], 0)).all()
    np.testing.assert_allclose(compiled, lapack, rtol=1e-13)


def test_isotropic_and_diagonal_matrices_are_exact(monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    q, _ = np.linalg.qr(np.random.default_rng(1).normal(size=(6, 6)))
    diag = np.diag([3.0, -1.0, 0.5, 2.0, 0.0, 7.0])
    out = small_singular_values(np.stack([2.5 * q, diag]))
    np.testing.assert_allclose(out[0], 2.5, rtol=1e-15)
    assert out[1].tolist() == [7.0, 3.0, 2.0, 1.0, 0.5, 0.0]
