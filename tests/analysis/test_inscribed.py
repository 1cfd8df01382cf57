"""Largest inscribed squares/cubes refined in centre and side: closed forms, symmetry, grid
independence, and an independent fine-grid answer."""

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.inscribed import largest_box
from pkmkit.analysis.workspace import Criteria, check_region, compute_workspace


def _points(c, h, offsets):
    return c + h * offsets


@pytest.mark.parametrize("name, slack, start, half, exact", [
    # ellipse x²/4 + y² ≤ 1: the square's corners on it, side 2ab/√(a²+b²)
    ("ellipse", lambda p: 1 - np.hypot(p[:, 0] / 2, p[:, 1]), [0.7, 0.3], 0.2,
     4 / np.sqrt(5)),
    # right triangle x, y ≥ 0, x + y ≤ 1: held by two legs and a slanted side, side 1/2
    ("triangle", lambda p: np.minimum.reduce([p[:, 0], p[:, 1], 1 - p.sum(axis=1)]),
     [0.3, 0.1], 0.05, 0.5),
    # unit ball: the cube's corners on the sphere, side 2/√3
    ("ball", lambda p: 1 - np.linalg.norm(p, axis=1), [0.2, -0.1, 0.1], 0.1, 2 / np.sqrt(3)),
])
def test_largest_box_closed_forms(name, slack, start, half, exact):
    d = len(start)
    center, h = largest_box(slack, _points, np.array(start), half, -5 * np.ones(d),
                            5 * np.ones(d), samples=41 if d == 2 else 11)
    assert 2 * h == pytest.approx(exact, rel=1e-6), name
    # feasible up to the optimiser's tolerance (refine_box then checks and shrinks)
    assert np.all(slack(_points(center, h, np.array([[-1.0] * d, [1.0] * d]))) >= -1e-7)


def test_largest_box_stays_within_bounds():
    # the whole plane is feasible: the bounds [0, 1] × [0, 3] hold the square, side 1
    center, h = largest_box(lambda p: np.ones(len(p)), _points, np.array([0.3, 1.0]), 0.1,
                            np.array([0.0, 0.0]), np.array([1.0, 3.0]), samples=5)
    assert 2 * h == pytest.approx(1.0, rel=1e-9) and center[0] == pytest.approx(0.5)


@pytest.mark.ci
def test_orthoglide_cube_is_centred_on_the_symmetry_axis_and_beats_the_grid():
    """The Orthoglide is symmetric about x = y = z: so is its largest cube under 1/2 ≤ λ ≤ 2.
    The refined cube is at least as large as any cube about the grid's centre."""
    m = pkmkit.machine("orthoglide")
    criteria = Criteria(bounds=(0.5, 2.0))
    grid = make_grid([-0.2] * 3, [0.2] * 3, free=(0, 1, 2), base=np.zeros(3),
                     names=m.pose_names, resolution=31)
    raw = compute_workspace(m, grid, criteria).inscribed
    box = compute_workspace(m, grid, criteria, refine=True).inscribed
    assert np.ptp(box.center) < 1e-6 * box.side
    assert box.side > raw.side
    assert check_region(m, box.center, box.side, criteria).feasible
    # about the grid's centre, the best cube is smaller (the centre had to move)
    assert not check_region(m, raw.center, box.side, criteria).feasible
    lo, hi = check_region(m, box.center, box.side, criteria).factor_range
    assert hi == pytest.approx(2.0, rel=1e-6) or lo == pytest.approx(0.5, rel=1e-6)


@pytest.mark.ci
def test_refined_square_does_not_depend_on_the_grid_and_matches_a_fine_grid():
    """Five-bar, 1/3 ≤ λ ≤ 3 in a box that cuts the workspace: the refined square from a 31- and
    a 61-point grid agree to 1e-4, and a 601-point grid (no refinement: an independent method,
    separable minimum filters) is at most a step or two smaller."""
    m = pkmkit.machine("five-bar")
    criteria = Criteria(bounds=(1 / 3, 3.0))
    lower, upper = [0.55, -0.3], [1.35, 0.35]

    def grid(n):
        return make_grid(lower, upper, free=(0, 1), base=m.home_pose, names=m.pose_names,
                         resolution=n)

    coarse = compute_workspace(m, grid(31), criteria, refine=True).inscribed
    medium = compute_workspace(m, grid(61), criteria, refine=True).inscribed
    fine_grid = grid(601)
    fine = compute_workspace(m, fine_grid, criteria).inscribed
    assert coarse.side == pytest.approx(medium.side, rel=1e-4)
    np.testing.assert_allclose(coarse.center, medium.center, atol=2e-4 * coarse.side)
    assert fine.side <= coarse.side * (1 + 1e-6)
    assert coarse.side - fine.side <= 2.5 * fine_grid.step


@pytest.mark.ci
def test_seed004_useful_workspace_squares_are_refined():
    """The issue's figures: the squares inscribed in seed 004's useful workspaces were 0.5–0.9 %
    small when only grown about the grid's centre."""
    from pkmkit.analysis.joint_space import useful_workspace

    for name, before in (("five-bar-isotropic", 0.345952), ("five-bar-biglide", 0.134342)):
        useful = useful_workspace(pkmkit.machine(name), Criteria(bounds=(1 / 3, 3.0)),
                                  resolution=151)
        assert useful.inscribed.side > before * 1.004, name
        assert useful.workspace.inscribed_check.feasible
