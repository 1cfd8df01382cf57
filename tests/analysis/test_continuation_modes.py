"""Continuation checked against the legs' assembly modes (issue 22 §3, fourth pass): a grid solved
slab by slab from neighbours (the default) gives the start from home's answer — every mask,
q and transmission factor — at every point where the start from home ends in the legs' home
assembly modes (``machine.in_home_modes``); elsewhere (the start from home fails or ends in
another mode, e.g. a leg slide of the opposite sign) continuation may report the mode
containing home instead, and the strokes mask never changes. Without the mode check a
neighbour's start moves points into other modes and changes the strokes mask (what the check
prevents)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.continuation import inverse_of_chunk
from pkmkit.analysis.criteria import Criteria, evaluate_grid
from pkmkit.analysis.grids import make_grid

#: The TriMule's study box (m): `pkmkit workspace trimule-600`'s default box once widened.
TRIMULE_BOX = ((-1.324, -1.617, 0.053), (1.263, 1.550, 1.901))
#: The Tripteor's study boxes (m): `workspace tripteor-x7`, and with `--no-strokes`.
TRIPTEOR_BOX = ((-0.160, -0.584, 1.818), (-0.039, -0.488, 1.858))
TRIPTEOR_FREE_BOX = ((-1.066, -1.315, 1.508), (0.867, 0.231, 2.153))


def _grid(m, box, resolution):
    lo, hi = (np.array(b) for b in box)
    return make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                     resolution=resolution)


def _check_against_home(m, g, strokes):
    """Continuation (default criteria) against every point from home: equal wherever the
    start from home is in home's modes; the strokes mask equal everywhere; where they differ
    continuation's closure is in home's modes. Returns the points that differ."""
    crit = Criteria(strokes=strokes, bounds=(0.2, 5.0))
    assert crit.continuation
    home = evaluate_grid(m, g, replace(crit, continuation=False))
    cont = evaluate_grid(m, g, crit)
    start = m.ik(g.points, full_output=True)
    in_modes = m.in_home_modes(start.solution)
    if strokes:  # out-of-stroke points may change mode, never the strokes mask
        np.testing.assert_array_equal(cont.masks["strokes"], home.masks["strokes"])
    for name in home.masks:
        np.testing.assert_array_equal(cont.masks[name][in_modes], home.masks[name][in_modes],
                                      err_msg=name)
    np.testing.assert_allclose(cont.q[in_modes], home.q[in_modes], rtol=0, atol=1e-12)
    np.testing.assert_allclose(cont.factors[in_modes], home.factors[in_modes], rtol=1e-10,
                               atol=0)
    with np.errstate(invalid="ignore"):
        moved = ((np.abs(cont.q - home.q) > 1e-12) | (np.isnan(cont.q) != np.isnan(home.q))
                 ).any(axis=1)
    solved = inverse_of_chunk(m, g.points, g.size // g.shape[0])
    assert m.in_home_modes(solved.solution[moved]).all()
    return moved


@pytest.fixture(scope="module")
def trimule():
    """The TriMule with its closed-form start turned off (session 33): the first-order start,
    whose answers leave the legs' home modes at some points of the grid — what these tests
    need to see the mode check at work."""
    m = pkmkit.machine("trimule-600")
    object.__setattr__(m, "_closed_start_ok", False)  # chain_starts.closed_starts: none
    return m


def test_the_trimule_grid_by_continuation_is_the_start_from_home(trimule):
    g = _grid(trimule, TRIMULE_BOX, 13)
    moved = _check_against_home(trimule, g, strokes=True)
    assert moved.any()  # points whose start from home ended in another mode: home's now
    # with the closed-form start (the default) the start from home stays in home's modes
    # there, and a warm start that fails is solved again from it: nothing moves
    assert not _check_against_home(pkmkit.machine("trimule-600"), g, strokes=True).any()


def test_without_the_mode_check_continuation_moves_points_to_other_modes(trimule,
                                                                         monkeypatch):
    """A grid of the same box with every continued closure accepted (the check off): points
    whose start from home is in home's modes get another closure (other q), and points the
    start from home does not reach become reachable in other modes (with ``--no-strokes``
    they would join the workspace) — what the check prevents."""
    from pkmkit.machines.joint_chain import JointChainMachine

    g = _grid(trimule, TRIMULE_BOX, 9)
    crit = Criteria()
    home = evaluate_grid(trimule, g, replace(crit, continuation=False))
    in_modes = trimule.in_home_modes(trimule.ik(g.points, full_output=True).solution)
    monkeypatch.setattr(JointChainMachine, "in_home_modes",
                        lambda self, u: np.ones(len(u), dtype=bool))
    cont = evaluate_grid(trimule, g, crit)
    with np.errstate(invalid="ignore"):
        moved = ((np.abs(cont.q - home.q) > 1e-9) | (np.isnan(cont.q) != np.isnan(home.q))
                 ).any(axis=1)
    assert (moved & in_modes).any()
    gained = cont.masks["reachable"] & ~home.masks["reachable"]
    assert gained.any()


def test_the_mode_signature_of_the_trimule():
    """Home is in its modes; a leg slide of the opposite sign, a universal joint turned half a
    turn, are not; the head's joints do not count (its branch has its own rule)."""
    m = pkmkit.machine("trimule-600")
    home = np.concatenate([m.home_platform, m.home_values])[None]
    assert m.in_home_modes(home).all()
    names = m.model.variables
    for name, change in (("Q2", -2.0), ("psi2", np.pi), ("theta4", 2.5), ("eta1", np.pi)):
        u = home.copy()
        k = 6 + names.index(name)
        u[0, k] = u[0, k] * change if name == "Q2" else u[0, k] + change
        assert not m.in_home_modes(u).any(), name
    u = home.copy()
    u[0, 6 + names.index("Q4")] += np.pi
    assert m.in_home_modes(u).all()
    assert not m.in_home_modes(np.full_like(home, np.nan)).any()


@pytest.mark.ci
@pytest.mark.parametrize("resolution", [21, 31])
@pytest.mark.parametrize("strokes", [True, False])
def test_larger_trimule_grids(trimule, resolution, strokes):
    _check_against_home(trimule, _grid(trimule, TRIMULE_BOX, resolution), strokes)


@pytest.mark.ci
@pytest.mark.parametrize("box, strokes", [(TRIPTEOR_BOX, True), (TRIPTEOR_FREE_BOX, True),
                                          (TRIPTEOR_FREE_BOX, False)])
def test_tripteor_grids(box, strokes):
    m = pkmkit.machine("tripteor-x7")
    moved = _check_against_home(m, _grid(m, box, 25), strokes)
    assert not moved.any()  # every point as from home
