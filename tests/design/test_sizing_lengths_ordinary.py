"""Cheap checks of the sizings' length scales for the ordinary run (each well under a second).

The sizings' own tests (the seed cubes, the bounds sweeps, the 1000-times-smaller cube) are
marked ``ci``: a sizing on the default grids costs seconds. These size on the coarsest grids and
check each result against an oracle written out here: the seeds' closed forms (seed 000 for the
linear Delta, seed 004 for the five-bar) and the seeds' reference numbers (seed 001 for the
Orthoglide). Each test fails with a scale factor of the sizing dropped or inverted
(docs/testing.md, "Mutation scores of the ordinary run", issue 22 §4).
"""

import numpy as np
import pytest

from pkmkit.design.five_bar import size_five_bar
from pkmkit.design.linear_delta import size_linear_delta
from pkmkit.design.orthoglide import size_orthoglide

THETA = np.radians([0.0, 120.0, 240.0])


def delta_slides(d, length, points):
    """Seed 000 (III.5): q_i = z + sqrt(L² − (x − d cos θ_i)² − (y − d sin θ_i)²), and the
    singular values of J = J_x⁻¹ J_q (IV.5, IV.6), decreasing; NaN where out of reach."""
    x, y, z = points[:, :1], points[:, 1:2], points[:, 2:]
    dx, dy = x - d * np.cos(THETA), y - d * np.sin(THETA)
    with np.errstate(invalid="ignore", divide="ignore"):
        q = z + np.sqrt(length**2 - dx**2 - dy**2)
        j_inv = np.stack([dx, dy, z - q], axis=-1) / (z - q)[:, :, None]
    sv = np.full((len(points), 3), np.nan)
    ok = np.isfinite(j_inv).all(axis=(1, 2))
    sv[ok] = 1.0 / np.linalg.svd(j_inv[ok], compute_uv=False)[:, ::-1]
    return q, sv


def cube(side, n):
    """n³ points of the cube of side ``side`` standing on z = 0 (the sizing's default)."""
    g = np.linspace(-side / 2, side / 2, n)
    return np.stack(np.meshgrid(g, g, g + side / 2, indexing="ij"), -1).reshape(-1, 3)


def search_compactness(d, length, side, bounds):
    """Lw / stroke on the 3³ search grid where the bounds hold there (seed formulas), else 0."""
    q, sv = delta_slides(d, length, cube(side, 3))
    if not (np.isfinite(sv).all() and sv[:, -1].min() >= bounds[0]
            and sv[:, 0].max() <= bounds[1]):
        return 0.0
    return side / float(np.max(q.max(axis=0) - q.min(axis=0)))


@pytest.mark.parametrize("side", [1e-4, 1e3])
def test_most_compact_linear_delta_of_a_tenth_of_a_millimetre_and_of_a_kilometre(side):
    """Largest Lw / stroke with arms up to 3 Lw, on 3 points per edge: no slide offset d of a
    fine scan does better (seed formulas on the same 3³ grid), and the design is the same
    machine in units of Lw at both sizes (a similarity: transmission factors are
    dimensionless). The Brent search of d over [1e-3 L, L] and the scan of d over the same
    range scale with L: in metres, a 0.1 mm cube's arms (0.3 mm) would be shorter than the
    range's start. A 1 km cube was refused before: its candidates kept the base machine's
    stops of [0.7, 2] m, and a home 2.6 km "beyond its stroke" reads as a unit slip."""
    bounds = (0.4, 1.2)
    res = size_linear_delta(side, bounds, objective="compactness", max_leg=3 * side,
                            samples=3, search_samples=3)
    assert res.check.feasible and res.L == 3 * side
    found = search_compactness(res.d, res.L, side, bounds)
    ds = np.linspace(1e-3, 1.0, 400) * res.L
    scan = [search_compactness(d, res.L, side, bounds) for d in ds]
    assert max(scan) > 0.4
    assert found >= max(scan) - 1e-6
    # the scan's best offset, to its step (L / 400), and the design's strokes: the slider
    # ranges over the cube (seed formulas at the sized d, on the 3³ grid of the check)
    assert res.d == pytest.approx(ds[int(np.argmax(scan))], abs=res.L / 400)
    q, _ = delta_slides(res.d, res.L, cube(side, 3))
    np.testing.assert_allclose(res.q_min, q.min(axis=0), rtol=1e-9)
    np.testing.assert_allclose(res.q_max, q.max(axis=0), rtol=1e-9)
    assert res.compactness == pytest.approx(found, rel=1e-9)

def test_five_bar_strokes_are_the_joint_ranges_of_its_square():
    """The isotropic five-bar sized for a 0.2 m square with λ in [1/3, 3]: its slider stops
    q_min, q_min + stroke are the ranges of ρ1, ρ2 over the square (seed 004's closed form,
    ρ_i = (p − a_i)·u_i − sqrt(L² − |p − a_i|² + ((p − a_i)·u_i)²), the branch of its
    isotropic home), to the 31-point study's grid. A stroke in units of L (0.77 here: L is
    0.29 m) or divided by L would leave the square's needs."""
    res = size_five_bar(0.2, (1 / 3, 3.0), design="isotropic", resolution=31)
    g = np.linspace(-0.1, 0.1, 41)
    p = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2) + res.square_center
    starts = np.stack([res.machine.params["A"], res.machine.params["B"]])
    alphas = (res.machine.params["alpha1"], res.machine.params["alpha2"])
    u = np.array([[np.cos(a), np.sin(a)] for a in alphas])
    rel = p[:, None, :] - starts[None]
    along = np.einsum("kij,ij->ki", rel, u)
    rho = along - np.sqrt(res.L**2 - (rel**2).sum(axis=-1) + along**2)
    np.testing.assert_allclose(rho.min(axis=0), res.q_min, rtol=1e-3)
    np.testing.assert_allclose(rho.max(axis=0), res.q_max, rtol=1e-3)
    assert res.stroke == pytest.approx(float(np.max(np.ptp(rho, axis=0))), rel=1e-3)
    # the square's side in units of L, as the sizing states it
    assert res.side_per_L == pytest.approx(0.2 / res.L, rel=1e-12)


def test_orthoglide_side_over_leg_of_the_seed_prototype():
    """Seed 001 §4: Lw = 200 mm with λ in [0.5, 2] needs legs of 310 mm, Lw / L = 0.645."""
    res = size_orthoglide(0.2, (0.5, 2.0), samples=9)
    assert res.L == pytest.approx(0.310, abs=0.001)
    assert res.side_over_L == pytest.approx(200 / 310, abs=0.003)
    assert res.side_over_L == pytest.approx(0.2 / res.L, rel=1e-12)
