"""Figures of the design layer: Pareto fronts and sizing sweeps."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from pkmkit.design.optimize import OptimizationResult
from pkmkit.plot.save import save_figure


def plot_pareto(result: OptimizationResult, *,
                references: Sequence[tuple[str, dict[str, float]]] = (),
                title: str = "", path: str | Path | None = None,
                units: str | None = None) -> Figure:
    """Evaluated designs in the plane of the first two objectives, the Pareto front, and
    reference designs (label, metrics in SI) for comparison. ``units``: None for SI, or a
    command-line length unit (see :class:`OptimizationResult`); the axis labels name it."""
    o1, o2 = result.problem.objectives[:2]
    fig = Figure(figsize=(6.6, 5.2), layout="constrained")
    ax = fig.add_subplot()

    def values(records: Sequence[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
        return (np.array([result.to_units(o1.metric, float(r[o1.metric]), units)
                          for r in records], dtype=float),
                np.array([result.to_units(o2.metric, float(r[o2.metric]), units)
                          for r in records], dtype=float))

    infeasible = [r for r in result.records if not r["feasible"]]
    feasible = [r for r in result.records if r["feasible"]]
    if infeasible:
        ax.scatter(*values(infeasible), s=8, color="0.8", label="infeasible")
    if feasible:
        ax.scatter(*values(feasible), s=10, color="tab:blue", alpha=0.5, label="feasible")
    if result.pareto:
        x, y = values(result.pareto)
        order = np.argsort(x)
        ax.plot(x[order], y[order], "o-", color="tab:red", ms=4, label="Pareto front")
    for label, metrics in references:
        x, y = values([metrics])
        ax.plot(x[0], y[0], "k*", ms=12)
        ax.annotate(label, (x[0], y[0]), textcoords="offset points", xytext=(6, 6), fontsize=8)

    def axis_label(objective) -> str:
        unit = result.unit_of(objective.metric, units)
        return f"{objective.metric} ({objective.sense})" + (f" [{unit}]" if unit else "")

    ax.set_xlabel(axis_label(o1))
    ax.set_ylabel(axis_label(o2))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or f"{result.problem.base.name}: {len(result.records)} designs",
                 fontsize=9)
    if path is not None:
        save_figure(fig, path, dpi=120, bbox_inches="tight")
    return fig


def plot_sizing_sweep(rows: Sequence[dict[str, float]], *, x: str, ys: Sequence[str],
                      xlabel: str, title: str = "", labels: dict[str, str] | None = None,
                      path: str | Path | None = None) -> Figure:
    """Curves of several sizing results (``ys``) against a swept input ``x``; ``labels`` maps
    a result's key to the words of its legend entry (default: the key)."""
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
    ax = fig.add_subplot()
    xs = [r[x] for r in rows]
    labels = labels or {}
    for name in ys:
        ax.plot(xs, [r[name] for r in rows], "o-", label=labels.get(name, name))
    ax.set_xlabel(xlabel)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title, fontsize=9)
    if path is not None:
        save_figure(fig, path, dpi=120, bbox_inches="tight")
    return fig
