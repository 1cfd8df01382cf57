"""``pkmkit analyze``, ``map``, ``workspace`` and ``useful-workspace`` commands."""

from __future__ import annotations

import sys
from dataclasses import replace
from types import ModuleType

import click
import numpy as np

from pkmkit.analysis.chain_workspace import CHAIN_INDICES
from pkmkit.analysis.grids import PoseFrame
from pkmkit.analysis.indices import SCALAR_INDICES, index_values, indices
from pkmkit.analysis.inscribed import DEFAULT_RTOL as INSCRIBED_RTOL
from pkmkit.analysis.joint_space import useful_workspace
from pkmkit.analysis.workspace import (
    Criteria,
    WorkspaceMap,
    check_region,
    check_region_samples,
    compute_workspace,
)
from pkmkit.boundary.coordinates import (
    actuator_scales,
    actuator_units,
    parse_pose,
    pose_from_cli,
    pose_to_cli,
)
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible
from pkmkit.stiffness.indices import STIFFNESS_INDICES
from pkmkit.stiffness.results import linear_range_problem

from .grid_options import (
    _coordinates,
    build_grid,
    enclosing_frame,
    machine_frame,
    parse_bounds,
    parse_orientation,
    parse_slice,
)
from .options import (
    ANGLES_OPTION,
    JSON_OPTION,
    SET_OPTION,
    UNITS_OPTION,
    emit_json,
    fmt,
    resolve_machine,
)
from .scheduler import SCHEDULER_OPTION
from .stiffness_cmds import PER_MICRO, machine_and_data, parse_wrench
from .stiffness_options import (
    MAX_DEFLECTION_OPTION,
    MIN_STIFFNESS_OPTION,
    WRENCH_OPTION,
    analyze_stiffness,
    criteria_fields,
    print_workspace_stiffness,
    stiffness_criteria,
    stiffness_map_values,
    workspace_stiffness,
)


def _maps() -> ModuleType:
    """:mod:`pkmkit.plot.maps`, imported when a figure is asked for (matplotlib: ≈ 0.3–0.6 s of
    a fresh process otherwise spent by every ``workspace`` and ``analyze``)."""
    from pkmkit.plot import maps

    return maps


BOUNDS_OPTION = click.option(
    "--bounds", metavar="LO,HI",
    help="Bounds on every velocity transmission factor, e.g. 0.5,2.")
KAPPA_OPTION = click.option("--kappa-max", type=float, help="Largest admissible condition number.")
ORIENTATION_OPTION = click.option(
    "--orientation", "orientation_text", metavar="A,B,C|I,J,K",
    help="Orientation held over the grid (default: home): angles in degrees (--angles "
         "convention) for a full-pose machine, the tool axis for a joint-chain machine.")
RESOLUTION_OPTION = click.option(
    "--resolution", type=click.IntRange(5, 2001), default=None,
    help="Grid points along the longest side (default 201 in 2-D, 61 in 3-D).")

# The family dispatch tables of these commands (the rest reads the machine protocol).
#: ``analyze`` reads rod machines' A and B matrices: the families it refuses, and why.
_ANALYZE_REFUSED = {
    "chain": ("analyze reads rod machines' A and B matrices; for the joint-chain machine "
              "{id!r} run `pkmkit jacobian {name} --pose X,Y,Z,I,J,K` (or --q): its Jacobian, "
              "singular values, condition number and closure rank")}
#: ``map``: the indices of the families that do not have them all.
_MAP_INDICES = {"chain": (*CHAIN_INDICES, *STIFFNESS_INDICES, "actuators")}
#: ``workspace``: the inscribed box's relative tolerance where it is not refined (joint chains:
#: no smooth slack, the grid box only).
_INSCRIBED_RTOLS = {"chain": None}


def _criteria(bounds, kappa_max, no_strokes, whole_grid: bool = False) -> Criteria:
    if kappa_max is not None and not (np.isfinite(kappa_max) and kappa_max >= 1):
        raise InputError(f"--kappa-max must be a condition number >= 1, got {kappa_max:g}")
    check_plausible("--kappa-max", kappa_max, "condition")
    return Criteria(bounds=parse_bounds(bounds), kappa_max=kappa_max, strokes=not no_strokes,
                    whole_grid=whole_grid)


def register(cli: click.Group) -> None:
    """Add the analysis commands to the ``pkmkit`` group."""
    cli.add_command(analyze)
    cli.add_command(map_cmd)
    cli.add_command(workspace)
    cli.add_command(useful_workspace_cmd)


@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Platform position X,Y[,Z], or X,Y,Z,A,B,C for a full-pose machine "
              "(angles in degrees, --angles convention; default: the home pose).")
@click.option("--isotropy-tol", type=float, default=1e-9, show_default=True,
              help="The pose counts as isotropic when κ ≤ 1 + this tolerance.")
@click.option("--stiffness", "with_stiffness", is_flag=True,
              help="Add the translational eigen-stiffnesses (N/µm; --set "
                   "actuator_stiffness=... as for `pkmkit stiffness`).")
@WRENCH_OPTION
@ANGLES_OPTION
@UNITS_OPTION
@JSON_OPTION
def analyze(machine_name, assignments, pose, isotropy_tol, with_stiffness, wrench_text,
            convention, units, as_json):
    """All kinetostatic indices at a pose: transmission factors, conditioning, ellipsoid,
    distances to singularities.

    With --stiffness (or --wrench), the stiffness and the deflection."""
    m, data = machine_and_data(machine_name, assignments, units)
    refusal = _ANALYZE_REFUSED.get(m.family)
    if refusal is not None:
        raise InputError(refusal.format(id=m.id, name=machine_name))
    scale = length_scale(units)
    if not (np.isfinite(isotropy_tol) and isotropy_tol >= 0):
        raise InputError(f"--isotropy-tol must be a finite number >= 0, got {isotropy_tol}")
    check_plausible("--isotropy-tol", isotropy_tol, "ratio")
    if pose is None:
        x = m.home_pose
    else:
        x = pose_from_cli(parse_pose(pose, m, "--pose", units), m, units,
                          convention)[0]
    shown = x / scale if x.size <= 3 else pose_to_cli(x, m, units, convention)[0]
    ind = indices(m, x, ellipsoids=True, isotropy_tol=isotropy_tol)
    jac = m.jacobian(x)
    q_units = actuator_units(m, units)  # a crank's angle in degrees, not in the length unit
    payload = {
        "machine": m.id, "units": units, "pose": shown, "q": jac.q / actuator_scales(m, units),
        "actuator_units": q_units,
        "velocity_factors": ind.velocity_factors, "force_factors": ind.force_factors,
        "condition": ind.condition, "inverse_condition": ind.inverse_condition,
        "isotropic": bool(ind.isotropic), "isotropy_tol": isotropy_tol,
        "ellipsoid": {"axes": ind.ellipsoid_axes, "directions": ind.ellipsoid_directions},
        "parallel_distance": ind.parallel_distance, "serial_distance": ind.serial_distance,
        "manipulability": float(np.prod(ind.velocity_factors)),
        "det_A": jac.det_A / scale ** m.n_actuators, "det_B": jac.det_B / scale ** m.n_actuators,
        "status": jac.status,
    }
    lines: list[str] = []
    if with_stiffness or wrench_text is not None:
        wrench, note = parse_wrench(wrench_text, m)
        payload["stiffness"] = analyze_stiffness(m, data, x, wrench, units)
        lines = payload["stiffness"].pop("lines") + ([f"  note: {note}"] if note else [])
    doubtful = payload.get("stiffness", {}).get("beyond_linear_range")
    if as_json:
        emit_json(payload)
        _doubtful(doubtful)
        return
    angles = f" (angles {convention}, deg)" if len(shown) == 6 else ""
    q_text = (f"{fmt(payload['q'])} {q_units[0]}" if len(set(q_units)) == 1 else
              "[" + ", ".join(f"{v:.6g} {u}" for v, u in zip(payload["q"], q_units,
                                                          strict=True)) + "]")
    click.echo(f"{m.name}: pose {fmt(shown)} {units}{angles}, q {q_text}")
    click.echo(f"  velocity transmission factors: {fmt(ind.velocity_factors)}")
    click.echo(f"  force transmission factors:    {fmt(ind.force_factors)}")
    click.echo(f"  condition number {_condition_text(float(ind.condition))} (inverse "
               f"{fmt(ind.inverse_condition)}), isotropic: {bool(ind.isotropic)} (κ ≤ 1 + "
               f"{isotropy_tol:g})")
    click.echo(f"  distance to parallel singularity {fmt(ind.parallel_distance)}, to serial "
               f"singularity {fmt(ind.serial_distance)}; status {jac.status}")
    for k in range(len(ind.ellipsoid_axes)):
        click.echo(f"  ellipsoid axis {k + 1}: {ind.ellipsoid_axes[k]:.6g} along "
                   f"{fmt(ind.ellipsoid_directions[:, k])}")
    for line in lines:
        click.echo(line)
    _doubtful(doubtful)


def _doubtful(problem: str | None) -> None:
    """Exit with status 3 after the output when the deflection is doubtful."""
    if problem:
        click.echo(f"doubtful: {problem}", err=True)
        sys.exit(3)


def _condition_text(kappa: float) -> str:
    """κ with the digits that matter: ``1 + 3.4e-09`` when it differs from 1 below the
    display precision, so that the isotropy verdict and the number agree."""
    if np.isfinite(kappa) and 0 < kappa - 1 < 1e-4:
        return f"1 + {kappa - 1:.2g}"
    return fmt(kappa)


@click.command("map")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--index", "index_name", required=True,
              type=click.Choice([*SCALAR_INDICES, *STIFFNESS_INDICES, "actuators"]),
              help="Index to map ('actuators' maps every actuator coordinate; 'stiffness' the "
                   "smallest translational stiffness in N/µm, 'deflection' the deflection "
                   "under --wrench in µm).")
@click.option("--slice", "slice_text", help="Plane of a spatial machine, e.g. z=0.2.")
@click.option("--range", "range_text", metavar="AMIN,AMAX,BMIN,BMAX",
              help="Extent of the two free coordinates (default: the machine's box).")
@ORIENTATION_OPTION
@ANGLES_OPTION
@RESOLUTION_OPTION
@click.option("--scale", "color_scale", type=click.Choice(["auto", "linear", "log"]),
              default="auto", show_default=True,
              help="Colour levels: log when the values span more than a decade (auto); "
              "values far above the 95th percentile (near a singularity) take the top colour.")
@click.option("--out", "out", required=True, type=click.Path(dir_okay=False),
              help="Figure file (.png, .svg, .pdf).")
@WRENCH_OPTION
@SCHEDULER_OPTION
@UNITS_OPTION
@JSON_OPTION
def map_cmd(machine_name, assignments, index_name, slice_text, range_text, orientation_text,
            convention, resolution, color_scale, out, wrench_text, scheduler, units, as_json):
    """Iso-contours of an index (or actuator coordinates) over a plane."""
    _maps().check_figure_path(out)
    m, data = machine_and_data(machine_name, assignments, units)
    scale = length_scale(units)
    wrench, _ = parse_wrench(wrench_text, m)
    if (index_name == "deflection") != (wrench is not None):
        raise InputError("--index deflection and --wrench FX,FY,FZ[,MX,MY,MZ] go together")
    allowed = _MAP_INDICES.get(m.family)
    if allowed is not None and index_name not in allowed:
        raise InputError(f"index {index_name!r} is not defined for a joint-chain machine; its "
                         f"indices: {', '.join(allowed)}")
    frame = machine_frame(m, parse_orientation(m, orientation_text, convention))
    if frame.positions == 3 and slice_text is None:
        raise InputError("a spatial machine needs --slice NAME=VALUE (e.g. --slice z=0)")
    slice_ = parse_slice(frame, slice_text, scale)
    if range_text is None:  # the default box, widened to hold the plane's workspace
        frame = enclosing_frame(m, frame, Criteria(), slice_, scale, scheduler, resolution)[0]
    grid = build_grid(frame, range_text, slice_, scale, resolution)
    points = grid.points
    q = m.ik(points)
    reachable = np.isfinite(q).all(axis=1)
    if not reachable.any():
        raise InputError("no point of this plane is reachable; change --slice or --range")
    summary = {"machine": m.id, "units": units, "index": index_name, "figure": out,
               "plane": list(grid.free_names), "reachable_points": int(reachable.sum()),
               "points": grid.size, "step": grid.step / scale}
    if index_name == "actuators":
        _maps().plot_actuator_maps(m, grid, unit=units, path=out)
        summary["min"] = np.nanmin(q, axis=0) / scale
        summary["max"] = np.nanmax(q, axis=0) / scale
    else:
        if index_name in STIFFNESS_INDICES:
            values, label, title = stiffness_map_values(m, points, index_name, data, wrench,
                                                        summary)
        else:
            values = index_values(m, points, index_name, scheduler=scheduler)
            label, title = index_name, SCALAR_INDICES[index_name]
        finite = np.isfinite(values)
        if not finite.any():
            raise InputError(f"{index_name} is undefined on every reachable point of the plane")
        _maps().plot_scalar_map(grid, values.reshape(grid.shape),
                                title=f"{m.name}: {title}", label=label, scale=color_scale,
                                unit=units, path=out)
        k_min, k_max = np.nanargmin(values), np.nanargmax(values)
        summary.update({"min": float(values[k_min]), "at_min": points[k_min] / scale,
                        "max": float(values[k_max]), "at_max": points[k_max] / scale})
    doubtful = ""
    if index_name == "deflection":  # µm: the largest against the linear model's range
        worst = np.zeros(len(wrench))
        worst[0] = summary["max"] / PER_MICRO
        doubtful = linear_range_problem(worst, m.length_scale, units)
        if doubtful:
            summary["beyond_linear_range"] = doubtful
    if as_json:
        emit_json(summary)
        _doubtful(doubtful)
        return
    click.echo(f"{m.name}: {index_name} over {'-'.join(grid.free_names)} "
               f"({summary['reachable_points']}/{grid.size} points reachable)")
    unit = f" {summary['index_unit']}" if "index_unit" in summary else ""
    click.echo(f"  min {fmt(summary['min'])}{unit}, max {fmt(summary['max'])}{unit} over the "
               f"grid points (step {summary['step']:.4g} {units}: not between them); figure "
               f"{out}")
    _doubtful(doubtful)


def workspace_summary(m: Machine, wmap: WorkspaceMap, scale: float, units: str) -> dict:
    """JSON-ready summary of a workspace map (lengths in ``units``)."""
    grid = wmap.grid
    two_d = len(grid.free) == 2
    box = wmap.inscribed
    crit = wmap.criteria
    factor_box = wmap.factor_range()
    p = min(grid.base.size, 3)  # the position coordinates (the orientation is held)
    summary = {
        "machine": m.id, "units": units,
        "grid": {"free": list(grid.free_names),
                 "lower": [float(a[0]) / scale for a in grid.axes],
                 "upper": [float(a[-1]) / scale for a in grid.axes],
                 "step": grid.step / scale, "shape": list(grid.shape),
                 "fixed": {grid.names[k]: float(grid.base[k]) / scale
                           for k in range(min(grid.base.size, 3)) if k not in grid.free}},
        "criteria": {"bounds": crit.bounds, "kappa_max": crit.kappa_max,
                     "strokes": crit.strokes, "connected": crit.connected},
        ("area" if two_d else "volume"): wmap.measure / scale ** len(grid.free),
        "feasible_points": int(wmap.feasible.sum()),
        # after a flood fill from home, over the points evaluated (not the whole grid)
        "points_per_criterion": wmap.criteria_counts,
        "points_evaluated": wmap.points_evaluated,
        "evaluation": "whole grid" if wmap.evaluated is None else "flood fill from home",
        "reference": wmap.reference,
        "faces_reached": wmap.faces_reached(),
        "inscribed": None if box is None else {
            "side": box.side / scale, "center": box.center[:p] / scale,
            "lower": box.lower[:p] / scale,
            "rtol": _INSCRIBED_RTOLS.get(m.family, INSCRIBED_RTOL),
            "samples_per_edge": check_region_samples(len(grid.free))},
        "index_range": list(factor_box),
        "workspace_index_range": list(wmap.factor_range(wmap.feasible)),
        "global_conditioning_index": wmap.global_conditioning_index(),
    }
    if wmap.inscribed_check is not None:
        q_lo, q_hi = wmap.inscribed_check.q_range
        summary["inscribed"]["q_min"] = q_lo / scale
        summary["inscribed"]["q_max"] = q_hi / scale
        summary["inscribed"]["verified"] = wmap.inscribed_check.feasible
    return summary


@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@BOUNDS_OPTION
@KAPPA_OPTION
@click.option("--box", "box_text", metavar="XMIN,XMAX,YMIN,YMAX[,ZMIN,ZMAX]",
              help="Region studied (default: the machine's box).")
@click.option("--slice", "slice_text", help="Study a plane of a spatial machine, e.g. z=0.")
@ORIENTATION_OPTION
@ANGLES_OPTION
@click.option("--no-strokes", is_flag=True, help="Ignore the actuator strokes.")
@click.option("--whole-grid", is_flag=True,
              help="Evaluate every grid point (joint chains are otherwise evaluated by a flood "
                   "fill from home: the same workspace, fewer points evaluated).")
@click.option("--cube", "cube", type=float, metavar="SIDE",
              help="Check a prescribed square/cube of this side (needs --center).")
@click.option("--center", "center_text", help="Centre X,Y[,Z] of the prescribed square/cube.")
@MIN_STIFFNESS_OPTION
@MAX_DEFLECTION_OPTION
@WRENCH_OPTION
@click.option("--stiffness", "with_stiffness", is_flag=True,
              help="Report the smallest translational stiffness over the workspace (N/µm).")
@RESOLUTION_OPTION
@click.option("--out", "out", type=click.Path(dir_okay=False), help="Figure file.")
@SCHEDULER_OPTION
@UNITS_OPTION
@JSON_OPTION
def workspace(machine_name, assignments, bounds, kappa_max, box_text, slice_text,
              orientation_text, convention, no_strokes, whole_grid, cube, center_text,
              min_stiffness, max_deflection, wrench_text, with_stiffness, resolution, out,
              scheduler, units, as_json):
    """Workspace over a box or a plane: area/volume, largest inscribed square/cube, transmission
    factors inside it, global conditioning index, and (with --cube/--center) whether a
    prescribed one is feasible (in the --slice plane when one is given).

    With --min-stiffness, --max-deflection or --wrench, stiffness is a criterion or a figure
    (docs/stiffness.md)."""
    if out is not None:
        _maps().check_figure_path(out)
    m, data = machine_and_data(machine_name, assignments, units)
    scale = length_scale(units)
    elastic, _ = stiffness_criteria(m, data, min_stiffness, max_deflection, wrench_text)
    criteria = replace(_criteria(bounds, kappa_max, no_strokes, whole_grid), **elastic)
    frame = machine_frame(m, parse_orientation(m, orientation_text, convention))
    slice_ = parse_slice(frame, slice_text, scale)
    grid = build_grid(frame, box_text, slice_, scale, resolution)
    center = None
    if cube is not None or center_text is not None:
        if cube is None or center_text is None:
            raise InputError("--cube and --center go together")
        if not (np.isfinite(cube) and cube > 0):
            raise InputError(f"--cube must be a side > 0, got {cube:g}")
        center = _region_center(frame, center_text, slice_, scale)
    widened = 0
    if box_text is None:
        frame, widened = enclosing_frame(m, frame, criteria, slice_, scale, scheduler,
                                         resolution)
        grid = build_grid(frame, None, slice_, scale, resolution)
    wmap = compute_workspace(m, grid, criteria, refine=True, scheduler=scheduler)
    if not wmap.masks["reachable"].any():
        raise InputError("no pose of the box is reachable; choose another --box or --slice")
    if not wmap.feasible.any():
        counts = ", ".join(f"{k} {v}" for k, v in wmap.criteria_counts.items())
        raise InputError(f"no pose of the box satisfies every criterion (points passing each: "
                         f"{counts} of {wmap.points_evaluated} evaluated)")
    summary = workspace_summary(m, wmap, scale, units)
    summary["grid"]["default_box_widened"] = widened
    summary["criteria"].update(criteria_fields(criteria))
    if with_stiffness or elastic:
        summary["stiffness"] = workspace_stiffness(m, wmap, data, scale)
    if frame.positions < len(frame.base):
        summary["orientation"] = _orientation_fields(m, frame, convention)
    if center is not None:
        check = check_region(m, center, cube * scale, criteria, free=grid.free)
        per_edge = check_region_samples(len(grid.free))
        summary["check"] = {"side": cube, "center": center / scale, "feasible": check.feasible,
                            "samples": check.samples, "samples_per_edge": per_edge,
                            "spacing": cube / (per_edge - 1), "failures": check.failures,
                            "worst": check.worst, "index_range": list(check.factor_range),
                            "q_min": check.q_range[0] / scale, "q_max": check.q_range[1] / scale}
    if out is not None:
        _maps().plot_workspace(wmap, m, unit=units, path=out)
        summary["figure"] = out
    if as_json:
        emit_json(summary)
        return
    _print_workspace(m, summary, units)


def _region_center(frame: PoseFrame, text: str, slice_: tuple[int, float] | None,
                   scale: float) -> np.ndarray:
    """``--center``: every position coordinate, or with ``--slice`` the free ones only; a full
    centre must lie in the slice plane (the square is checked in that plane). The orientation
    is the frame's."""
    values = _coordinates(text, "--center", scale)
    p = frame.positions
    center = frame.base.copy()
    if slice_ is None:
        if values.size != p:
            raise InputError(f"--center needs {p} comma-separated values, got {values.size}")
        center[:p] = values
        return center
    axis, value = slice_
    free = [k for k in range(p) if k != axis]
    name = frame.names[axis]
    if values.size == p:
        if not np.isclose(values[axis], value, rtol=1e-12, atol=1e-12):
            raise InputError(f"--center {name} = {values[axis] / scale:g} is not in the --slice "
                             f"plane {name} = {value / scale:g}; give the plane's value or only "
                             f"the {len(free)} in-plane coordinates")
        center[:p] = values
        center[axis] = value
        return center
    if values.size != len(free):
        raise InputError(f"--center with --slice needs the {len(free)} in-plane coordinates "
                         f"({', '.join(frame.names[k] for k in free)}) or all {p}, got "
                         f"{values.size}")
    center[free] = values
    center[axis] = value
    return center


def _orientation_fields(m, frame: PoseFrame, convention: str) -> dict:
    """JSON fields of the orientation a grid holds."""
    held = frame.base[frame.positions:]
    if m.pose_orientation == "axis":
        return {"tool_axis": held}
    from pkmkit.spatial.poses import pose_to_angles

    angles = pose_to_angles(frame.base, convention, degrees=True)[1]
    return {"rotation_vector": held, "angles_deg": np.asarray(angles).ravel(),
            "convention": convention}


def _print_workspace(m: Machine, s: dict, units: str) -> None:
    what = "area" if "area" in s else "volume"
    power = 2 if what == "area" else 3
    click.echo(f"{m.name}: workspace over {'-'.join(s['grid']['free'])} "
               f"(step {s['grid']['step']:.4g} {units}, kept: {s['reference']})")
    if s["grid"].get("default_box_widened"):
        g = s["grid"]
        click.echo(f"  default box widened {g['default_box_widened']} time(s) to hold the "
                   f"workspace: {fmt(g['lower'])} to {fmt(g['upper'])} {units}")
    flood = ("" if s["evaluation"] == "whole grid" else
             f"; {s['points_evaluated']} evaluated, by a flood fill from home")
    click.echo(f"  {what}: {s[what]:.6g} {units}^{power} "
               f"({s['feasible_points']} of {int(np.prod(s['grid']['shape']))} points{flood})")
    if "orientation" in s:
        o = s["orientation"]
        held = (f"tool axis {fmt(o['tool_axis'])}" if "tool_axis" in o else
                f"angles ({o['convention']}) {fmt(o['angles_deg'])} deg")
        click.echo(f"  orientation held over the grid: {held}")
    if s["faces_reached"]:
        click.echo(f"  the workspace reaches the box's faces {', '.join(s['faces_reached'])}: "
                   f"it extends beyond the box studied (widen --box); the {what} is a lower "
                   "bound")
    box = s["inscribed"]
    if box is None:
        click.echo("  no inscribed square/cube")
    else:
        how = ("on the grid, within one step" if box["rtol"] is None else
               f"centre and side refined to {box['rtol']:.0e} of the side")
        click.echo(f"  largest inscribed {'square' if power == 2 else 'cube'}: side "
                   f"{box['side']:.6g} {units}, centre {fmt(box['center'])} {units} ({how}, "
                   f"{box['samples_per_edge']} checks per edge)")
        click.echo(f"  transmission factors inside it: {fmt(s['index_range'])}")
    click.echo(f"  transmission factors over the workspace: {fmt(s['workspace_index_range'])}")
    click.echo(f"  global conditioning index (mean 1/κ over the workspace): "
               f"{fmt(s['global_conditioning_index'], 4)}")
    click.echo(f"  the {what}, the factors over the workspace and the GCI hold at the grid's "
               f"resolution ({s['grid']['step']:.4g} {units}): a feature narrower than a step "
               "can lie between grid points")
    if "check" in s:
        c = s["check"]
        verdict = "feasible" if c["feasible"] else "NOT feasible"
        click.echo(f"  prescribed side {c['side']:g} {units} at {fmt(c['center'])}: {verdict} "
                   f"({c['samples']} samples, {c['samples_per_edge']} per edge every "
                   f"{c['spacing']:.4g} {units}; factors {fmt(c['index_range'])})")
        for name, text in c["worst"].items():
            click.echo(f"    {name}: {c['failures'][name]} samples fail; worst {text}")
    if "stiffness" in s:
        print_workspace_stiffness(s["stiffness"], units, s["criteria"])
    if "figure" in s:
        click.echo(f"  figure {s['figure']}")


@click.command("useful-workspace")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@BOUNDS_OPTION
@KAPPA_OPTION
@click.option("--anywhere", is_flag=True,
              help="Largest joint square anywhere instead of centred at the home configuration.")
@click.option("--resolution", type=click.IntRange(5, 2001), default=None,
              help="Grid points along the longest side, in joint space and in the workspace "
              "(default 301 with 2 actuators, 41 with 3).")
@click.option("--out", "out", type=click.Path(dir_okay=False),
              help="Figure file (2 actuators).")
@UNITS_OPTION
@JSON_OPTION
def useful_workspace_cmd(machine_name, assignments, bounds, kappa_max, anywhere, resolution,
                         out, units, as_json):
    """Seed 004's procedure: a square of actuator values satisfying the criteria (the useful
    zone), its image (the useful workspace) and the square inscribed in it; with 3 actuators,
    cubes. The transmission-factor range over the useful workspace is exact (extremes over the
    joint square refined by optimisation)."""
    if out is not None:
        _maps().check_figure_path(out)
    m = resolve_machine(machine_name, assignments, units)
    n = m.n_actuators
    if n not in (2, 3):
        raise InputError(f"useful-workspace needs 2 or 3 actuators, {m.id} has {n}")
    if out is not None and n != 2:
        raise InputError("--out draws joint-space squares: it needs 2 actuators (planar "
                         "machines); drop --out for a 3-actuator machine")
    scale = length_scale(units)
    criteria = Criteria(bounds=parse_bounds(bounds),
                        kappa_max=check_plausible("--kappa-max", kappa_max, "condition"))
    useful = useful_workspace(m, criteria, centred=not anywhere,
                              resolution=resolution or (301 if n == 2 else 41))
    sq, box = useful.joint_square, useful.inscribed
    shape = "square" if n == 2 else "cube"
    d = len(useful.workspace.grid.free)  # positions (the orientation of a module follows)
    measure_key = "useful_area" if d == 2 else "useful_volume"
    summary = {
        "machine": m.id, "units": units, "criteria": {"bounds": criteria.bounds,
                                                      "kappa_max": kappa_max},
        "joint_square": {"side": sq.side / scale, "q_min": sq.lower / scale,
                         "q_max": (sq.lower + sq.side) / scale, "centred": not anywhere},
        measure_key: useful.workspace.measure / scale**d,
        "inscribed": None if box is None else {"side": box.side / scale,
                                               "center": box.center / scale},
        "index_range": list(useful.factor_range),
        "inscribed_index_range": list(useful.inscribed_factor_range),
        "global_conditioning_index": useful.workspace.global_conditioning_index(),
    }
    if out is not None:
        _maps().plot_useful_workspace(useful, m, unit=units, path=out)
        summary["figure"] = out
    if as_json:
        emit_json(summary)
        return
    what = "area" if d == 2 else "volume"
    click.echo(f"{m.name}: useful zone = actuator {shape} of side {sq.side / scale:.6g} {units} "
               f"from {fmt(sq.lower / scale)}")
    click.echo(f"  useful workspace: {what} {summary[measure_key]:.6g} {units}^{d}, "
               f"transmission factors {fmt(useful.factor_range)}, GCI "
               f"{fmt(summary['global_conditioning_index'], 4)}")
    if box is not None:
        click.echo(f"  inscribed {shape}: side {box.side / scale:.6g} {units}, centre "
                   f"{fmt(box.center / scale)}, factors {fmt(useful.inscribed_factor_range)} "
                   f"(centre and side to {INSCRIBED_RTOL:.0e} of the side)")
    else:
        click.echo(f"  no inscribed {shape} on this grid; raise --resolution")
    if out is not None:
        click.echo(f"  figure {out}")
