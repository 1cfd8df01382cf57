"""The inscribed box optimised on its lattice's faces (:func:`~pkmkit.analysis.inscribed.
lattice_shell`) and on the whole lattice only when an interior point fails at that optimum
(:func:`pkmkit.analysis.workspace.refine_box`): the same box as the whole lattice throughout."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
import pkmkit.analysis.workspace as workspace
from pkmkit.analysis.criteria import Criteria, evaluate_poses
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.inscribed import largest_box, lattice_offsets, lattice_shell


@pytest.mark.parametrize("d,samples", [(1, 5), (2, 41), (3, 25), (3, 4)])
def test_the_shell_is_the_lattice_points_on_a_face_in_order(d, samples):
    whole = lattice_offsets(d, samples)
    shell = lattice_shell(d, samples)
    assert len(shell) == samples ** d - (samples - 2) ** d
    # each shell point is a lattice point with a coordinate at ±1, in the lattice's order
    on_face = [k for k, u in enumerate(whole) if any(abs(v) == 1.0 for v in u)]
    np.testing.assert_array_equal(shell, whole[on_face])


def _disc(p):
    return 1.0 - np.hypot(p[:, 0], p[:, 1])


#: A lattice point of the best square in the unit disc (side √2, centred): u = (0.1, 0.1).
HOLE = np.sqrt(0.5) * 0.1


def _disc_with_hole(p):
    """The unit disc without a small disc at an interior lattice point of its best square."""
    return np.minimum(_disc(p), np.hypot(p[:, 0] - HOLE, p[:, 1] - HOLE) - 0.005)


def _box(slack, offsets, center=(-0.3, -0.2), half=0.1):
    return largest_box(slack, lambda c, h, u: c + h * u, np.array(center), half,
                       np.full(2, -2.0), np.full(2, 2.0), samples=21, offsets=offsets)


def test_the_shell_gives_the_whole_lattices_box_when_no_interior_point_holds_it():
    center, half = _box(_disc, lattice_shell(2, 21))
    whole_center, whole_half = _box(_disc, None)
    assert half == pytest.approx(whole_half, rel=1e-9)
    assert half == pytest.approx(np.sqrt(0.5), rel=1e-6)  # the closed form: side √2
    np.testing.assert_allclose(center, whole_center, atol=1e-9)


def test_a_hole_inside_is_missed_by_the_shell_alone():
    """Why refine_box checks the interior at the shell's optimum: a hole between the faces
    holds the whole lattice's box and not the shell's, which then fails inside."""
    u = lattice_offsets(2, 21)
    assert _disc_with_hole(0.2 * u).min() > 0  # the start is feasible
    center, half = _box(_disc_with_hole, lattice_shell(2, 21), (0.0, 0.0), 0.2)
    whole_center, whole_half = _box(_disc_with_hole, None, (0.0, 0.0), 0.2)
    assert half == pytest.approx(np.sqrt(0.5), rel=1e-6) and whole_half < 0.9 * half
    inside = (np.abs(u) < 1.0).all(axis=1)
    assert _disc_with_hole(center + half * u[inside]).min() < -1e-3
    assert _disc_with_hole(whole_center + whole_half * u).min() > -1e-6


def _refined(monkeypatch, *, plant_inside: bool):
    """The hexapod's refined cube on a coarse grid, and each optimiser run's number of points
    constrained and optimum (centre, half side); ``plant_inside``: the lattice's middle point
    (interior) fails at the first whole-lattice check, so the box is optimised again on the
    whole lattice from the same start — the optimum of the rule before the shell."""
    m = pkmkit.machine("gough-stewart")
    grid = make_grid([-0.4, -0.4, 0.55], [0.4, 0.4, 1.05], free=[0, 1, 2], base=m.home_pose,
                     names=m.pose_names, resolution=9)
    runs: list[tuple[int, np.ndarray, float]] = []
    planted = [plant_inside]

    def counted_box(*args, offsets=None, **kwargs):
        center, half = largest_box(*args, offsets=offsets, **kwargs)
        runs.append((25 ** 3 if offsets is None else len(offsets), center, half))
        return center, half

    def planted_poses(machine, points, criteria, **kwargs):
        out = evaluate_poses(machine, points, criteria, **kwargs)
        if planted[0] and len(points) == 25 ** 3:
            planted[0] = False
            for mask in out.masks.values():
                mask[len(points) // 2] = False  # the centre of the lattice
        return out

    with monkeypatch.context() as patch:
        patch.setattr(workspace, "largest_box", counted_box)
        patch.setattr(workspace, "evaluate_poses", planted_poses)
        box = workspace.compute_workspace(m, grid, Criteria(), refine=True).inscribed
    return box, runs


def test_the_shells_box_is_the_whole_lattices_and_a_failing_interior_reruns_it(monkeypatch):
    """Fails if refine_box ignores a failing interior point (no second optimiser run on the
    whole lattice), runs the whole lattice when no interior point fails, or if the shell's box
    differs from the whole lattice's (the planted run's two optima, both from the grid's box:
    one run of the whole lattice instead of a third workspace, session 34)."""
    shell, runs = _refined(monkeypatch, plant_inside=False)
    assert [n for n, _, _ in runs] == [25 ** 3 - 23 ** 3]
    rerun, rerun_runs = _refined(monkeypatch, plant_inside=True)
    assert [n for n, _, _ in rerun_runs] == [25 ** 3 - 23 ** 3, 25 ** 3]
    (_, shell_center, shell_half), (_, whole_center, whole_half) = rerun_runs
    np.testing.assert_array_equal(shell_center, runs[0][1])  # the same first run
    assert shell_half == runs[0][2]
    assert shell_half == pytest.approx(whole_half, rel=1e-9)
    np.testing.assert_allclose(shell_center, whole_center, atol=1e-9)
    # each kept box is its own run's optimum through the same steps after the optimiser (the
    # same path: exact — session 35 restored the equality session 34 relaxed to 1e-9): its
    # centre that optimum's, its half side that optimum's cut by the same first passing cut
    free = [0, 1, 2]
    np.testing.assert_array_equal(shell.center[free], shell_center)
    np.testing.assert_array_equal(rerun.center[free], whole_center)
    cuts = [c for c in (0.0, 1e-10, 1e-8, 1e-6, 1e-5)
            if shell.side == 2.0 * (shell_half * (1.0 - c))]
    assert cuts and rerun.side == 2.0 * (whole_half * (1.0 - cuts[0]))
    # the box kept after the rerun and the one kept without it: two optimiser runs (the whole
    # lattice's and the shell's), the same box to rounding
    assert rerun.side == pytest.approx(shell.side, rel=1e-9)
    np.testing.assert_allclose(rerun.center, shell.center, atol=1e-9)
