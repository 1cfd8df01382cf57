"""Benchmark: studies on Dask, serial → 1 worker → 2 workers, results checked identical.

Three studies, each run in this process (serial, the reference) and on a Dask
``LocalCluster`` of 1 and then 2 worker processes (one thread each, the environment of
:func:`pkmkit.parallel.local_cluster`), started before the timings (their start-up is printed
apart):

- **workspace**: :func:`pkmkit.analysis.workspace.evaluate_grid` on an Orthoglide grid
  (``--resolution`` points per side, every mask, factors and q returned);
- **index map**: :func:`pkmkit.analysis.indices.index_values` of the conditioning over a
  five-bar plane (``--map-resolution``² points, one float returned per point);
- **design population**: :func:`pkmkit.design.optimize.evaluate_designs` of a linear-Delta
  sweep (``--designs`` candidates, each checked on ``--samples``³ poses).

Each timing is the median of ``--repeat`` runs; speed-ups are serial time / Dask time.

Usage::

    python bench/scaling.py [--resolution 120] [--map-resolution 1500] [--designs 96]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.indices import index_values
from pkmkit.analysis.workspace import Criteria, evaluate_grid
from pkmkit.design.metrics import Region
from pkmkit.design.optimize import DesignProblem, Objective, Variable, evaluate_designs
from pkmkit.parallel import local_cluster


def timed(func, repeat: int):
    times, value = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        value = func()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value


def studies(args) -> dict:
    ortho = pkmkit.machine("orthoglide")
    grid = make_grid(*ortho.default_box(), free=(0, 1, 2), base=ortho.home_pose,
                     names=ortho.pose_names, resolution=args.resolution)
    criteria = Criteria(bounds=(0.5, 2.0))
    five = pkmkit.machine("five-bar")
    plane = make_grid(*five.default_box(), free=(0, 1), base=five.home_pose,
                      names=five.pose_names, resolution=args.map_resolution).points
    problem = DesignProblem(
        base=pkmkit.machine("linear-delta"),
        variables=[Variable("R", 0.45, 1.0), Variable("r", 0.05, 0.2), Variable("L", 0.9, 1.6)],
        objectives=[Objective("compactness", "max")], region=Region(0.5, (0.0, 0.0, 0.25)),
        criteria=Criteria(bounds=(0.4, 2.5)), samples=args.samples)
    designs = np.random.default_rng(1).uniform(problem.bounds[:, 0], problem.bounds[:, 1],
                                               (args.designs, 3))
    return {
        f"workspace ({grid.size} poses)": lambda s: evaluate_grid(ortho, grid, criteria,
                                                                  scheduler=s),
        f"index map ({len(plane)} poses)": lambda s: index_values(five, plane, "condition",
                                                                  scheduler=s),
        f"design sweep ({args.designs} designs x {args.samples}^3 poses)":
            lambda s: evaluate_designs(problem, designs, scheduler=s),
    }


def same(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return np.array_equal(a, b, equal_nan=True)
    if isinstance(a, list):
        return all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if hasattr(a, "__dataclass_fields__"):
        return all(same(getattr(a, k), getattr(b, k)) for k in a.__dataclass_fields__)
    return a == b or (a != a and b != b)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--resolution", type=int, default=120)
    parser.add_argument("--map-resolution", type=int, default=1500)
    parser.add_argument("--designs", type=int, default=96)
    parser.add_argument("--samples", type=int, default=9)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    import distributed

    work = studies(args)
    print(f"pkmkit {pkmkit.__version__}, dask {distributed.__version__}, {os.cpu_count()} cores,"
          f" load average {os.getloadavg()[0]:.2f} at start")
    results = {}
    serial = {}
    for name, func in work.items():
        func(None)  # warm up (compiled kernels)
        serial[name] = timed(lambda f=func: f(None), args.repeat)
        results[name] = {"serial_s": serial[name][0]}
    for workers in (1, 2):
        start = time.perf_counter()
        with local_cluster(workers) as cluster, distributed.Client(cluster) as client:
            startup = time.perf_counter() - start
            for name, func in work.items():
                func(client)  # warm up the workers
                t, value = timed(lambda f=func, c=client: f(c), args.repeat)
                results[name][f"dask{workers}_s"] = t
                results[name][f"dask{workers}_identical"] = same(value, serial[name][1])
        results[f"startup{workers}_s"] = startup
    print(f"LocalCluster start-up: 1 worker {results['startup1_s']:.1f} s, 2 workers "
          f"{results['startup2_s']:.1f} s (not in the timings)")
    print(f"{'study':48} {'serial s':>9} {'1 worker':>9} {'2 workers':>10} {'1->2':>6} "
          f"{'identical':>9}")
    for name in work:
        r = results[name]
        print(f"{name:48} {r['serial_s']:9.2f} {r['dask1_s']:9.2f} {r['dask2_s']:10.2f} "
              f"{r['dask1_s'] / r['dask2_s']:5.2f}x "
              f"{r['dask1_identical'] and r['dask2_identical']!s:>9}")
    print(f"load average at the end {os.getloadavg()[0]:.2f}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(results, handle, indent=2)


if __name__ == "__main__":
    main()
