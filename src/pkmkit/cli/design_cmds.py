"""``pkmkit design orthoglide|five-bar`` and ``pkmkit optimize``."""

from __future__ import annotations

import json
from pathlib import Path

import click
import numpy as np

from pkmkit.analysis.workspace import Criteria
from pkmkit.design.five_bar import isotropic_orientations, size_five_bar
from pkmkit.design.metrics import METRICS, Region
from pkmkit.design.optimize import (
    Constraint,
    DesignProblem,
    Objective,
    Variable,
    optimize,
)
from pkmkit.design.orthoglide import size_orthoglide
from pkmkit.errors import InputError
from pkmkit.io.json_io import to_jsonable
from pkmkit.model.parameters import length_scale
from pkmkit.plot.design_figures import plot_pareto

from .analysis_cmds import BOUNDS_OPTION, KAPPA_OPTION, parse_bounds
from .options import JSON_OPTION, SET_OPTION, UNITS_OPTION, emit_json, fmt, resolve_machine


def register(cli: click.Group) -> None:
    """Add the design commands to the ``pkmkit`` group."""
    cli.add_command(design)
    cli.add_command(optimize_cmd)


def _required_bounds(text: str | None) -> tuple[float, float]:
    bounds = parse_bounds(text)
    if bounds is None:
        raise InputError("--bounds LO,HI is required")
    return bounds


@click.group()
def design() -> None:
    """Sizing rules: the Orthoglide for a cube, the isotropic five-bar for a square."""


@design.command("orthoglide")
@click.option("--cube", "cube", type=float, required=True, help="Prescribed cube side Lw.")
@BOUNDS_OPTION
@click.option("--max-leg", type=float, help="Largest admissible leg length.")
@UNITS_OPTION
@JSON_OPTION
def design_orthoglide(cube, bounds, max_leg, units, as_json):
    """Seed 001's rule: Q1, Q2 on the diagonal, leg length, slider positions and strokes,
    compactness — verified over the whole cube."""
    scale = length_scale(units)
    lo, hi = _required_bounds(bounds)
    res = size_orthoglide(cube * scale, (lo, hi),
                          max_leg=None if max_leg is None else max_leg * scale)
    payload = {
        "cube": cube, "bounds": [lo, hi], "units": units,
        "L": res.L / scale, "stroke": res.stroke / scale, "compactness": res.compactness,
        "side_over_L": res.side_over_L, "Q1": res.Q1 / scale, "Q2": res.Q2 / scale,
        "q_min": res.q_min / scale, "q_max": res.q_max / scale,
        "verified": {"feasible": res.check.feasible, "samples": res.check.samples,
                     "index_range": list(res.check.factor_range)},
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


@design.command("five-bar")
@click.option("--square", "square", type=float, required=True, help="Prescribed square side.")
@BOUNDS_OPTION
@click.option("--design", "design_name", type=click.Choice(["isotropic", "biglide", "both"]),
              default="both", show_default=True)
@UNITS_OPTION
@JSON_OPTION
def design_five_bar(square, bounds, design_name, units, as_json):
    """Seed 004's isotropic design (slide orientations from J⁻¹ = I) sized for a square
    workspace, compared with the biglide of the same size."""
    scale = length_scale(units)
    lo, hi = _required_bounds(bounds)
    names = ["isotropic", "biglide"] if design_name == "both" else [design_name]
    results = {}
    for name in names:
        res = size_five_bar(square * scale, (lo, hi), design=name)
        results[name] = {
            "L": res.L / scale, "A": res.A / scale, "B": res.B / scale,
            "alpha": np.degrees([res.machine.params["alpha1"], res.machine.params["alpha2"]]),
            "q_min": res.q_min / scale, "q_max": res.q_max / scale,
            "stroke": res.stroke / scale, "square_center": res.square_center / scale,
            "verified": {"feasible": res.check.feasible, "samples": res.check.samples,
                         "index_range": list(res.check.factor_range)},
        }
    payload = {"square": square, "bounds": [lo, hi], "units": units,
               "isotropic_orientations_deg": isotropic_orientations(), "designs": results}
    if as_json:
        emit_json(payload)
        return
    click.echo(f"five-bar for a {square:g} {units} square with transmission factors in "
               f"[{lo:g}, {hi:g}]")
    click.echo(f"  J⁻¹ = I is possible only for (α1, α2) = "
               f"{payload['isotropic_orientations_deg']} degrees")
    for name, r in results.items():
        click.echo(f"  {name}: L = {r['L']:.6g} {units}, A = {fmt(r['A'])}, B = {fmt(r['B'])}, "
                   f"α = {fmt(r['alpha'])} deg")
        click.echo(f"    joint stops {fmt(r['q_min'])} .. {fmt(r['q_max'])} {units} (stroke "
                   f"{r['stroke']:.6g}); square centred at {fmt(r['square_center'])}; verified "
                   f"factors {fmt(r['verified']['index_range'])}")


def _parse_vary(text: str, scale: float, machine) -> Variable:
    name, sep, rng = text.partition("=")
    lo, sep2, hi = rng.partition(":")
    if not sep or not sep2:
        raise InputError(f"--vary expects NAME=LO:HI, got {text!r}")
    try:
        lower, upper = float(lo), float(hi)
    except ValueError:
        raise InputError(f"--vary {text!r}: LO and HI must be numbers") from None
    base = name.split("[")[0].strip()
    spec = {s.name: s for s in machine.kind.parameters}.get(base) if machine.kind else None
    factor = 1.0
    if spec is not None and spec.quantity == "length":
        factor = scale
    elif spec is not None and spec.quantity == "angle":
        factor = np.pi / 180.0
    return Variable(name.strip(), lower * factor, upper * factor)


@click.command("optimize")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--vary", "vary", multiple=True, required=True, metavar="NAME=LO:HI",
              help="Design variable (repeatable): a parameter, or NAME[i] for a component.")
@click.option("--objective", "objectives", multiple=True, required=True,
              metavar="min:METRIC|max:METRIC",
              help=f"Objective (repeatable); metrics: {', '.join(METRICS)}.")
@click.option("--constraint", "constraints", multiple=True, metavar="METRIC<=V|METRIC>=V",
              help="Constraint on a metric (repeatable).")
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
@UNITS_OPTION
@JSON_OPTION
def optimize_cmd(machine_name, assignments, vary, objectives, constraints, region_text, bounds,
                 kappa_max, method, pareto, generations, population, seed, samples, no_progress,
                 out_dir, units, as_json):
    """Optimise parameters of any machine for a prescribed region (one or several objectives)."""
    m = resolve_machine(machine_name, assignments, units)
    scale = length_scale(units)
    if m.kind is None:
        raise InputError(f"{m.id!r} is described leg by leg: it has no parameters to vary")
    side_text, _, center_text = region_text.partition("@")
    try:
        side = float(side_text) * scale
        center = (tuple(float(v) * scale for v in center_text.split(",")) if center_text
                  else None)
    except ValueError:
        raise InputError(f"--region expects SIDE[@X,Y[,Z]], got {region_text!r}") from None
    objs = [Objective.parse(t) for t in objectives]
    if pareto and len(objs) < 2:
        raise InputError("--pareto needs at least two objectives")
    if len(objs) > 1 and not pareto and method != "nsga2":
        raise InputError("several objectives: add --pareto (NSGA-II)")
    problem = DesignProblem(
        base=m, variables=[_parse_vary(t, scale, m) for t in vary], objectives=objs,
        constraints=[Constraint.parse(t) for t in constraints], region=Region(side, center),
        criteria=Criteria(bounds=parse_bounds(bounds), kappa_max=kappa_max), samples=samples,
    )
    result = optimize(problem, method=method, seed=seed, generations=generations,
                      population=population, progress=not no_progress and not as_json)
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create {out_dir}: {exc.strerror or exc}") from None
    result.write_csv(out / "results.csv")
    result.write_json(out / "summary.json")
    summary = result.summary()
    if len(objs) >= 2:
        result.write_csv(out / "pareto.csv", result.pareto)
        plot_pareto(result, path=out / "pareto.png")
    if as_json:
        click.echo(json.dumps(to_jsonable(summary), indent=2))
        if summary["infeasibility"]:
            raise InputError(summary["infeasibility"])
        return
    click.echo(f"{summary['evaluations']} designs evaluated ({summary['feasible_evaluations']} "
               f"feasible) with {result.method}; results in {out_dir}/")
    if result.best is not None:
        best = {k: v for k, v in summary["best"].items() if k != "feasible"}
        click.echo("best: " + ", ".join(f"{k} = {v:.6g}" for k, v in best.items()
                                        if isinstance(v, float)))
    elif len(objs) >= 2:
        click.echo(f"Pareto front: {len(result.pareto)} designs (pareto.csv, pareto.png)")
    else:
        raise InputError(f"{result.infeasibility()}; relax the constraints or widen the "
                         f"variables (all {len(result.records)} designs are in {out_dir}/)")
