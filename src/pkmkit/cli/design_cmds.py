"""``pkmkit design orthoglide|five-bar|linear-delta`` and ``pkmkit optimize``.

Values on the command line and in every output are in command-line units: lengths in ``--units``
(m or mm), areas in its square, angles in degrees; outputs name their units.
"""

from __future__ import annotations

import json

import click
import numpy as np

from pkmkit.analysis.workspace import Criteria
from pkmkit.design.design_space import boundary_factor, scalar_parameters
from pkmkit.design.five_bar import isotropic_orientations, size_five_bar
from pkmkit.design.linear_delta import OBJECTIVES as DELTA_OBJECTIVES
from pkmkit.design.linear_delta import size_linear_delta
from pkmkit.design.metrics import METRIC_QUANTITIES, METRICS, Region
from pkmkit.design.optimize import (
    Constraint,
    DesignProblem,
    Objective,
    Variable,
    optimize,
)
from pkmkit.design.orthoglide import size_orthoglide
from pkmkit.exceptions import InputError, PkmError
from pkmkit.io.atomic import check_output_dir
from pkmkit.io.json_io import to_jsonable
from pkmkit.io.sized_machine import box_corners, check_destination, write_sized_machine
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible

from .analysis_cmds import BOUNDS_OPTION, KAPPA_OPTION, parse_bounds
from .options import (
    JSON_OPTION,
    SET_OPTION,
    UNITS_OPTION,
    check_each,
    emit_json,
    fmt,
    parse_vector,
)
from .scheduler import SCHEDULER_OPTION
from .stiffness_cmds import machine_and_data


def _verified(check) -> dict:
    """The brute-force verification of a sizing, for JSON."""
    return {"feasible": check.feasible, "samples": check.samples,
            "index_range": list(check.factor_range)}


def register(cli: click.Group) -> None:
    """Add the design commands to the ``pkmkit`` group."""
    cli.add_command(design)
    cli.add_command(optimize_cmd)


def _required_bounds(text: str | None) -> tuple[float, float]:
    bounds = parse_bounds(text)
    if bounds is None:
        raise InputError("--bounds LO,HI is required")
    return bounds


def _max_leg(value: float | None, scale: float, units: str) -> float | None:
    """``--max-leg`` in m (None when not given); must be a positive finite number."""
    if value is None:
        return None
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"--max-leg must be a positive length, got {value:g}")
    check_plausible("--max-leg", value, "length", scale=scale, unit=units)
    return value * scale


MACHINE_OUT_OPTION = click.option(
    "--out", "machine_out", type=click.Path(dir_okay=False), metavar="FILE.toml",
    help="Also write the sized machine as a machine file (lengths in --units) that "
         "`pkmkit.load` and every --machine option read back.")


def _write_machine(path: str | None, machine, center, side: float, units: str,
                   name: str, command: str) -> str | None:
    """Write the sized ``machine`` to ``path`` (if given), checked at home and at the corners of
    the sized region (``center``, ``side`` in m), with ``name`` and the ``command`` that sized
    it as its source; the path written, or None."""
    if path is None:
        return None
    poses = np.vstack([machine.home_pose, box_corners(center, side)])
    write_sized_machine(path, machine, poses, units=units, name=name, source=command)
    return path


def _echo_notes(notes) -> None:
    for note in notes:
        click.echo(f"  note: {note}")


@click.group()
def design() -> None:
    """Sizing rules: the Orthoglide for a cube, the isotropic five-bar for a square, the linear
    Delta for a cube."""


@design.command("orthoglide")
@click.option("--cube", "cube", type=float, required=True, help="Prescribed cube side Lw.")
@BOUNDS_OPTION
@click.option("--max-leg", type=float, help="Largest admissible leg length.")
@MACHINE_OUT_OPTION
@UNITS_OPTION
@JSON_OPTION
def design_orthoglide(cube, bounds, max_leg, machine_out, units, as_json):
    """Seed 001's rule: Q1, Q2 on the diagonal, leg length, slider positions and strokes,
    compactness — verified over the whole cube."""
    scale = length_scale(units)
    lo, hi = _required_bounds(bounds)
    if machine_out is not None:
        check_destination(machine_out)
    res = size_orthoglide(cube * scale, (lo, hi), max_leg=_max_leg(max_leg, scale, units))
    written = _write_machine(
        machine_out, res.machine, 0.5 * (res.Q1 + res.Q2), res.cube_side, units,
        f"Orthoglide for a {cube:g} {units} cube",
        f"pkmkit design orthoglide --cube {cube:g} --bounds {lo:g},{hi:g} --units {units}")
    payload = {
        "cube": cube, "bounds": [lo, hi], "units": units,
        "L": res.L / scale, "stroke": res.stroke / scale, "compactness": res.compactness,
        "side_over_L": res.side_over_L, "Q1": res.Q1 / scale, "Q2": res.Q2 / scale,
        "q_min": res.q_min / scale, "q_max": res.q_max / scale,
        "verified": _verified(res.check),
        "notes": list(res.notes),
        "machine_file": written,
    }
    if as_json:
        emit_json(payload)
        return
    click.echo(f"Orthoglide for a {cube:g} {units} cube with transmission factors in "
               f"[{lo:g}, {hi:g}]:")
    click.echo(f"  Q1 = {fmt(payload['Q1'])} {units}, Q2 = {fmt(payload['Q2'])} {units}")
    click.echo(f"  leg length L = {payload['L']:.6g} {units}")
    click.echo(f"  sliders from {fmt(payload['q_min'])} to {fmt(payload['q_max'])} {units}: "
               f"stroke {payload['stroke']:.6g} {units}")
    click.echo(f"  compactness Lw/stroke = {res.compactness:.4f}, Lw/L = {res.side_over_L:.4f}")
    click.echo(f"  verified on {res.check.samples} poses of the cube: factors in "
               f"{fmt(res.check.factor_range)}")
    _echo_notes(res.notes)
    _echo_written(written)


def _echo_written(path: str | None) -> None:
    if path is not None:
        click.echo(f"  machine file: {path}")


@design.command("five-bar")
@click.option("--square", "square", type=float, required=True, help="Prescribed square side.")
@BOUNDS_OPTION
@click.option("--design", "design_name", type=click.Choice(["isotropic", "biglide", "both"]),
              default="both", show_default=True)
@MACHINE_OUT_OPTION
@UNITS_OPTION
@JSON_OPTION
def design_five_bar(square, bounds, design_name, machine_out, units, as_json):
    """Seed 004's isotropic design (slide orientations from J⁻¹ = I) sized for a square
    workspace, compared with the biglide of the same size."""
    scale = length_scale(units)
    lo, hi = _required_bounds(bounds)
    if machine_out is not None and design_name == "both":
        raise InputError("--out writes one machine: choose --design isotropic or biglide")
    if machine_out is not None:
        check_destination(machine_out)
    names = ["isotropic", "biglide"] if design_name == "both" else [design_name]
    results, failed, written = {}, {}, None
    for name in names:
        try:
            res = size_five_bar(square * scale, (lo, hi), design=name)
        except PkmError as exc:
            if design_name != "both":
                raise
            failed[name] = str(exc)
            continue
        written = _write_machine(
            machine_out, res.machine, res.square_center, square * scale, units,
            f"{name} five-bar for a {square:g} {units} square",
            f"pkmkit design five-bar --square {square:g} --bounds {lo:g},{hi:g} "
            f"--design {name} --units {units}")
        results[name] = {
            "feasible": True,
            "L": res.L / scale, "A": res.A / scale, "B": res.B / scale,
            "alpha": np.degrees([res.machine.params["alpha1"], res.machine.params["alpha2"]]),
            "q_min": res.q_min / scale, "q_max": res.q_max / scale,
            "stroke": res.stroke / scale, "square_center": res.square_center / scale,
            "verified": _verified(res.check),
            "notes": list(res.notes),
        }
    if not results:  # both designs fail: say why for each
        raise InputError("; ".join(f"{k}: {v}" for k, v in failed.items()))
    designs = {**results, **{k: {"feasible": False, "reason": v} for k, v in failed.items()}}
    payload = {"square": square, "bounds": [lo, hi], "units": units, "angle_unit": "deg",
               "isotropic_orientations_deg": isotropic_orientations(), "designs": designs,
               "machine_file": written}
    if as_json:
        emit_json(payload)
        return
    click.echo(f"five-bar for a {square:g} {units} square with transmission factors in "
               f"[{lo:g}, {hi:g}]")
    click.echo(f"  J⁻¹ = I is possible only for (α1, α2) = "
               f"{payload['isotropic_orientations_deg']} degrees")
    for name, r in results.items():
        click.echo(f"  {name}: L = {r['L']:.6g} {units}, A = {fmt(r['A'])} {units}, B = "
                   f"{fmt(r['B'])} {units}, α = {fmt(r['alpha'])} deg")
        click.echo(f"    joint stops {fmt(r['q_min'])} .. {fmt(r['q_max'])} {units} (stroke "
                   f"{r['stroke']:.6g} {units}); square centred at {fmt(r['square_center'])} "
                   f"{units}; verified factors {fmt(r['verified']['index_range'])}")
        _echo_notes(r["notes"])
    for name, reason in failed.items():
        click.echo(f"  {name}: infeasible — {reason}")
    _echo_written(written)


@design.command("linear-delta")
@click.option("--cube", "cube", type=float, required=True, help="Prescribed cube side Lw.")
@click.option("--center", "center_text", metavar="X,Y,Z",
              help="Centre of the cube (default 0,0,Lw/2: the cube stands on z = 0 under the "
                   "centre of the slides).")
@BOUNDS_OPTION
@click.option("--r", "nacelle", type=float,
              help="Nacelle radius r (default 0.3 Lw); only R − r enters the kinematics.")
@click.option("--objective", type=click.Choice(DELTA_OBJECTIVES), default="size",
              show_default=True,
              help="size: shortest arms; compactness: largest Lw/stroke with L <= --max-leg.")
@click.option("--max-leg", type=float, help="Largest admissible arm length.")
@MACHINE_OUT_OPTION
@UNITS_OPTION
@JSON_OPTION
def design_linear_delta(cube, center_text, bounds, nacelle, objective, max_leg, machine_out,
                        units, as_json):
    """R, r, L and the slider strokes of a vertical-slide linear Delta for a prescribed cube
    with bounds on the transmission factors — verified by brute force over the cube."""
    scale = length_scale(units)
    lo, hi = _required_bounds(bounds)
    center = (parse_vector(center_text, 3, "--center", units) if center_text is not None
              else None)
    if nacelle is not None and not (np.isfinite(nacelle) and nacelle > 0):
        raise InputError(f"--r must be a positive length, got {nacelle:g}")
    if machine_out is not None:
        check_destination(machine_out)
    res = size_linear_delta(cube * scale, (lo, hi), center=center,
                            r=None if nacelle is None else nacelle * scale,
                            objective=objective, max_leg=_max_leg(max_leg, scale, units))
    written = _write_machine(
        machine_out, res.machine, res.center, cube * scale, units,
        f"linear Delta for a {cube:g} {units} cube",
        f"pkmkit design linear-delta --cube {cube:g} --bounds {lo:g},{hi:g} "
        f"--center {','.join(f'{v:g}' for v in res.center / scale)} "
        f"--objective {objective} --units {units}")
    payload = {
        "cube": cube, "center": res.center / scale, "bounds": [lo, hi], "units": units,
        "objective": objective, "R": res.R / scale, "r": res.r / scale, "L": res.L / scale,
        "d": res.d / scale, "stroke": res.stroke / scale, "q_min": res.q_min / scale,
        "q_max": res.q_max / scale, "compactness": res.compactness, "gci": res.gci,
        "index_range": list(res.index_range),
        "verified": _verified(res.check),
        "notes": list(res.notes),
        "machine_file": written,
    }
    if as_json:
        emit_json(payload)
        return
    click.echo(f"linear Delta for a {cube:g} {units} cube centred at {fmt(payload['center'])} "
               f"{units}, transmission factors in [{lo:g}, {hi:g}] ({objective}):")
    click.echo(f"  R = {payload['R']:.6g} {units}, r = {payload['r']:.6g} {units} "
               f"(R − r = {payload['d']:.6g}), arms L = {payload['L']:.6g} {units}")
    click.echo(f"  sliders from {fmt(payload['q_min'])} to {fmt(payload['q_max'])} {units}: "
               f"stroke {payload['stroke']:.6g} {units}")
    click.echo(f"  compactness Lw/stroke = {res.compactness:.4f}, GCI over the cube = "
               f"{res.gci:.4f}")
    click.echo(f"  verified on {res.check.samples} poses of the cube: factors in "
               f"{fmt(res.check.factor_range)}")
    _echo_notes(res.notes)
    _echo_written(written)


def _parse_vary(text: str, scale: float, machine) -> Variable:
    """``NAME=LO:HI`` in command-line units → a variable in SI units."""
    name, sep, rng = text.partition("=")
    lo, sep2, hi = rng.partition(":")
    if not sep or not sep2:
        raise InputError(f"--vary expects NAME=LO:HI, got {text!r}")
    try:
        lower, upper = float(lo), float(hi)
    except ValueError:
        raise InputError(f"--vary {text!r}: LO and HI must be numbers") from None
    name = name.strip()
    parameter = scalar_parameters(machine).get(name)
    factor = 1.0 if parameter is None else boundary_factor(parameter.quantity, scale)
    return Variable(name, lower * factor, upper * factor)


def _parse_constraint(text: str, scale: float) -> Constraint:
    """``METRIC<=V`` with V in command-line units → a constraint in SI units."""
    c = Constraint.parse(text)
    factor = boundary_factor(METRIC_QUANTITIES.get(c.metric, "number"), scale)
    return Constraint(c.metric, c.op, c.value * factor)


def _parse_region(text: str, scale: float, units: str) -> Region:
    """``--region SIDE[@X,Y[,Z]]`` in ``units`` (``scale`` m per unit) → SI; the side and
    each centre coordinate finite and within their plausible ranges."""
    side_text, _, center_text = text.partition("@")
    try:
        side = float(side_text)
        center = [float(v) for v in center_text.split(",")] if center_text else None
    except ValueError:
        raise InputError(f"--region expects SIDE[@X,Y[,Z]], got {text!r}") from None
    check_plausible("--region side", side, "length", scale=scale, unit=units)
    if center is not None:
        check_each("--region centre", center, [scale] * len(center), [units] * len(center),
                   labels="XYZ"[:len(center)] if len(center) <= 3 else None)
        center = tuple(v * scale for v in center)
    return Region(side * scale, center)


@click.command("optimize")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--vary", "vary", multiple=True, required=True, metavar="NAME=LO:HI",
              help="Design variable (repeatable): a parameter, NAME[i] for a component, or "
                   "legs[i].FIELD[k] for a leg of a rod-legs machine file (see docs/design.md).")
@click.option("--objective", "objectives", multiple=True, required=True,
              metavar="min:METRIC|max:METRIC",
              help=f"Objective (repeatable); metrics: {', '.join(METRICS)}.")
@click.option("--constraint", "constraints", multiple=True, metavar="METRIC<=V|METRIC>=V",
              help="Constraint on a metric (repeatable); lengths in --units.")
@click.option("--region", "region_text", required=True, metavar="SIDE[@X,Y[,Z]]",
              help="Prescribed square/cube: side, optionally @centre (default: home).")
@BOUNDS_OPTION
@KAPPA_OPTION
@click.option("--method", type=click.Choice(["de", "cmaes", "nsga2"]),
              help="Optimiser (default: de for one objective, nsga2 for several).")
@click.option("--pareto", is_flag=True, help="Several objectives: compute the Pareto front.")
@click.option("--generations", type=click.IntRange(1, 10_000), default=30, show_default=True)
@click.option("--population", type=click.IntRange(4, 10_000), default=24, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--samples", type=click.IntRange(3, 101), default=9, show_default=True,
              help="Grid points per edge of the region.")
@click.option("--no-progress", is_flag=True, help="Hide the progress bar.")
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False),
              help="Directory for results.csv, summary.json and pareto.png.")
@SCHEDULER_OPTION
@UNITS_OPTION
@JSON_OPTION
def optimize_cmd(machine_name, assignments, vary, objectives, constraints, region_text, bounds,
                 kappa_max, method, pareto, generations, population, seed, samples, no_progress,
                 out_dir, scheduler, units, as_json):
    """Optimise parameters of any machine for a prescribed region (one or several objectives).

    Lengths (variables, constraints, region, outputs) are in --units, angles in degrees; the
    outputs name their units. The metric min_stiffness (smallest translational stiffness over
    the region, N/µm) takes the elastic data of `pkmkit stiffness` (--set
    actuator_stiffness=...)."""
    m, elastic = machine_and_data(machine_name, assignments, units)
    scale = length_scale(units)
    region = _parse_region(region_text, scale, units)
    objs = [Objective.parse(t) for t in objectives]
    if pareto and len(objs) < 2:
        raise InputError("--pareto needs at least two objectives")
    if len(objs) > 1 and not pareto and method != "nsga2":
        raise InputError("several objectives: add --pareto (NSGA-II)")
    problem = DesignProblem(
        base=m, variables=[_parse_vary(t, scale, m) for t in vary], objectives=objs,
        constraints=[_parse_constraint(t, scale) for t in constraints], region=region,
        criteria=Criteria(bounds=parse_bounds(bounds),
                          kappa_max=check_plausible("--kappa-max", kappa_max, "condition"),
                          stiffness_data=elastic), samples=samples,
    )
    out = check_output_dir(out_dir)
    result = optimize(problem, method=method, seed=seed, generations=generations,
                      population=population, progress=not no_progress and not as_json,
                      scheduler=scheduler)
    try:
        result.write_csv(out / "results.csv", units=units)
        result.write_json(out / "summary.json", units=units)
        if len(objs) >= 2:
            result.write_csv(out / "pareto.csv", result.pareto, units=units)
            from pkmkit.plot.design_figures import plot_pareto  # matplotlib: only here

            plot_pareto(result, path=out / "pareto.png", units=units)
    except OSError as exc:
        raise InputError(f"cannot write into {out_dir}: {exc.strerror or exc}") from None
    summary = result.summary(units)
    summary["machine_file"], machine_note = _write_best(result, region, out / "machine.toml",
                                                        units)
    if as_json:
        click.echo(json.dumps(to_jsonable(summary), indent=2))
        if summary["infeasibility"]:
            raise InputError(summary["infeasibility"])
        return
    click.echo(f"{summary['evaluations']} designs evaluated ({summary['feasible_evaluations']} "
               f"feasible) with {result.method}; results in {out_dir}/ (lengths in {units}, "
               "angles in deg)")
    if result.best is not None:
        click.echo("best: " + ", ".join(_shown(result, k, v, units)
                                        for k, v in summary["best"].items()
                                        if k != "feasible" and isinstance(v, float)))
        click.echo(machine_note)
    elif len(objs) >= 2:
        click.echo(f"Pareto front: {len(result.pareto)} designs (pareto.csv, pareto.png)")
    else:
        raise InputError(f"{result.infeasibility(units)}; relax the constraints or widen the "
                         f"variables (all {len(result.records)} designs are in {out_dir}/)")


def _write_best(result, region: Region, path, units: str) -> tuple[str | None, str]:
    """Write the best design of a single-objective run to ``path`` (``machine.toml``), checked
    at home and at the corners of the region: its path (None when nothing is written) and a
    line saying what was done. A ``machine.toml`` left by an earlier run in the folder is
    removed when this run writes none, so that it is never taken for this run's result."""
    best = result.best
    machine = None if best is None else result.problem.build(
        np.array([best[v.name] for v in result.problem.variables]))
    if machine is None or machine.kind is None:
        stale = path.exists()
        if stale:
            path.unlink()
        if best is None:
            return None, ""
        return None, ("machine file: not written (only machines of a built-in kind are "
                      "written as a machine file)" + ("; the earlier machine.toml was removed"
                                                      if stale else ""))
    corners = region.points(machine, 2)
    write_sized_machine(path, machine, np.vstack([machine.home_pose, corners]), units=units,
                        name=f"{machine.name} (optimised)",
                        source=f"pkmkit optimize, best design ({result.method})")
    return str(path), f"machine file: {path}"


def _shown(result, name: str, value: float, units: str) -> str:
    unit = result.unit_of(name, units)
    return f"{name} = {value:.6g}" + (f" {unit}" if unit else "")
