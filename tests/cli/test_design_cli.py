"""``pkmkit design`` and ``pkmkit optimize`` end to end."""

import json

import numpy as np
import pytest


@pytest.mark.ci
def test_design_orthoglide(run, as_json):
    data = as_json(run("design", "orthoglide", "--cube", "200", "--bounds", "0.5,2",
                       "--units", "mm", "--json"))
    for key in ("L", "stroke", "Q1", "Q2", "compactness"):
        assert key in data
    assert data["L"] == pytest.approx(310.6, abs=0.1)
    assert data["stroke"] == pytest.approx(257.0, abs=0.1)
    assert data["compactness"] == pytest.approx(0.778, abs=1e-3)
    assert data["verified"]["feasible"] is True
    text = run("design", "orthoglide", "--cube", "0.2", "--bounds", "0.3333,3").output
    assert "compactness" in text


@pytest.mark.ci
def test_design_five_bar(run, as_json):
    data = as_json(run("design", "five-bar", "--square", "0.2", "--bounds", "0.333333,3",
                       "--json"))
    assert data["isotropic_orientations_deg"] == [[0.0, 90.0]]
    iso, big = data["designs"]["isotropic"], data["designs"]["biglide"]
    assert iso["L"] < big["L"] and iso["verified"]["feasible"] and big["verified"]["feasible"]


@pytest.mark.ci
def test_optimize_single_and_pareto(run, tmp_path, as_json):
    out = tmp_path / "single"
    data = as_json(run("optimize", "linear-delta", "--vary", "R=0.5:1.0", "--vary",
                       "L=0.9:1.6", "--objective", "max:compactness", "--region",
                       "0.5@0,0,0.25", "--bounds", "0.4,2.5", "--generations", "5",
                       "--samples", "5", "--out", out, "--json"))
    assert data["best"]["feasible"] and (out / "results.csv").exists()
    out = tmp_path / "pareto"
    result = run("optimize", "linear-delta", "--vary", "R=500:1000", "--vary", "L=900:1600",
                 "--units", "mm", "--objective", "max:compactness", "--objective", "max:gci",
                 "--pareto", "--region", "500@0,0,250", "--bounds", "0.4,2.5",
                 "--generations", "4", "--population", "12", "--samples", "5",
                 "--out", out, "--no-progress")
    assert result.exit_code == 0 and "Pareto front" in result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["pareto"] and (out / "pareto.png").stat().st_size > 10_000
    radii = [r["R"] for r in summary["pareto"]]
    assert 500 <= min(radii) and max(radii) <= 1000  # in the command's units, mm
    assert summary["units"]["length"] == "mm" and summary["column_units"]["R"] == "mm"
    assert (out / "pareto.csv").read_text().startswith("R [mm],L [mm],")


@pytest.mark.parametrize(
    "args, message",
    [
        (["design", "orthoglide", "--cube", "0.2", "--bounds", "1.5,3"], "isotropic"),
        (["design", "orthoglide", "--cube", "0.2"], "--bounds"),
        (["design", "orthoglide", "--cube", "-1", "--bounds", "0.5,2"], "must be > 0"),
        (["optimize", "linear-delta", "--vary", "R=1:0.5", "--objective", "max:gci",
          "--region", "0.5", "--out", "o"], "empty range"),
        (["optimize", "linear-delta", "--vary", "R", "--objective", "max:gci",
          "--region", "0.5", "--out", "o"], "NAME=LO:HI"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:beauty",
          "--region", "0.5", "--out", "o"], "unknown metric"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--objective", "min:stroke", "--region", "0.5", "--out", "o"], "--pareto"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--region", "big", "--out", "o"], "SIDE"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--region", "0.5@1,2", "--out", "o"], "needs 3 coordinates"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--region", "0.5@nan,0,0", "--out", "o"], "--region centre X nan m is outside"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--constraint", "gci>=1e", "--region", "0.5", "--out", "o"], "not a finite number"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--objective", "max:gci",
          "--constraint", "gci>=1.2.3", "--region", "0.5", "--out", "o"],
         "not a finite number"),
        (["optimize", "linear-delta", "--vary", "R=0.5:1", "--vary", "R=0.6:0.9",
          "--objective", "max:gci", "--region", "0.5", "--out", "o"], "given twice"),
        (["optimize", "linear-delta", "--vary", "q_min[0]=0.1:0.5", "--objective", "max:gci",
          "--region", "0.5@0,0,0.25", "--out", "o", "--no-progress"], "change none of the"),
        (["optimize", "linear-delta", "--vary", "parallelogram_width=0.05:0.2", "--objective",
          "max:gci", "--region", "0.5@0,0,0.25", "--out", "o", "--no-progress"],
         "change none of the"),
        (["design", "orthoglide", "--cube", "1e-300", "--bounds", "0.5,2"], "between 1e-06 m"),
        (["design", "orthoglide", "--cube", "0.2", "--bounds", "0.5,2", "--max-leg", "nan"],
         "--max-leg must be a positive length"),
        (["design", "orthoglide", "--cube", "0.2", "--bounds", "0.5,2", "--max-leg", "-1"],
         "--max-leg must be a positive length"),
        (["design", "linear-delta", "--cube", "0.5", "--bounds", "0.6,2"], "exclude 1/√3"),
        (["design", "linear-delta", "--cube", "0.5", "--bounds", "0.4,2.5", "--objective",
          "compactness"], "needs a largest arm length"),
        (["design", "five-bar", "--square", "0.2", "--bounds", "1.5,3"],
         "isotropic: bounds [1.5, 3] exclude"),
    ],
)
def test_design_bad_input(run, args, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code in (1, 2), result.output
    assert message in result.output and "Traceback" not in result.output


def test_optimize_reports_infeasible_specification(run, tmp_path):
    result = run("optimize", "linear-delta", "--vary", "R=0.5:0.6", "--objective",
                 "max:compactness", "--constraint", "gci>=0.99", "--region", "0.5@0,0,0.25",
                 "--bounds", "0.4,2.5", "--generations", "2", "--samples", "5",
                 "--out", tmp_path / "o", "--no-progress")
    assert result.exit_code == 1 and "no evaluated design satisfies" in result.output
    assert "gci>=0.99" in result.output and "best" in result.output


@pytest.mark.ci
def test_optimize_units_are_consistent(run, tmp_path):
    """--units mm: the constraint value, the variables and the region are read in mm and every
    output is in mm (angles in degrees) and says so. Before, "stroke<=750" was compared with
    metres and the outputs were in m and rad."""
    out = tmp_path / "mm"
    result = run("optimize", "linear-delta", "--vary", "R=500:1000", "--vary",
                 "angles[1]=110:130", "--objective", "max:gci", "--constraint", "stroke<=750",
                 "--region", "500@0,0,250", "--bounds", "0.4,2.5", "--units", "mm",
                 "--generations", "4", "--samples", "5", "--out", out, "--no-progress")
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    best = summary["best"]
    assert best["stroke"] <= 750 and 500 <= best["R"] <= 1000 and 110 <= best["angles[1]"] <= 130
    assert summary["constraints"][0] == "stroke<=750 mm"
    assert summary["units"] == {"length": "mm", "area": "mm^2", "angle": "deg"}
    assert f"stroke = {best['stroke']:.6g} mm" in result.output
    assert f"angles[1] = {best['angles[1]']:.6g} deg" in result.output
    rows = (out / "results.csv").read_text().splitlines()
    assert rows[0] == "R [mm],angles[1] [deg],gci,stroke [mm],violation,feasible"
    strokes = [float(r.split(",")[3]) for r in rows[1:] if r.endswith("True")]
    assert strokes and max(strokes) <= 750 and min(strokes) > 100  # mm, not m
    # the same problem in metres gives the same optimum
    again = run("optimize", "linear-delta", "--vary", "R=0.5:1", "--vary",
                "angles[1]=110:130", "--objective", "max:gci", "--constraint", "stroke<=0.75",
                "--region", "0.5@0,0,0.25", "--bounds", "0.4,2.5", "--generations", "4",
                "--samples", "5", "--out", tmp_path / "m", "--no-progress")
    metres = json.loads((tmp_path / "m" / "summary.json").read_text())["best"]
    assert metres["R"] * 1e3 == pytest.approx(best["R"], rel=1e-9)
    assert metres["gci"] == pytest.approx(best["gci"], rel=1e-12)
    assert again.exit_code == 0


def test_optimize_cmaes_with_one_variable(run, tmp_path, as_json):
    data = as_json(run("optimize", "linear-delta", "--vary", "R=0.5:1", "--method", "cmaes",
                       "--objective", "max:gci", "--region", "0.5@0,0,0.25", "--bounds",
                       "0.4,2.5", "--generations", "3", "--population", "4", "--samples", "5",
                       "--out", tmp_path / "c", "--json"))
    assert data["method"] == "cmaes" and 0.5 <= data["best"]["R"] <= 1.0


def test_optimize_a_rod_legs_file(run, tmp_path):
    path = tmp_path / "tripod.toml"
    path.write_text(TRIPOD)
    out = tmp_path / "t"
    result = run("optimize", path, "--vary", "legs[0].length=850:1000", "--vary",
                 "legs[2].base[0]=-300:-200", "--units", "mm", "--objective", "max:gci",
                 "--region", "100", "--generations", "3", "--samples", "5", "--out", out,
                 "--no-progress")
    assert result.exit_code == 0, result.output
    best = json.loads((out / "summary.json").read_text())["best"]
    assert 850 <= best["legs[0].length"] <= 1000 and -300 <= best["legs[2].base[0]"] <= -200
    assert "legs[0].length = " in result.output and " mm" in result.output


TRIPOD = """[machine]
kind = "rod-legs"
units = "mm"
home = [0, 0, -800]
[[legs]]
base = [500, 0, 0]
axis = [0, 0, 1]
platform = [100, 0, 0]
length = 900
[[legs]]
type = "strut"
base = [-250, 433, 0]
platform = [-50, 86.6, 0]
length = 700
[[legs]]
base = [-250, -433, 0]
axis = [0, 0, 1]
platform = [-50, -86.6, 0]
length = 900
"""


def test_design_orthoglide_tie_at_the_reference_points(run, as_json):
    """[0.9, 2] in mm was rejected with "λ_min = 0.9 < 0.9" (a rounding tie at Q2)."""
    data = as_json(run("design", "orthoglide", "--cube", "200", "--bounds", "0.9,2", "--units",
                       "mm", "--json"))
    assert data["verified"]["feasible"]
    assert data["verified"]["index_range"][0] == pytest.approx(0.9, rel=1e-6)
    assert data["notes"] == []


@pytest.mark.ci
def test_design_orthoglide_degenerate_bounds_say_so(run):
    result = run("design", "orthoglide", "--cube", "0.2", "--bounds", "0.999999,1.000001")
    assert result.exit_code == 0 and "note: degenerate specification" in result.output


@pytest.mark.ci
def test_design_five_bar_both_reports_the_isotropic_design(run, as_json):
    """With [0.9, 1.1] the biglide cannot work (λ = 0.707 at home) but the isotropic design
    can: the default --design both reports it and says why the biglide is infeasible."""
    data = as_json(run("design", "five-bar", "--square", "0.2", "--bounds", "0.9,1.1",
                       "--json"))
    assert data["designs"]["isotropic"]["verified"]["feasible"]
    assert data["designs"]["isotropic"]["feasible"] is True
    biglide = data["designs"]["biglide"]
    assert biglide["feasible"] is False and "[0.7071, 0.7071]" in biglide["reason"]


@pytest.mark.ci
def test_design_linear_delta(run, as_json):
    """An off-axis cube in mm with a given nacelle radius: every length in the output is in mm,
    R = r + d, the stroke is the largest slider range, and the factors are verified; the
    kinematics of the sized machine match the seed's closed form q_i = z + sqrt(L² − ρ_i²)."""
    data = as_json(run("design", "linear-delta", "--cube", "200", "--center", "100,0,0",
                       "--r", "50", "--bounds", "0.4,2.5", "--units", "mm", "--json"))
    for key in ("R", "r", "L", "stroke", "q_min", "q_max", "compactness", "index_range"):
        assert key in data
    assert data["units"] == "mm" and data["center"] == [100.0, 0.0, 0.0]
    assert data["R"] == pytest.approx(data["r"] + data["d"]) and data["r"] == pytest.approx(50)
    assert data["stroke"] == pytest.approx(max(np.subtract(data["q_max"], data["q_min"])))
    assert data["compactness"] == pytest.approx(200 / data["stroke"])
    lo, hi = data["index_range"]
    assert 0.4 * (1 - 1e-6) <= lo and hi <= 2.5 * (1 + 1e-6)
    assert data["verified"]["feasible"]
    # slider range from the seed's closed form over the cube's corners and face centres
    g = np.array([-100.0, 0.0, 100.0])
    pts = np.stack(np.meshgrid(g + 100, g, g, indexing="ij"), -1).reshape(-1, 3)
    theta = np.radians([0, 120, 240])
    rho2 = ((pts[:, :1] - data["d"] * np.cos(theta)) ** 2
            + (pts[:, 1:2] - data["d"] * np.sin(theta)) ** 2)
    q = pts[:, 2:] + np.sqrt(data["L"] ** 2 - rho2)
    assert (q.min(0) >= np.array(data["q_min"]) - 1e-6).all()
    assert (q.max(0) <= np.array(data["q_max"]) + 1e-6).all()
