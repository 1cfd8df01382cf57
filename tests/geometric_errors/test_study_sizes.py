"""Sizes of the geometric-error studies refused up front with the limit (issue 18 §5), as
``workspace`` refuses a grid: ``sensitivity_analysis(n_points=10**9)`` hung drawing a billion
configurations, a fractional or NaN count was truncated or raised ``ValueError``; Monte Carlo
analyses of 10⁹ samples ran out of memory."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.configurations import sample_configurations
from pkmkit.geometric_errors.sensitivity import sensitivity_analysis
from pkmkit.geometric_errors.tolerance import accuracy_map, monte_carlo, tolerances


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("linear-delta")


@pytest.mark.parametrize("n, words", [
    (10**9, "n_points = 1e+09 is above the limit of 1e+05"),
    (10**300, "above the limit"),
    (0, "must be ≥ 1, got 0"),
    (-5, "must be ≥ 1, got -5"),
    (2.5, "must be a whole number, got 2.5"),
    (float("nan"), "must be a whole number"),
    (float("inf"), "must be a whole number"),
    (True, "must be a whole number, got True"),
    ("10", "must be a whole number, got '10'"),
])
def test_sensitivity_analysis_refuses_absurd_sizes_before_any_work(machine, n, words):
    with pytest.raises(InputError, match="n_points") as info:
        sensitivity_analysis(machine, n_points=n)
    assert words in str(info.value)


def test_sensitivity_analysis_bounds_configurations_times_defects(machine, monkeypatch):
    """The product is what takes memory: 1e5 configurations of a 30-defect machine pass the
    count but hold 3e6 sensitivity columns; the bound is checked before any draw."""
    import pkmkit.geometric_errors.sensitivity as sens

    monkeypatch.setattr(sens, "MAX_SENSITIVITY_ENTRIES", 100)
    with pytest.raises(InputError, match="configurations × defects = 150"):
        sensitivity_analysis(machine, n_points=5)
    big_q = np.zeros((200_001, 3))
    with pytest.raises(InputError, match="rows of q"):
        sensitivity_analysis(machine, q=big_q)


def test_plausible_sizes_still_run(machine):
    table = sensitivity_analysis(machine, n_points=np.int64(7))
    assert table.q.shape == (7, 3) and table.max_displacement.size == len(table.names)
    assert sample_configurations(machine, 3.0).q.shape == (3, 3)  # a whole float is a count


def test_monte_carlo_sizes_are_refused_before_sampling(machine):
    tol = tolerances(machine)
    q = sample_configurations(machine, 10).q
    with pytest.raises(InputError, match="n_samples = 1e\\+09 is above the limit of 5e\\+06"):
        monte_carlo(machine, q, tol, 10**9)
    with pytest.raises(InputError, match="n_samples"):
        monte_carlo(machine, q, tol, 0.5)
    with pytest.raises(InputError, match="n_samples × resolution²"):
        accuracy_map(machine, tol, n_samples=10**6, resolution=101)
