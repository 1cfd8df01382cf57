"""Benchmark: Orthoglide and linear-Delta sizing times, and a 3-variable linear-Delta
optimisation with the batched evaluator against the same optimisation evaluating every design
pose by pose.

Both optimisations run differential evolution with the same seed, bounds and budget in the same
process; the per-pose evaluator computes the same metrics with one ``m.ik``/``m.jacobian`` call
per pose of the prescribed cube, so both runs visit the same designs and must find the same
optimum (checked).

The machines are shared and noisy: every timing is repeated and the **median** is reported (with
the fastest and slowest run); the ratio is the ratio of the medians. Batched and per-pose runs
alternate, so a slow spell of the machine hits both.

Usage::

    python bench/design.py [--generations 8] [--samples 7] [--repeats 5] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time

import numpy as np

import pkmkit
from pkmkit.analysis.workspace import Criteria
from pkmkit.design.linear_delta import size_linear_delta
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
            # the sizing judges strokes itself (they are its output): no per-pose warning
            jac = machine.jacobian(x, q=machine.ik(x, strokes="ignore"))
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


def timed(func, repeats):
    """(result of the last call, list of wall times in s)."""
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = func()
        times.append(time.perf_counter() - start)
    return result, times


def spread(times):
    return {"median": statistics.median(times), "min": min(times), "max": max(times),
            "runs": len(times)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--generations", type=int, default=8)
    parser.add_argument("--samples", type=int, default=7)
    parser.add_argument("--repeats", type=int, default=5,
                        help="runs of each timing (median reported)")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    repeats = max(1, args.repeats)

    size_orthoglide(0.2, (0.5, 2.0))  # warm-up (imports, caches)
    sized, t_sizing = timed(lambda: size_orthoglide(0.2, (0.5, 2.0)), 2 * repeats)
    delta, t_delta = timed(
        lambda: size_linear_delta(0.5, (0.4, 2.5), center=(0.0, 0.0, 0.25)), repeats)

    def problem(evaluator=None):
        extra = {} if evaluator is None else {"evaluator": evaluator}
        return DesignProblem(
            base=pkmkit.machine("linear-delta"),
            variables=[Variable("R", 0.45, 1.0), Variable("r", 0.05, 0.3), Variable("L", 0.9, 1.6)],
            objectives=[Objective("compactness", "max")], region=Region(0.5, (0, 0, 0.25)),
            criteria=Criteria(bounds=(0.4, 2.5)), samples=args.samples, **extra)

    def run(evaluator=None):
        return optimize(problem(evaluator), seed=3, generations=args.generations, population=15)

    t_batched, t_looped = [], []
    for _ in range(repeats):  # alternate, so that a slow spell hits both
        batched, t = timed(run, 1)
        t_batched += t
        looped, t = timed(lambda: run(per_pose_metrics), 1)
        t_looped += t
    same = (batched.best is not None and looped.best is not None
            and abs(batched.best["compactness"] - looped.best["compactness"]) < 1e-9)
    ratio = statistics.median(t_looped) / statistics.median(t_batched)
    result = {
        "orthoglide_sizing_seconds": spread(t_sizing),
        "orthoglide_L_mm": sized.L * 1e3,
        "linear_delta_sizing_seconds": spread(t_delta),
        "linear_delta_sizing": {"R": delta.R, "r": delta.r, "L": delta.L, "stroke": delta.stroke,
                                "compactness": delta.compactness},
        "designs": len(batched.records),
        "poses_per_design": args.samples**3,
        "batched_seconds": spread(t_batched),
        "per_pose_seconds": spread(t_looped),
        "ratio_of_medians": ratio,
        "same_optimum": bool(same),
        "best": {k: batched.best[k] for k in ("R", "r", "L", "compactness")},
    }

    def show(times):
        return (f"median {statistics.median(times) * 1e3:.0f} ms (min {min(times) * 1e3:.0f}, "
                f"max {max(times) * 1e3:.0f}, {len(times)} runs)")

    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"Orthoglide sizing (200 mm cube, [0.5, 2], verified on 41^3 poses): "
          f"{show(t_sizing)} per call (L = {sized.L * 1e3:.1f} mm)")
    print(f"linear-Delta sizing (0.5 m cube, [0.4, 2.5], shortest arms, verified on 25^3 poses): "
          f"{show(t_delta)} per call (R = {delta.R:.4f} m, L = {delta.L:.4f} m)")
    print(f"linear-Delta optimisation, 3 variables, {result['designs']} designs x "
          f"{result['poses_per_design']} poses:")
    print(f"  batched   {show(t_batched)}")
    print(f"  per pose  {show(t_looped)}")
    print(f"  ratio of the medians {ratio:.0f}x; same optimum: {same} "
          f"(compactness {batched.best['compactness']:.4f})")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
