"""An arc whose end is its start (G2/G3 with the same end point) is a whole turn, in either
sense: its length is 2πr and a quarter of the way along it the radius vector has turned by
+90° (G3, counter-clockwise about the normal) or −90° (G2)."""

import math

import numpy as np
import pytest

from pkmkit.motion.paths import arc_through


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0)])
def test_full_circle_in_either_sense(clockwise, normal):
    n = np.asarray(normal)
    centre = np.array([0.01, 0.02, 0.03])
    r0 = np.cross(n, [0.3, 0.5, 0.7])
    r0 = 0.04 * r0 / np.linalg.norm(r0)
    start = centre + r0
    arc = arc_through(start, start, centre, normal, clockwise=clockwise)
    assert arc.length == pytest.approx(2 * math.pi * 0.04, rel=1e-12)
    quarter = arc.evaluate(np.array([arc.length / 4]))[0][0] - centre
    turned = np.cross(n, r0) * (-1.0 if clockwise else 1.0)
    np.testing.assert_allclose(quarter, turned, atol=1e-15)
    np.testing.assert_allclose(arc.end, start, atol=1e-15)


@pytest.mark.parametrize("clockwise", [False, True])
def test_extra_full_turns_add_whole_circles(clockwise):
    start, centre = np.array([0.05, 0.0, 0.0]), np.zeros(3)
    one = arc_through(start, start, centre, (0, 0, 1), clockwise=clockwise)
    three = arc_through(start, start, centre, (0, 0, 1), clockwise=clockwise, full_turns=2)
    assert three.length == pytest.approx(3 * one.length, rel=1e-12)
    assert abs(one.sweep) == pytest.approx(2 * math.pi, rel=1e-12)
