"""Full-pose and joint-chain parts of ``pkmkit demo``.

Writes figures into ``OUT/full-pose/`` and ``OUT/joint-chains/`` and returns JSON-ready summaries:

- the Gough–Stewart hexapod: kinematics at its reference poses, the constant-orientation
  workspace (volume, inscribed cube), the orientation workspace at home (largest tilt per
  azimuth), every real assembly mode of Dietmaier's general 6-6 platform (40 real);
- the Verne-type module: the tilt its rods impose over its workspace (map) and its assembly
  modes;
- the Tripteor X7 and the TriMule 600: drawings, hyperstatism counts, the passive joints along
  a move, and the workspace of the parallel part (platform positions over the actuator strokes);
  the crank–slider's count.
"""

from __future__ import annotations

import re
import time
from pathlib import Path
from typing import Any

import click
import numpy as np
from matplotlib.figure import Figure

from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.orientation import coupled_orientation, orientation_workspace
from pkmkit.analysis.workspace import Criteria, compute_workspace
from pkmkit.machines.registry import machine
from pkmkit.plot.chain_drawing import draw_chain_machine
from pkmkit.plot.drawing import draw_machine
from pkmkit.plot.maps import plot_workspace
from pkmkit.plot.save import save_figure


def run_full_pose_demo(out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """The hexapod and Verne-type module studies (figures in ``out_dir/full-pose``)."""
    out = out_dir / "full-pose"
    out.mkdir(parents=True, exist_ok=True)
    summary: dict[str, Any] = {}
    hexapod = machine("gough-stewart")
    draw_machine(hexapod, hexapod.reference_poses()["tilted"], path=out / "gough-stewart.png")
    poses = {}
    for name, pose in hexapod.reference_poses().items():
        q = hexapod.ik(pose)
        jac = hexapod.jacobian(pose)
        back = hexapod.fk(q)
        poses[name] = {"pose": pose, "q": q, "round_trip": float(np.abs(back - pose).max()),
                       "condition": float(jac.condition), "status": jac.status}
    lo, hi = np.array([-0.5, -0.5, 0.5]), np.array([0.5, 0.5, 1.1])
    grid = make_grid(lo, hi, free=(0, 1, 2), base=hexapod.home_pose, names=hexapod.pose_names,
                     resolution=15 if quick else 31)
    wmap = compute_workspace(hexapod, grid, Criteria(), refine=False)
    plot_workspace(wmap, hexapod, title="Gough–Stewart hexapod: constant-orientation workspace "
                   "(platform parallel to the base, strokes 650–1100 mm)",
                   path=out / "gough-stewart-workspace.png")
    ows = orientation_workspace(hexapod, hexapod.home_pose[:3], max_tilt=np.radians(85),
                                azimuths=36 if quick else 72, tilts=86 if quick else 171)
    _plot_tilt(ows, out / "gough-stewart-orientation.png")
    general = machine("dietmaier-hexapod")
    start = time.perf_counter()
    modes = general.fk_all(general.home_q)
    elapsed = time.perf_counter() - start
    _plot_modes(general, modes, out / "dietmaier-modes.png")
    summary["gough-stewart"] = {
        "reference_poses": poses,
        "workspace": {"volume": wmap.measure, "inscribed_cube": None if wmap.inscribed is None
                      else wmap.inscribed.side, "resolution": float(np.max(grid.step))},
        "max_tilt_deg": {"min": float(np.degrees(np.nanmin(ows.max_tilt))),
                         "max": float(np.degrees(np.nanmax(ows.max_tilt))),
                         "resolution": float(np.degrees(ows.resolution))},
        "figures": ["gough-stewart.png", "gough-stewart-workspace.png",
                    "gough-stewart-orientation.png"]}
    summary["dietmaier"] = {
        "real_modes": int(modes.count), "finite_solutions": int(modes.n_finite),
        "worst_residual": float(np.nanmax(modes.residual)), "seconds": elapsed,
        "working": int(modes.working), "status": "complete" if int(modes.status) == 0 else
        "not certified", "figure": "dietmaier-modes.png"}
    verne = machine("verne")
    draw_machine(verne, verne.ik(verne.reference_poses()["offset"], full_output=True).pose,
                 path=out / "verne.png")
    n = 31 if quick else 61
    xs = np.linspace(-0.2, 0.2, n)
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    tilt = coupled_orientation(verne, np.column_stack([gx.ravel(), gy.ravel(),
                                                       np.zeros(gx.size)]))
    _plot_tilt_map(gx, gy, np.degrees(tilt.tilt).reshape(gx.shape), out / "verne-tilt.png")
    vmodes = verne.fk_all(verne.home_q)
    summary["verne"] = {
        "tilt_deg": {"max": float(np.degrees(np.nanmax(tilt.tilt))),
                     "on_plane_x0": float(np.degrees(np.nanmax(tilt.tilt[np.isclose(
                         tilt.positions[:, 0], 0.0)])))},
        "assembly_modes_at_home": int(vmodes.count),
        "figures": ["verne.png", "verne-tilt.png"]}
    _echo_full_pose(summary)
    return summary


def run_chain_demo(out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """The joint-chain machines' studies (figures in ``out_dir/joint-chains``)."""
    out = out_dir / "joint-chains"
    out.mkdir(parents=True, exist_ok=True)
    summary: dict[str, Any] = {}
    for ident, move in (("tripteor-x7", "Q1"), ("trimule-600", "Q1"), ("crank-slider", None)):
        m = machine(ident)
        count = m.hyperstatism()
        entry: dict[str, Any] = {"hyperstatism": count.__dict__}
        if ident != "crank-slider":
            draw_chain_machine(m, m.reference_poses().get("wrist", m.home_q),
                               path=out / f"{ident}.png")
            entry["passive_along_a_move"] = _passive_move(m, move, out / f"{ident}-passive.png")
            entry["parallel_workspace"] = _parallel_workspace(
                m, out / f"{ident}-workspace.png", 5 if quick else 9)
            entry["figures"] = [f"{ident}.png", f"{ident}-passive.png",
                                f"{ident}-workspace.png"]
        summary[ident] = entry
        h = count
        click.echo(f"\n== {ident}: {m.name}")
        click.echo(f"   parallel part: {h.joints} one-DOF joints, {h.bodies} bodies, {h.loops} "
                   f"loops, mobility {h.mobility}, hyperstatism h = {h.hyperstatism} (rank "
                   f"test {h.rank_hyperstatism})")
        if "parallel_workspace" in entry:
            w = entry["parallel_workspace"]
            click.echo(f"   platform over the actuator strokes: x {_span(w['x'])}, y "
                       f"{_span(w['y'])}, z {_span(w['z'])} mm; tilt up to "
                       f"{w['tilt_max_deg']:.2f}°")
            p = entry["passive_along_a_move"]
            click.echo(f"   {p['move']}: " + ", ".join(
                f"{k} {v[0]:+.3f}..{v[1]:+.3f}°" for k, v in p["ranges_deg"].items()
                if k in ("psi1", "eta2", "theta4", "psi2")))
    return summary


def _span(values) -> str:
    return f"{values[0] * 1000:.1f}..{values[1] * 1000:.1f}"


_LINE_STYLES = ("-", "--", ":", "-.", (0, (5, 1, 1, 1, 1, 1)))
_MARKERS = ("o", "s", "^", "v", "D")


def _symbol_and_leg(label: str) -> tuple[str, str]:
    """``("θ", "2")`` for ``"θ2"``: a joint's symbol and its leg number (``""`` without)."""
    match = re.fullmatch(r"(.*?)(\d+)", label)
    return (match.group(1), match.group(2)) if match else (label, "")


def _passive_move(m, name: str, path: Path) -> dict[str, Any]:
    """The passive joints while actuator ``name`` sweeps its stroke (or ±5 % around home)."""
    k = m.actuator_names.index(name)
    lo, hi = m.model.q_min[np.flatnonzero(m.model.actuated)[k]], m.model.q_max[
        np.flatnonzero(m.model.actuated)[k]]
    home = m.home_q
    if not (np.isfinite(lo) and np.isfinite(hi)):
        lo, hi = 0.95 * home[k], 1.05 * home[k]
    values = np.linspace(lo, hi, 41)
    q = np.tile(home, (len(values), 1))
    q[:, k] = values
    res = m.fk(q, full_output=True, strokes="ignore")
    fig = Figure(figsize=(8.2, 4.6), layout="constrained")
    ax = fig.add_subplot()
    ranges = {}
    legs: dict[str, int] = {}
    kinds: dict[str, int] = {}
    for i, joint in enumerate(m.passive_names):
        element = next(e for e in m.model.elements if e.name == joint)
        if element.type != "R":
            continue
        deg = np.degrees(res.passive[:, i])
        ranges[joint] = (float(np.nanmin(deg)), float(np.nanmax(deg)))
        label = element.display or joint
        # one colour per leg (the label's number), one line style and marker per joint symbol
        kind, leg = _symbol_and_leg(label)
        colour = f"C{legs.setdefault(leg, len(legs)) % 10}"
        style = kinds.setdefault(kind, len(kinds))
        ax.plot(values * 1000, deg - deg[len(deg) // 2], label=label, color=colour,
                linestyle=_LINE_STYLES[style % len(_LINE_STYLES)],
                marker=_MARKERS[style % len(_MARKERS)], markevery=(style, 8), markersize=4)
    ax.set_xlabel(f"{name} [mm]")
    ax.set_ylabel("passive joint − its value at mid-stroke [deg]")
    ax.set_title(f"{m.name}: passive joints while {name} moves (others at home);\n"
                 "colour: leg, line and marker: joint", fontsize=9)
    ax.legend(fontsize=7, ncol=1 if len(ranges) <= 12 else 2, loc="center left",
              bbox_to_anchor=(1.01, 0.5))
    ax.grid(alpha=0.3)
    save_figure(fig, path, dpi=120)
    return {"move": f"{name} from {lo * 1000:.1f} to {hi * 1000:.1f} mm", "ranges_deg": ranges,
            "closure_residual_max": float(np.nanmax(res.closure_residual))}


def _parallel_workspace(m, path: Path, per_axis: int) -> dict[str, Any]:
    """Platform positions over a grid of the leg actuators' strokes (head at home)."""
    act = np.flatnonzero(m.model.actuated)
    loop = [j for j, v in enumerate(act) if m.model.loop_variables[v]]
    axes = []
    for j in loop:
        lo, hi = m.model.q_min[act[j]], m.model.q_max[act[j]]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            lo, hi = 0.97 * m.home_q[j], 1.03 * m.home_q[j]
        axes.append(np.linspace(lo, hi, per_axis))
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(loop))
    q = np.tile(m.home_q, (len(grid), 1))
    q[:, loop] = grid
    res = m.fk(q, full_output=True, strokes="ignore")
    ok = np.isfinite(res.platform).all(axis=1)
    p = res.platform[ok, :3]
    from scipy.spatial.transform import Rotation

    z = Rotation.from_rotvec(res.platform[ok, 3:]).apply([0.0, 0.0, 1.0])
    home = np.array(m.fk(m.home_q, full_output=True).platform[3:])  # scipy: writeable only
    z0 = Rotation.from_rotvec(home).apply([0, 0, 1.0])
    tilt = np.degrees(np.arccos(np.clip(z @ z0, -1, 1)))
    fig = Figure(figsize=(12, 4), layout="constrained")
    for panel, (a, b) in enumerate(((0, 1), (0, 2), (1, 2))):
        ax = fig.add_subplot(1, 3, panel + 1)
        sc = ax.scatter(p[:, a] * 1000, p[:, b] * 1000, c=tilt, s=8, cmap="viridis")
        ax.set_xlabel(f"{'xyz'[a]} [mm]")
        ax.set_ylabel(f"{'xyz'[b]} [mm]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    fig.colorbar(sc, ax=fig.axes, label="platform tilt from home [deg]")
    fig.suptitle(f"{m.name}: platform positions over the leg actuators' strokes "
                 f"({per_axis}³ configurations)", fontsize=9)
    save_figure(fig, path, dpi=110)
    return {"configurations": len(grid), "assembled": int(ok.sum()),
            "x": (float(p[:, 0].min()), float(p[:, 0].max())),
            "y": (float(p[:, 1].min()), float(p[:, 1].max())),
            "z": (float(p[:, 2].min()), float(p[:, 2].max())),
            "tilt_max_deg": float(tilt.max())}


def _plot_tilt(ows, path: Path) -> None:
    fig = Figure(figsize=(5.2, 5.2), layout="constrained")
    ax = fig.add_subplot(projection="polar")
    az = np.append(ows.azimuth, ows.azimuth[0])
    tilt = np.degrees(np.append(ows.max_tilt, ows.max_tilt[0]))
    ax.plot(az, tilt, "tab:blue")
    ax.fill(az, tilt, alpha=0.25)
    step = np.degrees(ows.resolution)
    ax.set_title(f"largest tilt per azimuth at home (torsion 0), grid {step:.1f}°", fontsize=9)
    save_figure(fig, path, dpi=120)


def _plot_tilt_map(gx, gy, tilt, path: Path) -> None:
    fig = Figure(figsize=(6.2, 5.2), layout="constrained")
    ax = fig.add_subplot()
    cs = ax.contourf(gx * 1000, gy * 1000, tilt, levels=20, cmap="viridis")
    ax.contour(gx * 1000, gy * 1000, tilt, levels=[0.5, 1, 2, 3], colors="w", linewidths=0.6)
    fig.colorbar(cs, ax=ax, label="platform tilt [deg]")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_aspect("equal")
    ax.set_title("Verne-type module: the tilt its rods impose at z = 0 (zero on x = 0)",
                 fontsize=9)
    save_figure(fig, path, dpi=120)


def _plot_modes(m, modes, path: Path) -> None:
    fig = Figure(figsize=(6.2, 5.6), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    count = int(modes.count)
    p = modes.poses[:count, :3]
    sign = modes.mode_sign[:count]
    for s, colour, label in ((1, "tab:blue", "det A > 0"), (-1, "tab:orange", "det A < 0")):
        sel = sign == s
        ax.scatter(*p[sel].T, color=colour, s=18, label=label)
    w = int(modes.working)
    ax.scatter(*p[w], color="crimson", marker="*", s=150, label="working mode")
    ax.set_title(f"Dietmaier's general hexapod: its {count} real assembly modes\n(platform "
                 "origins, m) for one set of strut lengths", fontsize=8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.legend(fontsize=7)
    save_figure(fig, path, dpi=120)


def _echo_full_pose(summary: dict[str, Any]) -> None:
    g, d, v = summary["gough-stewart"], summary["dietmaier"], summary["verne"]
    click.echo("\n== gough-stewart: Gough–Stewart hexapod (6-UPS)")
    for name, p in g["reference_poses"].items():
        click.echo(f"   {name:<8} q ({', '.join(f'{x:.4f}' for x in p['q'])}) m, round trip "
                   f"{p['round_trip']:.1e}, condition {p['condition']:.3f} ({p['status']})")
    click.echo(f"   constant-orientation workspace {g['workspace']['volume'] * 1e3:.1f} dm³ "
               f"(grid step {g['workspace']['resolution'] * 1000:.0f} mm), inscribed cube "
               f"{g['workspace']['inscribed_cube'] * 1000:.0f} mm; largest tilt at home "
               f"{g['max_tilt_deg']['min']:.1f}..{g['max_tilt_deg']['max']:.1f}° by azimuth")
    click.echo(f"   Dietmaier's general 6-6 platform: {d['real_modes']} real assembly modes of "
               f"{d['finite_solutions']} ({d['status']}), worst residual "
               f"{d['worst_residual']:.1e} m, {d['seconds']:.2f} s")
    click.echo("\n== verne: Verne-type module (3 slides, 6 rods)")
    click.echo(f"   tilt imposed by the rods: up to {v['tilt_deg']['max']:.2f}° over ±200 mm at "
               f"z = 0, {v['tilt_deg']['on_plane_x0']:.1e}° on the plane x = 0; "
               f"{v['assembly_modes_at_home']} real assembly modes at home")
