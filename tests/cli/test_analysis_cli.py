"""``pkmkit analyze``, ``map``, ``workspace`` and ``useful-workspace`` end to end."""


import numpy as np
import pytest


def test_analyze(run, as_json):
    data = as_json(run("analyze", "orthoglide", "--pose", "0,0,0", "--json"))
    np.testing.assert_allclose(data["velocity_factors"], [1, 1, 1], atol=1e-14)
    assert data["isotropic"] is True and data["condition"] == pytest.approx(1.0)
    text = run("analyze", "five-bar", "--pose", "1.1,0.05").output
    assert "force transmission factors" in text and "ellipsoid axis 2" in text


def test_map_index_and_actuators(run, tmp_path, as_json):
    out = tmp_path / "cond.png"
    data = as_json(run("map", "linear-delta", "--index", "condition", "--slice", "z=0",
                       "--range", "-0.25,0.25,-0.25,0.25", "--out", out, "--json"))
    assert out.stat().st_size > 10_000 and data["min"] >= 1.0
    acts = as_json(run("map", "linear-delta", "--index", "actuators", "--slice", "z=0",
                       "--range", "-250,250,-250,250", "--units", "mm",
                       "--out", tmp_path / "q.png", "--json"))
    np.testing.assert_allclose(acts["min"], [993.7, 941.7, 941.7], atol=0.1)
    np.testing.assert_allclose(acts["max"], [1264.9, 1279.9, 1279.9], atol=0.1)
    planar = as_json(run("map", "five-bar", "--index", "lambda_min", "--out",
                         tmp_path / "l.png", "--json"))
    assert planar["plane"] == ["x", "y"]


def test_workspace_json_summary(run, tmp_path, as_json):
    data = as_json(run("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "41",
                       "--json", "--out", tmp_path / "w.png"))
    box = data["inscribed"]
    assert 0.19 < box["side"] <= 0.201 and box["verified"] is True
    lo, hi = data["index_range"]
    assert lo >= 0.5 - 1e-9 and hi <= 2 + 1e-9
    assert data["volume"] > box["side"] ** 3 and (tmp_path / "w.png").exists()
    planar = as_json(run("workspace", "five-bar", "--bounds", "0.3333,3", "--json"))
    assert "area" in planar and planar["inscribed"]["side"] > 0


def test_workspace_prescribed_cube(run, as_json):
    center = "-0.0267442,-0.0267442,-0.0267442"
    ok = as_json(run("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "21",
                     "--cube", "0.1996", "--center", center, "--json"))
    assert ok["check"]["feasible"] is True
    bad = run("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "21",
              "--cube", "0.25", "--center", center)
    assert bad.exit_code == 0 and "NOT feasible" in bad.output and "λ" in bad.output


def test_useful_workspace(run, tmp_path, as_json):
    data = as_json(run("useful-workspace", "five-bar", "--bounds", "0.3333333,3",
                       "--resolution", "151", "--json", "--out", tmp_path / "u.png"))
    assert data["joint_square"]["side"] == pytest.approx(0.3868, abs=2e-3)
    assert 0.33 < data["index_range"][0] < data["index_range"][1] < 3.0
    assert (tmp_path / "u.png").exists()


@pytest.mark.parametrize(
    "args, message",
    [
        (["workspace", "orthoglide", "--bounds", "2,0.5"], "must be below"),
        (["workspace", "orthoglide", "--bounds", "0.5"], "LO,HI"),
        (["workspace", "orthoglide", "--box", "5,6,5,6,5,6"], "no pose of the box is reachable"),
        (["workspace", "orthoglide", "--bounds", "1.5,3", "--resolution", "11"],
         "satisfies every criterion"),
        (["workspace", "orthoglide", "--box", "0,1"], "needs 6 values"),
        (["workspace", "orthoglide", "--cube", "0.1"], "go together"),
        (["map", "linear-delta", "--index", "condition", "--out", "x.png"], "--slice"),
        (["map", "linear-delta", "--index", "condition", "--slice", "w=0", "--out", "x.png"],
         "NAME=VALUE"),
        (["map", "linear-delta", "--index", "condition", "--slice", "z=0", "--range",
          "5,6,5,6", "--out", "x.png"], "no point of this plane is reachable"),
        (["map", "five-bar", "--index", "condition", "--slice", "z=0", "--out", "x.png"],
         "planar machine"),
        (["useful-workspace", "orthoglide", "--bounds", "0.5,2"], "2 actuators"),
    ],
)
def test_bad_input(run, args, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code == 1, result.output
    assert message in result.output and "Traceback" not in result.output
