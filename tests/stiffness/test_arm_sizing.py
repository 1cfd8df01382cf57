"""The arms' axial rigidity a machine needs for a stiffness bound, against hand computations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pkmkit.design.metrics import Region
from pkmkit.dynamics.arms import size_arm
from pkmkit.exceptions import InputError
from pkmkit.machines.registry import machine
from pkmkit.stiffness import Section, default_data, stiffness
from pkmkit.stiffness.arm_sizing import required_axial_rigidity


def test_orthoglide_isotropic_point_by_hand():
    """At the Orthoglide's isotropic point each axis is a drive (k_a = 1e8 N/m) in series with
    a parallelogram of two rods of length ℓ = 0.31 m: 1/B = 1/k_a + ℓ/(2 EA), so the bound
    B = 50 N/µm needs EA = ℓ / (2 (1/B − 1/k_a)) = 1.55e7 N, an arm of 0.31 m 5e7 N/m."""
    m = machine("orthoglide")
    req = required_axial_rigidity(m, np.zeros((1, 3)), 50e6)
    assert req.feasible
    assert req.axial_rigidity == pytest.approx(0.31 / (2 * (1 / 50e6 - 1 / 1e8)), rel=1e-8)
    assert req.arm_stiffness(0.31) == pytest.approx(5e7, rel=1e-8)
    assert req.rigid_stiffness == pytest.approx(1e8, rel=1e-12)


def test_the_bound_binds_at_the_worst_pose_of_a_region():
    """Linear Delta over a 150 mm cube: with the required EA the least stiffness over the
    region (recomputed with a real tube of that E·A) is the bound, and slightly less EA misses
    it; the binding pose is where that least stiffness is."""
    m = machine("linear-delta")
    points = Region(0.15).points(m, 5)
    req = required_axial_rigidity(m, points, 20e6)
    e = default_data(m).rod_material.E

    def smallest(ea):
        area = ea / e
        data = dataclasses.replace(default_data(m), rod_section=Section.circle(
            np.sqrt(4 * area / np.pi)))
        return stiffness(m, points, data=data).translational[:, 0]

    at = smallest(req.axial_rigidity)
    assert at.min() == pytest.approx(20e6, rel=1e-7) and at.min() >= 20e6 * (1 - 1e-12)
    assert smallest(req.axial_rigidity * (1 - 1e-4)).min() < 20e6
    np.testing.assert_array_equal(req.worst_pose, points[np.argmin(at)])


def test_a_bound_the_drives_cannot_meet_is_infeasible():
    m = machine("linear-delta")
    req = required_axial_rigidity(m, Region(0.15).points(m, 5), 40e6)
    assert not req.feasible and req.axial_rigidity == np.inf
    assert req.rigid_stiffness < 40e6


def test_sizing_with_the_requirement_meets_it():
    m = machine("orthoglide")
    req = required_axial_rigidity(m, np.zeros((1, 3)), 50e6)
    design = size_arm(axial_force=1000, length=0.31, min_stiffness=req.arm_stiffness(0.31))
    assert design.feasible and design.analysis.axial_stiffness >= 5e7 * (1 - 1e-6)


def test_refusals():
    with pytest.raises(InputError, match="links, not rods"):
        required_axial_rigidity(machine("tripteor-x7"), np.zeros((1, 6)), 1e6)
    with pytest.raises(InputError, match="bound"):
        required_axial_rigidity(machine("orthoglide"), np.zeros((1, 3)), -1.0)
