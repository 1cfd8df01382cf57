"""Time laws are invariant under a similarity: the same path, feed, acceleration and jerk all
scaled by s (a part drawn in other units, or a machine s times the size) take exactly the same
time. In particular the decision to stop where the curvature changes between two tangent arcs
(a jerk-limited S-curve must, the normal acceleration jumping there) cannot depend on s."""

import math

import numpy as np
import pytest

from pkmkit.motion.paths import Path, arc_through
from pkmkit.motion.timelaw import plan


def _two_tangent_arcs(scale: float, change: float) -> Path:
    """A quarter circle of radius r about the origin from (r, 0) to (0, r), then a quarter of
    radius r(1 + change), tangent to it at (0, r), turning the same way."""
    r1 = 0.05 * scale
    r2 = r1 * (1.0 + change)
    n = (0.0, 0.0, 1.0)
    first = arc_through([r1, 0, 0], [0, r1, 0], [0, 0, 0], n, clockwise=False)
    c2 = np.array([0.0, r1 - r2, 0.0])
    second = arc_through([0, r1, 0], c2 - np.array([r2, 0.0, 0.0]), c2, n, clockwise=False)
    return Path((first, second))


def _duration(path: Path, scale: float) -> float:
    return plan(path, feed=0.1 * scale, accel=1.0 * scale, jerk=10.0 * scale,
                period=0.01).duration


@pytest.mark.parametrize("change", [0.0, 1e-8, 1e-3])
def test_similar_paths_take_the_same_time(change):
    durations = [_duration(_two_tangent_arcs(s, change), s) for s in (1e-2, 1.0, 1e2)]
    np.testing.assert_allclose(durations, durations[1], rtol=1e-9)


def test_a_change_of_curvature_stops_the_s_curve_and_a_split_circle_does_not():
    one_radius = _duration(_two_tangent_arcs(1.0, 0.0), 1.0)
    changed = _duration(_two_tangent_arcs(1.0, 1e-8), 1.0)
    # without the stop: the half circle of length π r at feed, plus the ramps at its two ends
    assert changed > one_radius + 0.01
    length = math.pi * 0.05
    assert one_radius < 2 * length / 0.1
