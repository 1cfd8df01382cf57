"""Seed 003's ball-bar protocol: the plan's geometry, its file, and the iteration."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.simulate import random_defects
from pkmkit.exceptions import InputError
from pkmkit.machining.ballbar_plan import (
    ballbar_iterations,
    ballbar_plan,
    format_plan,
    hemisphere,
    read_plan,
)
from pkmkit.model.defects_table import apply_defect_vector


@pytest.fixture(scope="module")
def verne():
    return pkmkit.machine("verne")


def test_seed_plan_is_324_points_by_3_table_points_by_2_tools(verne):
    plan = ballbar_plan(verne)
    assert len(plan) == 324 * 3 * 2
    assert len(np.unique(plan.pivot, axis=0)) == 3
    assert sorted(set(plan.tool_length)) == [0.0, 0.1]
    assert len(set(plan.ids)) == len(plan) and plan.ids[0] == "P1-T1-001"
    radius = np.linalg.norm(plan.targets - plan.pivot, axis=1)
    np.testing.assert_allclose(radius, 0.15, rtol=1e-14)
    elevation = np.arcsin((plan.targets[:, 2] - plan.pivot[:, 2]) / radius)
    assert elevation.min() >= np.radians(10.0)


def test_hemisphere_points_are_equal_area():
    """On a sphere, area above height z is proportional to 1 − z (Archimedes): an equal-area
    spread has its heights uniform over the cap, and its azimuths turning by the golden angle."""
    d = hemisphere(324, np.radians(10.0))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-15)
    z = np.sort(d[:, 2])
    gaps = np.diff(z)
    np.testing.assert_allclose(gaps, gaps[0], rtol=1e-9)
    assert np.isclose(z[0] - np.sin(np.radians(10.0)), gaps[0] / 2)


def test_plan_file_round_trip_and_errors(verne, tmp_path):
    plan = ballbar_plan(verne, points=20)
    path = tmp_path / "plan.csv"
    path.write_text(format_plan(plan, units="mm"))
    back = read_plan(path)
    np.testing.assert_allclose(back.targets, plan.targets, atol=1e-12)
    np.testing.assert_allclose(back.pivot, plan.pivot, atol=1e-12)
    assert back.ids == plan.ids and back.tool == plan.tool
    lines = path.read_text().splitlines()
    fields = lines[7].split(",")
    fields[0] = str(float(fields[0]) + 1.0)
    lines[7] = ",".join(fields)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError, match=r"plan.csv:8: column 'x': the point is .* from its "
                                         r"table point, the plan's bar is 150 mm"):
        read_plan(path)


def test_unreachable_plan_names_its_acquisition(verne):
    with pytest.raises(InputError, match=r"acquisition P2-T1: 30 of 30 hemisphere points"):
        ballbar_plan(verne, table_points=[[0.0, 0.0, -0.2], [0.9, 0.0, -0.2]], points=30)


def test_iteration_converges(verne):
    """Round 1 starts from the nominal controller (its model error, hundreds of µm); after one
    update the controller's residual is the bar's noise, and the next rounds stay there."""
    true = apply_defect_vector(verne, random_defects(verne, np.random.default_rng(3)))
    plan = ballbar_plan(verne, points=60)
    sigma = 5e-7
    rounds = ballbar_iterations(true, verne, plan, np.random.default_rng(4), iterations=2,
                                sigma=sigma)
    assert rounds[0]["rms_before"] > 200 * sigma
    assert rounds[0]["rms_after"] < 1.3 * sigma
    assert rounds[1]["rms_before"] < 1.5 * sigma
    assert rounds[1]["along_x"] < 20e-6 and rounds[1]["along_y"] < 40e-6
