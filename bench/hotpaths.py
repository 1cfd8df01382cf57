"""Benchmark: the hot paths against their limit and their naive baseline, quiet and loaded.

For each condition — ``quiet``, and ``loaded`` with one competing process keeping a core and the
memory bus busy (:mod:`load`) — every figure is a median of interleaved runs (each timing and
its baselines alternate, so they see the same load):

- **inverse model** ``m.ik(X)`` on 10⁶ poses of each built-in kind, compiled kernel (default)
  and NumPy reference (``PKMKIT_COMPILED=0``), against
  the *limit* — ``X.copy()``, a plain copy of the same arrays (same bytes read and written),
  the *naive baseline* — the minimal formula as a per-pose Python loop (on ``--loop-poses``
  poses), and the former implementation — one BLAS product per chunk with the default BLAS
  threads (what collapsed under load);
- **velocity model** ``m.jacobian(X)`` reading ``singular_values`` and ``condition`` on 10⁶
  Orthoglide poses (inverse model included), compiled and NumPy, against the naive baseline —
  ``numpy.linalg.cond`` pose by pose on J (on ``--cond-poses`` poses), and the limit — copying
  the same bytes (X in, q, the singular values and the condition out); and every field read.

Usage::

    python bench/hotpaths.py [--poses 1000000] [--load none|busy|both] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from kinematics import loop_ik
from load import conditions

import pkmkit
from pkmkit.machines.closed_form import CHUNK

KINDS = ("orthoglide", "linear-delta", "five-bar")


def timed(func) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start


def medians(funcs: dict, repeat: int, every: dict | None = None) -> dict:
    """Median time of each function, runs interleaved (``every[name] = k``: run every k-th);
    also ``best:NAME``, the shortest run (what the code does when nothing else competes)."""
    every = every or {}
    times = {name: [] for name in funcs}
    for k in range(repeat):
        for name, func in funcs.items():
            if k % every.get(name, 1) == 0:
                times[name].append(timed(func))
    out = {name: statistics.median(t) for name, t in times.items()}
    out.update({f"best:{name}": min(t) for name, t in times.items()})
    return out


def numpy_path(func):
    """Run ``func`` with the compiled kernels switched off (the NumPy reference)."""
    def run():
        os.environ["PKMKIT_COMPILED"] = "0"
        try:
            return func()
        finally:
            os.environ.pop("PKMKIT_COMPILED")
    return run


def blas_inverse(m: pkmkit.Machine, x: np.ndarray) -> np.ndarray:
    """The former NumPy inverse model: one BLAS product gives every projection per chunk."""
    closed = m._closed
    dims, n = m.dims, m.n_actuators
    proj_t = np.ascontiguousarray(closed.projection.T)
    out = np.empty((n, x.shape[0]))
    with np.errstate(invalid="ignore"):
        for start in range(0, x.shape[0], CHUNK):
            y = proj_t @ x[start:start + CHUNK].T - closed.offset[:, None]
            for i in range(n):
                perp = y[i * dims + 1] ** 2 + (y[i * dims + 2] ** 2 if dims == 3 else 0.0)
                root = np.sqrt(closed.length_sq[i] - perp)
                out[i, start:start + CHUNK] = y[i * dims] + m.model.leg_branch[i] * root
    return out.T


def bench_ik(args) -> list[dict]:
    rows = []
    for kind in KINDS:
        m = pkmkit.machine(kind)
        h = 0.25 * float(m.model.leg_length.min())
        x = m.home_pose + np.random.default_rng(7).uniform(-h, h, (args.poses, m.dims))
        loop_x = x[: args.loop_poses]
        q = m.ik(x)
        ref = np.array(loop_ik(m, loop_x[:2000]))
        error = max(float(np.abs(ref - q[:2000]).max()),
                    float(np.abs(numpy_path(lambda m=m, x=x: m.ik(x))() - q).max()),
                    float(np.abs(blas_inverse(m, x) - q).max()))
        # the call and its limit alone first (the baselines below churn the allocator, whose
        # page faults then weigh on both), then everything interleaved
        limit = medians({"ik": lambda m=m, x=x: m.ik(x), "copy": lambda x=x: x.copy()},
                        args.repeat)
        t = medians({"ik": lambda m=m, x=x: m.ik(x),
                     "copy": lambda x=x: x.copy(),
                     "numpy": numpy_path(lambda m=m, x=x: m.ik(x)),
                     "blas": lambda m=m, x=x: blas_inverse(m, x),
                     "loop": lambda m=m, lx=loop_x: loop_ik(m, lx)},
                    args.repeat, {"loop": max(1, args.repeat // 3)})
        loop_per_pose = t["loop"] / len(loop_x)
        rows.append({
            "machine": kind, "ik_s": t["ik"], "copy_s": t["copy"], "numpy_s": t["numpy"],
            "blas_s": t["blas"], "loop_per_pose_s": loop_per_pose,
            "ik_over_copy": t["ik"] / t["copy"], "numpy_over_copy": t["numpy"] / t["copy"],
            "best_ik_over_copy": t["best:ik"] / t["best:copy"],
            "alone_ik_s": limit["ik"], "alone_copy_s": limit["copy"],
            "alone_ik_over_copy": limit["ik"] / limit["copy"],
            "loop_ratio": loop_per_pose * args.poses / t["ik"],
            "numpy_loop_ratio": loop_per_pose * args.poses / t["numpy"],
            "blas_over_ik": t["blas"] / t["ik"], "max_difference_m": error,
        })
    return rows


def bench_jacobian(args) -> dict:
    m = pkmkit.machine("orthoglide")
    x = np.random.default_rng(2026).uniform(-0.1, 0.07, (args.poses, 3))

    def summary():
        jac = m.jacobian(x)
        return jac.singular_values, jac.condition

    def every_field():
        jac = m.jacobian(x)
        return [getattr(jac, f) for f in ("A", "B", "J", "J_inv", "singular_values",
                                          "condition", "det_A", "det_B", "parallel_measure",
                                          "serial_measure", "singularity", "q", "mode")]

    def limit():  # the bytes of the call: X read, q, σ (N, 3) and κ (N,) written
        return x.copy(), x.copy(), x.copy(), x[:, 0].copy()

    sv, cond = summary()
    sv_np, cond_np = numpy_path(summary)()
    j = np.ascontiguousarray(m.jacobian(x[: args.cond_poses]).J)
    loop_cond = np.array([np.linalg.cond(a) for a in j[:2000]])
    t = medians({"jacobian": summary, "numpy": numpy_path(summary), "all": every_field,
                 "limit": limit, "cond": lambda: [np.linalg.cond(a) for a in j]},
                args.jac_repeat, {"cond": 3, "all": 3, "numpy": 2})
    cond_per_pose = t["cond"] / len(j)
    return {
        "jacobian_s": t["jacobian"], "numpy_s": t["numpy"], "all_fields_s": t["all"],
        "limit_s": t["limit"], "cond_per_pose_s": cond_per_pose,
        "over_limit": t["jacobian"] / t["limit"], "best_jacobian_s": t["best:jacobian"],
        "cond_ratio": cond_per_pose * args.poses / t["jacobian"],
        "numpy_cond_ratio": cond_per_pose * args.poses / t["numpy"],
        "max_rel_difference_vs_numpy_path": float(np.nanmax(np.abs(sv - sv_np) / sv_np)),
        "max_rel_difference_condition_vs_cond": float(np.nanmax(
            np.abs(cond[:2000] / loop_cond - 1))),
        "same_nan_rows": bool((np.isnan(cond) == np.isnan(cond_np)).all()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--loop-poses", type=int, default=20_000)
    parser.add_argument("--cond-poses", type=int, default=20_000)
    parser.add_argument("--repeat", type=int, default=15, help="runs per IK timing")
    parser.add_argument("--jac-repeat", type=int, default=9, help="runs per velocity timing")
    parser.add_argument("--load", choices=("none", "busy", "both"), default="both")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    _ = pkmkit.machine("orthoglide").jacobian(np.zeros((10_000, 3))).condition  # compile, load
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores; "
          f"{args.poses} poses; medians of interleaved runs")
    results = {}
    for label, context in conditions(args.load):
        with context():
            ik_rows = bench_ik(args)
            jac = bench_jacobian(args)
        results[label] = {"ik": ik_rows, "jacobian": jac}
        print(f"\n[{label}] inverse model m.ik(X)")
        print(f"{'machine':13} {'alone: ik ms':>12} {'copy ms':>8} {'xcopy':>6} | {'ik ms':>7} "
              f"{'copy ms':>8} {'xcopy':>6} {'xloop':>6} {'numpy ms':>9} {'xcopy':>6} {'xloop':>6} "
              f"{'BLAS ms':>8}")
        for r in ik_rows:
            print(f"{r['machine']:13} {r['alone_ik_s'] * 1e3:12.2f} {r['alone_copy_s'] * 1e3:8.2f} "
                  f"{r['alone_ik_over_copy']:6.2f} | {r['ik_s'] * 1e3:7.2f} "
                  f"{r['copy_s'] * 1e3:8.2f} {r['ik_over_copy']:6.2f} "
                  f"{r['loop_ratio']:6.0f} {r['numpy_s'] * 1e3:9.2f} "
                  f"{r['numpy_over_copy']:6.1f} {r['numpy_loop_ratio']:6.0f} "
                  f"{r['blas_s'] * 1e3:8.2f}")
        print(f"  largest difference loop / NumPy / BLAS vs kernel: "
              f"{max(r['max_difference_m'] for r in ik_rows):.1e} m")
        print(f"[{label}] velocity model m.jacobian(X): singular values + condition "
              f"{jac['jacobian_s']:.3f} s (best {jac['best_jacobian_s']:.3f} s; "
              f"x{jac['cond_ratio']:.0f} numpy.linalg.cond per "
              f"pose, {jac['over_limit']:.0f}x the copy limit {jac['limit_s'] * 1e3:.1f} ms); "
              f"NumPy path {jac['numpy_s']:.3f} s (x{jac['numpy_cond_ratio']:.0f}); every "
              f"field {jac['all_fields_s']:.3f} s")
        print(f"  numpy.linalg.cond: {1 / jac['cond_per_pose_s']:.0f} poses/s; largest "
              f"relative difference vs the NumPy path {jac['max_rel_difference_vs_numpy_path']:.1e}"
              f", condition vs numpy.linalg.cond "
              f"{jac['max_rel_difference_condition_vs_cond']:.1e}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(results, handle, indent=2)


if __name__ == "__main__":
    main()
