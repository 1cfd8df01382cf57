"""The seed reproductions at reduced size: the numbers docs/calibration.md reports (at full
size) hold their shape — the identification reaches the tracker noise, the machined part the
seed's accuracy class, the Delta's bed its flatness — and the demo's study writes its reports."""

from __future__ import annotations

import json

import numpy as np

from pkmkit.calibration import studies


def test_verne_part_reaches_the_seed_accuracy_class():
    study = studies.verne_part(sections=120)
    s = study.summary()
    assert s["machined"]["nominal"]["along_x"] > 0.1  # mm
    assert s["machined"]["compensated"]["along_x"] < 0.02
    assert s["machined"]["compensated"]["along_y"] < 0.04
    assert s["validation"]["rms"] < 0.01


def test_delta_height_probe_trap_and_flatness():
    study = studies.delta_height_probe(points=40)
    assert set(study.trap) == {"dL1", "dL2", "dL3"}
    assert all(why.startswith("weakly identifiable") for why in study.trap.values())
    assert study.flatness["compensated"] < 0.05 * study.flatness["nominal"]
    assert study.flatness["compensated"] < 20e-6


def test_demo_study_writes_reports(tmp_path, monkeypatch):
    """The demo entry point, with the studies made small."""
    from pkmkit.cli import demo_calibration

    monkeypatch.setattr(demo_calibration, "tripteor_laser_tracker",
                        lambda: studies.tripteor_laser_tracker(identification=40, validation=12,
                                                               thesis_set=False))
    monkeypatch.setattr(demo_calibration, "verne_part", lambda: studies.verne_part(sections=60))
    summary = demo_calibration.run_calibration_demo(tmp_path, echo=False)
    json.dumps(summary)
    trip = summary["tripteor"]
    assert trip["poses"] == {"identification": 40, "validation": 12}
    assert 0.01 < trip["identification"]["mean"] < 0.04  # mm: tracker noise level
    # before: the nominal model's error, well above the tracker noise the calibration reaches
    assert trip["identification"]["mean_before"] > 3 * trip["identification"]["mean"]
    assert trip["thesis"]["identification (thesis)"]["mean"] == 0.0216
    assert "dJ41" in trip["unidentifiable_no_effect"]
    for folder in ("calibration-tripteor", "calibration-verne-part"):
        files = {p.name for p in (tmp_path / folder).iterdir()}
        assert {"report.html", "measurements.csv", "validation.csv",
                "calibration.json"} <= files
    assert (tmp_path / "calibration-tripteor" / "frame.json").exists()
    assert np.isfinite(summary["verne_part"]["machined"]["compensated"]["along_x"])
