"""Circles and helices about a tilted normal: the sense of rotation and the rise follow the
right-hand rule about the normal given (counter-clockwise unless ``clockwise``), whatever the
normal — checked on the sampled points, not on the arc's own basis vectors."""

import numpy as np
import pytest

from pkmkit.motion.paths import circle, helix

NORMALS = [(1.0, 1.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.2, -0.9, 0.4),
           (0.0, 0.0, -1.0)]


@pytest.mark.parametrize("normal", NORMALS)
@pytest.mark.parametrize("clockwise", [False, True])
def test_helix_turns_about_its_normal_and_rises_along_it(normal, clockwise):
    n = np.asarray(normal) / np.linalg.norm(normal)
    centre = np.array([0.1, -0.2, 0.3])
    radius, pitch, turns = 0.05, 0.02, 2.0
    seg = helix(centre, radius, pitch=pitch, turns=turns, normal=normal,
                clockwise=clockwise).segments[0]
    s = np.linspace(0.0, seg.length, 401)
    x = seg.evaluate(s)[0]
    # the rise: after two whole turns the tool is pitch·turns along +n from where it started
    np.testing.assert_allclose(x[-1] - x[0], pitch * turns * n, atol=1e-12)
    # every point at the radius from the axis through the centre along n
    rel = x - centre
    radial = rel - np.outer(rel @ n, n)
    np.testing.assert_allclose(np.linalg.norm(radial, axis=1), radius, rtol=1e-12)
    # sense: successive radial vectors turn about +n (counter-clockwise) or -n (clockwise)
    turn = np.cross(radial[:-1], radial[1:]) @ n
    assert (np.sign(turn) == (-1.0 if clockwise else 1.0)).all()


@pytest.mark.parametrize("normal", NORMALS)
def test_circle_quarter_turn_is_the_right_hand_rotation_of_the_start(normal):
    """A quarter of a counter-clockwise circle takes the start's radius vector r to n × r."""
    n = np.asarray(normal) / np.linalg.norm(normal)
    centre = np.array([1.0, 2.0, 3.0])
    seg = circle(centre, 0.2, normal=normal).segments[0]
    r0 = seg.evaluate(np.array([0.0]))[0][0] - centre
    r1 = seg.evaluate(np.array([seg.length / 4]))[0][0] - centre
    assert abs(r0 @ n) < 1e-15
    np.testing.assert_allclose(r1, np.cross(n, r0), atol=1e-14)
