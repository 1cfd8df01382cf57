import numpy as np
import pytest

from pkmkit.errors import InputError
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.paths import circle, line, raster
from pkmkit.motion.timelaw import plan, scurve, trapezoid


@pytest.mark.parametrize("distance", [0.001, 0.05, 1.0])
def test_profiles_reach_the_distance_within_limits(distance):
    for prof in (trapezoid(distance, 0.2, 1.0), scurve(distance, 0.2, 1.0, 10.0)):
        t = np.linspace(0, prof.duration, 20001)
        s, v, a = prof.evaluate(t)
        assert s[-1] == pytest.approx(distance, rel=1e-9) and abs(v[-1]) < 1e-9
        assert v.max() <= 0.2 + 1e-12 and np.abs(a).max() <= 1.0 + 1e-12
        assert (np.diff(s) >= -1e-15).all()
        np.testing.assert_allclose(np.gradient(s, t), v, atol=2e-4)
    jerk = np.diff(scurve(distance, 0.2, 1.0, 10.0).evaluate(t)[2]) / np.diff(t)
    assert np.abs(jerk).max() <= 10.0 * (1 + 1e-6)


def test_limits_hold_on_arcs_and_through_corners():
    a_max, j_max = 2.0, 20.0
    path = read_gcode("G21 G90\nG0 X0 Y0\nG1 X50 F6000\nG3 X50 Y20 R10\nG1 X0 Y20\nG1 X0 Y0\n")
    for profile in ("scurve", "trapezoid"):
        tr = plan(path, feed=0.1, accel=a_max, jerk=j_max, profile=profile, period=1e-4)
        acc = np.linalg.norm(tr.xdd, axis=1)
        assert acc.max() <= a_max * (1 + 1e-9)
        if profile == "scurve":
            jerk = np.linalg.norm(np.diff(tr.xdd, axis=0), axis=1) / np.diff(tr.t)
            assert jerk.max() <= j_max * 1.001
        assert np.linalg.norm(tr.xd, axis=1).max() <= 0.1 + 1e-12
        np.testing.assert_allclose(tr.x[-1], [0, 0, 0], atol=1e-12)
        # exact stops at the corners (and, jerk-limited, where a line meets the arc)
        assert len(tr.blocks) == (4 if profile == "scurve" else 2)


def test_circle_at_constant_speed_and_sampling():
    tr = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=0.002)
    speed = np.linalg.norm(tr.xd, axis=1)
    assert speed.max() == pytest.approx(0.12)
    assert np.diff(tr.t).max() <= 0.002 + 1e-12 and tr.t[-1] == pytest.approx(tr.duration)
    np.testing.assert_allclose(np.linalg.norm(tr.x[:, :2], axis=1), 0.15, atol=1e-12)


def test_zigzag_facing_is_faster_than_one_way():
    """Seed 000 (L1509): the second strategy takes less time than the first."""
    kw = {"feed": 0.05, "accel": 0.5, "jerk": 5.0, "period": 0.01}
    zig = plan(raster([0, 0, 0], 0.2, 0.1, 5, strategy="zigzag"), **kw)
    one = plan(raster([0, 0, 0], 0.2, 0.1, 5, strategy="one-way"), rapid_feed=0.2, **kw)
    assert zig.duration < one.duration


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"feed": 0.0, "accel": 1.0, "jerk": 1.0}, "feed"),
        ({"feed": 0.1, "accel": -1.0, "jerk": 1.0}, "accel"),
        ({"feed": 0.1, "accel": 1.0}, "jerk"),
        ({"feed": 0.1, "accel": 1.0, "jerk": 1.0, "profile": "sine"}, "profile"),
        ({"feed": 0.1, "accel": 1.0, "jerk": 1.0, "period": 1e-9}, "samples"),
    ],
)
def test_bad_plans(kwargs, message):
    with pytest.raises(InputError, match=message):
        plan(line([0, 0, 0], [1, 0, 0]), **kwargs)
