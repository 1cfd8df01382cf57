"""``pkmkit errors``, ``identifiability`` and ``select-poses`` end to end."""

import csv

import numpy as np
import pytest


def test_compatibility_json(run, as_json):
    out = as_json(run("errors", "tripteor-x7", "--compatibility", "--orientation-only",
                      "--thesis", "--json"))
    assert out["forced_zero"] == ["dK21", "dK41", "dI51", "dK51", "dI13", "dK13", "dK23",
                                  "dK43", "dI53", "dK53", "dI63", "dJ63"]
    assert out["conditions"] == [] and out["compatible_dimension"] == 16
    text = run("errors", "crank-slider", "--compatibility", "--thesis", "--exclude", "*F")
    assert text.exit_code == 0
    assert "forced to zero (5): dI2, dJ2, dI3, dJ3, dJ4" in text.output
    assert "dimension 5 of 10" in text.output


def test_defect_listing_and_bad_names(run, as_json):
    out = as_json(run("errors", "gough-stewart", "--json"))
    assert len(out["defects"]) == 48 and out["defects"][0]["name"] == "dA1x"
    bad = run("errors", "tripteor-x7", "--compatibility", "--exclude", "dZ9")
    assert bad.exit_code == 1 and "unknown defect or owner 'dZ9'" in bad.output


@pytest.mark.ci
def test_sensitivity_and_tolerance_write_figures(run, as_json, tmp_path):
    out = as_json(run("errors", "linear-delta", "--sensitivity", "--units", "mm", "--region",
                      "-100,100,-100,100,0,200", "--points", "20", "--out", tmp_path,
                      "--json"))["sensitivity"]
    assert out["rows"][0]["name"].startswith("dL")
    assert 0.01 < out["rows"][0]["max_displacement"] < 0.03  # mm, for 10 µm defects
    assert (tmp_path / "sensitivity.png").stat().st_size > 0
    tol = tmp_path / "tol.toml"
    tol.write_text('units = "mm"\n[classes]\nlength = 0.01\nbase = 0.01\n')
    res = as_json(run("errors", "gough-stewart", "--tolerance", tol, "--monte-carlo", "50",
                      "--resolution", "4", "--units", "mm", "--out", tmp_path,
                      "--json"))["tolerance"]
    assert 0 < res["exact_percentile_max"] < 0.1 and res["failed_pairs"] == 0
    assert (tmp_path / "accuracy-map.png").stat().st_size > 0
    tol.write_text('[classes]\nlength = -0.01\n')
    bad = run("errors", "gough-stewart", "--tolerance", tol, "--monte-carlo", "5")
    assert bad.exit_code == 1 and "tol.toml:2" in bad.output and "≥ 0" in bad.output


def test_identifiability_and_pose_selection(run, as_json, tmp_path):
    out = as_json(run("identifiability", "linear-delta", "--measure", "point", "--poses", "20",
                      "--json"))
    assert out["rank"] == 18 and out["n_parameters"] == 30
    assert set(out["indices"]) == {"O1", "O2", "O3", "O4", "O5"} and out["condition"] > 1
    assert out["unidentifiable"] == []
    poses = tmp_path / "poses.csv"
    sel = as_json(run("select-poses", "linear-delta", "--measure", "height", "--n", "12",
                      "--parameters", "dL*,dq*,du*", "--out", poses, "--units", "mm",
                      "--json"))
    assert sel["gain"] > 1
    with open(poses) as handle:
        assert next(handle) == "# units: mm\n"
        rows = list(csv.reader(handle))
    assert rows[0] == ["q1", "q2", "q3"] and len(rows) == 13
    assert 500 < float(rows[1][0]) < 3000  # mm
    again = as_json(run("identifiability", "linear-delta", "--measure", "height", "--poses",
                        poses, "--units", "mm", "--parameters", "dL*,dq*,du*", "--json"))
    assert np.isclose(again["indices"]["O1"], sel["value"], rtol=1e-6)
    in_m = run("identifiability", "linear-delta", "--measure", "height", "--poses", poses)
    assert in_m.exit_code == 1  # the file says mm: read in metres it is refused
    assert "column 'q1' is in mm but the command reads m (--units m); give --units mm" in (
        in_m.output)
    few = run("identifiability", "linear-delta", "--measure", "height", "--poses", "4")
    assert few.exit_code == 1 and "4 scalar measurements for 30 parameters" in few.output
    wrong = run("identifiability", "tripteor-x7", "--measure", "part", "--poses", "3")
    assert wrong.exit_code == 1 and "rod machines" in wrong.output


@pytest.mark.ci
def test_demo_summary(tmp_path):
    from pkmkit.calibration.identifiability import observability
    from pkmkit.demos.errors import error_summary

    s = error_summary(tmp_path)
    comp = s["tripteor_compatibility"]
    assert comp["orientation_only"]["matches_thesis_legs_1_3"]
    assert comp["orientation_only"]["thesis_leg_2_not_required"] == ["dI42", "dJ42", "dK52",
                                                                    "dK62"]
    assert comp["with_positions"]["added_by_positions"] == ["da13", "dc13"]
    assert s["tripteor_identifiability"]["rank"] == 19
    amap = s["hexapod_accuracy_map"]
    assert (tmp_path / "errors-hexapod-accuracy-map.png").stat().st_size > 0
    assert 1e-5 < amap["p95_min_m"] <= amap["p95_max_m"] < 1e-3
    assert observability(np.eye(3))["condition"] == 1.0


def test_identifiable_combinations_in_the_requested_units(run):
    """The Tripteor's tool-point combination ``daT + ℓ·dIT`` (ℓ the tool length, 0.169889 m;
    daT a length, dIT a direction component) reads 0.16989 with ``--units m`` and 169.89 with
    ``--units mm``: the same physical combination in each unit (it used to read 0.67956 —
    ℓ / L², L = 0.5 m the characteristic length — whatever the unit)."""
    import re

    coefficient = {}
    for unit in ("m", "mm"):
        out = run("identifiability", "tripteor-x7", "--measure", "point", "--poses", "40",
                  "--units", unit)
        assert out.exit_code == 0, out.output
        coefficient[unit] = float(re.search(r"daT \+ ([0-9.e+-]+)·dIT", out.output).group(1))
    assert coefficient["m"] == pytest.approx(0.169889, rel=1e-4)
    assert coefficient["mm"] == pytest.approx(1000 * coefficient["m"], rel=1e-4)
