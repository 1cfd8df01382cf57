"""The tool-point deflection along a move beside its joint trajectories."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.model.parameters import length_scale
from pkmkit.motion.joints import JointTrajectory
from pkmkit.plot.save import save_figure


def plot_path_deflection(motion: JointTrajectory, names: Sequence[str], deflection,
                         *, title: str = "", length_unit: str = "m",
                         path: str | Path | None = None) -> Figure:
    """Two panels against time: the actuator positions ``q`` (``length_unit``) and the
    tool-point deflection (µm) — its components (solid), its norm (black) and the part due to
    the weight of the moving parts (dashed norm). ``deflection``: a
    :class:`~pkmkit.stiffness.along_path.PathDeflection` of the same samples; its peak over
    continuous time is marked."""
    scale = 1.0 / length_scale(length_unit)
    fig = Figure(figsize=(8.0, 5.2), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    for k, name in enumerate(names):
        top.plot(motion.t, motion.q[:, k] * scale, color=f"C{k % 10}", label=name)
    top.set_ylabel(f"q [{length_unit}]")
    top.legend(fontsize=7, loc="best")
    micro = 1e6
    total = np.asarray(deflection.total) * micro
    for k in range(total.shape[1]):
        bottom.plot(deflection.t, total[:, k], color=f"C{k % 10}", lw=1.0,
                    label=f"δ{'xyz'[k]}")
    bottom.plot(deflection.t, np.linalg.norm(total, axis=1), color="k", lw=1.4, label="|δ|")
    bottom.plot(deflection.t, np.linalg.norm(deflection.gravity, axis=1) * micro, color="k",
                lw=1.0, ls="--", label="|δ| gravity only")
    peak = deflection.peak
    bottom.plot([peak["t"]], [peak["value"] * micro], "o", color="C3", ms=5,
                label=f"peak {peak['value'] * micro:.3g} µm"
                      + (f" (line {peak['line']})" if peak["line"] else ""))
    bottom.set_ylabel("tool deflection [µm]")
    bottom.set_xlabel("t [s]")
    bottom.legend(fontsize=7, loc="best", ncol=3)
    for ax in (top, bottom):
        ax.grid(True, lw=0.3)
    if title:
        fig.suptitle(title, fontsize=10)
    if path is not None:
        save_figure(fig, path, dpi=100)
    return fig
