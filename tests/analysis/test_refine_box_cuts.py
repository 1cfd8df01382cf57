"""The inscribed box's last shrink (:func:`pkmkit.analysis.workspace.refine_box`): a cut of the
optimum is checked on its whole lattice only once the lattice points that failed at the
optimum pass — the same box as checking every cut's whole lattice."""

from __future__ import annotations

import numpy as np

import pkmkit
import pkmkit.analysis.workspace as workspace
from pkmkit.analysis.criteria import Criteria, evaluate_poses
from pkmkit.analysis.grids import make_grid


def _refined(monkeypatch, screen: bool):
    """The hexapod's refined cube on a coarse grid of its default box, and the sizes of the
    batches evaluated; ``screen=False``: every subset check passes, so each cut is decided by
    its whole lattice (the rule before the screen)."""
    m = pkmkit.machine("gough-stewart")
    grid = make_grid([-0.4, -0.4, 0.55], [0.4, 0.4, 1.05], free=[0, 1, 2], base=m.home_pose,
                     names=m.pose_names, resolution=9)
    sizes = []

    def counted(machine, points, criteria, **kwargs):
        sizes.append(len(points))
        out = evaluate_poses(machine, points, criteria, **kwargs)
        if not screen and len(points) < 25 ** 3:
            for mask in out.masks.values():
                mask[:] = True
        return out

    with monkeypatch.context() as patch:
        patch.setattr(workspace, "evaluate_poses", counted)
        box = workspace.compute_workspace(m, grid, Criteria(), refine=True).inscribed
    return box, sizes


def test_screened_cuts_give_the_box_of_whole_lattices(monkeypatch):
    """Fails on a screen that rejects a cut its whole lattice accepts (the box then shrinks
    further, by bisection)."""
    screened, sizes = _refined(monkeypatch, True)
    whole, _ = _refined(monkeypatch, False)
    assert any(0 < size < 100 for size in sizes)  # the optimum failed: cuts were screened
    assert screened.side == whole.side
    np.testing.assert_array_equal(screened.center, whole.center)
