"""Figures drawn in --units (issue 18 §5): `map`, `workspace`, `useful-workspace` and `errors
--tolerance --out` label their axes in the unit the command was given, and their ticks span the
numbers of that unit (a 400 mm workspace drawn in mm reads 400, not 0.4). Each figure is caught
at the plot boundary (its save call) and its axes are read."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from pkmkit.cli.main import cli


def _figures(monkeypatch, module: str) -> list:
    """The figures the command saves (``module``'s ``save_figure``), nothing written."""
    figures: list = []
    monkeypatch.setattr(f"pkmkit.plot.{module}.save_figure",
                        lambda fig, path, **kw: figures.append(fig))
    return figures


def _run(*args: str) -> None:
    result = CliRunner().invoke(cli, list(args), catch_exceptions=False)
    assert result.exit_code == 0, result.output


def _span(ax, axis: str) -> float:
    lo, hi = ax.get_xlim() if axis == "x" else ax.get_ylim()
    return hi - lo


@pytest.mark.parametrize("index", ["condition", "actuators"])
def test_map_in_mm_draws_mm(monkeypatch, tmp_path, index):
    """Drawn in metres (axes "x [m]", 0.4 wide) whatever --units said."""
    figures = _figures(monkeypatch, "maps")
    _run("map", "orthoglide", "--index", index, "--slice", "z=0", "--units", "mm",
         "--resolution", "11", "--out", str(tmp_path / "map.png"))
    (fig,) = figures
    panels = [ax for ax in fig.axes if ax.get_xlabel().startswith("x")]
    assert panels
    for ax in panels:
        assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [mm]", "y [mm]")
        assert 200 < _span(ax, "x") < 2000 and 200 < _span(ax, "y") < 2000
    if index == "actuators":  # the colour bars and the titles: carriage positions in mm
        bars = [ax.get_ylabel() for ax in fig.axes if ax not in panels]
        assert bars == ["rho1 [mm]", "rho2 [mm]", "rho3 [mm]"]
        low = float(panels[0].get_title().split(": ")[1].split(" … ")[0])
        assert panels[0].get_title().endswith(" mm") and abs(low) > 10


def test_map_of_crank_actuators_in_degrees(monkeypatch, tmp_path):
    """The Delta robot's cranks were labelled "q1 [m]" with values in radians."""
    figures = _figures(monkeypatch, "maps")
    _run("map", "delta", "--index", "actuators", "--slice", "z=-0.3", "--resolution", "11",
         "--units", "mm", "--out", str(tmp_path / "map.png"))
    bars = [ax.get_ylabel() for ax in figures[0].axes if not ax.get_xlabel()]
    assert bars == ["q1 [deg]", "q2 [deg]", "q3 [deg]"]


@pytest.mark.parametrize("units, low, high", [("mm", 200, 2000), ("m", 0.2, 2.0),
                                              ("in", 8, 80)])
def test_workspace_in_units(monkeypatch, tmp_path, units, low, high):
    figures = _figures(monkeypatch, "maps")
    _run("workspace", "five-bar", "--units", units, "--resolution", "21",
         "--out", str(tmp_path / "w.png"))
    ax = figures[0].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == (f"x [{units}]", f"y [{units}]")
    assert low < _span(ax, "x") < high
    assert f"{units}²" in ax.get_title() and "inscribed side" in ax.get_title()
    side = float(ax.get_title().split("inscribed side ")[1].split()[0])
    home = next(line for line in ax.get_lines() if line.get_label() == "home")
    # the square and the home star are drawn in the same unit as the grid
    x0, x1 = ax.get_xlim()
    assert x0 <= home.get_xdata()[0] <= x1 and 0 < side < x1 - x0


@pytest.mark.ci
def test_useful_workspace_in_mm(monkeypatch, tmp_path):
    figures = _figures(monkeypatch, "maps")
    _run("useful-workspace", "five-bar", "--units", "mm", "--out", str(tmp_path / "u.png"))
    joint, work = figures[0].axes[:2]
    assert (joint.get_xlabel(), joint.get_ylabel()) == ("rho1 [mm]", "rho2 [mm]")
    assert (work.get_xlabel(), work.get_ylabel()) == ("x [mm]", "y [mm]")
    assert _span(joint, "x") > 100 and _span(work, "x") > 100
    assert joint.get_title().endswith(" mm") and work.get_title().endswith(" mm")


@pytest.mark.parametrize("units, error_unit", [("in", "in"), ("m", "µm"), ("mm", "mm")])
def test_accuracy_map_positions_in_units(monkeypatch, tmp_path, units, error_unit):
    """--units in drew the positions and the errors in mm."""
    figures = _figures(monkeypatch, "error_figures")
    tol = tmp_path / "tol.toml"
    tol.write_text('units = "mm"\n[classes]\nlength = 0.01\nbase = 0.01\n')
    _run("errors", "gough-stewart", "--tolerance", str(tol), "--monte-carlo", "20",
         "--resolution", "4", "--units", units, "--out", str(tmp_path))
    fig = figures[0]
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == (f"x ({units})", f"y ({units})")
    span = {"in": (2, 40), "m": (0.05, 1.0), "mm": (50, 1000)}[units]
    assert span[0] < _span(ax, "x") < span[1]
    bar = next(a.get_ylabel() for a in fig.axes if "percentile" in a.get_ylabel())
    assert bar.endswith(f"({error_unit})")
    assert np.isfinite(_span(ax, "y"))
