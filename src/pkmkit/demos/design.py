"""Design part of ``pkmkit demo``: the Orthoglide sizing rule, the isotropic five-bar design, the
linear-Delta sizing for the seed 000 cube and a linear-Delta Pareto front (figures in
``OUT/design/``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from pkmkit.analysis.workspace import Criteria
from pkmkit.design.five_bar import isotropic_orientations, size_five_bar
from pkmkit.design.linear_delta import size_linear_delta
from pkmkit.design.metrics import Region, evaluate_metrics
from pkmkit.design.optimize import DesignProblem, Objective, Variable, optimize
from pkmkit.design.orthoglide import size_orthoglide
from pkmkit.machines.registry import machine
from pkmkit.plot.design_figures import plot_pareto, plot_sizing_sweep

#: The seed 000 cube (Table III.2): x, y in ±0.25 m, z in [0, 0.5] m.
DELTA_REGION = Region(0.5, (0.0, 0.0, 0.25))
DELTA_CRITERIA = Criteria(bounds=(0.4, 2.5))


def orthoglide_sizing(out: Path) -> dict[str, Any]:
    """Seed 001's prototype (200 mm, [0.5, 2]) and how the result moves with the bounds."""
    proto = size_orthoglide(0.2, (0.5, 2.0))
    rows = []
    for hi in (1.5, 2.0, 2.5, 3.0, 4.0):
        r = size_orthoglide(0.2, (1 / hi, hi), samples=21)
        rows.append({"psi_max": hi, "L": r.L, "stroke": r.stroke,
                     "compactness": r.compactness, "side_over_L": r.side_over_L})
    plot_sizing_sweep(rows, x="psi_max", ys=("compactness", "side_over_L"),
                      xlabel="ψmax (ψmin = 1/ψmax)",
                      labels={"compactness": "compactness Lw/stroke",
                              "side_over_L": "cube side / leg length Lw/L"},
                      title="Orthoglide for a 200 mm cube: Lw/stroke and Lw/L vs the bounds",
                      path=out / "orthoglide-sizing-sweep.png")
    return {"prototype": {"L": proto.L, "stroke": proto.stroke, "compactness": proto.compactness,
                          "Q1": proto.Q1, "Q2": proto.Q2, "q_min": proto.q_min,
                          "q_max": proto.q_max, "verified": proto.check.feasible,
                          "index_range": proto.check.factor_range},
            "seed": {"L": 0.310, "stroke": 0.257, "compactness": 0.78},
            "sweep": rows, "figure": "orthoglide-sizing-sweep.png"}


def five_bar_design(resolution: int = 301) -> dict[str, Any]:
    """Slide orientations from J⁻¹ = I, and both designs sized for a 0.2 m square."""
    out = {"orientations_deg": isotropic_orientations()}
    for name in ("isotropic", "biglide"):
        res = size_five_bar(0.2, (1 / 3, 3.0), design=name, resolution=resolution)
        out[name] = {"L": res.L, "stroke": res.stroke, "B": res.B,
                     "verified": res.check.feasible}
    return out


def delta_sizing() -> dict[str, Any]:
    """The shortest-arm linear Delta for the Table III.2 cube and λ in [0.4, 2.5]."""
    res = size_linear_delta(DELTA_REGION.side, DELTA_CRITERIA.bounds,
                            center=DELTA_REGION.center)
    return {"R": res.R, "r": res.r, "L": res.L, "stroke": res.stroke, "q_min": res.q_min,
            "q_max": res.q_max, "compactness": res.compactness, "gci": res.gci,
            "index_range": res.index_range, "verified": res.check.feasible}


def delta_pareto(out: Path, generations: int = 25,
                 sized: dict[str, Any] | None = None) -> dict[str, Any]:
    """Compactness vs GCI over the Table III.2 cube, with the seed's two dimension sets and the
    sized design (:func:`delta_sizing`, computed unless given).

    Only d = R − r and L enter the kinematics, so the metrics of the front (compactness, GCI)
    depend on (R − r, L): varying r as well would only add a line of identical designs per
    point. r is therefore fixed at the seed's 0.15 m (the nacelle that carries the spindle) and
    R is varied."""
    base = machine("linear-delta")
    problem = DesignProblem(
        base=base, variables=[Variable("R", 0.45, 1.0), Variable("L", 0.9, 1.6)],
        objectives=[Objective("compactness", "max"), Objective("gci", "max")],
        region=DELTA_REGION, criteria=DELTA_CRITERIA, samples=9)
    result = optimize(problem, seed=1, generations=generations, population=32)
    names = ("compactness", "gci", "violation", "lambda_min", "lambda_max", "stroke")
    references = []
    for ident, label in (("linear-delta-ch3", "seed set A (L = 1.3 m)"),
                         ("linear-delta-table-iv1", "seed set B (L = 1.04 m)")):
        metrics = evaluate_metrics(machine(ident), DELTA_REGION, DELTA_CRITERIA, names, 9)
        references.append((label, metrics))
    sized = delta_sizing() if sized is None else sized
    shown = [*references,
             (f"sized, shortest arms (L = {sized['L']:.2f} m)",
              evaluate_metrics(base.with_params(R=sized["R"], r=sized["r"], L=sized["L"]),
                               DELTA_REGION, DELTA_CRITERIA, names, 9))]
    plot_pareto(result, references=shown,
                title="Linear Delta, 0.5 m cube, λ in [0.4, 2.5]: compactness vs GCI",
                path=out / "linear-delta-pareto.png")
    return {"evaluations": len(result.records), "pareto_size": len(result.pareto),
            "pareto": [{k: r[k] for k in ("R", "L", "compactness", "gci")}
                       for r in result.pareto],
            "seed_sets": {label: m for label, m in references},
            "figure": "linear-delta-pareto.png"}


def run_design_demo(out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """All of the above; prints a few lines (``quick``: a shorter Pareto search)."""
    out = out_dir / "design"
    out.mkdir(parents=True, exist_ok=True)
    click.echo("\n== design (figures in design/)")
    ortho = orthoglide_sizing(out)
    p = ortho["prototype"]
    click.echo(f"   Orthoglide, 200 mm cube, λ in [0.5, 2]: L = {p['L'] * 1e3:.1f} mm (seed 310), "
               f"stroke {p['stroke'] * 1e3:.1f} mm (seed 257), r = {p['compactness']:.3f} "
               f"(seed 0.78), verified: {p['verified']}")
    five = five_bar_design(121 if quick else 301)
    click.echo(f"   five-bar: J⁻¹ = I needs (α1, α2) = {five['orientations_deg']} deg; for a 0.2 m "
               f"square, isotropic L = {five['isotropic']['L']:.3f} m, stroke "
               f"{five['isotropic']['stroke']:.3f} m; biglide L = {five['biglide']['L']:.3f} m, "
               f"stroke {five['biglide']['stroke']:.3f} m")
    sized = delta_sizing()
    click.echo(f"   linear Delta for the 0.5 m cube, λ in [0.4, 2.5], shortest arms: "
               f"R = {sized['R']:.3f} m, r = {sized['r']:.3f} m, L = {sized['L']:.3f} m, stroke "
               f"{sized['stroke']:.3f} m, compactness {sized['compactness']:.3f}, verified: "
               f"{sized['verified']}")
    delta = delta_pareto(out, generations=8 if quick else 25, sized=sized)
    delta["sizing"] = sized
    seeds = "; ".join(f"{k}: compactness {v['compactness']:.3f}, GCI {v['gci']:.3f}"
                      for k, v in delta["seed_sets"].items())
    best = max(delta["pareto"], key=lambda r: r["compactness"])
    click.echo(f"   linear Delta Pareto front: {delta['pareto_size']} designs, compactness up to "
               f"{best['compactness']:.3f} (R = {best['R']:.3f}, L = {best['L']:.3f} m); {seeds}")
    return {"orthoglide": ortho, "five_bar": five, "linear_delta": delta, "units": "m"}
