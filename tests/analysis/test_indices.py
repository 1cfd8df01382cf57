import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.indices import (
    SCALAR_INDICES,
    global_conditioning_index,
    homogenize,
    indices,
    scalar_index,
)
from pkmkit.errors import InputError
from tests.conftest import random_poses


def test_factors_and_ellipsoid_against_svd(preset):
    x = random_poses(preset, 50, seed=21)
    ind = indices(preset, x, ellipsoids=True)
    j = preset.jacobian(x).J
    u, s, _ = np.linalg.svd(j)
    np.testing.assert_allclose(ind.velocity_factors, s, rtol=1e-12)
    np.testing.assert_allclose(ind.force_factors, 1 / s[:, ::-1], rtol=1e-12)
    # force factors are the singular values of J^-T
    np.testing.assert_allclose(ind.force_factors,
                               np.linalg.svd(np.linalg.inv(j).transpose(0, 2, 1),
                                             compute_uv=False), rtol=1e-10)
    np.testing.assert_allclose(ind.inverse_condition * ind.condition, 1.0, rtol=1e-12)
    # principal directions: J Jᵀ d = σ² d
    for k in range(preset.dims):
        d = ind.ellipsoid_directions[:, :, k]
        lhs = np.einsum("nij,nj->ni", j @ j.transpose(0, 2, 1), d)
        np.testing.assert_allclose(lhs, ind.ellipsoid_axes[:, k, None] ** 2 * d, atol=1e-10)
    np.testing.assert_allclose(np.abs(np.einsum("nik,nik->nk", u, ind.ellipsoid_directions)),
                               1.0, atol=1e-10)


def test_isotropy_flag():
    ortho = pkmkit.machine("orthoglide")
    ind = indices(ortho, [[0, 0, 0], [0.05, 0, 0]])
    assert ind.isotropic.tolist() == [True, False]
    five = pkmkit.machine("five-bar")
    assert bool(indices(five, five.home_pose).isotropic)


def test_scalar_indices_and_unknown_name():
    m = pkmkit.machine("linear-delta")
    ind = indices(m, [[0.1, 0.0, 0.2], [5.0, 0.0, 0.0]])
    for name in SCALAR_INDICES:
        values = scalar_index(ind, name)
        assert values.shape == (2,) and np.isfinite(values[0]) and np.isnan(values[1])
    assert scalar_index(ind, "manipulability")[0] == pytest.approx(
        abs(np.linalg.det(m.jacobian([0.1, 0.0, 0.2]).J)))
    with pytest.raises(InputError, match="valid indices"):
        scalar_index(ind, "stiffness")


def test_global_conditioning_index():
    ortho = pkmkit.machine("orthoglide")
    assert global_conditioning_index(ortho, np.zeros((4, 3))) == pytest.approx(1.0)
    x = random_poses(ortho, 500, seed=3)
    gci = global_conditioning_index(ortho, x)
    assert 0.3 < gci < 1.0
    assert np.isnan(global_conditioning_index(ortho, x, mask=np.zeros(500, bool)))


def test_homogenize_scales_angular_rows():
    j = np.arange(12.0).reshape(4, 3)
    out = homogenize(j, [2, 3], 0.5)
    np.testing.assert_array_equal(out[:2], j[:2])
    np.testing.assert_array_equal(out[2:], 0.5 * j[2:])
    with pytest.raises(InputError):
        homogenize(j, [2], 0.0)
