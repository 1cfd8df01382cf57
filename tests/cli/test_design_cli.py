"""``pkmkit design`` and ``pkmkit optimize`` end to end."""

import json

import pytest


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


def test_design_five_bar(run, as_json):
    data = as_json(run("design", "five-bar", "--square", "0.2", "--bounds", "0.333333,3",
                       "--json"))
    assert data["isotropic_orientations_deg"] == [[0.0, 90.0]]
    iso, big = data["designs"]["isotropic"], data["designs"]["biglide"]
    assert iso["L"] < big["L"] and iso["verified"]["feasible"] and big["verified"]["feasible"]


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
    assert 0.5 <= min(radii) and max(radii) <= 1.0  # mm converted to m


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
