"""The seed reproductions at reduced size: the numbers docs/calibration.md reports (at full
size) hold their shape — the identification reaches the tracker noise, the machined part the
seed's bounds (on simulated readings: the residuals are the injected noise), the Delta's bed its
flatness — and the demo's study writes its reports."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pkmkit.calibration import studies


@pytest.mark.ci
def test_verne_part_within_the_seed_bounds():
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


@pytest.mark.slow  # 15-40 s: .ci/run runs it (-m "slow or ci")
def test_demo_study_writes_reports(tmp_path, monkeypatch):
    """The demo entry point, with the studies made small."""
    from pkmkit.demos import calibration as demo_calibration

    made = {}

    def small_tripteor():
        made["tripteor"] = studies.tripteor_laser_tracker(identification=40, validation=12,
                                                          thesis_set=False)
        return made["tripteor"]

    def small_part():
        made["part"] = studies.verne_part(sections=60)
        return made["part"]

    monkeypatch.setattr(demo_calibration, "tripteor_laser_tracker", small_tripteor)
    monkeypatch.setattr(demo_calibration, "verne_part", small_part)
    summary = demo_calibration.run_calibration_demo(tmp_path, echo=False)
    # the summaries' lengths: in mm by default, the same physical values in m
    for study in made.values():
        _same_lengths(study.summary(), study.summary(scale=1.0), 1e3)
    r = made["tripteor"].result
    assert summary["tripteor"]["identification"]["max"] == pytest.approx(r.after.max * 1e3)
    assert summary["tripteor"]["registration_rms_table_5_4"] == pytest.approx(0.085)
    p = made["part"].result
    assert summary["verne_part"]["identification"]["rms"] == pytest.approx(p.after.rms * 1e3)
    assert summary["verne_part"]["seed_targets"] == {"x": pytest.approx(0.02),
                                                     "y": pytest.approx(0.04)}
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
    # the report's tool-point uncertainty (k = 2) is of the residuals' scale: at most
    # 2 σ̂ √(unknowns / observations) in RMS (linear least squares; the frame is identified,
    # so the free rigid motion is removed). The machine-parameter covariance alone gave ~1.6 mm
    # against a 0.024 mm residual.
    cal = json.loads((tmp_path / "calibration-tripteor" / "calibration.json").read_text())
    band = cal["tool_uncertainty_k2"]
    unknowns = len(cal["parameters"]) + len(cal["setup"])
    assert band["rigid_motion_removed"]
    assert 0.1 * cal["sigma_posterior"] < band["rms"] <= 2.0 * cal["sigma_posterior"] * np.sqrt(
        unknowns / cal["poses"]) * 1.01
    assert np.isfinite(summary["verne_part"]["machined"]["compensated"]["along_x"])


#: Summary entries that are not lengths (counts, ratios, times, names).
NOT_LENGTHS = {"poses", "identified", "rank", "condition", "seconds", "unidentifiable_no_effect",
               "candidates", "J41", "report"}


def _same_lengths(mm: dict, m: dict, factor: float, path: str = "") -> None:
    """Every numeric leaf of ``mm`` is ``factor`` times that of ``m`` (lengths)."""
    assert mm.keys() == m.keys(), path
    for key, value in mm.items():
        if key in NOT_LENGTHS:
            continue
        if isinstance(value, dict):
            _same_lengths(value, m[key], factor, f"{path}.{key}")
        elif isinstance(value, float | int) and not isinstance(value, bool):
            assert value == pytest.approx(factor * m[key], rel=1e-12), f"{path}.{key}"


@pytest.mark.ci
def test_tripteor_residual_scales_with_the_injected_tracker_noise():
    """The synthetic Tripteor residuals are the injected noise: the same study (same defects,
    poses and draws) without noise leaves a floor of a few µm (weakly identifiable defects
    left at nominal), with twice the noise twice the residual, and at 1× the mean is that of
    the 3-D noise vector, σ·sqrt(8/π) (docs/calibration.md §5.1). A residual that did not
    follow the noise would mean the figures measure the model, not the simulated tracker."""
    rows = studies.tripteor_noise_sweep(identification=40, validation=12)
    assert [r["scale"] for r in rows] == [0.0, 1.0, 2.0]
    none, once, twice = rows
    assert once["sigma"] == pytest.approx(15e-6)
    assert none["identification_mean"] < 0.1 * once["identification_mean"]
    for key in ("identification_mean", "identification_max", "validation_mean",
                "validation_max"):
        assert twice[key] / once[key] == pytest.approx(2.0, rel=0.1)
    alone = once["sigma"] * np.sqrt(8.0 / np.pi)
    assert 0.75 * alone < once["identification_mean"] < 1.05 * alone
    table = studies.noise_sweep_table(rows).splitlines()
    assert len(table) == 4 and table[2].startswith("1×")


def test_noise_scale_multiplies_every_sigma():
    from pkmkit.calibration.simulate import Noise
    from pkmkit.exceptions import InputError

    pts = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 1.0]])
    base, double = Noise("tracker"), Noise("tracker", scale=2.0)
    np.testing.assert_allclose(double.position_sigma(pts), 2 * base.position_sigma(pts))
    assert double.rotation_sigma() == 2 * base.rotation_sigma()
    assert not Noise("cmm", scale=0.0).position_sigma(pts).any()
    with pytest.raises(InputError, match="noise scale"):
        Noise("tracker", scale=-1.0)


def test_simulated_registration_follows_table_5_4_direction_convention():
    """Table 5.4's i, j, k are short-tool tip minus long-tool tip (tip → spindle, as the CNC's
    vectors; docs/tripteor-x7.md §4): the study's simulated registration readings follow it,
    so turned into the machine frame they point against the tool axis (tip outwards)."""
    import pkmkit

    m = pkmkit.machine("tripteor-x7")
    frame = studies.tracker_frame()
    _, _, dm, dn = studies._registration_measurements(m, m, np.random.default_rng(0),
                                                      frame, 0.0)
    gap = 0.169889 - 0.110006
    np.testing.assert_allclose(np.linalg.norm(dm, axis=1), gap, atol=1e-9)
    # the same vector in both frames (noise-free, true = nominal machine)
    np.testing.assert_allclose(frame.apply_directions(dm) / gap, dn, atol=1e-6)
    # ... and it is minus the tool axis: at home (row 1) the axis of m.fk points tip outwards
    axis = m.fk(m.home_q, tool_length=0.169889)[3:]
    assert dn[0] @ axis == pytest.approx(-1.0, abs=1e-12)


@pytest.mark.ci
def test_verne_part_residual_scales_with_the_injected_cmm_noise():
    """Seed 003's synthetic part: the identification residual is the CMM noise (none → a floor
    well below, twice the noise → twice the residual) and the compensated part is best without
    noise (docs/calibration.md §5.2)."""
    table = studies.verne_noise_sweep(sections=60).splitlines()
    rows = np.array([[float(v) for v in line.split()[1:]] for line in table[1:]])
    sigma, rms, along_x, along_y = rows.T
    np.testing.assert_allclose(sigma, [0.0, 1.5, 3.0])
    assert rms[0] < 0.1 * rms[1] and rms[2] / rms[1] == pytest.approx(2.0, rel=0.15)
    assert max(along_x[0], along_y[0]) < min(max(along_x[1], along_y[1]),
                                             max(along_x[2], along_y[2]))


def _thesis_set_problem(poses: int):
    from pkmkit.calibration.identify import identification_problem

    study = studies.tripteor_laser_tracker(identification=poses, validation=12, thesis_set=False)
    names = [v for v in studies.TABLE_5_5.values() if v is not None]
    return study, names, identification_problem(
        study.result.nominal, study.data, parameters=names, frame=study.registration,
        compatible=False, rcond=1e-30, prune=False)


def test_thesis_set_at_the_nominal_geometry_has_fourteen_zero_columns():
    """Table 5.5's 43 minimal parameters, tool points, the thesis's poses (107): the ten
    THESIS_GAUGES and da51, da52, da53, dI52 have columns zero to round-off at the nominal
    geometry, and the analytic rank is 27 (docs/calibration.md §5.1, the "thesis way")."""
    _, names, problem = _thesis_set_problem(107)
    assert len(names) == 43
    jac = problem.jacobian(problem.u0)
    norms = np.linalg.norm(jac, axis=0)
    zero = {problem.names[k] for k in np.flatnonzero(norms <= 1e-12 * norms.max())}
    assert zero == set(studies.THESIS_GAUGES) | {"da51", "da52", "da53", "dI52"}
    # the others are far above round-off (the smallest, db32, at 3e-7 of the largest)
    assert np.sort(norms)[len(zero)] > 1e-8 * norms.max()
    sv = np.linalg.svd(jac, compute_uv=False)
    assert int((sv > studies.ROUND_OFF * sv[0]).sum()) == 27


@pytest.mark.slow
def test_thesis_way_finite_differences_hide_the_zero_columns():
    """The thesis way, small (40 poses, 5 iterations): finite differences give all 43 columns
    a rank while 14 are zero; the ten angles are then set by the differencing noise, and
    setting them to zero and fitting the others again fits as well: they carry nothing."""
    study, names, _ = _thesis_set_problem(40)
    out = studies.thesis_way_identification(study.result.nominal, study.data, names,
                                            study.registration, max_nfev=5)
    assert out["fd_rank"] == 43 > out["nominal_rank"]
    assert len(out["nominal_zero_columns"]) == 14
    assert 0 < max(abs(a) for a in out["angles_deg"].values())
    assert out["rms_refit"] <= out["rms"] * (1 + 1e-6)
    assert out["rms_reset"] >= out["rms_refit"]
