"""The batched full-pose velocity model computes J, its singular values, J⁻¹ and det B when
read (:mod:`pkmkit.machines.full_pose_velocity_batch`): the same numbers as every field
computed at once (the plain record a pickle carries), and the workspace's masks without the
singular values of J (``evaluate_poses(..., factors=False)``)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.criteria import Criteria, evaluate_poses
from pkmkit.machines.full_pose import FullPoseJacobians
from pkmkit.machines.full_pose_velocity_batch import LAZY_FIELDS
from pkmkit.machines.full_pose_velocity_one import FIELDS


def _poses(m, count=400, spread=0.4, seed=9):
    rng = np.random.default_rng(seed)
    width = 3 if m.position_controlled else 6
    points = np.tile(m.home_pose[:width], (count, 1))
    points[:, :3] += rng.uniform(-spread, spread, (count, 3))
    return points


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_fields_read_late_are_the_fields_computed_at_once(name):
    m = pkmkit.machine(name)
    points = _poses(m)
    lazy = m.jacobian(points)
    assert not set(LAZY_FIELDS) & set(lazy._cache)  # nothing costly computed yet
    assert np.isfinite(lazy.parallel_measure).any() and np.isfinite(lazy.det_A).any()
    assert "J" not in lazy._cache  # the assembly mode's fields do not need J
    plain = pickle.loads(pickle.dumps(m.jacobian(points)))
    assert type(plain) is FullPoseJacobians
    for name_ in FIELDS:
        np.testing.assert_array_equal(getattr(lazy, name_), getattr(plain, name_), name_)


@pytest.mark.parametrize("criteria", [Criteria(), Criteria(bounds=(0.45, 2.2)),
                                      Criteria(kappa_max=4.5)], ids=["default", "bounds", "kappa"])
def test_masks_without_factors_are_the_masks(criteria):
    m = pkmkit.machine("gough-stewart")
    points = _poses(m, 2000, 0.5)
    full = evaluate_poses(m, points, criteria)
    lean = evaluate_poses(m, points, criteria, factors=False)
    for key, mask in full.masks.items():
        np.testing.assert_array_equal(lean.masks[key], mask, key)
    assert full.feasible.any() and not full.feasible.all()
    read = criteria.bounds is not None or criteria.kappa_max is not None
    assert np.isnan(lean.factors).all() != read
