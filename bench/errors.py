"""Benchmark of the geometric error analyses (issue 10), each against a baseline run in the same
process on the same inputs:

1. identification Jacobian of the Tripteor (107 poses, every defect, tool points): analytic
   through the closure vs central finite differences of the exact model (the machine rebuilt
   with ± h on each defect, its direct model on the 107 poses);
2. compatibility analysis of the Tripteor (every loop defect, 40 configurations);
3. Monte Carlo tolerance analysis on the hexapod: the batched exact model (per-sample
   geometry) vs the machine rebuilt per sample and its own direct model, on a subset.

Usage::

    python bench/errors.py [--mc-poses 100] [--mc-samples 10000] [--load] [--json FILE]

``--load`` runs a competing busy process (NumPy matrix products) during the measurements.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import platform
import time

import numpy as np

import pkmkit
from pkmkit.geometric_errors.compatibility import compatibility
from pkmkit.geometric_errors.configurations import sample_configurations
from pkmkit.geometric_errors.measurements import measure, measurement_jacobian
from pkmkit.geometric_errors.model import defect_set, with_defects
from pkmkit.geometric_errors.tolerance import exact_rod_points, tolerances


def _busy(stop) -> None:  # pragma: no cover - a competing process
    a = np.random.default_rng(0).random((300, 300))
    while not stop.is_set():
        a = a @ a
        a /= np.abs(a).max()


def _median_time(func, repeat: int) -> float:
    func()
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def identification(repeat: int) -> dict:
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(0)
    lo = np.array([0.975, 1.055, 0.975, -0.26, 0.0])
    hi = np.array([0.995, 1.075, 0.995, 0.26, 0.96])
    q = rng.uniform(lo, hi, (107, 5))
    ds = defect_set(m)
    t_analytic = _median_time(lambda: measurement_jacobian(m, "point", q), repeat)
    jac = measurement_jacobian(m, "point", q)
    h = 1e-6
    start = time.perf_counter()
    fd = np.empty_like(jac)
    for i, name in enumerate(ds.names):
        plus = measure(with_defects(m, {name: h}), "point", q)
        minus = measure(with_defects(m, {name: -h}), "point", q)
        fd[:, :, i] = (plus - minus) / (2 * h)
    t_fd = time.perf_counter() - start
    return {"poses": 107, "defects": len(ds), "analytic_ms": 1e3 * t_analytic,
            "finite_differences_ms": 1e3 * t_fd, "ratio": t_fd / t_analytic,
            "largest_difference": float(np.abs(fd - jac).max())}


def compatibility_bench(repeat: int) -> dict:
    m = pkmkit.machine("tripteor-x7")
    t = _median_time(lambda: compatibility(m), repeat)
    r = compatibility(m)
    return {"seconds": t, "defects": len(r.names), "conditions": r.rank,
            "compatible_dimension": r.compatible_dimension}


def monte_carlo_bench(poses: int, samples: int, loop_samples: int) -> dict:
    m = pkmkit.machine("gough-stewart")
    tol = tolerances(m, classes={"base": 5e-5, "platform": 5e-5, "length": 2e-5,
                                 "offset": 1e-5})
    q = sample_configurations(m, poses, seed=1).q
    draws = tol.sample(samples, np.random.default_rng(0))
    exact_rod_points(m, q, draws[:100])
    wall = time.perf_counter()
    cpu = time.process_time()
    points = exact_rod_points(m, q, draws)
    wall = time.perf_counter() - wall
    cpu = time.process_time() - cpu
    start = time.perf_counter()
    ref = np.stack([np.atleast_2d(with_defects(m, d).fk(q))[:, :3] for d in draws[:loop_samples]],
                   axis=1)
    t_loop = time.perf_counter() - start
    pairs = poses * samples
    loop_rate = poses * loop_samples / t_loop
    return {"pairs": pairs, "rate_wall": pairs / wall, "rate_cpu": pairs / cpu,
            "loop_rate": loop_rate, "ratio": pairs / wall / loop_rate,
            "largest_difference": float(np.abs(points[:, :loop_samples] - ref).max()),
            "failed": int(np.isnan(points).any(axis=2).sum())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mc-poses", type=int, default=100)
    parser.add_argument("--mc-samples", type=int, default=10_000)
    parser.add_argument("--loop-samples", type=int, default=20)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--load", action="store_true", help="run a competing busy process")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()
    stop, worker = None, None
    if args.load:
        stop = mp.Event()
        worker = mp.Process(target=_busy, args=(stop,), daemon=True)
        worker.start()
    try:
        print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
              f"{platform.python_version()}, {platform.machine()}"
              f"{', with a competing process' if args.load else ''}")
        ident = identification(args.repeat)
        print(f"Tripteor identification Jacobian, {ident['poses']} poses x {ident['defects']} "
              f"defects: analytic {ident['analytic_ms']:.1f} ms, finite differences "
              f"{ident['finite_differences_ms']:.0f} ms (x{ident['ratio']:.0f}); largest "
              f"difference {ident['largest_difference']:.1e}")
        comp = compatibility_bench(max(3, args.repeat // 2))
        print(f"Tripteor compatibility, {comp['defects']} loop defects, 40 configurations: "
              f"{comp['seconds']:.2f} s ({comp['conditions']} conditions, compatible dimension "
              f"{comp['compatible_dimension']})")
        mc = monte_carlo_bench(args.mc_poses, args.mc_samples, args.loop_samples)
        print(f"Hexapod Monte Carlo, {mc['pairs']} (pose, sample) pairs: "
              f"{mc['rate_wall'] / 1e6:.2f} M/s wall, {mc['rate_cpu'] / 1e6:.2f} M/s per CPU "
              f"second; machine rebuilt per sample {mc['loop_rate']:.0f} /s (x{mc['ratio']:.0f});"
              f" largest difference {mc['largest_difference']:.1e} m, {mc['failed']} failed")
    finally:
        if worker is not None:
            stop.set()
            worker.join(timeout=5)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            json.dump({"identification": ident, "compatibility": comp, "monte_carlo": mc,
                       "load": args.load}, handle, indent=2)


if __name__ == "__main__":
    main()
