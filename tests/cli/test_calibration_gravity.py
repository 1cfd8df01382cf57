"""The calibration report shows the gravity deflection predicted at the measured
configurations beside the residual (:mod:`pkmkit.calibration.gravity`,
:mod:`pkmkit.plot.gravity_section`)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.gravity import gravity_deflection


@pytest.mark.ci
def test_report_and_json_carry_the_sag_at_the_measured_configurations(run, tmp_path):
    res = run("simulate-measurements", "linear-delta", "--measure", "point", "--poses", 30,
              "--defects", "random", "--seed", 3, "--units", "mm", "--out", tmp_path / "m.csv")
    assert res.exit_code == 0, res.output
    res = run("calibrate", "linear-delta", "--measure", "point", "--measurements",
              tmp_path / "m.csv", "--out", tmp_path / "cal", "--json")
    assert res.exit_code in (0, 3), res.output
    payload = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    g = payload["gravity"]
    assert g["available"] and g["configurations"] == 30
    assert g["residual_rms"] == payload["rms_after"]  # both in mm
    # the same figure from the measured q and the calibrated machine, computed here
    lines = [r for r in (tmp_path / "m.csv").read_text().splitlines() if not r.startswith("#")]
    q = np.array([[float(v) for v in r.split(",")[:3]] for r in lines[1:]]) * 1e-3
    machine = pkmkit.load(tmp_path / "cal" / "linear-delta-calibrated.toml")
    sag = np.linalg.norm(gravity_deflection(machine, q).deflection[:, :3], axis=1)
    assert np.isclose(g["rms"], np.sqrt(np.mean(sag**2)) * 1e3, rtol=1e-6)
    report = (tmp_path / "cal" / "report.html").read_text()
    assert "Geometric and elastic error" in report and "illustrative masses" in report
