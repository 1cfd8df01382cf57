"""Drawings of joint-chain machines (Tripteor, TriMule, crank–slider, files): every leg as the
polyline through its joint frames, the platform, the head and the tool axis."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.model.chains import FIXED
from pkmkit.plot.save import save_figure
from pkmkit.solve.chains import chain_pose
from pkmkit.spatial.rotation import rotvec_to_matrix

_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def chain_points(model, chain, values: np.ndarray, start=None) -> np.ndarray:
    """Origins ``(k, 3)`` of the frames along ``chain`` (after each joint), one configuration
    ``values (n_var,)``; the chain's start first."""
    points = [np.zeros(3) if start is None else start[1][:, 0]]
    for k in range(1, len(chain) + 1):
        end = chain_pose(model, chain[:k], values[:, None], start=start)
        points.append(end.p[:, 0])
    return np.array(points)


def draw_chain_machine(machine, q=None, *, title: str | None = None,
                       path: str | Path | None = None, ax=None) -> Figure:
    """Draw a joint-chain machine at actuator coordinates ``q`` (default home)."""
    q = machine.home_q if q is None else np.asarray(q, dtype=float)
    res = machine.fk(q, full_output=True)
    model = machine.model
    values = model.home.copy()
    act = np.flatnonzero(model.actuated)
    passive = np.flatnonzero(~model.actuated & model.loop_variables)
    values[act] = q
    values[passive] = res.passive
    if ax is None:
        fig = Figure(figsize=(6.4, 5.6))
        ax = fig.add_subplot(projection="3d")
    fig = ax.figure
    everything = []
    for i, (name, leg) in enumerate(zip(model.leg_names, model.legs, strict=True)):
        pts = chain_points(model, leg, values)
        joints = [0] + [k + 1 for k, e in enumerate(leg) if model.elements[e].type != FIXED]
        ax.plot(*pts.T, color=_COLOURS[i % len(_COLOURS)], lw=2, label=name)
        ax.scatter(*pts[joints].T, color="k", s=10)
        everything.append(pts)
    rot = rotvec_to_matrix(res.platform[3:])[0]
    start = (rot[:, :, None], res.platform[:3, None])
    if model.head:
        head = chain_points(model, model.head, values, start=start)
        ax.plot(*head.T, color="0.4", lw=3, label="head")
        everything.append(head)
    tip = res.pose[:3]
    axis = res.pose[3:]
    base = res.tool_frame[:3]
    ax.plot(*np.stack([base, tip]).T, color="crimson", lw=2, label="tool")
    ax.scatter(*tip, color="crimson", marker="*", s=120)
    everything.append(np.stack([base, tip]))
    points = np.concatenate(everything)
    centre = 0.5 * (points.max(axis=0) + points.min(axis=0))
    half = 0.5 * (points.max(axis=0) - points.min(axis=0)).max()
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    if title is None:
        q_txt = ", ".join(f"{np.degrees(v):.1f}°" if kind == "angle" else f"{v * 1000:.1f} mm"
                          for v, kind in zip(q, machine.actuator_quantities, strict=True))
        title = (f"{machine.name}\nq ({q_txt}); tool axis "
                 f"({', '.join(f'{v:.3f}' for v in axis)})")
    ax.set_title(title, fontsize=8)
    ax.legend(loc="upper left", fontsize=7)
    if path is not None:
        save_figure(fig, path, dpi=120, bbox_inches="tight")
    return fig
