"""The connected part of the workspace kept by default is the one containing home (issue 18
§5): ``workspace tripteor-x7`` printed "kept: largest connected part (home not in it)" because
home sits at an actuator's stroke end and its nearest grid point, one step away, lies just
outside the strokes; with one part that was harmless, with two the part away from home would
have been reported. Home within one grid step of a part now keeps that part."""

from __future__ import annotations

import numpy as np

from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.workspace import _connected_part


def _grid():
    return make_grid([0.0, 0.0], [1.0, 1.0], free=[0, 1], base=[0.0, 0.0],
                     names=["x", "y"], resolution=11)  # step 0.1


def _two_parts():
    feasible = np.zeros((11, 11), dtype=bool)
    feasible[0:4, :] = True   # a large part at x ≤ 0.3
    feasible[7:11, 3:8] = True  # a small one at x ≥ 0.7
    return feasible


def test_home_one_step_from_a_part_keeps_that_part():
    home = np.array([0.64, 0.5])  # nearest grid point x = 0.6: outside both parts
    kept, reference = _connected_part(_two_parts(), _grid(), home)
    assert reference == "home (within one grid step of it)"
    assert kept[7:11, 3:8].all() and not kept[0:4].any()  # the large part before


def test_home_on_a_part_and_home_far_from_every_part():
    grid, feasible = _grid(), _two_parts()
    kept, reference = _connected_part(feasible, grid, np.array([0.8, 0.5]))
    assert reference == "home" and kept[7:11, 3:8].all()
    kept, reference = _connected_part(feasible, grid, np.array([0.5, 0.0]))
    assert reference == "largest connected part (home not in it)"
    assert kept[0:4].all() and not kept[7:].any()
