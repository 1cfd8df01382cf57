"""The demo's figures say what they show (issue 18 §8): readable position ticks on error maps
in µm, the machine's name on ellipse figures, words rather than code names in legends, one
style per curve on the passive-joint figures, labelled axes on the assembly-modes figure."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from matplotlib.figure import Figure

import pkmkit
from pkmkit.plot.design_figures import plot_sizing_sweep
from pkmkit.plot.error_figures import plot_accuracy_map
from pkmkit.plot.maps import plot_ellipses


def test_error_maps_in_um_keep_their_positions_in_mm(tmp_path, monkeypatch):
    captured = {}
    monkeypatch.setattr("pkmkit.plot.error_figures.save_figure",
                        lambda fig, path, **kw: captured.setdefault("fig", fig))
    x = np.linspace(-0.15, 0.15, 4)
    amap = SimpleNamespace(x=x, y=x, exact=np.full((4, 4), 70e-6),
                           first_order=np.full((4, 4), 69e-6), axes=("x", "y"), level=95,
                           fixed={"z": 0.5}, n_samples=10)
    plot_accuracy_map(amap, tmp_path / "m.png", unit="µm")
    ax = captured["fig"].axes[0]
    assert ax.get_xlabel() == "x (mm)" and ax.get_ylabel() == "y (mm)"
    assert ax.get_xlim()[1] < 1000                    # 150 mm (+ half a cell), not 150000 µm
    assert "(µm)" in captured["fig"].axes[1].get_ylabel()   # the colour bar: errors in µm
    assert "z = 500 mm" in captured["fig"].texts[0].get_text()


def test_ellipse_figures_name_their_machine():
    m = pkmkit.machine("orthoglide")
    fig = plot_ellipses(m, m.home_pose[None])
    assert fig.axes[0].get_title().startswith(m.name)


def test_sizing_sweep_legends_use_words():
    rows = [{"psi": 1.5, "side_over_L": 0.4}, {"psi": 2.0, "side_over_L": 0.6}]
    fig = plot_sizing_sweep(rows, x="psi", ys=("side_over_L",), xlabel="ψ",
                            labels={"side_over_L": "cube side / leg length"})
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert texts == ["cube side / leg length"]


def test_passive_joint_curves_are_told_apart(tmp_path, monkeypatch):
    """16 curves of the TriMule: no two share colour, line style and marker; a leg keeps one
    colour."""
    from pkmkit.demos import machines as demo

    captured = {}
    monkeypatch.setattr(demo, "save_figure",
                        lambda fig, path, **kw: captured.setdefault("fig", fig))
    m = pkmkit.machine("trimule-600")
    demo._passive_move(m, m.actuator_names[0], tmp_path / "p.png")
    lines = captured["fig"].axes[0].get_lines()
    styles = [(line.get_color(), str(line.get_linestyle()), line.get_marker()) for line in lines]
    assert len(lines) > 10 and len(set(styles)) == len(styles)
    by_leg = {}
    for line in lines:
        by_leg.setdefault(line.get_label()[-1], set()).add(line.get_color())
    assert all(len(colours) == 1 for colours in by_leg.values())


def test_assembly_modes_figure_labels_its_axes(tmp_path, monkeypatch):
    from pkmkit.demos import machines as demo

    captured = {}
    monkeypatch.setattr(demo, "save_figure",
                        lambda fig, path, **kw: captured.setdefault("fig", fig))
    modes = SimpleNamespace(count=3, poses=np.array([[0.5, 0, 0.3, 0, 0, 0],
                                                     [0.6, 0.1, 0.2, 0, 0, 0],
                                                     [0.7, -0.1, 0.1, 0, 0, 0]]),
                            mode_sign=np.array([1, -1, 1]), working=0)
    demo._plot_modes(None, modes, tmp_path / "modes.png")
    ax = captured["fig"].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("x [m]", "y [m]", "z [m]")
    assert isinstance(captured["fig"], Figure)
