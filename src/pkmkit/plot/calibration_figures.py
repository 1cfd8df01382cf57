"""Figures of a calibration: residuals per observation and as histograms (before/after,
identification and validation), identified parameters with their uncertainties, the
identifiability spectrum and the correlations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.plot.save import save_figure

#: Colours of the nominal (before) and identified (after) machines.
BEFORE, AFTER = "#d62728", "#1f77b4"


def _save(fig: Figure, path: str | Path | None) -> Figure:
    if path is not None:
        save_figure(fig, path, dpi=100)
    return fig


def plot_residuals(result, *, units: str = "mm", path: str | Path | None = None) -> Figure:
    """Error of each observation before and after identification (log scale), identification
    then validation set (seed 002's Fig. 5.4 layout)."""
    from pkmkit.model.parameters import length_scale

    scale = length_scale(units)
    sets = [("identification", result.before, result.after)]
    if result.validation is not None:
        sets.append(("validation", result.validation.before, result.validation.after))
    fig = Figure(figsize=(8.5, 3.4), layout="constrained")
    ax = fig.add_subplot()
    start = 0
    for k, (name, before, after) in enumerate(sets):
        x = start + np.arange(before.per_pose.size)
        ax.semilogy(x, np.maximum(before.per_pose / scale, 1e-9), "o", ms=3, color=BEFORE,
                    alpha=0.8, label="nominal machine" if k == 0 else None)
        ax.semilogy(x, np.maximum(after.per_pose / scale, 1e-9), "s", ms=3, color=AFTER,
                    alpha=0.8, label="identified machine" if k == 0 else None)
        if k:
            ax.axvline(start - 0.5, color="k", ls="--", lw=0.8)
        ax.text(start + 0.5, 1.0, name, transform=ax.get_xaxis_transform(), va="bottom",
                fontsize=8)
        start += before.per_pose.size
    ax.set_xlabel("observation")
    ax.set_ylabel(f"error [{units}]")
    ax.grid(True, which="both", alpha=0.25)
    ax.legend(fontsize=8, loc="center right")
    return _save(fig, path)


def plot_histograms(result, *, units: str = "mm", path: str | Path | None = None) -> Figure:
    """Histograms of the errors before and after (identification and validation sets)."""
    from pkmkit.model.parameters import length_scale

    scale = length_scale(units)
    sets = [("identification", result.before, result.after)]
    if result.validation is not None:
        sets.append(("validation", result.validation.before, result.validation.after))
    fig = Figure(figsize=(4.2 * len(sets), 3.0), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(sets)))
    for ax, (name, before, after) in zip(axes, sets, strict=True):
        b, a = before.per_pose / scale, after.per_pose / scale
        lo = max(min(a.min(), b.min()), 1e-9)
        bins = np.geomspace(lo, max(b.max(), a.max()) * 1.01, 30)
        ax.hist(b, bins=bins, color=BEFORE, alpha=0.6, label="nominal")
        ax.hist(a, bins=bins, color=AFTER, alpha=0.6, label="identified")
        ax.set_xscale("log")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(f"error [{units}]")
        ax.set_ylabel("observations")
        ax.legend(fontsize=8)
    return _save(fig, path)


def plot_parameters(result, *, units: str = "mm", path: str | Path | None = None) -> Figure:
    """Identified parameters with ±2σ bars: lengths (in ``units``) and angles/direction
    components (millidegrees; a component ≈ its angle in rad)."""
    from pkmkit.model.parameters import length_scale

    scale = length_scale(units)
    groups = [("length", [i for i, u in enumerate(result.units) if u == "m"], 1.0 / scale,
               f"[{units}]"),
              ("angle", [i for i, u in enumerate(result.units) if u != "m"],
               np.degrees(1.0) * 1e3, "[mdeg]")]
    groups = [g for g in groups if g[1]]
    fig = Figure(figsize=(8.5, 2.6 * max(1, len(groups)) + 0.4), layout="constrained")
    axes = np.atleast_1d(fig.subplots(max(1, len(groups)), 1))
    for ax, (name, idx, factor, label) in zip(axes, groups, strict=False):
        v = result.values[idx] * factor
        e = 2 * result.std[idx] * factor
        x = np.arange(len(idx))
        ax.errorbar(x, v, yerr=e, fmt="o", ms=3, color=AFTER, ecolor="0.4", capsize=2)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xticks(x, [result.names[i] for i in idx], rotation=90, fontsize=7)
        ax.set_ylabel(f"{name} {label}")
        ax.grid(True, alpha=0.25)
    if not groups:
        axes[0].text(0.5, 0.5, "no machine parameter identified", ha="center")
    return _save(fig, path)


def plot_identifiability(result, *, path: str | Path | None = None) -> Figure:
    """Singular values of the identified problem (whitened, tolerance-scaled: 1 means one
    tolerance-sized change moves the readings by one noise σ) and the correlation matrix."""
    fig = Figure(figsize=(9.0, 3.6), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2, width_ratios=[1.0, 1.1])
    sv = result.singular_values
    ax1.semilogy(np.arange(1, sv.size + 1), sv, "o-", ms=3, color=AFTER)
    ax1.axhline(1.0, color="k", ls=":", lw=0.8)
    ax1.set_xlabel("index")
    ax1.set_ylabel("singular value")
    ax1.set_title(f"rank {result.rank}, condition {result.condition:.3g}", fontsize=9)
    ax1.grid(True, which="both", alpha=0.25)
    names = result.names + result.setup_names
    ax2.set_title("correlations", fontsize=9)
    if not names:  # nothing identified (an identification that did not converge)
        ax2.set_axis_off()
        ax2.text(0.5, 0.5, "nothing identified", ha="center", va="center")
        return _save(fig, path)
    im = ax2.imshow(result.correlation, vmin=-1, vmax=1, cmap="RdBu_r")
    if len(names) <= 40:
        ax2.set_xticks(range(len(names)), names, rotation=90, fontsize=6)
        ax2.set_yticks(range(len(names)), names, fontsize=6)
    fig.colorbar(im, ax=ax2, shrink=0.8)
    return _save(fig, path)


def plot_error_maps(result, *, units: str = "mm", path: str | Path | None = None,
                    workspace: dict | None = None) -> Figure:
    """Over the workspace, seen from above (x–y): at the measured configurations' tool points,
    the error of each observation before and after identification and the identified
    machine's tool-point uncertainty (k = 2) from the parameters' covariance; with
    ``workspace`` (:meth:`~pkmkit.calibration.results.CalibrationResult.workspace_uncertainty`)
    that uncertainty at configurations drawn over the machine's workspace. The free rigid
    motion is removed when the set-up absorbs it (:mod:`pkmkit.calibration.uncertainty`)."""
    from pkmkit.model.parameters import length_scale

    scale = length_scale(units)
    rigid = getattr(result, "tool_uncertainty_rigid_removed", False)
    note = ",\nfree rigid motion removed" if rigid else ""
    panels = []
    if result.tool_points is not None:
        pts = np.asarray(result.tool_points) / scale
        panels += [("error, nominal machine", pts, result.before.per_pose / scale),
                   ("error, identified machine", pts, result.after.per_pose / scale)]
        if result.tool_uncertainty is not None:
            panels.append((f"tool-point uncertainty (k = 2){note}", pts,
                           np.asarray(result.tool_uncertainty) / scale))
    if workspace is not None:
        panels.append((f"uncertainty (k = 2) over the workspace\n"
                       f"({len(workspace['points'])} configurations){note.replace(chr(10), ' ')}",
                       np.asarray(workspace["points"]) / scale,
                       np.asarray(workspace["uncertainty"]) / scale))
    fig = Figure(figsize=(4.0 * max(len(panels), 1), 3.6), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, max(len(panels), 1)))
    for ax, (name, pts, value) in zip(axes, panels, strict=False):
        finite = np.isfinite(value)
        sc = ax.scatter(pts[finite, 0], pts[finite, 1], c=value[finite], s=14, cmap="viridis")
        if (~finite).any():
            ax.scatter(pts[~finite, 0], pts[~finite, 1], marker="x", color="r", s=14,
                       label="undetermined")
            ax.legend(fontsize=7)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(f"x [{units}]")
        ax.set_ylabel(f"y [{units}]")
        ax.grid(True, alpha=0.25)
        fig.colorbar(sc, ax=ax, shrink=0.8, label=f"[{units}]")
    return _save(fig, path)
