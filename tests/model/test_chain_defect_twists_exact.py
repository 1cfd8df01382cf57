"""Defect twists of joint chains are exact derivatives at non-zero defects too (calibration's
Gauss–Newton needs them there): central finite differences of the exactly applied defects."""

from __future__ import annotations

import numpy as np

import pkmkit
from pkmkit.solve.chains import chain_pose
from pkmkit.spatial.rotation import matrix_to_rotvec


def test_twists_match_finite_differences_away_from_nominal():
    m = pkmkit.machine("tripteor-x7")
    model = m.model
    rng = np.random.default_rng(4)
    base = rng.uniform(-1, 1, len(model.defect_index)) * np.where(
        np.array(model.defect_index.units) == "m", 1e-4, 8e-3)
    current = model.with_defects(base)
    values = np.tile(m._home["values"], (2, 1)).T.copy()
    chain = model.legs[1] + model.head  # leg 2 then the head: fixed frames, spins, revolutes
    pose = chain_pose(current, chain, values, defects=True)
    h = 1e-7
    checked = 0
    for i in range(len(base)):
        if not np.any(pose.defect_twists[:, i]):
            continue
        plus = model.with_defects(base + h * np.eye(len(base))[i])
        minus = model.with_defects(base - h * np.eye(len(base))[i])
        a, b = chain_pose(plus, chain, values), chain_pose(minus, chain, values)
        w = matrix_to_rotvec((a.R[:, :, 0] @ b.R[:, :, 0].T)[None])[0] / (2 * h)
        dp = (a.p[:, 0] - b.p[:, 0]) / (2 * h)
        tw = pose.defect_twists[:, i, 0]
        np.testing.assert_allclose(tw[3:], w, atol=2e-7)
        np.testing.assert_allclose(tw[:3] + np.cross(tw[3:], pose.p[:, 0]), dp, atol=2e-7)
        checked += 1
    assert checked > 30
