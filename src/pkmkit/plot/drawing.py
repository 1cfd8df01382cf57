"""Drawings of a rod-leg machine at a pose (matplotlib, any backend; PNG/SVG by extension)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.machines.machine import Machine
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.plot.save import save_figure
from pkmkit.solve.rod_closure import rod_base_points
from pkmkit.spatial.rotation import rotvec_to_matrix

_LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown")


def machine_geometry(machine: Machine, pose: np.ndarray, q: np.ndarray) -> dict[str, np.ndarray]:
    """3-D points of the drawing at ``pose (dims,)`` with actuator coordinates ``q (n,)``.

    Returns a dict with ``carriage (m, 3)`` and ``platform (m, 3)`` rod end points,
    ``rails (n, 2, 3)`` one guide segment per leg — the slide around its carriage, the crank
    arm from its pivot to its tip, a point for a strut —, ``tool (3,)``.
    """
    model = machine.model
    x = np.asarray(pose, dtype=float)[None]
    p = model.pad(x)[0]
    q = np.asarray(q, dtype=float)
    carriage = rod_base_points(model, q[:, None])[:, :, 0].T
    rotation = rotvec_to_matrix(x[0, 3:6])[0] if model.full_pose else np.eye(3)
    platform = p + model.rod_platform @ rotation.T
    span = 0.6 * float(model.leg_length.max())
    # one guide per leg, through the middle of its rods' base joints (a parallelogram's midline)
    leg_carriage = np.array([carriage[model.rod_leg == i].mean(axis=0)
                             for i in range(model.n_legs)])
    rails = np.stack([leg_carriage - span * model.leg_axis, leg_carriage + span * model.leg_axis],
                     axis=1)
    crank = model.leg_kind == CRANK
    rails[crank, 0] = model.leg_pivot[crank]
    rails[crank, 1] = leg_carriage[crank]
    return {"carriage": carriage, "platform": platform, "rails": rails, "tool": p}


def _draw_parts(ax, machine: Machine, geo: dict, coords: slice) -> None:
    """Guides (slides, crank arms), rods coloured by leg, joints and the tool point."""
    def line(points: np.ndarray, **style) -> None:
        ax.plot(*points[:, coords].T, **style)

    guide_names = {SLIDE: "slides", CRANK: "crank arms"}
    for i, rail in enumerate(geo["rails"]):
        kind = int(machine.model.leg_kind[i])
        first = kind in guide_names and i == int(
            np.flatnonzero(machine.model.leg_kind == kind)[0])
        line(rail, color="0.6", lw=4, solid_capstyle="butt",
             label=guide_names[kind] if first else None)
    for j in range(machine.model.n_rods):
        leg = int(machine.model.rod_leg[j])
        colour = _LEG_COLOURS[leg % len(_LEG_COLOURS)]
        line(np.stack([geo["carriage"][j], geo["platform"][j]]), color=colour, lw=1.8,
             label=machine.model.leg_names[leg] if j == np.flatnonzero(
                 machine.model.rod_leg == leg)[0] else None)
    ax.scatter(*geo["carriage"][:, coords].T, color="k", s=14, zorder=3)
    ax.scatter(*geo["platform"][:, coords].T, color="k", s=10, zorder=3)
    ax.scatter(*geo["tool"][coords], color="crimson", marker="*", s=120, zorder=4,
               label="tool point")


def _frame_axes(ax, geo: dict, spatial: bool) -> None:
    """Axis labels (m); a cube around the machine in 3-D, equal aspect and a grid in 2-D."""
    units = "m"
    ax.set_xlabel(f"x [{units}]")
    ax.set_ylabel(f"y [{units}]")
    if spatial:
        ax.set_zlabel(f"z [{units}]")
        points = np.concatenate([geo["carriage"], geo["platform"], geo["rails"].reshape(-1, 3)])
        centre = 0.5 * (points.max(axis=0) + points.min(axis=0))
        half = 0.5 * (points.max(axis=0) - points.min(axis=0)).max()
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
    else:
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, alpha=0.3)


def _pose_and_q_text(machine: Machine, pose: np.ndarray, q: np.ndarray) -> str:
    """``pose (…)   q (…)`` for the default title: m, rotation vector in rad, crank angles in
    degrees."""
    pose_txt = ", ".join(f"{v:.3f}" for v in pose[:3])
    if machine.model.full_pose:
        pose_txt += " m, rotation vector " + ", ".join(f"{v:.3f}" for v in pose[3:]) + " rad"
    else:
        pose_txt += " m"
    q_txt = ", ".join(f"{np.degrees(v):.1f}°" if quantity == "angle" else f"{v:.3f} m"
                      for v, quantity in zip(q, machine.model.actuator_quantities, strict=True))
    return f"pose ({pose_txt})   q ({q_txt})"


def draw_machine(machine: Machine, pose=None, *, q=None, ax=None, title: str | None = None,
                 path: str | Path | None = None) -> Figure:
    """Draw ``machine`` at ``pose`` (default: home): slides, carriages, rods, platform, tool.

    Args:
        machine: the machine.
        pose: ``(dims,)`` pose in m (must be reachable).
        q: actuator coordinates (default: inverse model, working branches) — pass them to draw
            another assembly mode of the same q.
        ax: draw into these axes (3-D axes for a spatial machine) instead of a new figure.
        title: axes title (default: machine name, pose and q).
        path: if given, the figure is saved there (format from the extension).

    Returns:
        The matplotlib ``Figure`` (pyplot-free, so no GUI backend is involved).
    """
    pose = machine.home_pose if pose is None else np.asarray(pose, dtype=float)
    q = machine.ik(pose) if q is None else np.asarray(q, dtype=float)
    geo = machine_geometry(machine, pose, q)
    spatial = machine.dims != 2
    if ax is None:
        fig = Figure(figsize=(6.4, 5.6))
        ax = fig.add_subplot(projection="3d" if spatial else None)
    fig = ax.figure
    coords = slice(0, 3 if spatial else 2)
    _draw_parts(ax, machine, geo, coords)
    _frame_axes(ax, geo, spatial)
    if title is None:
        title = f"{machine.name}\n{_pose_and_q_text(machine, pose, q)}"
    ax.set_title(title, fontsize=9)
    ax.legend(loc="upper left", fontsize=7)
    if path is not None:
        save_figure(fig, path, dpi=120, bbox_inches="tight")
    return fig
