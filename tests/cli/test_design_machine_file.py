"""``pkmkit design ... --out FILE.toml`` and ``pkmkit optimize --out DIR`` (``machine.toml``):
the sized machine as a machine file that :func:`pkmkit.load` reads back as the same machine.

The reference is the sizing function's own machine (``size_orthoglide(...).machine`` ...),
compared with the loaded file parameter by parameter, stroke by stroke and by the inverse
kinematics at home and at every corner of the sized region."""

import itertools
import os

import numpy as np
import pytest

import pkmkit
from pkmkit.design import size_five_bar, size_linear_delta, size_orthoglide
from pkmkit.design.design_space import with_values
from pkmkit.exceptions import ExportCheckError, UnsupportedExportError
from pkmkit.io.sized_machine import check_reproduces, load_text, sized_machine_text

MM = 1e-3


def corners(center, side):
    c = np.asarray(center, dtype=float)
    return np.array([c + side * np.array(s) for s in
                     itertools.product((-0.5, 0.5), repeat=c.size)])


def assert_same_machine(ref, loaded, center, side):
    assert loaded.kind is ref.kind
    for spec in ref.kind.parameters:
        np.testing.assert_allclose(np.asarray(loaded.params[spec.name], dtype=float),
                                   np.asarray(ref.params[spec.name], dtype=float),
                                   rtol=1e-12, atol=0, err_msg=spec.name)
    np.testing.assert_allclose(loaded.model.q_min, ref.model.q_min, rtol=1e-12, atol=0)
    np.testing.assert_allclose(loaded.model.q_max, ref.model.q_max, rtol=1e-12, atol=0)
    poses = np.vstack([ref.home_pose, corners(center, side)])
    assert len(poses) == 1 + 2 ** ref.dims
    q_ref = ref.ik(poses, strokes="ignore")
    assert np.isfinite(q_ref).all()
    np.testing.assert_allclose(loaded.ik(poses, strokes="ignore"), q_ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(loaded.home_pose, ref.home_pose, rtol=0, atol=1e-12)


@pytest.mark.ci
def test_design_orthoglide_writes_machine_file(run, tmp_path, as_json):
    path = tmp_path / "ortho.toml"
    data = as_json(run("design", "orthoglide", "--cube", "200", "--bounds", "0.5,2", "--units",
                       "mm", "--out", path, "--json"))
    assert data["machine_file"] == str(path)
    text = path.read_text()
    assert 'units = "mm"' in text and 'kind = "orthoglide"' in text
    loaded = pkmkit.load(path)
    assert loaded.params["L"] == pytest.approx(310.583 * MM, abs=1e-6)  # seed 001: 310 mm
    ref = size_orthoglide(0.2, (0.5, 2.0))
    assert_same_machine(ref.machine, loaded, 0.5 * (ref.Q1 + ref.Q2), 0.2)
    np.testing.assert_allclose(loaded.model.q_max - loaded.model.q_min, ref.stroke, atol=1e-12)


@pytest.mark.ci
def test_design_linear_delta_writes_machine_file(run, tmp_path):
    path = tmp_path / "delta.toml"
    result = run("design", "linear-delta", "--cube", "200", "--bounds", "0.5,2", "--units", "mm",
                 "--out", path)
    assert result.exit_code == 0, result.output
    assert f"machine file: {path}" in result.output
    assert "angles = [0.0, 120.0, 240.0]" in path.read_text()
    ref = size_linear_delta(0.2, (0.5, 2.0))
    assert_same_machine(ref.machine, pkmkit.load(path), ref.center, 0.2)


@pytest.mark.ci
def test_design_five_bar_writes_machine_file(run, tmp_path):
    path = tmp_path / "five.toml"
    result = run("design", "five-bar", "--square", "0.2", "--bounds", "0.5,2", "--design",
                 "isotropic", "--out", path)
    assert result.exit_code == 0, result.output
    ref = size_five_bar(0.2, (0.5, 2.0), design="isotropic")
    assert_same_machine(ref.machine, pkmkit.load(path), ref.square_center, 0.2)


def test_optimize_writes_best_machine_file(run, tmp_path, as_json):
    out = tmp_path / "opt"
    data = as_json(run("optimize", "linear-delta", "--vary", "R=500:1000", "--vary",
                       "L=900:1600", "--units", "mm", "--objective", "max:compactness",
                       "--region", "500@0,0,250", "--bounds", "0.4,2.5", "--generations", "3",
                       "--population", "6", "--samples", "4", "--out", out, "--json"))
    path = out / "machine.toml"
    assert data["machine_file"] == str(path) and data["best"]["feasible"]
    best = {"R": data["best"]["R"] * MM, "L": data["best"]["L"] * MM}  # summary in mm
    ref = with_values(pkmkit.machine("linear-delta"), best)
    loaded = pkmkit.load(path)
    # the summary's best values are the optimiser's, printed with repr: same to 1e-12
    assert_same_machine(ref, loaded, (0.0, 0.0, 0.25), 0.5)


def test_optimize_pareto_writes_no_machine_file(run, tmp_path, as_json):
    """A Pareto run has no single best design: no machine.toml, and one left in the folder by
    an earlier run is removed (it would pass for this run's result)."""
    out = tmp_path / "pareto"
    out.mkdir()
    (out / "machine.toml").write_text("# an earlier run's best design\n")
    data = as_json(run("optimize", "linear-delta", "--vary", "R=0.5:1", "--vary", "L=0.9:1.6",
                       "--objective", "max:compactness", "--objective", "max:gci", "--pareto",
                       "--region", "0.5@0,0,0.25", "--bounds", "0.4,2.5", "--generations", "2",
                       "--population", "8", "--samples", "3", "--out", out, "--json"))
    assert data["machine_file"] is None and not (out / "machine.toml").exists()


@pytest.mark.parametrize("args", [
    ["orthoglide", "--cube", "200", "--bounds", "0.5,2", "--units", "mm"],
    ["five-bar", "--square", "0.2", "--bounds", "0.5,2", "--design", "biglide"],
])
def test_unwritable_destination_is_refused(run, tmp_path, args):
    missing = tmp_path / "no-such-dir" / "m.toml"
    result = run("design", *args, "--out", missing)
    assert result.exit_code == 1
    assert "does not exist" in result.output and not missing.parent.exists()
    result = run("design", *args, "--out", tmp_path / "m.yaml")
    assert result.exit_code == 1 and ".toml" in result.output
    assert not (tmp_path / "m.yaml").exists()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_directory_is_refused(run, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        result = run("design", "orthoglide", "--cube", "200", "--bounds", "0.5,2", "--units",
                     "mm", "--out", locked / "m.toml")
    finally:
        locked.chmod(0o700)
    assert result.exit_code == 1 and "not writable" in result.output
    assert list(locked.iterdir()) == []


def test_five_bar_both_designs_refuse_one_file(run, tmp_path):
    result = run("design", "five-bar", "--square", "0.2", "--bounds", "0.5,2", "--out",
                 tmp_path / "m.toml")
    assert result.exit_code == 1 and "--design isotropic or biglide" in result.output
    assert not (tmp_path / "m.toml").exists()


def test_check_catches_a_file_that_differs():
    """The round-trip check fails on a file whose leg length differs by 1e-9 mm."""
    ref = size_orthoglide(0.2, (0.5, 2.0))
    text = sized_machine_text(ref.machine, "mm")
    check_reproduces(ref.machine, load_text(text, "m.toml"), ref.Q1[None])
    line = next(s for s in text.splitlines() if s.startswith("L = "))
    bad = text.replace(line, f"L = {float(line[4:]) + 1e-9!r}")
    with pytest.raises(ExportCheckError, match="parameter L"):
        check_reproduces(ref.machine, load_text(bad, "m.toml"), ref.Q1[None])


def test_rod_legs_machine_is_refused(tmp_path):
    path = tmp_path / "planar.toml"
    path.write_text('[machine]\nkind = "rod-legs"\ndims = 2\nhome = [1.0, 0.0]\n'
                    "[[legs]]\nbase = [0, 0]\naxis = [1, 0]\nplatform = [0, 0]\nlength = 0.5\n"
                    "branch = -1\n[[legs]]\nbase = [1, -1]\naxis = [0, 1]\nplatform = [0, 0]\n"
                    "length = 0.5\n")
    with pytest.raises(UnsupportedExportError, match="built-in kind"):
        sized_machine_text(pkmkit.load(path))
