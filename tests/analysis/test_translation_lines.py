"""The workspace criteria of a machine whose rows share lines along its slides (the Verne
module, :meth:`translation_lines`): one velocity model and one set of criteria rates per line,
spread along it (:func:`pkmkit.analysis.criteria.evaluate_poses`,
:func:`pkmkit.analysis.slack.slack_and_gradient`), against every row evaluated on its own — the
same masks, factors and condition numbers, slacks and gradients to rounding, on a lattice
across the reach (every criterion failing somewhere)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.criteria import Criteria, evaluate_poses, study_length
from pkmkit.analysis.slack import slack_and_gradient
from pkmkit.machines.full_pose import FullPoseMachine

CRITERIA = [Criteria(), Criteria(bounds=(0.45, 2.2)), Criteria(kappa_max=4.5)]


def _lattice(m):
    """A 15 × 15 × 6 lattice over the Verne module's reach and beyond (positions, m)."""
    xy = np.linspace(-0.6, 0.6, 15)
    z = m.home_pose[2] + np.linspace(-0.5, 0.5, 6)
    return np.stack(np.meshgrid(xy, xy + 0.03, z, indexing="ij"), -1).reshape(-1, 3)


def _alone(monkeypatch, call):
    """``call()`` with every row evaluated on its own (no lines)."""
    with monkeypatch.context() as patch:
        patch.setattr(FullPoseMachine, "translation_lines", lambda self, points: None)
        return call()


@pytest.mark.parametrize("criteria", CRITERIA, ids=["default", "bounds", "kappa"])
def test_criteria_along_the_lines_as_row_by_row(criteria, monkeypatch):
    """Fails on a velocity model or rates spread to the wrong rows, or on a mode, factor or
    rate read at a line's solved row that differs from the row's own."""
    m = pkmkit.machine("verne")
    points = _lattice(m)
    lines = m.translation_lines(points)
    assert lines is not None and len(lines.rows) == 15 * 15
    shared = evaluate_poses(m, points, criteria)
    alone = _alone(monkeypatch, lambda: evaluate_poses(m, points, criteria))
    for name, mask in alone.masks.items():
        np.testing.assert_array_equal(shared.masks[name], mask, name)
        assert 0 < mask.sum() < len(points) or (name == "reachable" and mask.sum() > 0)
    assert not alone.feasible.all() and alone.feasible.any()
    np.testing.assert_allclose(shared.factors, alone.factors, rtol=1e-11, equal_nan=True)
    np.testing.assert_allclose(shared.condition, alone.condition, rtol=1e-11, equal_nan=True)
    length = study_length(m)
    value, grad = slack_and_gradient(m, points, criteria, length, (0, 1, 2))
    value0, grad0 = _alone(monkeypatch, lambda: slack_and_gradient(m, points, criteria,
                                                                   length, (0, 1, 2)))
    np.testing.assert_allclose(value, value0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(grad, grad0, rtol=1e-9, atol=1e-10)
    assert np.abs(grad0).max() > 0.1


def test_no_lines_for_poses_or_a_hexapod():
    """Full poses, a machine commanded by its whole pose, scattered positions: every row its
    own."""
    verne, hexapod = pkmkit.machine("verne"), pkmkit.machine("gough-stewart")
    points = _lattice(verne)
    assert verne.translation_lines(np.tile(verne.home_pose, (4, 1))) is None
    assert hexapod.translation_lines(np.tile(hexapod.home_pose, (4, 1))) is None
    assert verne.translation_lines(points[::6]) is None  # one z: no two rows on a line
