"""Every limit along a path: all actuators, all kinds, every excursion with its span, worst
excess and program line (analytic oracles and a dense sampling of the motion)."""

import math

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.motion import Limits, joint_trajectory, plan, read_gcode
from pkmkit.motion.extrema import all_excursions, continuous_extrema
from pkmkit.motion.limits import actuator_strokes, stroke_excess

#: Rapid to a start point, then a pocket's first moves (lines 3, 4, 5).
PROGRAM = "G21 G90 G17\n(rapid first)\nG0 X-50 Y-40 Z5\nG1 Z0 F600\nG1 X40 F1200\n"


def test_every_excursion_of_a_sine_with_its_exact_span_and_peak():
    """sin(t) on [0, 4π] above 0.5: two excursions, [π/6, 5π/6] and [13π/6, 17π/6], peak
    excess 0.5 at π/2 and 5π/2; below −0.8: two more (the lower limit)."""
    e = continuous_extrema(lambda t: {"s": np.sin(t)[:, None]}, np.array([0.0, 4 * math.pi]))
    spans = all_excursions(e, "s", 0, -2.0, 0.5)
    assert len(spans) == 2
    for span, k in zip(spans, (0, 2), strict=True):
        assert span.start == pytest.approx(k * math.pi + math.pi / 6, abs=1e-9)
        assert span.end == pytest.approx(k * math.pi + 5 * math.pi / 6, abs=1e-9)
        assert span.t_peak == pytest.approx(k * math.pi + math.pi / 2, abs=1e-5)
        assert span.excess == pytest.approx(0.5, abs=1e-10)
    low = all_excursions(e, "s", 0, -0.8, 2.0)
    assert len(low) == 2 and low[0].value == pytest.approx(-1.0, abs=1e-10)
    assert low[1].start == pytest.approx(3 * math.pi + math.asin(0.8), abs=1e-9)
    assert all_excursions(e, "s", 0, -1.5, 1.5) == []


def test_an_excursion_running_to_the_end_and_one_narrower_than_the_grid():
    narrow = lambda t: 1.0 + np.exp(-((t - 3.3037) / 2e-3) ** 2)  # noqa: E731
    e = continuous_extrema(lambda t: {"r": np.column_stack([t, narrow(t)])},
                           np.array([0.0, 4.0]))
    ramp = all_excursions(e, "r", 0, -1.0, 3.0)
    assert len(ramp) == 1 and ramp[0].start == pytest.approx(3.0, abs=1e-9)
    assert ramp[0].end == pytest.approx(4.0) and ramp[0].excess == pytest.approx(1.0, abs=1e-9)
    assert e.high["r"][1] == pytest.approx(2.0, abs=1e-9)  # found by the extrema
    spike = all_excursions(e, "r", 1, 0.0, 1.5)
    assert len(spike) == 1 and spike[0].excess == pytest.approx(0.5, abs=1e-6)
    # a limit just under the peak: its excursion (0.4 ms) falls between the grid points
    tip = all_excursions(e, "r", 1, 0.0, 1.99)
    grid_t = e.grid.t
    assert not ((grid_t > tip[0].start) & (grid_t < tip[0].end)).any()
    near = 2e-3 * math.sqrt(-math.log(0.99))
    assert len(tip) == 1 and tip[0].excess == pytest.approx(0.01, abs=1e-9)
    assert tip[0].start == pytest.approx(3.3037 - near, abs=1e-9)
    assert tip[0].end == pytest.approx(3.3037 + near, abs=1e-9)
    half = 2e-3 * math.sqrt(math.log(2.0))  # exp(-(d/w)²) = 1/2
    assert spike[0].start == pytest.approx(3.3037 - half, abs=1e-9)
    assert spike[0].end == pytest.approx(3.3037 + half, abs=1e-9)


@pytest.fixture(scope="module")
def fast_rapid():
    """The issue's case: a 60 mm/s actuator speed limit; the rapid drives q1 and q3 well
    beyond it (q1 to −143 mm/s, q3 to +192 mm/s)."""
    m = pkmkit.machine("linear-delta-table-iv1")
    path = read_gcode(PROGRAM, origin=(0.0, 0.0, 0.2))
    kwargs = dict(feed=0.02, accel=3.0, jerk=30.0, rapid_feed=3.0, period=0.01)
    r = simulate_path(m, path, limits=Limits(speed=0.06, accel=0.5), **kwargs)
    return m, path, kwargs, r


@pytest.mark.ci
def test_every_actuator_over_its_speed_limit_is_reported(fast_rapid):
    m, path, kwargs, r = fast_rapid
    speed = {v.joint: v for v in r.violations if v.kind == "speed"}
    assert sorted(speed) == ["q1", "q3"]  # before: only the first excursion, of q3
    dense = plan(path, period=2e-5, **{k: v for k, v in kwargs.items() if k != "period"})
    qd = joint_trajectory(m, dense).qd
    for a, name in enumerate(m.actuator_names):
        over = np.abs(qd[:, a]) > 0.06
        runs = int(np.sum(np.diff(np.concatenate([[0], over.astype(int)])) == 1))
        if name not in speed:
            assert runs == 0
            continue
        v = speed[name]
        assert len(v.excursions) == runs
        worst = np.abs(qd[:, a]).max() - 0.06
        assert v.worst.span.excess == pytest.approx(worst, rel=1e-4)
        first = dense.t[np.flatnonzero(over)[0]]
        last = dense.t[np.flatnonzero(over)[-1]]
        assert v.excursions[0].span.start == pytest.approx(first, abs=2e-5)
        assert v.excursions[-1].span.end == pytest.approx(last, abs=2e-5)
        assert v.worst.line == 3 and v.worst.block == "G0 X-50 Y-40 Z5"
    assert speed["q1"].worst.span.value < -0.14 and speed["q3"].worst.span.value > 0.19


def test_accelerations_are_reported_per_actuator_with_every_excursion_and_line(fast_rapid):
    m, _, _, r = fast_rapid
    accel = [v for v in r.violations if v.kind == "accel"]
    assert {v.joint for v in accel} == set(m.actuator_names)
    lines = {e.line for v in accel for e in v.excursions}
    assert {3, 4} <= lines  # the rapid and the plunge both exceed it
    summary = r.summary()["violations"]
    assert [(v["limit"], v["actuator"]) for v in summary] == \
        [(v.kind, v.joint) for v in r.violations]
    assert all(v["excursions"] == len(v["spans"]) for v in summary)
    kinds = [v.kind for v in r.violations]
    assert kinds == sorted(kinds, key=["stroke", "speed", "accel", "force"].index)


def test_strokes_of_every_family_and_their_excess():
    lo, hi = actuator_strokes(pkmkit.machine("tripteor-x7"))
    assert lo.shape == (5,) and np.isfinite(lo[:3]).all()
    m = pkmkit.machine("linear-delta")
    lo, hi = actuator_strokes(m)
    q = np.array([[lo[0] - 0.01, hi[1] + 0.02, 0.5 * (lo[2] + hi[2])]])
    np.testing.assert_allclose(stroke_excess(m, q), [[0.01, 0.02, 0.0]], atol=1e-12)
