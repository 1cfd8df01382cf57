import itertools
import math

import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.paths import Arc, Line, Path, circle, line, raster
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


def _arc_from(start, tangent, normal, radius, sweep, rise=0.0):
    """An arc leaving ``start`` along ``tangent`` (unit, ⊥ normal), turning about ``normal``."""
    side = np.cross(normal, tangent)
    sign = 1.0 if sweep > 0 else -1.0
    center = start + sign * radius * side
    e1 = -sign * side
    return Arc(center, radius, e1, np.cross(normal, e1), 0.0, sweep, rise)


def _random_chain(rng):
    """Lines and arcs (some helical) in random planes; joints tangent, nearly tangent (1e-4
    rad) or sharp, S-bends, and zero-length moves."""
    point, tangent = np.zeros(3), np.array([1.0, 0.0, 0.0])
    segs = []
    for _ in range(8):
        kind = rng.choice(["line", "arc", "arc", "zero"])
        normal = np.cross(tangent, rng.normal(size=3))
        normal /= np.linalg.norm(normal)
        if kind == "line":
            seg = Line(point, point + rng.uniform(0.002, 0.03) * tangent)
        elif kind == "zero":
            seg = Line(point, point.copy())
        else:
            rise = rng.choice([0.0, rng.uniform(-0.01, 0.01)])
            seg = _arc_from(point, tangent, normal, rng.uniform(0.002, 0.02),
                            rng.choice([-1, 1]) * rng.uniform(0.2, 3.0), rise)
        segs.append(seg)
        point = seg.end
        if seg.length > 0:
            tangent = seg.tangent(end=True) / np.linalg.norm(seg.tangent(end=True))
        turn = rng.choice(["tangent", "tangent", "tiny", "sharp"])
        if turn != "tangent":
            angle = 1e-4 if turn == "tiny" else rng.uniform(0.3, 3.0)
            axis = np.cross(tangent, rng.normal(size=3))
            axis /= np.linalg.norm(axis)
            tangent = np.cos(angle) * tangent + np.sin(angle) * np.cross(axis, tangent)
    return Path(tuple(segs))


@pytest.mark.parametrize("seed", range(12))
def test_limits_hold_on_random_chains(seed):
    """Acceleration, jerk and speed from finite differences of the sampled positions (not the
    planner's own derivatives) stay within the limits, and the reported ẋ, ẍ match them."""
    rng = np.random.default_rng(seed)
    path = _random_chain(rng)
    a_max, j_max, feed, h = 2.0, 20.0, 0.1, 2e-4
    for profile in ("scurve", "trapezoid"):
        tr = plan(path, feed=feed, accel=a_max, jerk=j_max, profile=profile, period=h)
        x = tr.x[: np.flatnonzero(np.abs(np.diff(tr.t) - h) > 1e-12)[0] + 1]  # uniform part
        vel = np.diff(x, axis=0) / h
        acc = np.diff(x, 2, axis=0) / h**2
        assert np.linalg.norm(vel, axis=1).max() <= feed * (1 + 1e-6)
        assert np.linalg.norm(acc, axis=1).max() <= a_max * (1 + 1e-3)
        np.testing.assert_allclose(tr.x[-1], path.segments[-1].end, atol=1e-12)
        if profile == "scurve":
            jerk = np.diff(x, 3, axis=0) / h**3
            assert np.linalg.norm(jerk, axis=1).max() <= j_max * (1 + 1e-2)
            np.testing.assert_allclose(acc, tr.xdd[1:len(x) - 1], atol=a_max * 1e-2)


def test_s_bend_zero_length_and_polyline_stops():
    # an S-bend: two tangent arcs turning opposite ways — the normal acceleration flips
    s_bend = read_gcode("G21 G90\nG0 X0 Y0\nG3 X20 Y0 R10 F6000\nG2 X40 Y0 R10\n")
    bend = plan(s_bend, feed=0.1, accel=2.0, jerk=20.0, period=1e-3)
    assert [b.segments for b in bend.blocks] == [(0,), (1,)]
    # a reversal hidden behind a zero-length move stops the tool
    back = Path((Line(np.zeros(3), np.array([0.1, 0, 0])), Line(np.array([0.1, 0, 0]),
                                                               np.array([0.1, 0, 0])),
                 Line(np.array([0.1, 0, 0]), np.zeros(3))))
    tr = plan(back, feed=0.1, accel=1.0, jerk=10.0, period=1e-3)
    assert len(tr.blocks) == 2 and np.isfinite(tr.x).all()
    # a polyline approximating a circle stops at each vertex (no corner blending)
    angles = np.linspace(0, 2 * np.pi, 41)
    pts = np.column_stack([0.05 * np.cos(angles), 0.05 * np.sin(angles), np.zeros(41)])
    poly = Path(tuple(Line(a, b) for a, b in itertools.pairwise(pts)))
    assert len(plan(poly, feed=0.1, accel=1.0, jerk=10.0, period=1e-3).blocks) == 40
    with pytest.raises(InputError, match="zero length"):
        plan(Path((Line(np.zeros(3), np.zeros(3)),)), feed=0.1, accel=1.0, jerk=10.0)


def test_trapezoid_ignores_the_jerk():
    arc = circle([0, 0, 0], 0.04)
    plain = plan(arc, feed=0.1, accel=2.0, profile="trapezoid")
    with_jerk = plan(arc, feed=0.1, accel=2.0, jerk=1.0, profile="trapezoid")
    assert with_jerk.duration == pytest.approx(plain.duration)


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
        ({"feed": 0.1, "accel": 1.0, "jerk": -1.0}, "jerk"),
        ({"feed": 0.1, "accel": 1.0, "jerk": float("nan")}, "jerk"),
        ({"feed": 0.1, "accel": 1.0, "jerk": 1.0, "profile": "sine"}, "profile"),
        ({"feed": 0.1, "accel": 1.0, "jerk": 1.0, "period": 1e-9}, "samples"),
    ],
)
def test_bad_plans(kwargs, message):
    with pytest.raises(InputError, match=message):
        plan(line([0, 0, 0], [1, 0, 0]), **kwargs)


def test_default_jerk_is_ten_times_the_acceleration():
    """An S-curve without a jerk uses DEFAULT_JERK_PER_ACCEL × accel (documented default)."""
    from pkmkit.motion.timelaw import DEFAULT_JERK_PER_ACCEL

    path = line([0, 0, 0], [0.2, 0, 0])
    implicit = plan(path, feed=0.1, accel=0.5, period=1e-3)
    explicit = plan(path, feed=0.1, accel=0.5, jerk=DEFAULT_JERK_PER_ACCEL * 0.5, period=1e-3)
    np.testing.assert_array_equal(implicit.x, explicit.x)
    other = plan(path, feed=0.1, accel=0.5, jerk=50.0, period=1e-3)
    assert implicit.t[-1] != other.t[-1]


@pytest.mark.parametrize("radius, accel, jerk, feed", [
    (0.02, 2.0, 20.0, 1.0),     # the jerk of the turning acceleration, 3 v a_t κ ≤ J/3, binds
    (0.02, 2.0, 2000.0, 1.0),   # the normal acceleration v²κ ≤ A/2 binds
    (0.05, 3.0, 500.0, 0.05),   # the feed binds
])
def test_arc_limits_are_the_documented_ones(radius, accel, jerk, feed):
    """On a circle (κ = 1/r) the cruise speed is min(F, √(A/2κ), (J/3κ²)^⅓, J/(9 a_t κ)) with
    a_t = (√3/2) A; along the whole move the tangential jerk stays ≤ J/3, the normal
    acceleration ≤ A/2, the tangential one ≤ (√3/2) A, and the jerk ≤ (√6/3) J (module
    docstring). Each is measured on the samples, not read from the plan."""
    kappa = 1.0 / radius
    a_t = math.sqrt(3) / 2 * accel
    cruise = min(feed, math.sqrt(accel / 2 / kappa), (jerk / 3 / kappa**2) ** (1 / 3),
                 jerk / 9 / (a_t * kappa))
    tr = plan(circle([0.1, -0.2, 0.05], radius), feed=feed, accel=accel, jerk=jerk,
              period=2e-4)
    speed = np.linalg.norm(tr.xd, axis=1)
    assert speed.max() == pytest.approx(cruise, rel=1e-9)
    tangential = np.einsum("ij,ij->i", tr.xdd, tr.xd) / np.maximum(speed, 1e-300)
    normal = np.sqrt(np.maximum(np.einsum("ij,ij->i", tr.xdd, tr.xdd) - tangential**2, 0.0))
    np.testing.assert_allclose(normal, speed**2 * kappa, atol=1e-9 * accel)
    assert np.abs(tangential).max() <= a_t * (1 + 1e-9)
    assert normal.max() <= accel / 2 * (1 + 1e-9)
    dt = np.diff(tr.t)
    assert np.abs(np.diff(tangential) / dt).max() <= jerk / 3 * (1 + 1e-6)
    total_jerk = np.linalg.norm(np.diff(tr.xdd, axis=0), axis=1) / dt
    assert total_jerk.max() <= math.sqrt(6) / 3 * jerk * (1 + 1e-3)
