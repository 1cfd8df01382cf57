"""End-to-end tests of the ``pkmkit`` command line."""

import json

import numpy as np
import pytest

import pkmkit
from tests.cli.conftest import table_lines


@pytest.mark.parametrize("command", [[], ["machines"], ["show"], ["ik"], ["fk"], ["jacobian"],
                                     ["demo"]])
def test_help_everywhere(run, command):
    result = run(*command, "--help")
    assert result.exit_code == 0 and "Usage:" in result.output


def test_machines(run, as_json):
    data = as_json(run("machines", "--json"))
    ids = {m["id"] for m in data["machines"]}
    assert {"orthoglide", "linear-delta", "five-bar"} <= ids
    text = run("machines").output
    assert "five-bar-biglide" in text
    # the columns line up, whatever the longest kind (gough-stewart once touched its dimension)
    lines = text.splitlines()
    assert len(lines) == len(ids)
    assert len({line.index("-D  ") for line in lines}) == 1
    assert all(line[line.index("-D  ") - 3] == " " for line in lines)


def test_show(run, as_json):
    data = as_json(run("show", "linear-delta", "--json", "--units", "mm"))
    params = {p["name"]: p for p in data["parameters"]}
    assert params["L"]["value"] == pytest.approx(1300) and params["L"]["unit"] == "mm"
    assert params["angles"]["value"] == pytest.approx([0, 120, 240])
    assert data["mobility"]["grubler"]["mobility"] == 3
    assert data["assembly_modes"]["working"] == "nacelle-below"
    text = run("show", "five-bar").output
    assert "Grübler" in text and "redundant constraints: 1" in text


def test_ik_reference_entry(run, as_json):
    data = as_json(run("ik", "linear-delta", "--pose", "0.25,0.25,0", "--json"))
    np.testing.assert_allclose(data["q"], [1.240, 1.1675, 0.94173], atol=5e-5)
    assert data["status"] == "ok"
    mm = as_json(run("ik", "linear-delta", "--pose", "250,250,0", "--units", "mm", "--json"))
    np.testing.assert_allclose(mm["q"], [1240.0, 1167.5, 941.73], atol=0.05)
    numeric = as_json(run("ik", "linear-delta", "--pose", "0.25,0.25,0", "--method", "numeric",
                          "--json"))
    np.testing.assert_allclose(numeric["q"], data["q"], atol=1e-12)


def test_set_overrides(run, as_json):
    data = as_json(run("ik", "linear-delta", "--set", "L=1.04", "--pose", "0,0,0", "--json"))
    np.testing.assert_allclose(data["q"], [0.882666] * 3, atol=1e-6)
    rotated = as_json(run("ik", "linear-delta", "--set", "angles=90,210,330", "--pose",
                          "0,0.55,0", "--json"))
    assert rotated["q"][0] == pytest.approx(1.3)  # leg 1 now on the y axis, rod vertical
    five = as_json(run("ik", "five-bar", "--set", "A=0,0", "--set", "B=1.2,-1.2", "--pose",
                       "1.2,0", "--json"))
    np.testing.assert_allclose(five["q"], [0.7, 0.7], atol=1e-12)


def test_fk_all_modes(run, as_json):
    data = as_json(run("fk", "orthoglide", "--q", "0.31,0.31,0.31", "--all", "--json"))
    np.testing.assert_allclose(data["pose"], [0, 0, 0], atol=1e-12)
    assert data["mode"] == "origin-side" and data["modes"] == ["origin-side", "far-side"]
    np.testing.assert_allclose(data["poses"][1], [0.31 * 2 / 3] * 3, atol=1e-12)
    other = as_json(run("fk", "orthoglide", "--q", "0.31,0.31,0.31", "--mode", "far-side",
                        "--json"))
    np.testing.assert_allclose(other["pose"], data["poses"][1], atol=1e-12)
    text = run("fk", "orthoglide", "--q", "310,310,310", "--units", "mm", "--all").output
    assert "far-side" in text and "206.666" in text


def test_jacobian(run, as_json):
    data = as_json(run("jacobian", "orthoglide", "--pose", "0,0,0", "--json"))
    for key in ("A", "B", "J", "singular_values", "condition", "status"):
        assert key in data
    np.testing.assert_allclose(data["J"], np.eye(3), atol=1e-15)
    assert data["status"] == "regular" and data["condition"] == pytest.approx(1.0)
    text = run("jacobian", "five-bar", "--pose", "1,0").output
    assert "transmission factors" in text
    # rho2 = 1.2 m there, beyond the five-bar's ±1 m strokes: the Jacobian is printed, its
    # status kept (serial), the stroke excess named and the exit status is 3
    result = run("jacobian", "five-bar", "--pose", "0.6,0.5", "--json")
    assert result.exit_code == 3, result.output
    singular = json.loads(result.stdout)
    assert singular["status"] == "serial" and singular["condition"] is None
    assert [d["joint"] for d in singular["out_of_stroke"]] == ["rho2"]
    assert singular["out_of_stroke"][0]["excess"] == pytest.approx(0.2)


def test_batch_csv_with_bad_rows(run, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y,z\n0.25,0.25,0\n5,0,0\nnan,0,0\n-0.25,-0.25,0.5\n")
    out = tmp_path / "q.csv"
    result = run("ik", "linear-delta", "--input", poses, "--output", out)
    assert result.exit_code == 3 and "2 flagged" in result.output
    lines = table_lines(out.read_text())
    assert lines[0] == "x,y,z,q1,q2,q3,mode,status"
    assert lines[1].endswith(",ok") and lines[2].endswith(",unreachable")
    assert lines[3].endswith(",invalid-input") and lines[4].endswith(",ok")

    good = tmp_path / "good.csv"
    good.write_text("\n".join([lines[0].replace(",mode", ""), *(
        ",".join(line.split(",")[:6] + line.split(",")[7:]) for line in (lines[1], lines[4]))])
                    + "\n")
    result = run("fk", "linear-delta", "--input", good, "--output", tmp_path / "x.csv")
    assert result.exit_code == 0
    back = table_lines((tmp_path / "x.csv").read_text())
    assert back[0] == "q1,q2,q3,x,y,z,mode,status"
    values = [float(v) for v in back[1].split(",")[3:6]]
    np.testing.assert_allclose(values, [0.25, 0.25, 0.0], atol=1e-12)

    result = run("fk", "linear-delta", "--all", "--input", good, "--output", tmp_path / "a.csv")
    assert result.exit_code == 0
    assert len(table_lines((tmp_path / "a.csv").read_text())) == 1 + 4  # two modes per row

    result = run("jacobian", "linear-delta", "--input", poses, "--output", tmp_path / "j.csv")
    assert result.exit_code == 3
    header = table_lines((tmp_path / "j.csv").read_text())[0].split(",")
    assert header[:6] == ["x", "y", "z", "q1", "q2", "q3"] and "J33" in header


@pytest.mark.parametrize(
    "args, message",
    [
        (["ik", "delta-x", "--pose", "0,0,0"], "unknown machine 'delta-x'; valid ids:"),
        (["ik", "linear-delta", "--set", "LL=1", "--pose", "0,0,0"], "valid parameters: L, R"),
        (["ik", "linear-delta", "--pose", "3,0,0"], "too short by"),
        (["ik", "linear-delta", "--pose", "0,0"], "needs 3 comma-separated"),
        (["ik", "linear-delta", "--pose", "0,a,0"], "cannot read"),
        (["ik", "linear-delta", "--pose", "0,nan,0"], "not finite"),
        (["fk", "five-bar", "--q", "5,-5"], "no real assembly"),
        (["fk", "five-bar", "--q", "0.5,0.5", "--mode", "upside"], "unknown assembly mode"),
        (["ik", "linear-delta", "--set", "L=abc", "--pose", "0,0,0"], "comma-separated"),
        (["ik", "linear-delta", "--set", "L", "--pose", "0,0,0"], "NAME=VALUE"),
    ],
)
def test_errors_exit_non_zero_with_a_message(run, args, message):
    result = run(*args)
    assert result.exit_code == 1
    assert message in result.output
    assert "Traceback" not in result.output


def test_usage_errors(run):
    assert run("ik", "linear-delta").exit_code == 2
    assert run("ik", "linear-delta", "--input", "x.csv").exit_code == 2
    assert run("fk", "linear-delta", "--q", "1,1,1", "--method", "guess").exit_code == 2


def test_malformed_machine_file(run, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[machine]\nkind = "linear-delta"\n[parameters]\nR = 0.7\nL = "long"\n')
    result = run("show", path)
    assert result.exit_code == 1 and "bad.toml:5:" in result.output and "numeric" in result.output


def test_user_machine_file_through_the_cli(run, tmp_path, as_json):
    path = tmp_path / "mine.toml"
    path.write_text('[machine]\nkind = "linear-delta"\nunits = "mm"\n[parameters]\n'
                    "R = 700\nr = 150\nL = 1040\n")
    data = as_json(run("ik", path, "--pose", "0,0,0", "--json"))
    np.testing.assert_allclose(data["q"], [0.882666] * 3, atol=1e-6)


def check_demo(run, out, *extra):
    """Run ``pkmkit demo`` into ``out``; check what both modes must get right; return the
    summary."""
    result = run("demo", "--out", out, *extra)
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["quick"] == ("--quick" in extra)
    machines = summary["machines"]
    assert {"orthoglide", "linear-delta-ch3", "five-bar-isotropic"} <= set(machines)
    delta = machines["linear-delta-ch3"]
    corner = next(p for p in delta["poses"] if p["name"] == "corner(+,+,0)")
    np.testing.assert_allclose(corner["q"], [1.240, 1.1675, 0.94173], atol=5e-5)
    assert corner["fk"]["mode"] == "nacelle-below" and corner["singularity"] == "regular"
    ortho = machines["orthoglide"]["poses"][0]
    np.testing.assert_allclose(ortho["transmission_factors"], [1, 1, 1], atol=1e-12)
    for ident in machines:
        assert (out / f"{ident}.png").stat().st_size > 10_000
        assert (out / f"{ident}.json").exists()
    assert "nacelle-below" in result.output
    analysis = summary["analysis"]
    ortho_cube = analysis["seed001_orthoglide"]
    assert ortho_cube["feasible"] and abs(ortho_cube["cube_side"] - 0.2) < 1e-3
    assert 6.0 < analysis["seed004_five_bar"]["inscribed_area_ratio"] < 7.5
    np.testing.assert_allclose(analysis["seed000_actuator_maps"]["q_max"],
                               [1.2649, 1.2799, 1.2799], atol=1e-4)
    design = summary["design"]
    proto = design["orthoglide"]["prototype"]
    assert abs(proto["L"] - 0.3106) < 1e-3 and abs(proto["stroke"] - 0.257) < 1e-3
    assert design["five_bar"]["orientations_deg"] == [[0.0, 90.0]]
    assert design["linear_delta"]["pareto_size"] > 5
    assert (out / "design" / "linear-delta-pareto.png").stat().st_size > 10_000
    motion = summary["motion"]
    circle = motion["circle"]
    np.testing.assert_allclose(circle["stroke"], 0.19084, atol=2e-5)
    np.testing.assert_allclose(circle["qd_max"], 0.07634, atol=2e-5)
    # the forces are dominated by weight: inertia at constant feed is about 1 % of them
    assert circle["inertial_cruise_force_max"] < 0.02 * max(circle["force_max"])
    assert abs(motion["helix"]["stroke"][0] - 0.381) < 1e-3
    lo, hi = motion["line"]["carriages_only_7.2kg"]["force_range"]
    assert 70.5 < lo <= hi < 72.0
    lo, hi = motion["line"]["carriages_7.2kg_nacelle_1kg"]["force_range"]
    assert lo > 72.0
    strokes = motion["line"]["stroke_violations_default_machine"]
    assert [(v["limit"], v["actuator"]) for v in strokes] == [("stroke", "q1"), ("stroke", "q2"),
                                                               ("stroke", "q3")]
    assert motion["facing"]["zigzag"]["duration"] < motion["facing"]["one-way"]["duration"]
    assert motion["arms"]["mass_error_g_max"] < 0.01 and motion["arms"]["sized_arm"]["feasible"]
    for name in circle["figures"]:
        assert (out / "motion" / name).stat().st_size > 10_000
    for ident, res in analysis["machines"].items():
        assert res["inscribed_side"] > 0, ident
        for name in res["figures"]:
            assert (out / "analysis" / name).stat().st_size > 10_000
    return summary


@pytest.mark.ci
def test_demo_quick_writes_json_and_pngs(run, tmp_path):
    """The demo's quick mode (coarser grids, shorter Pareto search): every study runs and
    writes its files, with the numbers that do not depend on the grids."""
    check_demo(run, tmp_path / "demo", "--quick")


@pytest.mark.slow
def test_full_demo_numbers(run, tmp_path):
    """The full demo (what `.ci/run` also runs after the tests), with its grid-refined numbers:
    the seed 004 area ratio on 301-point grids, the sized five-bar legs, the Pareto front."""
    summary = check_demo(run, tmp_path / "demo")
    five = summary["analysis"]["seed004_five_bar"]
    assert five["inscribed_area_ratio"] == pytest.approx(6.584, abs=0.01)
    assert summary["design"]["five_bar"]["isotropic"]["L"] == pytest.approx(0.28749, abs=1e-5)
    assert summary["design"]["linear_delta"]["evaluations"] == 25 * 32


def test_batch_keeps_good_rows_when_a_cell_is_bad(run, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_bytes(b"\xef\xbb\xbfx,y,z\n0,0,0\n0,,0\n")
    out = tmp_path / "q.csv"
    result = run("ik", "linear-delta", "--input", poses, "--output", out)
    assert result.exit_code == 3 and "poses.csv:3" in result.output
    lines = table_lines(out.read_text())
    assert lines[1].endswith(",ok") and lines[2].endswith(",invalid-input")


def test_jacobian_batch_statuses(run, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y\n1,0\nnan,0\n5,5\n0.6,0.5\n")
    out = tmp_path / "j.csv"
    result = run("jacobian", "five-bar", "--input", poses, "--output", out)
    assert result.exit_code == 3 and "1 singular rows" in result.output
    status = [line.rsplit(",", 1)[1] for line in table_lines(out.read_text())[1:]]
    # (0.6, 0.5) is a serial singularity, but rho2 = 1.2 m there is beyond the ±1 m stroke
    assert status == ["regular", "invalid-input", "unreachable", "out-of-stroke"]
    assert "row 3: out of stroke: rho2 (leg 2) = 1.2 m, 0.2 m beyond its stroke [-1, 1] m" in (
        result.output)


def test_output_and_demo_paths_errors(run, tmp_path):
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y,z\n0,0,0\n")
    result = run("ik", "linear-delta", "--input", poses, "--output", tmp_path / "no" / "o.csv")
    assert result.exit_code == 1 and "cannot write" in result.output
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = run("demo", "--out", blocker / "sub")
    assert result.exit_code != 0 and "Traceback" not in result.output


def test_modes_and_warm_starts_from_the_cli(run, as_json):
    other = as_json(run("fk", "linear-delta", "--q", "1.2,1.2,1.2", "--mode", "other", "--json"))
    by_sign = as_json(run("fk", "linear-delta", "--q", "1.2,1.2,1.2", "--mode", "1", "--json"))
    np.testing.assert_allclose(by_sign["pose"], other["pose"], atol=1e-12)
    numeric = as_json(run("fk", "linear-delta", "--q", "1.2,1.2,1.2", "--mode", "other",
                          "--method", "numeric", "--json"))
    np.testing.assert_allclose(numeric["pose"], other["pose"], atol=1e-9)
    warm = as_json(run("fk", "linear-delta", "--q", "1.2,1.2,1.2", "--method", "numeric",
                       "--x0", "0,0,0.1", "--json"))
    assert warm["mode"] == "nacelle-below"
    # leg 2 on its other branch puts its carriage below the 0.7 m stroke: printed, exit 3
    results = [run("ik", "linear-delta", "--pose", "0.1,0,0", "--branches", "1,-1,1", *method,
                   "--json") for method in (("--method", "numeric"), ())]
    assert [r.exit_code for r in results] == [3, 3]
    branch, closed = (json.loads(r.stdout) for r in results)
    assert branch["status"] == closed["status"] == "out-of-stroke"
    assert [d["joint"] for d in closed["out_of_stroke"]] == ["q2"]
    np.testing.assert_allclose(branch["q"], closed["q"], atol=1e-9)
    note = run("ik", "orthoglide", "--pose", "0.15,0.15,0.15").output
    assert "far-side" in note and "--mode far-side" in note


def test_batch_header_with_spaces_bom_and_mixed_order(run, tmp_path):
    """A spreadsheet's CSV (byte-order mark, spaces after the commas, columns z, x, y) gives the
    same actuator values as the poses typed in the x, y, z order."""
    poses = np.array([[0.25, 0.25, 0.0], [-0.1, 0.2, 0.3]])
    path = tmp_path / "poses.csv"
    rows = "".join(f"{z!r}, {x!r}, {y!r}\n" for x, y, z in poses.tolist())
    path.write_bytes(("\ufeff z , x, y\n" + rows).encode("utf-8"))
    out = tmp_path / "q.csv"
    result = run("ik", "linear-delta", "--input", path, "--output", out)
    assert result.exit_code == 0, result.output
    lines = table_lines(out.read_text())
    assert lines[0].split(",")[:3] == ["x", "y", "z"]
    q = np.array([[float(v) for v in line.split(",")[3:6]] for line in lines[1:]])
    np.testing.assert_allclose(q, pkmkit.machine("linear-delta").ik(poses), rtol=0, atol=1e-15)
