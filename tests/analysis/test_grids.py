"""Grids and the pose frames workspace studies run over."""

import pkmkit
from pkmkit.analysis.grids import make_grid


def test_faces_reached_names_the_box_faces_the_feasible_set_touches():
    from pkmkit.analysis.workspace import Criteria, compute_workspace

    m = pkmkit.machine("orthoglide")
    inner = make_grid([-0.05, -0.05, -0.05], [0.05, 0.05, 0.05], free=(0, 1, 2),
                      base=m.home_pose, names=m.pose_names, resolution=5)
    assert compute_workspace(m, inner, Criteria()).faces_reached() == [
        "x-", "x+", "y-", "y+", "z-", "z+"]
    lo, hi = m.default_box()
    whole = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                      resolution=21)
    assert compute_workspace(m, whole, Criteria()).faces_reached() == []
