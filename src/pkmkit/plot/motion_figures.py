"""Figures of trajectories: actuator positions, speeds, accelerations and forces vs time, and the
tool path."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.model.parameters import length_scale
from pkmkit.motion.joints import JointTrajectory
from pkmkit.plot.save import save_figure


def plot_joint_motion(motion: JointTrajectory, names, *, forces: np.ndarray | None = None,
                      title: str = "", length_unit: str = "m",
                      path: str | Path | None = None) -> Figure:
    """Stacked panels of q, q̇, q̈ (and forces) against time, one curve per actuator."""
    scale = 1.0 / length_scale(length_unit)
    panels = [(motion.q * scale, f"q [{length_unit}]"),
              (motion.qd * scale, f"q̇ [{length_unit}/s]"),
              (motion.qdd * scale, f"q̈ [{length_unit}/s²]")]
    if forces is not None:
        panels.append((forces, "force [N]"))
    fig = Figure(figsize=(8.0, 2.2 * len(panels) + 0.6), layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True)
    for ax, (values, label) in zip(axes, panels, strict=True):
        for k, name in enumerate(names):
            ax.plot(motion.t, values[:, k], lw=1.0, label=name)
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, ncols=len(names))
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(title, fontsize=10)
    if path is not None:
        save_figure(fig, path, dpi=110)
    return fig


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
