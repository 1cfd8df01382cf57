"""Figures of the geometric error analyses: sensitivity bars and accuracy maps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.model.parameters import length_scale
from pkmkit.plot.save import save_figure


def plot_sensitivity(table, path: str | Path, *, top: int = 30, unit: str = "mm",
                     title: str = "") -> Path:
    """Horizontal bars of the largest tool displacement per defect (most influential first),
    coloured by kind; ``unit`` "mm" or "um"."""
    scale, label = (1e3, "mm") if unit == "mm" else (1e6, "µm")
    order = table.order()[:top]
    kinds = sorted(set(table.kinds))
    colours = {k: f"C{i}" for i, k in enumerate(kinds)}
    fig = Figure(figsize=(7.5, 0.25 * len(order) + 1.6))
    ax = fig.add_subplot(1, 1, 1)
    y = np.arange(len(order))[::-1]
    ax.barh(y, table.max_displacement[order] * scale,
            color=[colours[table.kinds[i]] for i in order])
    if table.exact_max is not None:
        ax.plot(table.exact_max[order] * scale, y, "k|", markersize=9, label="exact model")
    ax.set_yticks(y, [table.names[i] for i in order], fontsize=8)
    ax.set_xlabel(f"largest tool displacement over the region ({label})")
    from matplotlib.patches import Patch

    handles = [Patch(color=colours[k], label=k) for k in kinds]
    if table.exact_max is not None:
        handles.append(ax.lines[0])
    ax.legend(handles=handles, fontsize=7, loc="lower right")
    sizes = sorted(set(np.round(table.size, 12)))
    ax.set_title(title or "sensitivity: defect sizes " + ", ".join(f"{s:.3g}" for s in sizes)
                 + " (SI)", fontsize=9)
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, dpi=110)
    return path


def _per_metre(unit: str) -> tuple[float, str]:
    """(numbers per metre, label) of a length unit, ``"µm"`` (or ``"um"``) included."""
    if unit in ("µm", "um"):
        return 1e6, "µm"
    return 1.0 / length_scale(unit), unit


def plot_accuracy_map(amap, path: str | Path, *, unit: str = "mm", title: str = "",
                      position_unit: str = "mm") -> Path:
    """Two panels: exact Monte Carlo and first-order percentile of the tool-point error.

    ``unit`` ("µm" or a length unit: "mm", "m", "in") is the unit of the errors (the colour
    scale); the positions are drawn in ``position_unit`` (a length unit), so that the axes of
    a workspace hundreds of mm wide keep readable ticks when the errors are in µm."""
    scale, label = _per_metre(unit)
    pscale, plabel = _per_metre(position_unit)
    fig = Figure(figsize=(10, 4.2))
    vmax = np.nanmax([np.nanmax(amap.exact), np.nanmax(amap.first_order)]) * scale
    vmin = np.nanmin([np.nanmin(amap.exact), np.nanmin(amap.first_order)]) * scale
    for k, (data, name) in enumerate(((amap.exact, "exact model (Monte Carlo)"),
                                      (amap.first_order, "first order, same samples"))):
        ax = fig.add_subplot(1, 2, k + 1)
        mesh = ax.pcolormesh(amap.x * pscale, amap.y * pscale, data * scale, shading="nearest",
                             vmin=vmin, vmax=vmax, cmap="viridis")
        ax.set_xlabel(f"{amap.axes[0]} ({plabel})")
        ax.set_ylabel(f"{amap.axes[1]} ({plabel})")
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=9)
        fig.colorbar(mesh, ax=ax, label=f"{amap.level:g}th percentile of |error| ({label})")
    fixed = ", ".join(f"{n} = {np.degrees(v):.4g}°" if n in ("rx", "ry", "rz") else
                      f"{n} = {v * pscale:.4g} {plabel}" for n, v in amap.fixed.items())
    fig.suptitle(title or f"tool-point error, {amap.n_samples} samples per point"
                 + (f" ({fixed})" if fixed else ""), fontsize=10)
    fig.tight_layout()
    path = Path(path)
    save_figure(fig, path, dpi=110)
    return path
