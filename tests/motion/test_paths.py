import math

import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.motion.paths import arc_through, chain, circle, helix, line, raster


def finite_difference_check(segment):
    s = np.linspace(0.01, segment.length - 0.01, 7)
    h = 1e-6
    x, dx, ddx = segment.evaluate(s)
    xp, xm = segment.evaluate(s + h)[0], segment.evaluate(s - h)[0]
    np.testing.assert_allclose(dx, (xp - xm) / (2 * h), atol=1e-8)
    np.testing.assert_allclose(ddx, (xp - 2 * x + xm) / h**2, atol=1e-3)
    np.testing.assert_allclose(np.linalg.norm(dx, axis=1), 1.0, atol=1e-12)  # arc length


def test_segment_derivatives_and_arc_length():
    finite_difference_check(line([0, 0, 0], [0.3, -0.1, 0.2]).segments[0])
    finite_difference_check(helix([0.1, 0, 0.2], 0.15, pitch=0.02, turns=2.5).segments[0])
    finite_difference_check(circle([0, 0, 0], 0.1, clockwise=True).segments[0])
    tilted = helix([0, 0, 0], 0.1, pitch=-0.01, turns=1, normal=[1, 1, 1])
    finite_difference_check(tilted.segments[0])


def test_lengths_and_endpoints():
    c = circle([0, 0, 0.2], 0.15)
    assert c.length == pytest.approx(2 * math.pi * 0.15)
    seg = c.segments[0]
    np.testing.assert_allclose(seg.start, [0.15, 0, 0.2], atol=1e-15)
    np.testing.assert_allclose(seg.end, seg.start, atol=1e-14)
    h = helix([0, 0, 0], 0.15, pitch=0.02, turns=10)
    assert h.length == pytest.approx(math.hypot(20 * math.pi * 0.15, 0.2))
    np.testing.assert_allclose(h.segments[0].end, [0.15, 0, 0.2], atol=1e-12)


def test_arc_through_directions():
    ccw = arc_through([1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 1], clockwise=False)
    cw = arc_through([1, 0, 0], [0, 1, 0], [0, 0, 0], [0, 0, 1], clockwise=True)
    assert ccw.sweep == pytest.approx(math.pi / 2) and cw.sweep == pytest.approx(-1.5 * math.pi)
    full = arc_through([1, 0, 0], [1, 0, 0.1], [0, 0, 0], [0, 0, 1], clockwise=False)
    assert full.sweep == pytest.approx(2 * math.pi) and full.rise == pytest.approx(0.1)
    with pytest.raises(InputError, match="inconsistent arc"):
        arc_through([1, 0, 0], [0, 1.1, 0], [0, 0, 0], [0, 0, 1], clockwise=False)


def test_raster_strategies():
    zig = raster([0, 0, 0], 0.2, 0.1, 5, strategy="zigzag")
    one = raster([0, 0, 0], 0.2, 0.1, 5, strategy="one-way")
    assert len(zig.segments) == 9 and zig.cutting_length == pytest.approx(5 * 0.2 + 0.1)
    assert sum(s.rapid for s in one.segments) == 8
    assert one.cutting_length == pytest.approx(5 * 0.2 + 4 * 0.01)  # passes and plunges
    ends = [s.end for s in zig.segments]
    np.testing.assert_allclose(ends[-1], [0.2, 0.1, 0.0])
    chained = chain([zig, line(zig.segments[-1].end, [0.3, 0.1, 0.0])])
    assert len(chained.segments) == 10


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: line([0, 0, 0], [0, 0, 0]), "distinct"),
        (lambda: circle([0, 0, 0], -1.0), "radius"),
        (lambda: helix([0, 0, 0], 0.1, pitch=0.01, turns=0), "turns"),
        (lambda: raster([0, 0, 0], 0.1, 0.1, 0), "passes"),
        (lambda: raster([0, 0, 0], 0.1, 0.1, 3, strategy="spiral"), "strategy"),
        (lambda: raster([0, 0, 0], -0.1, 0.1, 3), "width"),
        (lambda: raster([0, 0, 0], 0.1, -0.1, 3), "height"),
        (lambda: helix([0, 0, 0], 0.1, pitch=0.01, turns=1, normal=(0, np.inf, 1)),
         "^normal must be"),
        (lambda: line([0, 0, np.nan], [1, 0, 0]), "finite"),
        (lambda: chain([line([0, 0, 0], [1, 0, 0]), line([2, 0, 0], [3, 0, 0])]),
         "continuous"),
    ],
)
def test_bad_paths(make, message):
    with pytest.raises(InputError, match=message):
        make()


def test_planar_points_are_lifted_to_z_0():
    """Paths for planar machines: 2 coordinates are (x, y) at z = 0."""
    seg = line([0.1, 0.2], [0.4, -0.2]).segments[0]
    np.testing.assert_array_equal(seg.start, [0.1, 0.2, 0.0])
    np.testing.assert_array_equal(seg.end, [0.4, -0.2, 0.0])
    np.testing.assert_allclose(circle([1.0, 0.5], 0.2).segments[0].center, [1.0, 0.5, 0.0])


@pytest.mark.parametrize("width, height, passes", [(4.7e-180, 0.1, 2), (0.1, 1e-15, 3),
                                                   (1e-10, 0.0, 1)])
def test_raster_refuses_moves_of_nearly_zero_length(width, height, passes):
    """Found by fuzzing: a 4.7e-180 m wide rectangle gave passes of length 0."""
    with pytest.raises(InputError, match="shorter than 1e-09 m"):
        raster((0.0, 0.0, 0.0), width, height, passes)
