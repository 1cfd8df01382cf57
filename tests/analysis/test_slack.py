"""The criteria's slack with its analytic gradient (:func:`pkmkit.analysis.slack.
slack_and_gradient`, issue 22 §3): the same values as :func:`criteria_slack`, bit for bit, and a
gradient equal to central differences of :func:`criteria_slack` wherever the limiting criterion
does not change within the difference step — for the default criteria (reach, strokes, assembly
mode), factor bounds and a condition bound; the inscribed-box refinement then finds the box the
finite-difference search finds."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
import pkmkit.analysis.workspace as workspace
from pkmkit.analysis.criteria import Criteria, study_length
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.slack import criteria_slack, slack_and_gradient

H = 1e-6
CRITERIA = [Criteria(), Criteria(bounds=(0.45, 2.2)), Criteria(kappa_max=4.5)]


def _points(m, count, seed, spread):
    rng = np.random.default_rng(seed)
    width = 3 if m.position_controlled else 6
    points = np.tile(m.home_pose[:width], (count, 1))
    points[:, :3] += rng.uniform(-spread, spread, (count, 3))
    return points


@pytest.mark.parametrize("name,spread", [("gough-stewart", 0.3), ("verne", 0.45)])
@pytest.mark.parametrize("criteria", CRITERIA, ids=["default", "bounds", "kappa"])
def test_gradient_matches_central_differences(name, spread, criteria):
    m = pkmkit.machine(name)
    length = study_length(m)
    points = _points(m, 300, 5, spread)
    value, grad = slack_and_gradient(m, points, criteria, length, (0, 1, 2))
    np.testing.assert_array_equal(value, criteria_slack(m, points, criteria, length))
    checked = 0
    for axis in range(3):
        step = np.zeros(points.shape[1])
        step[axis] = H
        up = criteria_slack(m, points + step, criteria, length)
        down = criteria_slack(m, points - step, criteria, length)
        half_up = criteria_slack(m, points + step / 2, criteria, length)
        half_down = criteria_slack(m, points - step / 2, criteria, length)
        central, half = (up - down) / (2 * H), (half_up - half_down) / H
        # smooth there: the two steps agree (no change of limiting criterion in between)
        smooth = (np.abs(central - half) <= 1e-6 * np.maximum(1.0, np.abs(central))) & (
            value > -1.0)
        checked += int(smooth.sum())
        np.testing.assert_allclose(grad[smooth, axis], central[smooth], rtol=0,
                                   atol=2e-6 * max(1.0, float(np.abs(central[smooth]).max())),
                                   err_msg=f"{name} axis {axis}")
    assert checked > 300


def test_no_gradient_without_rates():
    """Machines with no analytic rates (translational ones) and stiffness criteria: None, the
    refinement then differences."""
    m = pkmkit.machine("orthoglide")
    points = m.home_pose + np.zeros((3, 3))
    assert slack_and_gradient(m, points, Criteria(), 1.0, (0, 1, 2)) is None
    hexapod = pkmkit.machine("gough-stewart")
    stiff = Criteria(min_stiffness=1e6)
    assert slack_and_gradient(hexapod, _points(hexapod, 3, 0, 0.01), stiff, 1.0, (0,)) is None


@pytest.mark.ci
def test_refined_box_as_with_finite_differences(monkeypatch):
    """The hexapod's square (z = 0.8 m) refined with the analytic gradient equals the one
    refined with finite differences to the refinement's tolerance (1e-4 of the side)."""
    m = pkmkit.machine("gough-stewart")
    base = m.home_pose.copy()
    base[2] = 0.8
    grid = make_grid([-0.3, -0.3], [0.3, 0.3], free=[0, 1], base=base, names=m.pose_names,
                     resolution=9)
    criteria = Criteria(bounds=(0.4, 2.1))
    analytic = workspace.compute_workspace(m, grid, criteria, refine=True).inscribed
    monkeypatch.setattr(workspace, "slack_and_gradient", lambda *args: None)
    differenced = workspace.compute_workspace(m, grid, criteria, refine=True).inscribed
    assert analytic.side > 0
    np.testing.assert_allclose(analytic.side, differenced.side, rtol=2e-4)
    np.testing.assert_allclose(analytic.center, differenced.center, atol=2e-4 * analytic.side)
