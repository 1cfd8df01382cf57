"""Benchmark: Orthoglide sizing time, and a 3-variable linear-Delta optimisation with the batched
evaluator against the same optimisation evaluating every design pose by pose.

Both optimisations run differential evolution with the same seed, bounds and budget in the same
process; the per-pose evaluator computes the same metrics with one ``m.ik``/``m.jacobian`` call
per pose of the prescribed cube, so both runs visit the same designs and must find the same
optimum (checked).

Usage::

    python bench/design.py [--generations 8] [--samples 7] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import pkmkit
from pkmkit.analysis.workspace import Criteria
from pkmkit.design.metrics import Region
from pkmkit.design.optimize import DesignProblem, Objective, Variable, optimize
from pkmkit.design.orthoglide import size_orthoglide


def per_pose_metrics(machine, region, criteria, names, samples):
    """Same metrics as pkmkit.design.metrics.metric_values, one pose at a time."""
    if machine is None:
        return {n: (float("inf") if n == "violation" else float("nan")) for n in names}
    points = region.points(machine, samples)
    qs, factors, conditions, reached = [], [], [], 0
    for x in points:
        try:
            jac = machine.jacobian(x)
        except pkmkit.PkmError:
            continue
        if jac.mode != machine.working_mode or jac.parallel_measure < criteria.tol:
            continue
        reached += 1
        qs.append(jac.q)
        factors.append(jac.singular_values)
        conditions.append(jac.condition)
    lo, hi = criteria.bounds
    if factors:
        f = np.array(factors)
        excess = max(0.0, float(np.max(lo / f[:, -1] - 1)), float(np.max(f[:, 0] / hi - 1)))
        q = np.array(qs)
        stroke = float(np.max(q.max(axis=0) - q.min(axis=0)))
    else:
        excess, stroke = 0.0, float("nan")
    values = {"violation": 1.0 - reached / len(points) + excess, "stroke": stroke,
              "compactness": region.side / stroke if stroke > 0 else float("nan"),
              "gci": float(np.mean(1.0 / np.array(conditions))) if conditions else float("nan")}
    return {n: values[n] for n in names}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--generations", type=int, default=8)
    parser.add_argument("--samples", type=int, default=7)
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    size_orthoglide(0.2, (0.5, 2.0))
    start = time.perf_counter()
    repeats = 5
    for _ in range(repeats):
        sized = size_orthoglide(0.2, (0.5, 2.0))
    t_sizing = (time.perf_counter() - start) / repeats

    def problem(evaluator=None):
        extra = {} if evaluator is None else {"evaluator": evaluator}
        return DesignProblem(
            base=pkmkit.machine("linear-delta"),
            variables=[Variable("R", 0.45, 1.0), Variable("r", 0.05, 0.3), Variable("L", 0.9, 1.6)],
            objectives=[Objective("compactness", "max")], region=Region(0.5, (0, 0, 0.25)),
            criteria=Criteria(bounds=(0.4, 2.5)), samples=args.samples, **extra)

    start = time.perf_counter()
    batched = optimize(problem(), seed=3, generations=args.generations, population=15)
    t_batched = time.perf_counter() - start
    start = time.perf_counter()
    looped = optimize(problem(per_pose_metrics), seed=3, generations=args.generations,
                      population=15)
    t_looped = time.perf_counter() - start
    same = (batched.best is not None and looped.best is not None
            and abs(batched.best["compactness"] - looped.best["compactness"]) < 1e-9)
    result = {
        "orthoglide_sizing_seconds": t_sizing,
        "orthoglide_L_mm": sized.L * 1e3,
        "designs": len(batched.records),
        "poses_per_design": args.samples**3,
        "batched_seconds": t_batched,
        "per_pose_seconds": t_looped,
        "ratio": t_looped / t_batched,
        "same_optimum": bool(same),
        "best": {k: batched.best[k] for k in ("R", "r", "L", "compactness")},
    }
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"Orthoglide sizing (200 mm cube, [0.5, 2], verified on 41^3 poses): "
          f"{t_sizing * 1e3:.0f} ms per call (L = {sized.L * 1e3:.1f} mm)")
    print(f"linear-Delta optimisation, 3 variables, {result['designs']} designs x "
          f"{result['poses_per_design']} poses: batched {t_batched:.2f} s, per pose "
          f"{t_looped:.2f} s -> ratio {result['ratio']:.0f}x; same optimum: {same} "
          f"(compactness {batched.best['compactness']:.4f})")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
