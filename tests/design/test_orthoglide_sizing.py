import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.workspace import Criteria, check_region, compute_workspace
from pkmkit.design.orthoglide import size_orthoglide
from pkmkit.exceptions import InputError


def test_seed_001_prototype():
    """Lw = 200 mm with [0.5, 2]: L ≈ 310 mm, stroke ≈ 257 mm, r ≈ 0.78 (seed 001 §4)."""
    res = size_orthoglide(0.2, (0.5, 2.0))
    assert res.L == pytest.approx(0.310, abs=0.001)
    assert res.stroke == pytest.approx(0.257, abs=0.0005)
    assert res.compactness == pytest.approx(0.78, abs=0.003)
    # Q1 and Q2 sit on the diagonal, Lw apart per axis, where the bounds are reached
    np.testing.assert_allclose(res.Q2 - res.Q1, 0.2, atol=1e-12)
    # exact positions (docs/design.md §1): Q1 = −L/√6 (1, 1, 1), Q2 = L/(3√2) (1, 1, 1), to
    # machine precision also where two singular values coincide (λ = (2, 2, 0.5) at Q1)
    np.testing.assert_allclose(res.Q1, -res.L / np.sqrt(6), rtol=1e-12)
    np.testing.assert_allclose(res.Q2, res.L / (3 * np.sqrt(2)), rtol=1e-12)
    sv1 = np.linalg.svd(res.machine.jacobian(res.Q1).J, compute_uv=False)
    sv2 = np.linalg.svd(res.machine.jacobian(res.Q2).J, compute_uv=False)
    assert max(sv1[0] / 2, 0.5 / sv1[-1]) == pytest.approx(1.0, abs=1e-12)
    assert max(sv2[0] / 2, 0.5 / sv2[-1]) == pytest.approx(1.0, abs=1e-12)
    assert res.check.feasible and res.check.samples == 41**3


def test_independent_brute_force_of_the_whole_cube():
    """Not through the sizing code: a fresh machine, a fresh dense grid over the cube."""
    res = size_orthoglide(0.2, (0.5, 2.0))
    m = pkmkit.machine("orthoglide", L=res.L)
    g = np.linspace(res.Q1[0], res.Q2[0], 31)
    cube = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    sv = np.linalg.svd(m.jacobian(cube).J, compute_uv=False)
    assert sv.min() >= 0.5 * (1 - 1e-12) and sv.max() <= 2.0 * (1 + 1e-12)
    q = m.ik(cube)
    assert (q.min(axis=0) >= res.q_min - 1e-12).all() and (q.max(axis=0) <= res.q_max + 1e-12).all()
    np.testing.assert_allclose(q.min(axis=0), res.q_min, atol=1e-4)
    np.testing.assert_allclose(q.max(axis=0), res.q_max, atol=1e-4)
    # the largest coordinate is reached inside a face (p_i at its maximum, the others at 0)
    top = res.Q2[0] + np.sqrt(res.L**2)
    assert res.q_max[0] == pytest.approx(top, abs=1e-9)
    # the sized machine's strokes are exactly what the cube needs
    assert check_region(res.machine, 0.5 * (res.Q1 + res.Q2), 0.2,
                        Criteria(bounds=(0.5, 2.0))).feasible


@pytest.mark.ci
def test_scaling_and_bounds_sweep():
    """L scales with Lw; widening the bounds shrinks the machine (Lw/L grows) but the
    compactness Lw/stroke decreases — the seed's claim that r increases is not reproduced."""
    a, b = size_orthoglide(0.2, (0.5, 2.0), samples=15), size_orthoglide(0.4, (0.5, 2.0),
                                                                          samples=15)
    assert b.L == pytest.approx(2 * a.L) and b.compactness == pytest.approx(a.compactness)
    wide = size_orthoglide(0.2, (1 / 3, 3.0), samples=15)
    assert wide.side_over_L > a.side_over_L
    assert wide.compactness < a.compactness
    assert wide.compactness == pytest.approx(0.743, abs=0.002)


@pytest.mark.parametrize(
    "side, bounds, kwargs, message",
    [
        (0.2, (1.2, 2.0), {}, "exclude the isotropic configuration"),
        (0.2, (0.5, 0.9), {}, "exclude the isotropic configuration"),
        (0.2, (2.0, 0.5), {}, "0 < lo < hi"),
        (0.0, (0.5, 2.0), {}, "must be > 0"),
        (0.2, (0.5, 2.0), {"max_leg": 0.25}, "longer than the admissible"),
    ],
)
def test_infeasible_specifications(side, bounds, kwargs, message):
    with pytest.raises(InputError, match=message):
        size_orthoglide(side, bounds, **kwargs)


# ---------------------------------------------------------------- ties at Q1/Q2 (review item 5)
#: Pairs of the reviewer's sweep that were rejected (ψmin = 0.9 with any ψmax, ψmax = 50 or 100;
#: symmetric pairs are swept in test_scaling_and_bounds_sweep and the demo).
SWEEP = [(0.9, 1.5), (0.9, 20.0), (0.5, 50.0), (0.01, 50.0), (0.3, 100.0)]


@pytest.mark.parametrize("bounds", SWEEP)
def test_sweep_of_bound_pairs_is_accepted_and_verified(bounds):
    """Q1 and Q2 are where a factor equals a bound; rounding at those corners must not reject
    the design (before the fix 26 of 111 such pairs failed with e.g. "λ_min = 0.9 < 0.9")."""
    res = size_orthoglide(0.2, bounds, samples=9)
    assert res.check.feasible
    lo, hi = bounds
    f_lo, f_hi = res.check.factor_range
    assert f_lo >= lo * (1 - 1e-6) and f_hi <= hi * (1 + 1e-6)
    # the cube is as large as asked, and is limited by the bounds: a slightly larger cube
    # about the same centre fails them
    np.testing.assert_allclose(res.Q2 - res.Q1, 0.2, rtol=1e-12)
    bigger = check_region(pkmkit.machine("orthoglide", L=res.L), 0.5 * (res.Q1 + res.Q2),
                          0.2 * 1.01, Criteria(bounds=bounds, strokes=False), samples=9)
    assert not bigger.feasible


@pytest.mark.ci
def test_very_wide_bounds_are_limited_by_a_singularity():
    """[1e-9, 1e9]: along the diagonal the factors stay within the bounds up to singularities,
    and the cube between those ends crosses singular configurations. Every design feasible for
    [1/3, 3] satisfies [1e-9, 1e9], so the sizing must not fail: the reference points are pulled
    in until the cube passes, and a note says so."""
    res = size_orthoglide(0.2, (1e-9, 1e9), samples=21)
    assert res.check.feasible and res.notes and "singularity" in res.notes[0]
    again = check_region(res.machine, 0.5 * (res.Q1 + res.Q2), 0.2,
                         Criteria(bounds=(1e-9, 1e9)), samples=31)
    assert again.feasible, again.worst


def test_degenerate_bounds_get_a_note():
    """[0.999999, 1.000001] gives 200 km legs for a 0.2 m cube: valid, but said to be
    degenerate."""
    res = size_orthoglide(0.2, (0.999999, 1.000001), samples=5)
    assert res.L > 1e5 and any("degenerate" in n for n in res.notes)
    assert not size_orthoglide(0.2, (0.5, 2.0), samples=5).notes


@pytest.mark.parametrize(
    "side, kwargs, message",
    [
        (1e-300, {}, "between 1e-06 m"),
        (float("nan"), {}, "must be > 0"),
        (1e9, {}, "between 1e-06 m"),
        (0.2, {"max_leg": float("nan")}, "must be > 0"),
        (0.2, {"max_leg": -1.0}, "must be > 0"),
    ],
)
def test_out_of_range_inputs(side, kwargs, message):
    with pytest.raises(InputError, match=message):
        size_orthoglide(side, (0.5, 2.0), **kwargs)


@pytest.mark.ci
def test_largest_cube_of_the_workspace_search_is_the_sized_cube():
    """Seed 001 errata #4, evidence independent of Q1/Q2: for the machine sized with
    [1/3, 3], the workspace search (grid over a box around the cube, largest inscribed cube,
    refined by dense checks) finds the largest cube whose factors stay within [1/3, 3] — and it
    is the prescribed 200 mm cube, with the same compactness r = 0.743 (below the 0.778 of
    [0.5, 2], contrary to the seed's sentence)."""
    res = size_orthoglide(0.2, (1 / 3, 3.0), samples=15)
    m = pkmkit.machine("orthoglide", L=res.L, q_min=(-10 * res.L,) * 3, q_max=(10 * res.L,) * 3)
    grid = make_grid(res.Q1 - 0.03, res.Q2 + 0.03, free=(0, 1, 2), base=m.home_pose,
                     names=m.pose_names, resolution=31)
    ws = compute_workspace(m, grid, Criteria(bounds=(1 / 3, 3.0), strokes=False), refine=True)
    assert ws.inscribed.side == pytest.approx(0.2, rel=1e-3)
    lo_q, hi_q = ws.inscribed_check.q_range
    r = ws.inscribed.side / float(np.max(hi_q - lo_q))
    assert r == pytest.approx(0.743, abs=0.002)
    assert r < size_orthoglide(0.2, (0.5, 2.0), samples=9).compactness - 0.03


def test_seed_001_motor_and_tool_speeds_describe_different_quantities():
    """Seed 001: tool speed 1 m/s (abstract), motors sized for 1.2 m/s at the isotropic
    configuration (§4) — not a contradiction (docs/seed-errata.md, seed 001 #3). A tool speed v
    in any direction needs at most max_i ‖row_i(J⁻¹)‖·v of a motor; over the prototype's cube
    that factor reaches √(3/2) = 1.2247 (1 at the isotropic point), so 1.2 m/s motors give the
    tool 0.98 m/s in every direction everywhere: the abstract's 1 m/s to 2 %. J⁻¹ here from the
    closed-form inverse model ρ_i = p_i + √(L² − |p|² + p_i²), not from pkmkit's Jacobian."""
    res = size_orthoglide(0.2, (0.5, 2.0))
    g = np.linspace(0.0, 1.0, 41)
    unit = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    p = res.Q1 + unit * (res.Q2 - res.Q1)
    root = np.sqrt(res.L**2 - (p**2).sum(axis=1, keepdims=True) + p**2)  # (N, 3), per leg
    # row i of J⁻¹ = ∂ρ_i/∂p = e_i + (p_i e_i − p) / root_i
    rows = np.eye(3)[None] + (p[:, :, None] * np.eye(3)[None] - p[:, None, :]) / root[:, :, None]
    factor = np.linalg.norm(rows, axis=2).max()
    assert factor == pytest.approx(np.sqrt(1.5), rel=1e-9)
    # the same from pkmkit's Jacobian, and 1 at the isotropic configuration (J = I)
    inverse = np.linalg.inv(res.machine.jacobian(p).J)
    assert np.linalg.norm(inverse, axis=2).max() == pytest.approx(factor, rel=1e-9)
    iso = np.linalg.inv(res.machine.jacobian(np.zeros(3)).J)
    np.testing.assert_allclose(np.linalg.norm(iso, axis=1), 1.0, atol=1e-12)
    assert 1.2 / factor == pytest.approx(0.98, abs=0.001)
