"""``continues_from`` (machines/warm_starts.py) on the joint chains with a two-axis head: an
inverse solution may seed a neighbouring point's solve unless the tool axis is within
``WRIST_SINGULAR_ANGLE`` (5°) of the head's first revolute axis. Oracle: configurations built
at home with the head's second axis turned by a known angle (on both machines the tool axis
is along the first wrist axis at home, so that angle is the one between them), solved back by
the inverse model; rows at 0.1 and 0.5 times the threshold are refused, rows at 2 and 4 times
it and at 0.2 rad accepted."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.warm_starts import WRIST_SINGULAR_ANGLE


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_rows_near_the_wrist_singularity_do_not_seed_a_neighbour(name):
    m = pkmkit.machine(name)
    factors = np.array([0.1, 0.5, 2.0, 4.0])
    angles = np.append(factors * WRIST_SINGULAR_ANGLE, 0.2)
    q = np.tile(m.home_q, (len(angles), 1))
    q[:, 4] = angles
    x = m.fk(q, strokes="ignore")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = m.ik(x, full_output=True, strokes="ignore")
    assert (res.status == 0).all()
    np.testing.assert_allclose(res.q, q, atol=1e-9)  # the same configurations solved back
    np.testing.assert_array_equal(m.continues_from(res.solution),
                                  angles > WRIST_SINGULAR_ANGLE)
    solution = res.solution.copy()
    solution[0, 0] = np.nan
    assert not m.continues_from(solution)[0]
