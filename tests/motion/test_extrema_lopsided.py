"""Extrema between grid points of a peak that is lopsided at the grid's scale (a slow rise and
a steep fall, analytic but far from a parabola between two samples): the refinement must
bracket the grid's own local maximum, or only the grid value is left and the tolerance is
missed. Oracle: the maximum worked out by hand."""

import math

import numpy as np
import pytest

from pkmkit.motion.extrema import DEFAULT_RTOL, continuous_extrema


def _lopsided(t0: float, eps: float, alpha: float):
    """f(t) = alpha (t − t0) − sqrt(eps² + (t − t0)²): slopes alpha − 1 after the peak and
    alpha + 1 before it (a smoothed kink); f' = 0 where (t − t0)/sqrt(eps² + (t − t0)²) =
    alpha, so the peak is at t0 + alpha eps / sqrt(1 − alpha²), of value −eps sqrt(1 − alpha²)."""
    def evaluate(t):
        d = t - t0
        return {"f": (alpha * d - np.sqrt(eps**2 + d**2))[:, None]}
    t_peak = t0 + alpha * eps / math.sqrt(1.0 - alpha**2)
    return evaluate, t_peak, -eps * math.sqrt(1.0 - alpha**2)


@pytest.mark.parametrize("t0", [0.3131, 0.50037, 0.7777])
@pytest.mark.parametrize("alpha", [-0.8, 0.8])
def test_a_lopsided_peak_between_samples_is_found_to_the_tolerance(t0, alpha):
    evaluate, t_peak, peak = _lopsided(t0, 1e-7, alpha)
    e = continuous_extrema(evaluate, np.array([0.0, 1.0]))
    span = e.high["f"][0] - e.low["f"][0]  # about 1: the range the tolerance is relative to
    assert e.converged
    assert abs(e.high["f"][0] - peak) <= DEFAULT_RTOL * span
    assert abs(e.t_high["f"][0] - t_peak) <= 1e-4
