import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import brentq

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.joint_space import joint_grid, joint_space_map, useful_workspace
from pkmkit.analysis.workspace import (
    Criteria,
    WorkspaceMap,
    check_region,
    compute_workspace,
    largest_inscribed_box,
)
from pkmkit.exceptions import InputError


def plane_grid(shape, step=1.0):
    axes = tuple(step * np.arange(n) for n in shape)
    from pkmkit.analysis.grids import Grid

    return Grid(axes=axes, free=tuple(range(len(shape))), base=np.zeros(len(shape)), step=step,
                names=("x", "y", "z")[: len(shape)])


def brute_force_largest(mask):
    best = 0
    for k in range(1, min(mask.shape) + 1):
        for i in range(mask.shape[0] - k + 1):
            for j in range(mask.shape[1] - k + 1):
                if mask[i:i + k, j:j + k].all():
                    best = k
    return best


@pytest.mark.parametrize("seed", range(6))
def test_inscribed_square_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    mask = ndimage_blob(rng)
    box = largest_inscribed_box(mask, plane_grid(mask.shape, 0.5))
    k = brute_force_largest(mask)
    assert box.points_per_side == k and box.side == pytest.approx(0.5 * (k - 1))
    i, j = (box.lower / 0.5).round().astype(int)
    assert mask[i:i + k, j:j + k].all()


def ndimage_blob(rng):
    from scipy import ndimage

    noise = ndimage.gaussian_filter(rng.normal(size=(30, 26)), 3)
    return noise > np.quantile(noise, 0.4)


def test_centred_box_and_3d():
    mask = np.ones((9, 9, 9), bool)
    mask[0, :, :] = False
    grid = plane_grid(mask.shape)
    box = largest_inscribed_box(mask, grid)
    assert box.points_per_side == 8
    centred = largest_inscribed_box(mask, grid, center=np.array([4.0, 4.0, 4.0]))
    assert centred.points_per_side == 7 and centred.side == 6.0
    np.testing.assert_allclose(centred.center, [4, 4, 4])
    assert largest_inscribed_box(np.zeros((3, 3), bool), plane_grid((3, 3))) is None


def orthoglide_rho_and_factors(p, length=0.31):
    """Orthoglide from seed 001's own formulas, without pkmkit: slide i carries its carriage
    along e_i, |p − ρ_i e_i| = L with ρ_i = p_i + sqrt(L² − |p|² + p_i²); A has rows
    (p − ρ_i e_i)ᵀ, B = diag(p_i − ρ_i), J = A⁻¹B; factors by numpy's SVD. ``p (N, 3)``."""
    p = np.atleast_2d(p)
    rho = p + np.sqrt(length**2 - (p**2).sum(axis=1, keepdims=True) + p**2)
    a = p[:, None, :] - rho[:, :, None] * np.eye(3)[None]
    b = np.zeros((len(p), 3, 3))
    b[:, np.arange(3), np.arange(3)] = p - rho
    return rho, np.linalg.svd(np.linalg.solve(a, b), compute_uv=False)


def orthoglide_q1_q2():
    """Points of the cube diagonal where a transmission factor reaches 0.5 or 2."""
    def excess(t):
        s = orthoglide_rho_and_factors(np.full(3, t))[1][0]
        return max(s[0] / 2, 0.5 / s[-1]) - 1

    return brentq(excess, -0.2, 0.0, xtol=1e-15), brentq(excess, 0.0, 0.1, xtol=1e-15)


@pytest.mark.ci
def test_orthoglide_prototype_cube_between_q1_and_q2():
    """Seed 001: the cube whose diagonal joins Q1 and Q2 keeps the factors within [0.5, 2];
    with L = 310 mm its side is 200 mm and the slider stroke 257 mm (r = 0.78). Reference:
    an independent brute force over the cube with the Orthoglide's own formulas."""
    m = pkmkit.machine("orthoglide")
    t1, t2 = orthoglide_q1_q2()
    side = t2 - t1
    assert side == pytest.approx(0.200, abs=0.001)
    center = np.full(3, 0.5 * (t1 + t2))
    check = check_region(m, center, side, Criteria(bounds=(0.5, 2.0)), samples=41)
    assert check.feasible, check.worst
    g = np.linspace(-side / 2, side / 2, 61)
    cube = center + np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    rho, factors = orthoglide_rho_and_factors(cube)
    assert factors.min() >= 0.5 - 1e-9 and factors.max() <= 2.0 + 1e-9
    lo, hi = check.factor_range
    assert lo == pytest.approx(factors.min(), abs=1e-9)
    assert hi == pytest.approx(factors.max(), abs=1e-9)
    # the stroke, in closed form: ρ_1 = p_1 + sqrt(L² − p_2² − p_3²) is largest at p_1 = t2,
    # p_2 = p_3 = 0 (inside a face, between the samples) and smallest at the corner Q1
    L = 0.31
    np.testing.assert_allclose(check.q_range[0], t1 + np.sqrt(L**2 - 2 * t1**2), atol=1e-9)
    np.testing.assert_allclose(check.q_range[1], t2 + L, atol=1e-9)
    assert (rho.max(axis=0) <= t2 + L + 1e-12).all()
    stroke = check.q_range[1] - check.q_range[0]
    np.testing.assert_allclose(stroke, 0.257, atol=0.001)
    assert side / stroke[0] == pytest.approx(0.78, abs=0.005)
    # a slightly larger cube fails, and the report says where
    bigger = check_region(m, np.full(3, 0.5 * (t1 + t2)), side * 1.02,
                          Criteria(bounds=(0.5, 2.0)))
    assert not bigger.feasible and "bounds" in bigger.failures
    assert "λ" in bigger.worst["bounds"]


@pytest.mark.ci
def test_orthoglide_workspace_inscribed_cube():
    m = pkmkit.machine("orthoglide")
    grid = make_grid([-0.2] * 3, [0.2] * 3, free=(0, 1, 2), base=np.zeros(3),
                     names=m.pose_names, resolution=41)
    w = compute_workspace(m, grid, Criteria(bounds=(0.5, 2.0)), refine=True)
    assert w.reference == "home" and w.inscribed_check.feasible
    assert 0.19 < w.inscribed.side <= 0.2 + 1e-3
    lo, hi = w.factor_range()
    assert lo >= 0.5 - 1e-9 and hi <= 2.0 + 1e-9
    # the cube stays inside the grid's box
    assert (w.inscribed.lower >= -0.2 - 1e-12).all()
    assert (w.inscribed.lower + w.inscribed.side <= 0.2 + 1e-12).all()
    assert w.boundary.any() and not (w.boundary & ~w.feasible).any()


def test_grid_measure_is_exact_on_boxes_and_converges_on_a_disc():
    # a box whose short axis does not end on a grid point: measured exactly
    g = make_grid([0.0, -0.05], [0.2, 0.075], free=(0, 1), base=np.zeros(2),
                  names=("x", "y"), resolution=21)
    assert g.axes[1][-1] < 0.075 - 1e-3
    assert g.measure(np.ones(g.shape, bool)) == pytest.approx(0.2 * 0.125, rel=1e-12)
    g3 = make_grid([0, 0, 0], [0.3, 0.2, 0.1], free=(0, 1, 2), base=np.zeros(3),
                   names=("x", "y", "z"), resolution=7)
    assert g3.measure(np.ones(g3.shape, bool)) == pytest.approx(0.006, rel=1e-12)
    assert g3.weights().sum() == pytest.approx(0.006, rel=1e-12)
    # a disc of radius 0.4 touching the box's edges: midpoint rule, no half-cell excess
    d = make_grid([-0.4, -0.4], [0.4, 0.4], free=(0, 1), base=np.zeros(2), names=("x", "y"),
                  resolution=161)
    x, y = np.meshgrid(*d.axes, indexing="ij")
    assert d.measure(x**2 + y**2 <= 0.16) == pytest.approx(np.pi * 0.16, rel=2e-3)
    with pytest.raises(InputError, match="does not fit"):
        d.measure(np.ones((3, 3), bool))


def test_workspace_measure_of_an_analytic_region():
    """Five-bar with only ρ1 ∈ [0.3, 0.5] enforced: ρ1 = x − sqrt(L² − y²), so every row
    |y| ≤ 0.3 of the region has length exactly 0.2: area 0.2 × 0.6 = 0.12 m². The old count ×
    step² over-estimated it by 2.6 % on this 41-point grid (half cells along y = ±0.3)."""
    m = pkmkit.machine("five-bar")
    crit = Criteria(q_limits=(np.array([0.3, -np.inf]), np.array([0.5, np.inf])),
                    connected=False)
    for resolution, tol in ((41, 2e-3), (201, 2e-4)):
        g = make_grid([0.6, -0.3], [1.2, 0.3], free=(0, 1), base=m.home_pose,
                      names=m.pose_names, resolution=resolution)
        w = compute_workspace(m, g, crit)
        assert w.measure == pytest.approx(0.12, rel=tol)


def test_fully_feasible_box_area_and_inscribed_square_stay_in_the_box():
    """Reviewer's case: the box 0.9..1.1 × −0.1..0.1 is entirely feasible; its area is 0.04
    (was 0.040401) and the refined square may not leave it (was side 0.202 from (0.899,
    −0.101))."""
    m = pkmkit.machine("five-bar")
    g = make_grid([0.9, -0.1], [1.1, 0.1], free=(0, 1), base=m.home_pose, names=m.pose_names,
                  resolution=201)
    w = compute_workspace(m, g, Criteria(bounds=(0.5, 2.0)), refine=True)
    assert w.feasible.all()
    assert w.measure == pytest.approx(0.04, rel=1e-12)
    box = w.inscribed
    assert box.side <= 0.2 + 1e-12
    assert (box.lower >= [0.9 - 1e-12, -0.1 - 1e-12]).all()
    assert (box.lower + box.side <= [1.1 + 1e-12, 0.1 + 1e-12]).all()
    assert w.global_conditioning_index() == pytest.approx(
        np.sum(g.weights() / w.condition) / 0.04, rel=1e-12)


def test_refined_cube_stays_in_a_small_box():
    """A box inside the Orthoglide's workspace: the cube is the box itself, not 2 steps more."""
    m = pkmkit.machine("orthoglide")
    g = make_grid([-0.05] * 3, [0.05] * 3, free=(0, 1, 2), base=np.zeros(3),
                  names=m.pose_names, resolution=11)
    w = compute_workspace(m, g, Criteria(bounds=(0.5, 2.0)), refine=True)
    assert w.feasible.all() and w.measure == pytest.approx(1e-3, rel=1e-12)
    assert w.inscribed.side == pytest.approx(0.1, rel=1e-12)
    assert (w.inscribed.lower >= -0.05 - 1e-12).all()


def test_global_conditioning_index_of_a_workspace_against_direct_mean():
    """Mean of 1/κ over the feasible grid points (cell-weighted), with κ from numpy's SVD of
    the Orthoglide's J written from its own formulas."""
    m = pkmkit.machine("orthoglide")
    g = make_grid([-0.15] * 3, [0.12] * 3, free=(0, 1, 2), base=np.zeros(3),
                  names=m.pose_names, resolution=19)
    w = compute_workspace(m, g, Criteria(bounds=(0.5, 2.0)))
    pts = g.points[w.feasible.ravel()]
    _, s = orthoglide_rho_and_factors(pts)
    weights = g.weights()[w.feasible]
    ref = np.sum(weights * s[:, -1] / s[:, 0]) / weights.sum()
    assert w.global_conditioning_index() == pytest.approx(ref, rel=1e-9)
    assert 0.4 < ref < 0.9


def test_no_warning_reaches_the_user_on_a_partly_unreachable_cube():
    """Reviewer's case (``workspace orthoglide --cube 0.5 --center 0,0,0``): L-BFGS-B used to
    get inf from _q_extremes and SciPy printed a RuntimeWarning."""
    m = pkmkit.machine("orthoglide")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check = check_region(m, np.zeros(3), 0.5, Criteria(bounds=(0.5, 2.0)))
    assert not check.feasible and "reachable" in check.failures
    assert np.isfinite(check.q_range[0]).all() and np.isfinite(check.q_range[1]).all()


def test_chunked_evaluation_matches_one_block(monkeypatch):
    import pkmkit.analysis.criteria as ws

    m = pkmkit.machine("linear-delta")
    lo, hi = m.default_box()
    g = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names, resolution=15)
    whole = ws.evaluate_poses(m, g.points, Criteria(bounds=(0.5, 2.0)))
    monkeypatch.setattr(ws, "EVALUATION_CHUNK", 257)
    parts = ws.evaluate_grid(m, g, Criteria(bounds=(0.5, 2.0)))
    np.testing.assert_array_equal(parts.q, whole.q)
    np.testing.assert_array_equal(parts.factors, whole.factors)
    for name in whole.masks:
        np.testing.assert_array_equal(parts.masks[name], whole.masks[name])


def test_grid_limits():
    names = ("x", "y", "z")
    with pytest.raises(InputError, match="limit of 5e"):
        make_grid([-1] * 3, [1] * 3, free=(0, 1, 2), base=np.zeros(3), names=names,
                  resolution=271)
    with pytest.raises(InputError, match="overflows"):
        make_grid([-1e308] * 2, [1e308] * 2, free=(0, 1), base=np.zeros(2), names=names)
    with pytest.raises(InputError, match="too thin"):
        make_grid([1e9, 0], [1e9 + 1e-6, 1e-6], free=(0, 1), base=np.zeros(2), names=names)


def test_masks_explain_failures():
    m = pkmkit.machine("five-bar")
    lo, hi = m.default_box()
    grid = make_grid(lo, hi, free=(0, 1), base=m.home_pose, names=m.pose_names, resolution=81)
    w = compute_workspace(m, grid, Criteria(bounds=(1 / 3, 3)))
    assert not w.masks["reachable"].all()
    assert (w.feasible <= w.masks["bounds"]).all() and (w.feasible <= w.masks["strokes"]).all()
    # an unreachable or out-of-stroke square is reported with its reason
    far = check_region(m, m.home_pose + np.array([0.9, 0.0]), 0.2)
    assert not far.feasible and "reachable" in far.failures and "too short" in far.worst[
        "reachable"]
    tight = pkmkit.machine("five-bar", q_max=(0.55, 0.55))
    stroke = check_region(tight, tight.home_pose, 0.2)
    assert "strokes" in stroke.failures and "above q_max" in stroke.worst["strokes"]


def test_parallel_singularity_splits_the_workspace():
    """Without bounds, poses past the Orthoglide's parallel singularity on the diagonal
    (t = L/√6, the tool in the carriages' plane) are in the other mode and cut off."""
    m = pkmkit.machine("orthoglide")
    grid = make_grid([-0.1] * 3, [0.25] * 3, free=(0, 1, 2), base=np.zeros(3),
                     names=m.pose_names, resolution=36)
    w = compute_workspace(m, grid, Criteria(strokes=False))
    t = grid.axes[0]
    diagonal = np.arange(len(t))
    reachable = w.masks["reachable"][diagonal, diagonal, diagonal]
    mode = w.masks["mode"][diagonal, diagonal, diagonal]
    past = t > 0.31 / np.sqrt(6)
    assert reachable[past].any() and not mode[past & reachable].any()
    assert mode[~past].all() and w.feasible[diagonal, diagonal, diagonal][~past].all()
    assert not w.feasible[diagonal, diagonal, diagonal][past].any()


@pytest.mark.ci
def test_useful_workspace_on_a_coarse_grid():
    """Reviewer's case ``useful-workspace five-bar --bounds 0.5,2 --resolution 11``: the grid
    square around home had side 0 ("criteria fail there" where λ = 1). The dense bisection now
    decides: same joint square as on a fine grid."""
    m = pkmkit.machine("five-bar")
    crit = Criteria(bounds=(0.5, 2.0))
    coarse = useful_workspace(m, crit, resolution=11)
    fine = useful_workspace(m, crit, resolution=201)
    assert coarse.joint_square.side == pytest.approx(fine.joint_square.side, abs=1e-6)
    np.testing.assert_allclose(coarse.factor_range, fine.factor_range, atol=1e-5)
    # the square is limited by λ_max = 2 on its boundary (λ_min = 2/3 at a corner)
    assert fine.factor_range == pytest.approx((2 / 3, 2.0), abs=1e-5)
    tight = useful_workspace(m, Criteria(bounds=(0.99, 1.01)), resolution=11)
    assert 0 < tight.joint_square.side < 0.02
    with pytest.raises(InputError, match="fail at the home configuration"):
        useful_workspace(m, Criteria(bounds=(1.5, 3.0)), resolution=11)


@pytest.mark.ci
def test_useful_workspace_with_three_actuators():
    """The same procedure with cubes for the Orthoglide, independent of the grid."""
    m = pkmkit.machine("orthoglide")
    crit = Criteria(bounds=(0.5, 2.0))
    coarse = useful_workspace(m, crit, resolution=11)
    fine = useful_workspace(m, crit, resolution=31)
    np.testing.assert_allclose(coarse.joint_square.center, m.home_q, atol=1e-12)
    assert coarse.joint_square.side == pytest.approx(fine.joint_square.side, abs=1e-5)
    lo, hi = fine.factor_range
    assert 0.5 <= lo and hi == pytest.approx(2.0, abs=1e-4)
    # independent check: the factors over the joint cube, by the Orthoglide's own formulas
    # at the poses of the cube's image
    q = fine.joint_square.lower + fine.joint_square.side * np.stack(np.meshgrid(
        *[np.linspace(0, 1, 15)] * 3, indexing="ij"), -1).reshape(-1, 3)
    _, s = orthoglide_rho_and_factors(m.fk(q))
    assert lo <= s.min() + 1e-9 and s.max() <= hi + 1e-9
    assert fine.inscribed is not None and fine.inscribed.side > 0


def test_joint_space_map_and_useful_workspace():
    m = pkmkit.machine("five-bar-isotropic")
    crit = Criteria(bounds=(1 / 3, 3))
    grid = joint_grid(m, m.home_q - 1, m.home_q + 1, resolution=101)
    j = joint_space_map(m, grid, crit)
    assert j.reference == "home" and j.feasible[grid.nearest_index(m.home_q)]
    np.testing.assert_allclose(j.poses[grid.nearest_index(m.home_q)], m.home_pose, atol=0.02)
    # poses and factors per grid point: the direct model and J's singular values there
    assert j.poses.shape == (101, 101, 2) and j.factors.shape == (101, 101, 2)
    k = (30, 70)
    q = grid.points.reshape(101, 101, 2)[k]
    np.testing.assert_allclose(j.poses[k], m.fk(q), atol=1e-12)
    np.testing.assert_allclose(j.factors[k], m.jacobian(m.fk(q), q=q).singular_values,
                               rtol=1e-12)
    useful = useful_workspace(m, crit, resolution=151)
    sq = useful.joint_square
    np.testing.assert_allclose(sq.center, m.home_q, atol=1e-12)
    lo, hi = useful.factor_range
    assert 1 / 3 <= lo < hi <= 3
    # every pose of the useful workspace maps back into the joint square
    q = useful.workspace.q[useful.workspace.feasible]
    assert (q >= sq.lower - 1e-12).all() and (q <= sq.lower + sq.side + 1e-12).all()


def test_bad_criteria_and_grids():
    with pytest.raises(InputError, match="0 < lo < hi"):
        Criteria(bounds=(2.0, 0.5))
    with pytest.raises(InputError, match="kappa_max"):
        Criteria(kappa_max=0.5)
    with pytest.raises(InputError, match="must be below"):
        make_grid([0, 1], [1, 1], free=(0, 1), base=np.zeros(2), names=("x", "y"))
    m = pkmkit.machine("five-bar")
    with pytest.raises(InputError, match="side must be > 0"):
        check_region(m, m.home_pose, 0.0)


def test_largest_connected_part_when_home_is_outside():
    """Three separate feasible blobs, home in none of them: the largest is kept (here the last
    one labelled)."""
    from pkmkit.analysis.workspace import _connected_part

    grid = make_grid([0.0, 0.0], [1.0, 1.0], free=(0, 1), base=np.zeros(2), names=("x", "y"),
                     resolution=21)
    mask = np.zeros(grid.shape, bool)
    mask[1:3, 1:3] = True   # 4 points
    mask[6:8, 6:9] = True   # 6 points
    mask[12:19, 12:19] = True  # 49 points, labelled last
    part, reference = _connected_part(mask, grid, np.array([0.5, 0.0]))
    assert reference.startswith("largest connected part") and part.sum() == 49
    assert part[15, 15] and not part[1, 1] and not part[7, 7]


def test_region_centre_must_have_the_machine_dimension():
    ortho = pkmkit.machine("orthoglide")
    with pytest.raises(InputError, match="3 finite coordinates"):
        check_region(ortho, [0.0, 0.0], 0.1, Criteria(bounds=(0.5, 2.0)))


def test_global_conditioning_index_over_a_sub_region():
    """WorkspaceMap.global_conditioning_index(region): the cell-weighted mean of 1/κ over that
    region only (here the feasible points with x < 0), from numpy's SVD."""
    m = pkmkit.machine("five-bar")
    lower, upper = m.default_box()
    grid = make_grid(lower, upper, free=(0, 1), base=m.home_pose, names=m.pose_names,
                     resolution=41)
    w = compute_workspace(m, grid, Criteria(bounds=(1 / 3, 3.0)))
    left = w.feasible & (grid.points[:, 0] < m.home_pose[0]).reshape(grid.shape)
    assert 0 < left.sum() < w.feasible.sum()
    s = np.linalg.svd(m.jacobian(grid.points[left.ravel()]).J, compute_uv=False)
    weights = grid.weights().ravel()[left.ravel()]
    assert w.global_conditioning_index(left) == pytest.approx(
        np.sum(s[:, -1] / s[:, 0] * weights) / weights.sum(), rel=1e-12)


@pytest.mark.slow
def test_useful_workspace_of_a_position_controlled_module_runs_over_positions():
    """The Verne module's useful workspace (seed 004's procedure on three actuators) is a
    volume over positions — its orientation follows from the rods — inside the image of the
    joint cube."""
    m = pkmkit.machine("verne")
    u = useful_workspace(m, Criteria(kappa_max=6), resolution=9)
    assert u.workspace.grid.free == (0, 1, 2) and u.workspace.grid.base.shape == (3,)
    assert 0 < u.inscribed.side ** 3 <= u.workspace.measure
    q = m.ik(u.workspace.grid.points[u.workspace.feasible.ravel()])
    lo, hi = u.joint_square.lower, u.joint_square.lower + u.joint_square.side
    assert ((q >= lo - 1e-9) & (q <= hi + 1e-9)).all()


def test_faces_reached_counts_the_layers_next_to_each_face():
    """A feasible set one layer inside the y+ face: not reached at one layer, reached at two
    (the workspace command then moves that face out by a step)."""
    feasible = np.zeros((5, 6, 6), dtype=bool)
    feasible[2, 4, 2] = True
    grid = SimpleNamespace(free=(0, 1, 2), names=("x", "y", "z"))
    view = SimpleNamespace(grid=grid, feasible=feasible)
    assert WorkspaceMap.faces_reached(view) == []
    assert WorkspaceMap.faces_reached(view, 2) == ["y+"]
    feasible[0, 0, 5] = True
    assert WorkspaceMap.faces_reached(view) == ["x-", "y-", "z+"]
    assert WorkspaceMap.faces_reached(view, 2) == ["x-", "y-", "y+", "z+"]


def test_feasible_set_alone_skips_the_inscribed_box_and_keeps_every_mask():
    """``inscribed=False`` (the command sizing its box) gives the same masks and feasible set
    as the full map, without the inscribed box and its dense check."""
    m = pkmkit.machine("orthoglide")
    grid = make_grid([-0.25] * 3, [0.2] * 3, free=(0, 1, 2), base=np.zeros(3),
                     names=("x", "y", "z"), resolution=9)
    full = compute_workspace(m, grid, Criteria(bounds=(0.5, 2.0)))
    alone = compute_workspace(m, grid, Criteria(bounds=(0.5, 2.0)), inscribed=False)
    assert full.inscribed is not None and full.inscribed_check is not None
    assert alone.inscribed is None and alone.inscribed_check is None
    assert np.array_equal(alone.feasible, full.feasible) and alone.feasible.any()
    for name, mask in full.masks.items():
        assert np.array_equal(alone.masks[name], mask)
    assert alone.faces_reached(2) == full.faces_reached(2)


def test_position_controlled_module_solves_its_inverse_once_per_evaluation(monkeypatch):
    """A Verne-type module's velocity model is taken at the complete poses its inverse model
    found: evaluating criteria solves the (iterative) inverse model once, not again inside
    the velocity model, with the same masks and factors as the velocity model of the
    positions."""
    from pkmkit.analysis.criteria import evaluate_poses
    from pkmkit.analysis.region_check import criteria_slack
    from pkmkit.machines.full_pose import FullPoseMachine

    m = pkmkit.machine("verne")
    points = np.random.default_rng(4).uniform(-0.6, 0.6, size=(300, 3))
    calls = []
    solve = FullPoseMachine._ik_position

    def counted(self, arr, *args, **kwargs):
        calls.append(len(arr))
        return solve(self, arr, *args, **kwargs)

    monkeypatch.setattr(FullPoseMachine, "_ik_position", counted)
    ev = evaluate_poses(m, points, Criteria(bounds=(0.3, 3.0)))
    assert calls == [300]
    calls.clear()
    criteria_slack(m, points, Criteria(bounds=(0.3, 3.0)), 1.0)
    assert calls == [300]
    jac = m.jacobian(points)
    reach = ev.masks["reachable"]
    assert 0 < reach.sum() < len(points)
    np.testing.assert_array_equal(ev.factors[reach], jac.singular_values[reach])
    np.testing.assert_array_equal(ev.condition[reach], jac.condition[reach])
