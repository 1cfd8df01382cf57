import numpy as np
import pytest
from scipy.optimize import brentq

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.workspace import (
    Criteria,
    check_region,
    compute_workspace,
    joint_grid,
    joint_space_map,
    largest_inscribed_box,
    useful_workspace,
)
from pkmkit.errors import InputError


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


def orthoglide_q1_q2(m):
    """Points of the cube diagonal where a transmission factor reaches 0.5 or 2."""
    def excess(t):
        s = m.jacobian([t] * 3).singular_values
        return max(s[0] / 2, 0.5 / s[-1]) - 1

    return brentq(excess, -0.2, 0.0), brentq(excess, 0.0, 0.1)


def test_orthoglide_prototype_cube_between_q1_and_q2():
    """Seed 001: the cube whose diagonal joins Q1 and Q2 keeps the factors within [0.5, 2];
    with L = 310 mm its side is 200 mm and the slider stroke 257 mm (r = 0.78)."""
    m = pkmkit.machine("orthoglide")
    t1, t2 = orthoglide_q1_q2(m)
    side = t2 - t1
    assert side == pytest.approx(0.200, abs=0.001)
    check = check_region(m, np.full(3, 0.5 * (t1 + t2)), side, Criteria(bounds=(0.5, 2.0)),
                         samples=41)
    assert check.feasible, check.worst
    lo, hi = check.factor_range
    assert lo == pytest.approx(0.5, abs=1e-9) and hi == pytest.approx(2.0, abs=1e-9)
    stroke = check.q_range[1] - check.q_range[0]
    np.testing.assert_allclose(stroke, 0.257, atol=0.001)
    assert side / stroke[0] == pytest.approx(0.78, abs=0.005)
    # a slightly larger cube fails, and the report says where
    bigger = check_region(m, np.full(3, 0.5 * (t1 + t2)), side * 1.02,
                          Criteria(bounds=(0.5, 2.0)))
    assert not bigger.feasible and "bounds" in bigger.failures
    assert "λ" in bigger.worst["bounds"]


def test_orthoglide_workspace_inscribed_cube():
    m = pkmkit.machine("orthoglide")
    grid = make_grid([-0.2] * 3, [0.2] * 3, free=(0, 1, 2), base=np.zeros(3),
                     names=m.pose_names, resolution=41)
    w = compute_workspace(m, grid, Criteria(bounds=(0.5, 2.0)), refine=True)
    assert w.reference == "home" and w.inscribed_check.feasible
    assert 0.19 < w.inscribed.side <= 0.2 + 1e-3
    lo, hi = w.factor_range()
    assert lo >= 0.5 - 1e-9 and hi <= 2.0 + 1e-9
    assert w.measure == pytest.approx(w.feasible.sum() * grid.step**3)
    assert w.boundary.any() and not (w.boundary & ~w.feasible).any()


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


def test_joint_space_map_and_useful_workspace():
    m = pkmkit.machine("five-bar-isotropic")
    crit = Criteria(bounds=(1 / 3, 3))
    grid = joint_grid(m, m.home_q - 1, m.home_q + 1, resolution=101)
    j = joint_space_map(m, grid, crit)
    assert j.reference == "home" and j.feasible[grid.nearest_index(m.home_q)]
    np.testing.assert_allclose(j.poses[grid.nearest_index(m.home_q)], m.home_pose, atol=0.02)
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
