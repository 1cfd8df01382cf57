"""The verdict's unit hypothesis on readings in another unit than the file says (values, not
the code against itself: the readings are rescaled by a known factor and the diagnosis must
name the true unit)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import calibrate, identify, random_defects, simulate
from pkmkit.exceptions import ConvergenceError, IdentificationDivergedError


def _readings():
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(5)
    # defects of a well-built machine (tool errors of a few 0.1 mm): a rescale must explain
    # the residual by far more than the defects do
    true = m.with_defects(random_defects(m, rng, magnitude={"m": 2e-5, "1": 2e-4,
                                                                    "rad": 2e-4}))
    return m, simulate(true, m, "point", 30, rng, noise=1e-5)


def test_readings_in_inches_in_a_millimetre_file_are_named():
    """Tracker readings written in inches in a file that says mm: read as mm they are 25.4×
    too small; the likely cause names inches."""
    m, data = _readings()
    read = replace(data, values=data.values * (1e-3 / 0.0254))
    res = calibrate(m, read, file_unit="mm")  # a ConvergenceError before (xfail, exit 1)
    assert not res.verdict.passed
    causes = [c for c in res.verdict.causes if c.cause == "unit"]
    assert causes, [c.message for c in res.verdict.causes]
    assert "look like they are in in, not mm" in causes[0].message
    assert "×25.4" in causes[0].message


def test_readings_in_millimetres_in_a_metre_file_are_named():
    m, data = _readings()
    res = calibrate(m, replace(data, values=data.values * 1e3), file_unit="m")
    assert not res.verdict.passed
    unit = [c for c in res.verdict.causes if c.cause == "unit"]
    assert unit and "look like they are in mm, not m" in unit[0].message


def test_an_identification_that_does_not_converge_is_still_judged():
    """No plausible machine fits readings 25.4× too small (the fit walks the defects away:
    :func:`pkmkit.calibration.identify.calibrate` raises); the judged call returns the nominal
    machine's fit, nothing identified, with a red verdict whose convergence check fails and
    whose likely cause is the unit."""
    m, data = _readings()
    read = replace(data, values=data.values * (1e-3 / 0.0254))
    with pytest.raises(ConvergenceError, match="did not converge") as info:
        identify.calibrate(m, read)
    assert isinstance(info.value, IdentificationDivergedError)
    # stopped once the defects went beyond any built machine's (not at the iteration limit)
    assert "times their tolerance" in str(info.value)
    res = calibrate(m, read, file_unit="mm")
    # the unit screen names the unit before any solve (the identification is not run)
    assert not res.converged and "identification not run" in res.convergence
    assert res.names == () and not np.any(res.defects) and res.machine is m
    assert res.after.rms == res.before.rms > 0.1  # the nominal machine: 0.5 m off
    failed = [c.name for c in res.verdict.failed]
    assert "convergence" in failed and "noise" in failed
    assert [c.cause for c in res.verdict.causes] == ["unit"]
    payload = res.to_json("mm")
    assert payload["converged"] is False and payload["verdict"]["passed"] is False


def test_a_set_up_that_cannot_be_fitted_is_still_judged(monkeypatch):
    """When even the set-up (here a ball-bar's pivots) cannot be fitted on the nominal
    machine, the judged call still returns a failed verdict (a ConvergenceError before)."""
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(2)
    data = simulate(m, m, "ballbar", 30, rng)

    def fails(machine, model, max_iter=50):
        raise ConvergenceError("the ballbar set-up parameters could not be fitted on the "
                               "machine (not-converged)")

    monkeypatch.setattr(identify, "fit_setup", fails)
    with pytest.raises(IdentificationDivergedError, match="could not be fitted"):
        identify.calibrate(m, data)
    res = calibrate(m, data)
    assert not res.converged and "could not be fitted" in res.convergence
    assert res.names == () and res.after.per_pose.shape == (30,)
    assert "convergence" in [c.name for c in res.verdict.failed]
    assert res.verdict.causes  # a named likely cause, never an empty red verdict
