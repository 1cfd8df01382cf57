"""Extrema and limit verdicts over continuous time: analytic oracles, and seed 000's circle
whose figures must not depend on the output period."""

import math

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics import default_masses, inverse_dynamics
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.motion import Limits, circle, joint_trajectory, line, plan
from pkmkit.motion.extrema import continuous_extrema, first_excursion


def _fn(funcs):
    def evaluate(t):
        return {name: np.column_stack([f(t) for f in fs]) for name, fs in funcs.items()}
    return evaluate


def test_smooth_peaks_between_grid_points_are_found_exactly():
    omega = 2 * math.pi / 7.3  # peaks at irrational places of a 0..10 s axis
    e = continuous_extrema(_fn({"s": [lambda t: np.sin(omega * t) + 3.0]}),
                           np.array([0.0, 10.0]))
    assert e.converged
    assert e.high["s"][0] == pytest.approx(4.0, abs=1e-12)
    assert e.t_high["s"][0] == pytest.approx(7.3 / 4, abs=1e-5)
    assert e.low["s"][0] == pytest.approx(2.0, abs=1e-12)
    assert e.t_low["s"][0] == pytest.approx(3 * 7.3 / 4, abs=1e-5)


def test_jumps_and_kinks_at_breakpoints_give_one_sided_limits():
    # t on [0, 1), t - 3 on [1, 2]; |t - 1.5| has a kink at 1.5
    e = continuous_extrema(_fn({"g": [lambda t: np.where(t < 1.0, t, t - 3.0)],
                                "k": [lambda t: -np.abs(t - 1.5)]}),
                           np.array([0.0, 1.0, 1.5, 2.0]))
    assert e.high["g"][0] == pytest.approx(1.0, abs=1e-8)  # the sup, approached from the left
    assert e.low["g"][0] == pytest.approx(-2.0, abs=1e-8)
    assert e.high["k"][0] == pytest.approx(0.0, abs=1e-8)


def test_first_excursion_crossing_and_peak():
    omega = 1.7
    e = continuous_extrema(_fn({"s": [lambda t: np.sin(omega * t)]}), np.array([0.0, 4.0]))
    hit = first_excursion(e, "s", 0, -2.0, 0.6)
    assert hit.t == pytest.approx(math.asin(0.6) / omega, abs=1e-9)
    assert hit.t_peak == pytest.approx(math.pi / 2 / omega, abs=1e-5)
    assert hit.value == pytest.approx(1.0, abs=1e-10) and hit.excess == pytest.approx(0.4)
    low = first_excursion(e, "s", 0, -0.9, 2.0)  # the lower limit, reached later
    assert low.t == pytest.approx((math.pi + math.asin(0.9)) / omega, abs=1e-9)
    assert low.value == pytest.approx(-1.0, abs=1e-10)
    assert first_excursion(e, "s", 0, -1.5, 1.5) is None


def test_a_narrow_excursion_between_grid_points_is_reported():
    # a peak just above the limit, far narrower than the grid spacing at level 0
    bump = lambda t: 0.999 + 0.002 * np.exp(-(((t - 3.14159) / 0.004) ** 2))  # noqa: E731
    e = continuous_extrema(_fn({"b": [bump]}), np.array([0.0, 10.0]))
    hit = first_excursion(e, "b", 0, 0.0, 1.0)
    assert hit is not None and hit.t_peak == pytest.approx(3.14159, abs=1e-5)
    assert hit.value == pytest.approx(1.001, abs=1e-9)


def _seed000_circle(period, **kw):
    m = pkmkit.machine("linear-delta-table-iv1")
    return m, simulate_path(m, circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0,
                            period=period, **kw)


FIGURES = ("stroke", "q_min", "q_max", "qd_max", "qdd_max", "force_max", "power_max",
           "leg_axial_max", "tool_speed_max", "tool_accel_max")


@pytest.mark.parametrize("period", [0.37, 2.0, 10.0])
def test_seed000_circle_figures_do_not_depend_on_the_period(period):
    _, fine = _seed000_circle(0.005)
    _, coarse = _seed000_circle(period)
    a, b = fine.summary(), coarse.summary()
    for key in FIGURES:
        x, y = np.atleast_1d(a[key]), np.atleast_1d(b[key])
        scale = np.maximum(np.abs(x), 1e-9)
        assert np.all(np.abs(x - y) <= 1e-4 * scale), key
    stroke = np.asarray(b["stroke"])
    assert np.all(np.abs(stroke - 0.190845) < 2e-6)  # seed ≈ 190 mm, not 0 or 3 % short
    assert b["samples"] <= b["duration"] / period + 2 and b["between_samples"]["converged"]


def test_seed000_circle_extrema_bound_a_dense_sampling():
    """Oracle: the same motion sampled every 0.2 ms and on both sides of every breakpoint (where
    the acceleration kinks); the continuous extrema are never below it and exceed it by no
    more than what that sampling can miss."""
    m, result = _seed000_circle(0.5)
    planned = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=2e-4)
    knots = planned.breakpoints()
    dense = planned.at(np.unique(np.concatenate([planned.t, knots - 1e-12, knots + 1e-12])))
    jt = joint_trajectory(m, dense)
    f = inverse_dynamics(m, default_masses(m), jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd)
    e = result.extrema
    for name, values in (("q", jt.q), ("qd", jt.qd), ("qdd", jt.qdd), ("force", f.force),
                         ("power", f.power)):
        span = values.max(axis=0) - values.min(axis=0)
        assert np.all(e.high[name] >= values.max(axis=0) - 1e-9 * span), name
        assert np.all(e.low[name] <= values.min(axis=0) + 1e-9 * span), name
        assert np.all(e.high[name] - values.max(axis=0) <= 1e-5 * span), name
        assert np.all(values.min(axis=0) - e.low[name] <= 1e-5 * span), name


@pytest.mark.ci
def test_limit_broken_between_samples_is_reported_whatever_the_period():
    """The issue's case: a speed limit six times too low, a period longer than the move."""
    for period in (0.005, 10.0):
        m, result = _seed000_circle(period, limits=Limits(speed=0.0125))
        speed = result.limits["speed"]
        assert speed["exceeded"]
        first = speed["first"]
        assert first["value"] == pytest.approx(0.0763378, abs=1e-6)
        assert first["t"] == pytest.approx(0.09, abs=0.06)  # while speeding up
    dense = plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0, jerk=10.0, period=1e-4)
    qd = joint_trajectory(m, dense).qd
    first_dense = dense.t[np.flatnonzero((np.abs(qd) > 0.0125).any(axis=1))[0]]
    assert first["t"] <= first_dense + 1e-12 and first["t"] > first_dense - 1e-4


@pytest.mark.ci
def test_trapezoid_acceleration_jumps_are_caught_at_any_period():
    """With a trapezoidal law the acceleration jumps at phase changes: the peak is a one-sided
    limit at a breakpoint, found whatever the period."""
    m = pkmkit.machine("linear-delta-table-iv1")
    path = line([-0.1, 0.0, 0.2], [0.1, 0.05, 0.25])
    peaks = []
    for period in (0.001, 0.7, 5.0):
        r = simulate_path(m, path, feed=0.1, accel=1.0, profile="trapezoid", period=period)
        peaks.append(r.summary()["qdd_max"])
    np.testing.assert_allclose(peaks[1], peaks[0], rtol=1e-6)
    np.testing.assert_allclose(peaks[2], peaks[0], rtol=1e-6)
