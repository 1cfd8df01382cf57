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
from pkmkit.machines.full_pose_velocity_batch import LAZY_FIELDS, _surely_above
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


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_parallel_flag_and_working_mode_as_from_the_measure(name):
    """The parallel-singularity flag, taken from the parallel measure only where its lower
    bound does not clear the tolerance, and ``in_working_mode`` read from that flag: the
    same as from the measure computed on every row, at tolerances from where the bound clears
    most rows to where most rows are flagged. Fails on a bound that is not one (a row cleared
    while its measure is below the tolerance) and on a flag read wrongly."""
    m = pkmkit.machine(name)
    points = _poses(m, 3000, 0.6, seed=3)
    first = m.jacobian(points)
    measure = first.parallel_measure
    assert np.isfinite(measure).sum() > 1000
    a = first.A
    unit = a / np.linalg.norm(a[:, :, :3], axis=2)[:, :, None]
    unit[:, :, 3:] /= m.characteristic_length
    with np.errstate(invalid="ignore"):
        det_unit = np.linalg.det(unit)
    tolerances = np.concatenate([np.geomspace(1e-4, 0.1, 16),
                                 np.nanquantile(measure, [0.1, 0.5, 0.9])])
    cleared, flagged_rows = 0, 0
    for tol in tolerances:
        jac = m.jacobian(points, tol=tol)
        parallel = jac.parallel_measure  # every row, read after the flags
        flagged = (np.asarray(jac.singularity) & 2).astype(bool)
        np.testing.assert_array_equal(flagged, parallel < tol)
        with np.errstate(invalid="ignore"):
            expected = (np.sign(jac.det_A) == m.working_mode) & (parallel >= tol)
        mode = m.in_working_mode(m.jacobian(points, tol=tol), tol)
        np.testing.assert_array_equal(mode, expected)
        cleared += int(_surely_above(unit, det_unit, tol).sum())
        flagged_rows += int(flagged.sum())
    assert cleared > 10000 and flagged_rows > 3000  # both paths taken, often
