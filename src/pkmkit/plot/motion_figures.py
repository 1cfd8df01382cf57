"""Figures of trajectories: actuator positions, speeds, accelerations and forces vs time, and the
tool path."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.model.parameters import length_scale
from pkmkit.motion.joints import JointTrajectory
from pkmkit.motion.limits import LimitViolation
from pkmkit.plot.save import save_figure


def plot_joint_motion(motion: JointTrajectory, names, *, forces: np.ndarray | None = None,
                      title: str = "", length_unit: str = "m",
                      limits: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
                      violations: Sequence[LimitViolation] = (),
                      path: str | Path | None = None) -> Figure:
    """Stacked panels of q, q̇, q̈ (and forces) against time, one curve per actuator.

    ``limits``: ``{kind: (lower (n,), upper (n,))}`` (SI units; kinds ``stroke``, ``speed``,
    ``accel``, ``force``) drawn as dashed lines in each actuator's colour (a stroke far from
    the motion is left out of the view unless violated); ``violations``: every excursion
    shaded on its panel and its worst point marked.
    """
    scale = 1.0 / length_scale(length_unit)
    panels = [("stroke", motion.q * scale, f"q [{length_unit}]", scale),
              ("speed", motion.qd * scale, f"q̇ [{length_unit}/s]", scale),
              ("accel", motion.qdd * scale, f"q̈ [{length_unit}/s²]", scale)]
    if forces is not None:
        panels.append(("force", forces, "force [N]", 1.0))
    fig = Figure(figsize=(8.0, 2.2 * len(panels) + 0.6), layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True)
    colours = [f"C{k % 10}" for k in range(len(names))]
    for ax, (kind, values, label, factor) in zip(axes, panels, strict=True):
        for k, name in enumerate(names):
            ax.plot(motion.t, values[:, k], lw=1.0, label=name, color=colours[k])
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        mine = [v for v in violations if v.kind == kind]
        _draw_limits(ax, (limits or {}).get(kind), factor, colours, bool(mine))
        for v in mine:
            k = list(names).index(v.joint) if v.joint in names else 0
            for e in v.excursions:
                ax.axvspan(e.span.start, e.span.end, color="red", alpha=0.12, lw=0)
            w = v.worst.span
            ax.plot([w.t_peak], [w.value * factor], marker="x", ms=8, mew=2,
                    color=colours[k], zorder=5)
    if violations:
        axes[0].plot([], [], color="red", alpha=0.3, lw=6, label="limit exceeded")
    axes[0].legend(fontsize=8, ncols=len(names) + (1 if violations else 0))
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(title, fontsize=10)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


def _draw_limits(ax, bounds, factor: float, colours: list[str], violated: bool) -> None:
    """Dashed lines at each actuator's limits; the view keeps the motion, widened to show
    limits within half its range of it (all of them when one is violated)."""
    if bounds is None:
        return
    lo_view, hi_view = ax.get_ylim()
    margin = 0.5 * (hi_view - lo_view)
    show_lo, show_hi = lo_view, hi_view
    for bound in bounds:
        values = np.broadcast_to(np.asarray(bound, dtype=float) * factor, (len(colours),))
        shared = bool(np.all(values == values[0]))  # one black line for a common limit
        for k, value in enumerate(values[:1] if shared else values):
            if not np.isfinite(value):
                continue
            if violated or lo_view - margin <= value <= hi_view + margin:
                ax.axhline(value, color="black" if shared else colours[k], ls="--", lw=0.9,
                           alpha=0.8)
                show_lo, show_hi = min(show_lo, value), max(show_hi, value)
    pad = 0.05 * (show_hi - show_lo)
    ax.set_ylim(show_lo - pad, show_hi + pad)


def plot_tool_path(motion: JointTrajectory, *, title: str = "", length_unit: str = "m",
                   path: str | Path | None = None) -> Figure:
    """The sampled tool path, coloured by speed (3-D for spatial machines)."""
    scale = 1.0 / length_scale(length_unit)
    x = motion.x * scale
    speed = np.linalg.norm(motion.xd, axis=1) * scale
    fig = Figure(figsize=(6.2, 5.2), layout="constrained")
    if x.shape[1] == 3:
        ax = fig.add_subplot(projection="3d")
        sc = ax.scatter(x[:, 0], x[:, 1], x[:, 2], c=speed, s=2, cmap="viridis")
        ax.set_zlabel(f"z [{length_unit}]")
    else:
        ax = fig.add_subplot()
        sc = ax.scatter(x[:, 0], x[:, 1], c=speed, s=2, cmap="viridis")
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x [{length_unit}]")
    ax.set_ylabel(f"y [{length_unit}]")
    fig.colorbar(sc, ax=ax, label=f"speed [{length_unit}/s]", shrink=0.7)
    ax.set_title(title, fontsize=9)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig
