"""The length slacks of :func:`criteria_slack` are divided by the length given (issue 18 §9,
plausible bugs: the reach shortfall or the stroke excess multiplied by it passed every test,
all of which used a length of 1 m). Oracle: the shortfall of the inverse model and the stroke
excess worked out in the test from the actuator values and the limits."""

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.region_check import criteria_slack
from pkmkit.analysis.workspace import Criteria

#: Orthoglide poses: beyond the upper stroke of slide 1, beyond the lower stroke of slide 1,
#: out of reach (two of them).
POINTS = np.array([[0.25, 0.0, 0.0], [-0.2, 0.0, 0.0], [0.3, 0.3, 0.3], [2.0, 0.0, 0.0]])


@pytest.mark.parametrize("length", [1.0, 0.01, 0.5])
def test_reach_and_stroke_slacks_in_units_of_the_length(length):
    m = pkmkit.machine("orthoglide")
    criteria = Criteria()
    inv = m.ik(POINTS, full_output=True)
    lo, hi = criteria.limits(m)
    stroke = np.minimum((inv.q - lo).min(axis=1), (hi - inv.q).min(axis=1))
    reach = -inv.shortfall.max(axis=1)
    assert np.all(stroke[:2] < 0) and np.all(np.isnan(inv.q[2:]))
    expected = np.concatenate([stroke[:2], reach[2:]]) / length
    np.testing.assert_allclose(expected[:2] * length, [0.3831 - 0.56, 0.11 - 0.1265], atol=1e-9)
    np.testing.assert_allclose(criteria_slack(m, POINTS, criteria, length), expected,
                               rtol=1e-12)
