"""The grid's inverse model by continuation (:mod:`pkmkit.analysis.continuation`): slab by slab
from the neighbouring slab's solution gives the criteria the start from home gives, in fewer
iterations; a machine whose inverse does not continue is evaluated at once as before."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.continuation import inverse_of_chunk
from pkmkit.analysis.criteria import Criteria, evaluate_grid, evaluate_poses
from pkmkit.analysis.grids import make_grid


@pytest.fixture(scope="module")
def grid_and_machine():
    """A 9 × 7 × 6 grid of tool points (6 × 5 × 4 cm) around a Tripteor X7 pose, the wrist at
    30° (away from its singularity, where the head's two branches meet), partly beyond the
    strokes."""
    m = pkmkit.machine("tripteor-x7")
    base = m.fk(np.array([0.985, 1.065, 0.985, 0.1, np.radians(30.0)]))
    half = np.array([0.03, 0.025, 0.02])
    g = make_grid(base[:3] - half, base[:3] + half, free=(0, 1, 2), base=base,
                  names=m.pose_names, resolution=9)
    assert g.shape == (9, 7, 6)
    return m, g


def test_continuation_gives_the_criteria_of_the_start_from_home(grid_and_machine):
    m, g = grid_and_machine
    crit = Criteria(bounds=(0.2, 5.0), kappa_max=30.0, continuation=True)
    home = evaluate_poses(m, g.points, crit)  # every point from home, in one batch
    cont = evaluate_grid(m, g, crit)  # slab by slab
    for name in home.masks:
        np.testing.assert_array_equal(cont.masks[name], home.masks[name], err_msg=name)
    assert home.masks["reachable"].all() and 0 < home.masks["strokes"].sum() < g.size
    np.testing.assert_allclose(cont.q, home.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cont.factors, home.factors, rtol=1e-10, atol=0)


def test_slabs_start_from_their_neighbours_in_fewer_iterations(grid_and_machine):
    m, g = grid_and_machine
    points = g.points
    slab = g.size // g.shape[0]
    cont = inverse_of_chunk(m, points, slab)
    home = m.ik(points, full_output=True)
    # the first slab from home, the others from their neighbours
    np.testing.assert_array_equal(cont.iterations[:slab], home.iterations[:slab])
    assert cont.iterations[slab:].mean() < 0.8 * home.iterations[slab:].mean()
    np.testing.assert_allclose(cont.q, home.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(cont.closure_start, home.closure_start, rtol=0, atol=1e-12)


def test_a_machine_without_continuation_is_solved_at_once():
    m = pkmkit.machine("linear-delta")
    lo, hi = m.default_box()
    g = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names, resolution=6)
    inv = inverse_of_chunk(m, g.points, g.size // g.shape[0])
    np.testing.assert_array_equal(inv.q, m.ik(g.points, full_output=True).q)


def test_chunks_cut_across_slabs_continue_the_same(grid_and_machine, monkeypatch):
    """Chunks of 100 points cut the 42-point slabs anywhere (the last piece of a chunk is
    shorter): point i still starts from point i − slab of its chunk."""
    import pkmkit.analysis.criteria as criteria

    m, g = grid_and_machine
    whole = evaluate_grid(m, g, Criteria(continuation=True))
    monkeypatch.setattr(criteria, "EVALUATION_CHUNK", 100)
    cut = evaluate_grid(m, g, Criteria(continuation=True))
    for name in whole.masks:
        np.testing.assert_array_equal(cut.masks[name], whole.masks[name], err_msg=name)
    np.testing.assert_allclose(cut.q, whole.q, rtol=0, atol=1e-12)


def test_continuation_is_asked_for(grid_and_machine, monkeypatch):
    """Off by default: the grid is solved at once, every point from home."""
    import pkmkit.analysis.criteria as criteria

    seen = []
    monkeypatch.setattr(criteria, "inverse_of_chunk",
                        lambda m, p, slab: seen.append(slab) or m.ik(p, full_output=True))
    m, g = grid_and_machine
    evaluate_grid(m, g, Criteria())
    evaluate_grid(m, g, Criteria(continuation=True))
    assert seen == [None, g.size // g.shape[0]]
