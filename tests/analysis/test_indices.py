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
from pkmkit.exceptions import InputError
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


def independent_scalar_indices(machine, x):
    """Every scalar index at poses ``x`` written from J, A and the slide axes with numpy only
    (singular values of J and of J⁻ᵀ, A with unit rows, leg/slide cosines)."""
    jac = machine.jacobian(x)
    s = np.linalg.svd(jac.J, compute_uv=False)
    force = np.linalg.svd(np.linalg.inv(jac.J).transpose(0, 2, 1), compute_uv=False)
    unit_rows = jac.A / np.linalg.norm(jac.A, axis=2, keepdims=True)
    sa = np.linalg.svd(unit_rows, compute_uv=False)
    legs = machine.model.pad(np.atleast_2d(x))[:, None, :] - (
        machine.model.leg_base[None] - machine.model.leg_platform[None]
        + jac.q[:, :, None] * machine.model.leg_axis[None])
    cosines = np.abs(np.einsum("kid,id->ki", legs, machine.model.leg_axis)) / np.linalg.norm(
        legs, axis=2)
    return {
        "lambda_min": s[:, -1], "lambda_max": s[:, 0], "condition": s[:, 0] / s[:, -1],
        "inverse_condition": s[:, -1] / s[:, 0], "force_min": force[:, -1],
        "force_max": force[:, 0], "parallel_distance": sa[:, -1] / sa[:, 0],
        "serial_distance": cosines.min(axis=1),
        "manipulability": np.abs(np.linalg.det(jac.J)),
    }


@pytest.mark.parametrize("ident", ["linear-delta", "orthoglide", "five-bar"])
def test_every_scalar_index_against_its_definition(ident):
    """Each name maps to its own quantity (λ_min is not λ_max, the smallest force factor is
    1/λ_max, ...) at anisotropic poses where all of them differ."""
    m = pkmkit.machine(ident)
    x = random_poses(m, 20, seed=31)
    ind = indices(m, x)
    expected = independent_scalar_indices(m, x)
    assert set(expected) == set(SCALAR_INDICES)
    assert (expected["lambda_max"] > expected["lambda_min"] * (1 + 1e-3)).all()
    for name, value in expected.items():
        np.testing.assert_allclose(scalar_index(ind, name), value, rtol=1e-10, err_msg=name)
    np.testing.assert_allclose(expected["force_min"] * expected["lambda_max"], 1.0, rtol=1e-12)


def test_global_conditioning_index_counts_parallel_singular_poses_as_zero():
    """Orthoglide: the isotropic point (1/κ = 1) and a parallel singularity on the diagonal
    (t = L√(3/2)/3, det A = 0, reachable, 1/κ → 0). The GCI of the two is 0.5, not 1.0 (the
    singular pose dropped) nor NaN; with three samples 2/3 and with weights (1, 3) 0.25."""
    ortho = pkmkit.machine("orthoglide")
    t = ortho.params["L"] * np.sqrt(1.5) / 3
    points = np.array([[0.0, 0.0, 0.0], [t, t, t]])
    jac = ortho.jacobian(points)
    assert jac.status == ["regular", "parallel"] and jac.reachable.all()
    assert global_conditioning_index(ortho, points) == pytest.approx(0.5, abs=1e-15)
    assert global_conditioning_index(ortho, points[[0, 1, 0]]) == pytest.approx(2 / 3, abs=1e-15)
    assert global_conditioning_index(ortho, points, weights=np.array([1.0, 3.0])) == \
        pytest.approx(0.25, abs=1e-15)


def five_bar_inverse_condition(p, a=(0.0, 0.0), b=(1.0, -1.0), length=0.5):
    """1/κ of the isotropic five-bar (slides along x from A and along y from B, legs of
    length L, working branches as at home) from seed 004's formulas and numpy's SVD; NaN where
    the pose is out of reach."""
    p = np.atleast_2d(p)
    dy, dx = p[:, 1] - a[1], p[:, 0] - b[0]
    with np.errstate(invalid="ignore"):
        rho1 = p[:, 0] - a[0] - np.sqrt(length**2 - dy**2)
        rho2 = p[:, 1] - b[1] - np.sqrt(length**2 - dx**2)
    c = np.stack([a[0] + rho1, np.full_like(rho1, a[1])], axis=1)
    d = np.stack([np.full_like(rho2, b[0]), b[1] + rho2], axis=1)
    out = np.full(len(p), np.nan)
    ok = np.isfinite(rho1) & np.isfinite(rho2)
    pc, pd = (p - c)[ok], (p - d)[ok]
    a_mat = np.stack([pc, pd], axis=1)                     # A = [(p − c)ᵀ; (p − d)ᵀ]
    b_mat = np.zeros((ok.sum(), 2, 2))
    b_mat[:, 0, 0], b_mat[:, 1, 1] = pc[:, 0], pd[:, 1]    # B = diag((p − c)·u1, (p − d)·u2)
    s = np.linalg.svd(np.linalg.solve(a_mat, b_mat), compute_uv=False)
    out[ok] = s[:, -1] / s[:, 0]
    return out


def test_planar_indices_at_unreachable_poses_are_nan():
    """Reviewer's case: the five-bar at (0.4, −0.6) is out of reach; its 2×2 singular values
    used to come out as (NaN, 0), i.e. κ = inf, 1/κ = 0, λ_min = 0."""
    m = pkmkit.machine("five-bar")
    ind = indices(m, [[0.4, -0.6], [1.1, 0.05]])
    assert ind.reachable.tolist() == [False, True]
    for name in SCALAR_INDICES:
        values = scalar_index(ind, name)
        assert np.isnan(values[0]) and np.isfinite(values[1]), name
    assert not ind.isotropic[0]
    assert np.isnan(ind.velocity_factors[0]).all() and np.isnan(ind.force_factors[0]).all()


def test_global_conditioning_index_against_independent_formula():
    """GCI = mean of 1/κ over the *reachable* samples (the unreachable ones used to count as
    1/κ = 0), compared with seed 004's formulas evaluated with numpy's SVD."""
    m = pkmkit.machine("five-bar")
    lo, hi = m.default_box()
    x = np.random.default_rng(7).uniform(lo, hi, (40_000, 2))
    ref = five_bar_inverse_condition(x)
    reach = np.isfinite(ref)
    assert 0.5 < reach.mean() < 0.9  # the box holds unreachable poses
    np.testing.assert_allclose(indices(m, x).inverse_condition, ref, atol=1e-10)
    gci = global_conditioning_index(m, x)
    assert gci == pytest.approx(ref[reach].mean(), abs=1e-10)
    assert gci == pytest.approx(0.442, abs=0.005)  # the default box's value (was 0.30)
    # a mask restricts the region further; weights weight the samples
    left = x[:, 0] < 1.0
    assert global_conditioning_index(m, x, mask=left) == pytest.approx(
        ref[reach & left].mean(), abs=1e-10)
    w = np.random.default_rng(8).uniform(0.5, 2.0, len(x))
    assert global_conditioning_index(m, x, weights=w) == pytest.approx(
        np.sum((ref * w)[reach]) / np.sum(w[reach]), abs=1e-10)
    ortho = pkmkit.machine("orthoglide")
    assert global_conditioning_index(ortho, np.zeros((4, 3))) == pytest.approx(1.0)
    assert np.isnan(global_conditioning_index(ortho, np.zeros((4, 3)),
                                              mask=np.zeros(4, bool)))


def test_indices_with_characteristic_length():
    """indices(..., rotational_rows, characteristic_length) takes every index on the
    homogenised J (rows scaled by L_c), checked against numpy's SVD of the scaled matrix."""
    m = pkmkit.machine("orthoglide")
    x = random_poses(m, 20, seed=5)
    j = m.jacobian(x).J.copy()
    j[:, 2, :] *= 0.25
    s = np.linalg.svd(j, compute_uv=False)
    ind = indices(m, x, rotational_rows=[2], characteristic_length=0.25)
    np.testing.assert_allclose(ind.velocity_factors, s, rtol=1e-12)
    np.testing.assert_allclose(ind.condition, s[:, 0] / s[:, -1], rtol=1e-12)
    with pytest.raises(InputError, match="both"):
        indices(m, x, characteristic_length=0.25)
    with pytest.raises(InputError, match="> 0"):
        indices(m, x, rotational_rows=[2], characteristic_length=-1.0)


def test_force_factors_meaning():
    """A unit tool force F needs actuator forces f = Jᵀ F of norm between λ_min and λ_max; a
    unit vector of actuator forces gives a tool force J⁻ᵀ f between 1/λ_max and 1/λ_min."""
    m = pkmkit.machine("linear-delta")
    x = np.array([0.1, 0.1, 0.2])
    ind = indices(m, x)
    j = m.jacobian(x).J
    dirs = np.random.default_rng(1).normal(size=(20_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    f = np.linalg.norm(dirs @ j, axis=1)  # |Jᵀ F| for unit F
    lam = ind.velocity_factors
    assert lam[-1] * (1 - 1e-12) <= f.min() < lam[-1] * 1.01
    assert lam[0] * 0.99 < f.max() <= lam[0] * (1 + 1e-12)
    tool = np.linalg.norm(np.linalg.solve(j.T, dirs.T).T, axis=1)  # |J⁻ᵀ f| for unit f
    assert ind.force_factors[-1] * (1 - 1e-12) <= tool.min()
    assert tool.max() <= ind.force_factors[0] * (1 + 1e-12)


def test_parallel_distance_is_conditioning_of_unit_leg_matrix(preset):
    """parallel_distance = σ_min/σ_max of A with unit rows (not σ_min of A), from numpy."""
    x = random_poses(preset, 30, seed=9)
    a = preset.jacobian(x).A
    s = np.linalg.svd(a / np.linalg.norm(a, axis=2, keepdims=True), compute_uv=False)
    np.testing.assert_allclose(indices(preset, x).parallel_distance, s[:, -1] / s[:, 0],
                               rtol=1e-10)


def test_homogenize_scales_angular_rows():
    j = np.arange(12.0).reshape(4, 3)
    out = homogenize(j, [2, 3], 0.5)
    np.testing.assert_array_equal(out[:2], j[:2])
    np.testing.assert_array_equal(out[2:], 0.5 * j[2:])
    with pytest.raises(InputError):
        homogenize(j, [2], 0.0)
