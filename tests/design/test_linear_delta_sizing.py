"""Linear Delta sizing, checked against the seed's own closed forms (written out here, not
through pkmkit's machine): q_i = z + sqrt(L² − (x − d cos θ_i)² − (y − d sin θ_i)²) and
J = J_x⁻¹ J_q with rows of J_x = (x − d cos θ_i, y − d sin θ_i, z − q_i), J_q = diag(z − q_i)
(seed 000, (III.5), (IV.5), (IV.6), with the errata of docs/seed-errata.md)."""

import math

import numpy as np
import pytest

import pkmkit
from pkmkit.design.linear_delta import VERTICAL_FACTOR, size_linear_delta
from pkmkit.exceptions import InputError

THETA = np.radians([0.0, 120.0, 240.0])
CENTER = np.array([0.0, 0.0, 0.25])


def seed_model(d, length, points):
    """(q (N, 3), singular values of J (N, 3) decreasing); NaN where unreachable."""
    x, y, z = points[:, :1], points[:, 1:2], points[:, 2:]
    dx = x - d * np.cos(THETA)
    dy = y - d * np.sin(THETA)
    with np.errstate(invalid="ignore"):
        q = z + np.sqrt(length**2 - dx**2 - dy**2)
    jx = np.stack([dx, dy, z - q], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        j_inv = jx / (z - q)[:, :, None]  # J⁻¹ = J_q⁻¹ J_x
    ok = np.isfinite(j_inv).all(axis=(1, 2))
    sv = np.full((len(points), 3), np.nan)
    with np.errstate(divide="ignore"):
        sv[ok] = 1.0 / np.linalg.svd(j_inv[ok], compute_uv=False)[:, ::-1]
    return q, sv


def cube(side, center, n):
    g = np.linspace(-side / 2, side / 2, n)
    return np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3) + center


def feasible(d, length, bounds, points):
    _, sv = seed_model(d, length, points)
    return bool(np.isfinite(sv).all() and sv[:, -1].min() >= bounds[0]
                and sv[:, 0].max() <= bounds[1])


@pytest.fixture(scope="module")
def shortest():
    return size_linear_delta(0.5, (0.4, 2.5))


@pytest.mark.ci
def test_shortest_arms_for_the_seed_cube(shortest):
    """x, y in ±0.25 m, z in [0, 0.5] m (Table III.2), λ in [0.4, 2.5]."""
    res = shortest
    assert res.check.feasible and res.objective == "size"
    np.testing.assert_allclose(res.center, CENTER)
    assert res.r == pytest.approx(0.15) and res.R == pytest.approx(res.d + 0.15)
    # brute force with the seed's formulas on a fresh, finer grid
    pts = cube(0.5, CENTER, 31)
    q, sv = seed_model(res.d, res.L, pts)
    assert np.isfinite(sv).all()
    assert sv[:, -1].min() >= 0.4 * (1 - 1e-6) and sv[:, 0].max() <= 2.5 * (1 + 1e-6)
    # both bounds are reached (the design is as small as the bounds allow)
    assert sv[:, -1].min() == pytest.approx(0.4, rel=2e-3)
    assert sv[:, 0].max() == pytest.approx(2.5, rel=2e-3)
    # the strokes are the slider range over the cube
    assert (q.min(axis=0) >= res.q_min - 1e-9).all() and (q.max(axis=0) <= res.q_max + 1e-9).all()
    np.testing.assert_allclose(q.min(axis=0), res.q_min, atol=2e-4)
    np.testing.assert_allclose(q.max(axis=0), res.q_max, atol=2e-4)
    assert res.stroke == pytest.approx(float(np.max(res.q_max - res.q_min)))
    assert res.compactness == pytest.approx(0.5 / res.stroke)
    # the sized machine carries those strokes
    np.testing.assert_allclose(res.machine.model.q_min, res.q_min)


@pytest.mark.ci
def test_no_shorter_arms_work(shortest):
    """1 % shorter arms: no slide offset d keeps the cube within the bounds (fine scan of d,
    seed formulas, 9³ poses)."""
    pts = cube(0.5, CENTER, 9)
    length = 0.99 * shortest.L
    assert not any(feasible(d, length, (0.4, 2.5), pts)
                   for d in np.linspace(0.005, length, 400))
    assert feasible(shortest.d, shortest.L, (0.4, 2.5), pts)


@pytest.mark.ci
def test_most_compact_design_with_bounded_arms():
    """Largest Lw / stroke with L ≤ 1.3 m (the seed's set A arms): no design of a (d, L) grid
    does better (seed formulas, 7³ poses; the grid stroke under-estimates the true one, hence
    the tolerance), and seed set A itself (d = 0.55 m, L = 1.3 m) is less compact."""
    res = size_linear_delta(0.5, (0.4, 2.5), objective="compactness", max_leg=1.3)
    assert res.check.feasible and res.L == pytest.approx(1.3)
    pts = cube(0.5, CENTER, 7)
    best = 0.0
    for length in np.linspace(0.7, 1.3, 7):
        for d in np.linspace(0.02, length, 40):
            if feasible(d, length, (0.4, 2.5), pts):
                q, _ = seed_model(d, length, pts)
                best = max(best, 0.5 / float(np.max(q.max(0) - q.min(0))))
    assert best > 0.6 and res.compactness >= best - 2e-3
    q, _ = seed_model(0.55, 1.3, cube(0.5, CENTER, 21))
    assert res.compactness > 0.5 / float(np.max(q.max(0) - q.min(0)))


def test_vertical_factor_is_always_there():
    """1/√3 lies between λ_min and λ_max at every pose of every vertical-slide Delta built by
    the library (J (1, 1, 1)/√3 = e_z/√3: moving every carriage alike lifts the nacelle as
    fast) — the reason bounds excluding it are refused."""
    rng = np.random.default_rng(3)
    assert VERTICAL_FACTOR == pytest.approx(1 / math.sqrt(3), rel=1e-15)
    for _ in range(20):
        small, d, length = rng.uniform(0.05, 0.2), rng.uniform(0.1, 1.0), rng.uniform(1.1, 2.0)
        m = pkmkit.machine("linear-delta", R=d + small, r=small, L=length)
        x = rng.uniform(-0.3, 0.3, (50, 3))
        jac = m.jacobian(x)
        ok = np.asarray(jac.reachable) & np.isfinite(jac.singular_values).all(axis=1)
        assert ok.sum() > 10
        sv = jac.singular_values[ok]
        lifted = np.einsum("kij,j->ki", jac.J[ok], np.ones(3) / math.sqrt(3))
        np.testing.assert_allclose(lifted, np.tile([0, 0, VERTICAL_FACTOR], (ok.sum(), 1)),
                                   atol=1e-12)
        assert (sv[:, -1] <= VERTICAL_FACTOR + 1e-12).all()
        assert (sv[:, 0] >= VERTICAL_FACTOR - 1e-12).all()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"bounds": (0.6, 2.0)}, "exclude 1/√3"),
        ({"bounds": (0.2, 0.5)}, "exclude 1/√3"),
        ({"objective": "compactness"}, "needs a largest arm length"),
        ({"objective": "beauty"}, "unknown objective"),
        ({"max_leg": -1.0}, "largest admissible arm length"),
        ({"max_leg": 0.5}, "no linear Delta with arms up to the admissible 0.5 m"),
        ({"max_leg": 0.3}, "cannot reach every corner"),
        ({"center": (0.0, float("nan"), 0.0)}, "3 finite coordinates"),
        ({"r": 0.0}, "nacelle radius"),
        ({"cube_side": 1e-300}, "between 1e-06 m"),
    ],
)
def test_bad_specifications(kwargs, message):
    args = {"cube_side": 0.5, "bounds": (0.4, 2.5)} | kwargs
    with pytest.raises(InputError, match=message):
        size_linear_delta(args.pop("cube_side"), args.pop("bounds"), **args)
