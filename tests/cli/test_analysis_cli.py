"""``pkmkit analyze``, ``map``, ``workspace`` and ``useful-workspace`` end to end."""


import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.joint_space import useful_workspace
from pkmkit.analysis.workspace import Criteria


def test_analyze(run, as_json):
    data = as_json(run("analyze", "orthoglide", "--pose", "0,0,0", "--json"))
    np.testing.assert_allclose(data["velocity_factors"], [1, 1, 1], atol=1e-14)
    assert data["isotropic"] is True and data["condition"] == pytest.approx(1.0)
    text = run("analyze", "five-bar", "--pose", "1.1,0.05").output
    assert "force transmission factors" in text and "ellipsoid axis 2" in text


@pytest.mark.ci
def test_map_index_and_actuators(run, tmp_path, as_json):
    out = tmp_path / "cond.png"
    data = as_json(run("map", "linear-delta", "--index", "condition", "--slice", "z=0",
                       "--range", "-0.25,0.25,-0.25,0.25", "--out", out, "--json"))
    assert out.stat().st_size > 10_000 and data["plane"] == ["x", "y"]
    acts = as_json(run("map", "linear-delta", "--index", "actuators", "--slice", "z=0",
                       "--range", "-250,250,-250,250", "--units", "mm",
                       "--out", tmp_path / "q.png", "--json"))
    np.testing.assert_allclose(acts["min"], [993.7, 941.7, 941.7], atol=0.1)
    np.testing.assert_allclose(acts["max"], [1264.9, 1279.9, 1279.9], atol=0.1)
    planar = as_json(run("map", "five-bar", "--index", "lambda_min", "--out",
                         tmp_path / "l.png", "--json"))
    assert planar["plane"] == ["x", "y"]


@pytest.mark.ci
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


@pytest.mark.ci
def test_workspace_prescribed_cube(run, as_json):
    center = "-0.0267442,-0.0267442,-0.0267442"
    ok = as_json(run("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "21",
                     "--cube", "0.1996", "--center", center, "--json"))
    assert ok["check"]["feasible"] is True
    bad = run("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "21",
              "--cube", "0.25", "--center", center)
    assert bad.exit_code == 0 and "NOT feasible" in bad.output and "λ" in bad.output


@pytest.mark.ci
def test_useful_workspace(run, tmp_path, as_json):
    data = as_json(run("useful-workspace", "five-bar", "--bounds", "0.3333333,3",
                       "--resolution", "151", "--json", "--out", tmp_path / "u.png"))
    assert data["joint_square"]["side"] == pytest.approx(0.3868, abs=2e-3)
    # exact range: the bound 3 is reached at a corner of the joint square
    assert data["index_range"] == pytest.approx([0.6, 3.0], abs=1e-5)
    # GCI: the cell-weighted mean of λ_min/λ_max (numpy's SVD) over the useful workspace
    useful = useful_workspace(pkmkit.machine("five-bar"), Criteria(bounds=(0.3333333, 3.0)),
                              resolution=151)
    feasible = useful.workspace.feasible.ravel()
    s = np.linalg.svd(pkmkit.machine("five-bar").jacobian(
        useful.workspace.grid.points[feasible]).J, compute_uv=False)
    weights = useful.workspace.grid.weights().ravel()[feasible]
    assert data["global_conditioning_index"] == pytest.approx(
        np.sum(s[:, -1] / s[:, 0] * weights) / weights.sum(), rel=1e-12)
    assert (tmp_path / "u.png").exists()


@pytest.mark.ci
def test_useful_workspace_coarse_grid_and_three_actuators(run, as_json):
    """``--resolution 11`` used to say "criteria fail there" at home, where λ = 1."""
    coarse = as_json(run("useful-workspace", "five-bar", "--bounds", "0.5,2", "--resolution",
                         "11", "--json"))
    assert coarse["joint_square"]["side"] == pytest.approx(0.341640, abs=1e-5)
    assert coarse["index_range"] == pytest.approx([2 / 3, 2.0], abs=1e-5)
    bad = run("useful-workspace", "five-bar", "--bounds", "1.5,3", "--resolution", "11")
    assert bad.exit_code == 1 and "fail at the home configuration" in bad.output
    cube = as_json(run("useful-workspace", "orthoglide", "--bounds", "0.5,2", "--resolution",
                       "15", "--json"))
    assert cube["joint_square"]["side"] > 0.1 and cube["useful_volume"] > 0
    text = run("useful-workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "15")
    assert "actuator cube" in text.output and "inscribed cube" in text.output


@pytest.mark.ci
def test_planar_map_ignores_unreachable_poses(run, tmp_path, as_json):
    """λ_min over the five-bar's box: the unreachable corner (0.4, −0.6) used to be reported
    as the minimum 0, and κ = inf as the maximum."""
    low = as_json(run("map", "five-bar", "--index", "lambda_min", "--out", tmp_path / "l.png",
                      "--json"))
    assert low["min"] > 0.05
    x, y = low["at_min"]
    assert (y - 0.0) ** 2 <= 0.25 + 1e-9 and (x - 1.0) ** 2 <= 0.25 + 1e-9  # reachable
    cond = as_json(run("map", "five-bar", "--index", "condition", "--out", tmp_path / "c.png",
                       "--json"))
    assert np.isfinite(cond["max"]) and cond["min"] == pytest.approx(1.0)


def test_condition_map_levels_are_readable():
    """κ up to 1e17 near a singularity: log levels stopping at the 95th percentile (linear
    levels to 1e17 put every usable pose in one colour)."""
    from pkmkit.plot.maps import color_levels

    values = np.concatenate([np.linspace(1.0, 20.0, 990), np.logspace(3, 17, 10)])
    levels, logarithmic, clipped = color_levels(values)
    assert logarithmic and clipped and levels[0] == 1.0 and levels[-1] < 25
    assert np.all(np.diff(levels) > 0) and np.searchsorted(levels, 5.0) >= 4
    levels, logarithmic, clipped = color_levels(np.linspace(0.5, 2.0, 100))
    assert not logarithmic and not clipped and levels[0] <= 0.5 and levels[-1] >= 2.0


def test_analyze_isotropy_display_matches_its_tolerance(run, as_json):
    """κ = 1 + 3.4e-9 used to print "condition number 1 ... isotropic: False"."""
    args = ("analyze", "five-bar-biglide", "--pose", "0.70710678,-0.35355339")
    text = run(*args).output
    assert "condition number 1 + 3.4e-09" in text and "isotropic: False (κ ≤ 1 + 1e-09)" in text
    loose = as_json(run(*args, "--isotropy-tol", "1e-6", "--json"))
    assert loose["isotropic"] is True and loose["isotropy_tol"] == 1e-6


def test_workspace_gci_and_fully_feasible_box(run, as_json):
    data = as_json(run("workspace", "five-bar", "--box", "0.9,1.1,-0.1,0.1", "--bounds", "0.5,2",
                       "--json"))
    assert data["area"] == pytest.approx(0.04, rel=1e-12)
    box = data["inscribed"]
    assert box["side"] <= 0.2 + 1e-12 and box["lower"][0] >= 0.9 - 1e-12
    assert 0.8 < data["global_conditioning_index"] < 1
    text = run("workspace", "five-bar", "--box", "0.9,1.1,-0.1,0.1", "--bounds", "0.5,2").output
    assert "global conditioning index" in text


@pytest.mark.ci
def test_workspace_slice_box_and_centre(run, as_json):
    base = ("workspace", "orthoglide", "--bounds", "0.5,2", "--resolution", "41")
    full = as_json(run(*base, "--slice", "z=0.05", "--box", "-0.2,0.2,-0.2,0.2,-0.2,0.2",
                       "--json"))
    assert full["grid"]["lower"] == [-0.2, -0.2] and full["grid"]["fixed"] == {"z": 0.05}
    in_plane = as_json(run(*base, "--slice", "z=0.05", "--cube", "0.1", "--center", "0,0",
                           "--json"))
    same = as_json(run(*base, "--slice", "z=0.05", "--cube", "0.1", "--center", "0,0,0.05",
                       "--json"))
    assert in_plane["check"]["center"] == [0.0, 0.0, 0.05]
    assert in_plane["check"]["index_range"] == same["check"]["index_range"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["map", "five-bar", "--index", "lambda_min", "--out", "missing/l.png"],
         "does not exist"),
        (["map", "five-bar", "--index", "lambda_min", "--out", "l.xyz"], "extension .xyz"),
        (["workspace", "five-bar", "--out", "w"], "no extension"),
        (["workspace", "five-bar", "--out", "missing/w.png"], "does not exist"),
        (["useful-workspace", "five-bar", "--bounds", "0.5,2", "--out", "u.txt"],
         "extension .txt"),
        (["useful-workspace", "orthoglide", "--bounds", "0.5,2", "--out", "u.png"],
         "needs 2 actuators"),
        (["map", "five-bar", "--index", "condition", "--range", "-1e308,1e308,-1e308,1e308",
          "--out", "m.png"], "beyond 1e+09 m"),
        (["workspace", "five-bar", "--box", "-1e308,1e308,-1e308,1e308"], "beyond 1e+09 m"),
        (["workspace", "five-bar", "--box", "0,nan,0,1"], "finite"),
        (["workspace", "orthoglide", "--slice", "z=0.05,9"], "one value"),
        (["workspace", "orthoglide", "--slice", "z=0.5", "--box",
          "-0.2,0.2,-0.2,0.2,-0.2,0.2"], "outside the box"),
        (["workspace", "orthoglide", "--slice", "z=0.05", "--cube", "0.1", "--center",
          "0,0,0"], "not in the --slice plane"),
        (["workspace", "orthoglide", "--slice", "z=0.05", "--cube", "0.1", "--center", "0"],
         "in-plane coordinates"),
        (["workspace", "orthoglide", "--cube", "nan", "--center", "0,0,0"], "side > 0"),
        (["workspace", "orthoglide", "--resolution", "271"], "limit of 5e+06"),
        (["analyze", "orthoglide", "--pose", "0,0,0", "--isotropy-tol", "-1"], "isotropy-tol"),
    ],
)
def test_bad_analysis_input(run, args, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code == 1, result.output
    assert message in result.output and "Traceback" not in result.output
    assert len(result.output.strip().splitlines()) == 1


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
        (["useful-workspace", "linear-delta", "--bounds", "0.5,2", "--out", "u.png"],
         "2 actuators"),
    ],
)
def test_bad_input(run, args, message, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = run(*args)
    assert result.exit_code == 1, result.output
    assert message in result.output and "Traceback" not in result.output


def test_analyze_defaults_to_the_home_pose(run, as_json):
    home = as_json(run("analyze", "five-bar", "--json"))
    explicit = as_json(run("analyze", "five-bar", "--pose", "1,0", "--json"))
    assert home == explicit
    result = run("workspace", "five-bar", "--kappa-max", "0.5")
    assert result.exit_code == 1 and "--kappa-max" in result.output


@pytest.mark.parametrize("name", ["lambda_min", "lambda_max", "force_min", "force_max",
                                  "condition", "inverse_condition", "manipulability"])
def test_map_reports_the_named_index(run, tmp_path, as_json, name):
    """`pkmkit map --index NAME`: the extreme values and where they are match NAME's definition
    from the singular values of J at that pose (λ_min must not plot λ_max)."""
    data = as_json(run("map", "linear-delta", "--index", name, "--slice", "z=0.1",
                       "--range", "-0.3,0.3,-0.3,0.3", "--resolution", "21",
                       "--out", tmp_path / "m.png", "--json"))
    m = pkmkit.machine("linear-delta")
    for key in ("min", "max"):
        s = np.linalg.svd(m.jacobian(np.asarray(data[f"at_{key}"])).J, compute_uv=False)
        value = {"lambda_min": s[-1], "lambda_max": s[0], "force_min": 1 / s[0],
                 "force_max": 1 / s[-1], "condition": s[0] / s[-1],
                 "inverse_condition": s[-1] / s[0], "manipulability": np.prod(s)}[name]
        assert data[key] == pytest.approx(value, rel=1e-12)


def test_analyze_shows_crank_angles_in_degrees(run, as_json):
    """The Delta robot's actuators are arm angles: analyze shows them in degrees (as ik does),
    not radians labelled with the length unit."""
    q_deg = as_json(run("ik", "delta", "--pose", "200,100,-900", "--units", "mm",
                        "--json"))["q"]
    data = as_json(run("analyze", "delta", "--pose", "200,100,-900", "--units", "mm", "--json"))
    np.testing.assert_allclose(data["q"], q_deg, rtol=1e-12)
    assert data["actuator_units"] == ["deg", "deg", "deg"]
    text = run("analyze", "delta", "--pose", "0.2,0.1,-0.9").output
    assert "q [35.6098, 62.4071, 33.4116] deg" in text
    assert " mm" in run("analyze", "orthoglide", "--pose", "0,0,0", "--units", "mm").output
