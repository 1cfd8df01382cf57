"""The 3-D view (export/view.py, `pkmkit view`): one self-contained page, a slider per
actuator whose positions are the direct model's, the options' content checked against pkmkit,
and the page itself loaded in headless Chromium when the machine has one."""

from __future__ import annotations

import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from click.testing import CliRunner

import pkmkit
from pkmkit.cli.main import cli
from pkmkit.exceptions import InputError
from pkmkit.export.view import view_figure, view_html

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _tool(frame_or_fig):
    tool = next(t for t in frame_or_fig.data if t.name == "tool point")
    return np.array([tool.x[0], tool.y[0], tool.z[0]])


@pytest.mark.parametrize("ident", ["orthoglide", "gough-stewart", "tripteor-x7"])
def test_each_slider_position_is_the_direct_model_at_that_actuator_value(ident):
    m = pkmkit.machine(ident)
    fig, content = view_figure(m, steps=5)
    assert len(fig.layout.sliders) == m.n_actuators
    assert set(content.steps) == set(m.actuator_names)
    frames = {f.name: f for f in fig.frames}
    k = m.n_actuators - 1
    name = m.actuator_names[k]
    for j in (0, 4):
        frame = frames.get(f"{name}:{j}")
        if frame is None:
            continue
        assert len(frame.data) == len(frame.traces)       # the machine's traces only
        from pkmkit.export.view import _slider_values

        q = m.home_q.copy()
        q[k] = _slider_values(m, k, 5)[j]
        pose = np.atleast_1d(m.fk(q, strokes="ignore"))
        np.testing.assert_allclose(_tool(frame), pose[:3] * 1000, atol=1e-9)
    np.testing.assert_allclose(_tool(fig), np.asarray(m.fk(m.home_q))[:3] * 1000, atol=1e-9)


def test_the_page_is_self_contained():
    html, _ = view_html(pkmkit.machine("delta"), steps=3)
    assert not re.search(r"<script[^>]+src=", html)          # no library fetched
    assert "Plotly" in html and "pkmkitReport" in html


def test_a_path_out_of_stroke_is_marked_and_counted(tmp_path):
    m = pkmkit.machine("orthoglide")
    program = "G21 G90\nG1 X0 Y0 Z0 F600\nG1 X40 Y0 Z0\nG1 X400 Y0 Z0\n"
    fig, content = view_figure(m, gcode=program, steps=2)
    names = [t.name for t in fig.data]
    assert "tool path" in names and "out of reach or stroke" in names
    assert 0 < content.path_refused < content.path_points
    bad = next(t for t in fig.data if t.name == "out of reach or stroke")
    x = np.asarray(bad.x) / 1000
    assert x.min() > 0.04                       # the first 40 mm are within the strokes
    poses = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    q = m.ik(poses, strokes="ignore")
    lo, hi = m.model.q_min, m.model.q_max
    out = ~np.isfinite(q).all(axis=1) | ((q < lo) | (q > hi)).any(axis=1)
    assert out.all()


def test_calibration_vectors_are_the_error_the_calibration_corrects():
    m = pkmkit.machine("linear-delta")
    calibrated = m.with_defects({"dL1": 0.001})
    fig, content = view_figure(m, calibrated=calibrated, steps=2, resolution=10)
    assert content.error_vectors > 0
    # a rod 1 mm longer moves the tool by at most 1 mm / the smallest transmission
    assert 1e-4 < content.error_max < 5e-3
    trace = next(t for t in fig.data if t.name.startswith("calibration"))
    assert f"max {content.error_max * 1e6:.1f} µm" in trace.name


def test_bad_steps_are_refused():
    with pytest.raises(InputError, match="slider positions"):
        view_figure(pkmkit.machine("delta"), steps=1)


def test_command_line_writes_the_page_and_flags_a_path(tmp_path):
    out = tmp_path / "v.html"
    gcode = tmp_path / "p.nc"
    gcode.write_text("G21 G90\nG1 X0 Y0 Z0 F600\nG1 X400 Y0 Z0\n")
    runner = CliRunner()
    done = runner.invoke(cli, ["view", "orthoglide", "--steps", "3", "--out", str(out),
                               "--json"])
    assert done.exit_code == 0, done.output
    payload = json.loads(done.output)
    assert payload["sliders"] == {"rho1": 3, "rho2": 3, "rho3": 3} and out.stat().st_size > 1e6
    done = runner.invoke(cli, ["view", "orthoglide", "--steps", "2", "--path", str(gcode),
                               "--out", str(out)])
    assert done.exit_code == 3 and "out of reach or stroke" in done.output
    done = runner.invoke(cli, ["view", "orthoglide", "--out", str(tmp_path / "v.png")])
    assert done.exit_code != 0 and "HTML" in done.output
    done = runner.invoke(cli, ["view", "orthoglide", "--calibration", str(tmp_path),
                               "--out", str(out)])
    assert done.exit_code == 1 and "calibration.json" in done.output


@pytest.mark.skipif(CHROMIUM is None, reason="headless Chromium is not installed")
@pytest.mark.ci
def test_the_page_loads_draws_and_its_slider_moves_the_platform(tmp_path):
    m = pkmkit.machine("orthoglide")
    html, _ = view_html(m, steps=5)
    page = tmp_path / "view.html"
    page.write_text(html, encoding="utf-8")

    def load(fragment: str = "") -> tuple[str, str]:
        done = subprocess.run(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr",
             "--virtual-time-budget=8000", "--dump-dom", f"file://{page}{fragment}"],
            capture_output=True, text=True, timeout=120)
        return done.stdout, done.stderr

    dom, log = load("#rho1:4")                # the page opened at rho1's last position
    assert "Uncaught" not in log and "ReferenceError" not in log
    moved = np.array(json.loads(re.search(r'data-tool="([^"]*)"', dom).group(1)))
    q = m.home_q.copy()
    q[0] = m.model.q_max[0]
    np.testing.assert_allclose(moved, np.asarray(m.fk(q))[:3] * 1000, atol=1e-6)
    shot = tmp_path / "view.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
                    "--virtual-time-budget=8000", "--window-size=900,800",
                    f"--screenshot={shot}", f"file://{page}"], capture_output=True, timeout=120)
    from matplotlib.image import imread

    pixels = imread(shot)[:, :, :3]
    assert pixels.std() > 0.05                                          # not a blank page
    drawn = (np.abs(pixels - pixels[5, 5]).sum(axis=2) > 0.1).mean()
    assert drawn > 0.05


@pytest.mark.ci
def test_the_workspace_surface_closes_on_the_study_box():
    """The hexapod's workspace fills its study box: the surface still closes, on the box's
    faces (a layer of infeasible points one step outside)."""
    m = pkmkit.machine("gough-stewart")
    fig, content = view_figure(m, workspace=True, steps=2, resolution=7)
    surface = next(t for t in fig.data if t.type == "isosurface")
    values = np.asarray(surface.value)
    x = np.asarray(surface.x)
    assert values.sum() == content.workspace_points > 0
    assert values.size > content.workspace_points           # the closing layer
    outside = (x < x.min() + 1e-9) | (x > x.max() - 1e-9)
    assert not values[outside].any()
    steps = np.unique(np.round(np.diff(np.unique(np.round(x, 9))), 6))
    assert steps.size == 1                                    # still a regular grid
