"""Readings in another length unit named before or after the identification (issue 18 §5):
a height-probe file in inches read as mm (its verdict passed, exit 0), a ball-bar file 25.4×
too large (failed, but blamed on the noise or the model), a machined part 25.4× too large
(refused as "does not assemble" without a word on the unit) and 25.4× too small (named only
after a 20–100 s identification). Values, not the code against itself: known factors are
applied to simulated readings and the diagnosis must name them."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import calibrate, random_defects, simulate
from pkmkit.calibration import identify as identify_module
from pkmkit.calibration.unit_screen import scaled_readings, screen_units
from pkmkit.exceptions import InputError

INCH = 25.4


def _true(m, seed):
    rng = np.random.default_rng(seed)
    return m.with_defects(random_defects(m, rng)), rng


@pytest.fixture(scope="module")
def heights():
    m = pkmkit.machine("linear-delta")
    true, rng = _true(m, 3)
    return m, simulate(true, m, "height", 60, rng)


@pytest.fixture(scope="module")
def part():
    m = pkmkit.machine("verne")
    true, rng = _true(m, 3)
    return m, simulate(true, m, "part", 60, rng)


def test_heights_in_inches_read_as_mm_fail_the_verdict_and_name_inches(heights):
    """Heights 25.4× too small are fitted by a machine 25.4× better, with an a-posteriori
    noise 0.04× the assumed one: the verdict passed with a warning (exit 0, a calibrated
    machine file) before."""
    m, data = heights
    good = calibrate(m, data, file_unit="mm")
    assert good.verdict.passed  # the file as simulated: no unit check fails
    res = calibrate(m, scaled_readings(data, 1 / INCH), file_unit="mm")
    assert not res.verdict.passed
    assert [c.name for c in res.verdict.failed] == ["unit"]
    assert [c.cause for c in res.verdict.causes] == ["unit"]
    message = res.verdict.causes[0].message
    assert "look like they are in in, not mm (25.4× too small)" in message
    assert "--units" in message and "--sigma" in message


def test_a_noise_stated_too_large_by_an_unrelated_factor_is_only_a_warning(heights):
    """The unit check needs a unit factor: readings 5× more precise than stated keep the
    warning of the noise check and a passed verdict."""
    m, data = heights
    res = calibrate(m, data, sigma=5 * identify_module.DEFAULT_SIGMA["height"])
    assert res.verdict.passed and res.verdict.warnings


def test_ballbar_lengths_25_4_times_too_large_name_the_unit():
    """Bars of 3.8 m on a 0.7 m machine: the identification settled on defects of 0.5 m and
    the verdict blamed the noise or the model."""
    m = pkmkit.machine("verne")
    true, rng = _true(m, 3)
    data = simulate(true, m, "ballbar", 60, rng)
    res = calibrate(m, scaled_readings(data, INCH), file_unit="mm")
    assert not res.converged and res.iterations == 0  # named before any solve
    assert [c.cause for c in res.verdict.causes] == ["unit"]
    assert "25.4× too large (inches and millimetres mixed up?)" in res.verdict.causes[0].message


@pytest.mark.ci
def test_a_part_25_4_times_too_large_is_refused_naming_the_unit(part):
    m, data = part
    with pytest.raises(InputError, match="does not assemble") as info:
        calibrate(m, scaled_readings(data, INCH), file_unit="mm")
    assert "wrong unit: the readings look 25.4× too large" in str(info.value)
    assert "rescaled ×0.0393701" in str(info.value)


@pytest.mark.ci
def test_a_part_25_4_times_too_small_is_named_before_the_identification(part, monkeypatch):
    """The identification walked the defects away for 561 iterations (20–100 s) before the
    verdict named the unit: now the screen names it and nothing is solved."""
    m, data = part

    def no_solve(*args, **kwargs):
        raise AssertionError("the identification ran")

    monkeypatch.setattr(identify_module, "calibrate", no_solve)
    res = calibrate(m, scaled_readings(data, 1 / INCH), file_unit="mm")
    assert not res.converged and "identification not run" in res.convergence
    assert [c.cause for c in res.verdict.causes] == ["unit"]
    assert "in in, not mm" in res.verdict.causes[0].message


def test_the_screen_leaves_plausible_readings_alone(part, heights):
    for m, data in (part, heights):
        rows = identify_module.sigma_rows(data.kind, m, identify_module.DEFAULT_SIGMA[data.kind])
        assert screen_units(m, data, rows) is None
