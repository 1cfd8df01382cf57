"""The grid's inverse model by continuation (:mod:`pkmkit.analysis.continuation`): slab by slab
from the neighbouring slab's solution gives the criteria the start from home gives, in fewer
iterations; a machine whose inverse does not continue is evaluated at once as before."""

from __future__ import annotations

from dataclasses import replace

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
    # the Tripteor's closed-form start (session 34) solves these poses at once (Q5 = 30°): the
    # default start is then the cheapest, continuation or not
    assert m.ik(points, full_output=True).iterations.mean() <= 0.1
    # the comparison below is the first-order start's (the closed start turned off)
    m = pkmkit.machine("tripteor-x7")
    object.__setattr__(m, "_closed_start_ok", False)
    slab = g.size // g.shape[0]
    cont = inverse_of_chunk(m, points, slab)
    home = m.ik(points, full_output=True)
    # the first slab from home, the others from their neighbours
    np.testing.assert_array_equal(cont.iterations[:slab], home.iterations[:slab])
    # the default start (home moved to first order towards the target) takes as few here:
    # fewer than from home itself
    from_home = m.ik(points, full_output=True,
                     start=np.concatenate([m._home["platform"], m._home["values"]]))
    assert cont.iterations[slab:].mean() < 0.8 * from_home.iterations[slab:].mean()
    assert cont.iterations[slab:].mean() <= home.iterations[slab:].mean()
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


def test_continuation_is_the_default(grid_and_machine, monkeypatch):
    """On by default (slab by slab: the legs' modes are checked,
    tests/analysis/test_continuation_modes.py); ``continuation=False`` solves the grid at
    once, every point from home."""
    import pkmkit.analysis.criteria as criteria

    seen = []
    monkeypatch.setattr(criteria, "inverse_of_chunk",
                        lambda m, p, slab: seen.append(slab) or m.ik(p, full_output=True))
    m, g = grid_and_machine
    evaluate_grid(m, g, Criteria())
    evaluate_grid(m, g, Criteria(continuation=False))
    assert seen == [g.size // g.shape[0], None]


@pytest.fixture(scope="module")
def wrist_grid():
    """A 25 × 4 × 4 grid crossing the Tripteor's wrist singularity (Q5 = 0: the tool axis along
    Q4's, where the head's two branches meet): its first axis tilts the tool axis (the i
    component from −0.1 to 0.6, Q5 from about −1° to 39°), the others move the tool point over
    10 × 10 cm of the default box's middle."""
    m = pkmkit.machine("tripteor-x7")
    lo, hi = m.default_box()
    c = (lo + hi) / 2
    g = make_grid(np.array([-0.1, c[0] - 0.05, c[1] - 0.05]),
                  np.array([0.6, c[0] + 0.05, c[1] + 0.05]), free=(3, 0, 1),
                  base=np.array([*c, *m.home_pose[3:]]), names=m.pose_names, resolution=25)
    assert g.shape == (25, 4, 4)
    return m, g


def _same_evaluations(a, b):
    for name in a.masks:
        np.testing.assert_array_equal(a.masks[name], b.masks[name], err_msg=name)
    np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.factors, b.factors, rtol=1e-10, atol=0)


def test_across_the_wrist_singularity_continuation_keeps_the_home_branch(wrist_grid):
    """Every mask, q and factor of the start from home, on a grid crossing the wrist
    singularity without strokes (every reachable point counts, both branches are within the
    passive joints' ranges) — while the points beyond 5° of it did continue from their
    neighbours, in fewer iterations."""
    m, g = wrist_grid
    crit = Criteria(strokes=False, bounds=(0.2, 5.0))
    home = evaluate_grid(m, g, crit)
    cont = evaluate_grid(m, g, replace(crit, continuation=True))
    _same_evaluations(cont, home)
    inv = m.ik(g.points, full_output=True)
    assert home.masks["reachable"].all()
    q5 = np.degrees(inv.q[:, 4])
    assert q5.min() < 0 < 30 < q5.max()
    near = ~m.continues_from(inv.solution)
    assert 0.05 * g.size < near.sum() < 0.5 * g.size
    slab = g.size // g.shape[0]
    sol = inverse_of_chunk(m, g.points, slab)
    far = np.flatnonzero(~near[slab:]) + slab
    # fewer than the first-order start's (the closed start turned off); the Tripteor's
    # closed-form start (session 34) takes fewer still: 0 where it answers
    off = pkmkit.machine("tripteor-x7")
    object.__setattr__(off, "_closed_start_ok", False)
    first_order = off.ik(g.points, full_output=True)
    assert sol.iterations[far].mean() < 0.8 * first_order.iterations[far].mean()
    assert inv.iterations[far].mean() <= sol.iterations[far].mean()


def test_without_the_rule_continuation_changes_branches(wrist_grid, monkeypatch):
    """The same grid, neighbours next to the singularity used as starts and no branch rule:
    points end on the head's other branch (Q4 + π), and the factors move — what the rule
    prevents."""
    import importlib

    from pkmkit.machines.joint_chain import JointChainMachine

    warm_starts = importlib.import_module("pkmkit.machines.warm_starts")
    m, g = wrist_grid
    crit = Criteria(strokes=False, continuation=True)
    home = evaluate_grid(m, g, replace(crit, continuation=False))
    monkeypatch.setattr(warm_starts, "WRIST_SINGULAR_ANGLE", 0.0)
    monkeypatch.setattr(JointChainMachine, "_nearest_branch", lambda *args: None)
    cont = evaluate_grid(m, g, crit)
    both = home.masks["reachable"] & cont.masks["reachable"]
    turned = np.abs(np.abs(cont.q[both, 3] - home.q[both, 3]) - np.pi) < 0.2
    assert turned.sum() > 0
    assert np.abs(cont.factors[both] - home.factors[both]).max() > 1e-3


def test_the_default_start_reports_the_branch_nearest_home():
    """A tool pose reached on the head's far branch (Q4 near 180° from home, from ``q0``): the
    inverse model started from that very solution (``start``, no ``q0``) reports the near
    branch, Q4 within a quarter turn of home, as the start from home does; with ``q0`` the
    caller's branch is kept."""
    m = pkmkit.machine("tripteor-x7")
    x = m.fk(np.array([*m.home_q[:3], np.radians(10.0), np.radians(30.0)]))
    far = m.ik(x, q0=[*m.home_q[:3], np.radians(190.0), np.radians(-30.0)], full_output=True,
               strokes="ignore")
    assert abs(np.degrees(far.q[3])) > 160
    near = m.ik(x, start=far.solution, strokes="ignore")
    assert abs(np.degrees(near[3]) - 10.0) < 1e-6 and abs(np.degrees(near[4]) - 30.0) < 1e-6
    np.testing.assert_allclose(near, m.ik(x, strokes="ignore"), rtol=0, atol=1e-12)


def test_the_trimule_reports_the_near_branch_within_its_strokes():
    """A TriMule tool pose whose start from home ended on the head's far branch (Q4 ≈ −164°,
    a joint beyond its stroke: the point was lost to its workspace): the stated branch is the
    near one (Q4 ≈ 15°), within every stroke."""
    m = pkmkit.machine("trimule-600")
    x = np.array([-0.5849, -0.1391, 1.215, 0.0, 0.0, 1.0])
    near = m.ik(x, full_output=True)
    assert abs(np.degrees(near.q[3])) < 90 and not near.out_of_stroke
    # Q4 a little past the far branch's: exactly near + π would put the near branch's Q4 +
    # 2π at the wrap's ±π boundary around q0, decided by the answer's last bit
    q0 = np.array(near.q) + np.array([0, 0, 0, np.pi + 0.05, 0])
    q0[4] = -q0[4]
    far = m.ik(x, q0=q0, full_output=True, strokes="ignore")
    assert abs(np.degrees(far.q[3])) > 90
    assert m.ik(x[None], q0=far.q[None], full_output=True).out_of_stroke[0]
