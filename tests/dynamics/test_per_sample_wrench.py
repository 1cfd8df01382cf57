"""A cutting force given one row per output sample, as ``(K, 3)`` forces or ``(K, 6)`` wrenches
(force, then moment), acts as the same force between the samples: with every row equal to F,
the continuous-time extrema of the actuator forces are those of the constant F."""

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.motion.paths import circle

FORCE = np.array([30.0, -20.0, 50.0])  # N


@pytest.fixture(scope="module")
def runs():
    m = pkmkit.machine("linear-delta-table-iv1")

    def run(wrench):
        return simulate_path(m, circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0,
                             period=0.1, wrench=wrench)

    constant = run(FORCE)
    k = len(constant.motion.t)
    return constant, run, k


@pytest.mark.parametrize("columns", [3, 6])
def test_rows_of_one_force_act_as_that_constant_force(runs, columns):
    constant, run, k = runs
    rows = np.zeros((k, columns))
    rows[:, :3] = FORCE
    per_sample = run(rows)
    np.testing.assert_allclose(per_sample.forces.force, constant.forces.force, rtol=1e-12)
    for name in ("force", "power"):
        np.testing.assert_allclose(per_sample.extrema.high[name], constant.extrema.high[name],
                                   rtol=1e-9)
        np.testing.assert_allclose(per_sample.extrema.low[name], constant.extrema.low[name],
                                   rtol=1e-9)
    # and the force does matter: without it the extrema are others
    assert not np.allclose(run(None).extrema.high["force"], constant.extrema.high["force"],
                           rtol=1e-3)
