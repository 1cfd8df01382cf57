"""Benchmark: singular values and condition number of J for 10⁶ Orthoglide poses.

``m.jacobian(X)`` (inverse model, A, B, J, singular values, condition, singularity class, all
batched) against baselines run in the same process on the same poses:

- ``numpy.linalg.cond`` called pose by pose on J (the loop a user would write), on the first
  ``--loop-poses`` poses, throughputs compared;
- ``numpy.linalg.svd`` batched over all the J matrices (LAPACK), for reference.

The machines are shared and noisy: every measurement is repeated (``--repeat`` times for the
batched call, interleaved with the loop so that both see the same load) and the script prints the
median and the best time of each, and the ratios of medians and of bests. The median is the
figure to quote; the best shows what the code does on a quiet machine.

Usage::

    python bench/analysis.py [--poses 1000000] [--loop-poses 20000] [--repeat 15] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import time

import numpy as np

import pkmkit


def timed(func) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--loop-poses", type=int, default=20_000)
    parser.add_argument("--repeat", type=int, default=15,
                        help="runs of the batched call (the loop runs every third time)")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    m = pkmkit.machine("orthoglide")
    rng = np.random.default_rng(2026)
    poses = rng.uniform(-0.1, 0.07, (args.poses, 3))  # the prescribed cube and around
    def full_call(x):
        """The call and every field this benchmark describes (m.jacobian computes its fields
        when they are read, see pkmkit.machines.velocity)."""
        jac = m.jacobian(x)
        _ = jac.J, jac.singular_values, jac.condition, jac.singularity
        return jac

    full_call(poses[:1000])
    jac = full_call(poses)
    j = np.ascontiguousarray(jac.J)
    sub = j[: args.loop_poses]
    t_batch, t_loop = [], []
    for k in range(args.repeat):  # interleaved: both see the same machine load
        t_batch.append(timed(lambda: full_call(poses)))
        if k % 3 == 0:
            t_loop.append(timed(lambda: [np.linalg.cond(x) for x in sub]) / len(sub))
    loop_cond = np.array([np.linalg.cond(x) for x in sub[:2000]])
    t_svd = [timed(lambda: np.linalg.svd(j, compute_uv=False)) for _ in range(3)]
    sv_ref = np.linalg.svd(j[:100_000], compute_uv=False)

    med, best = statistics.median(t_batch), min(t_batch)
    loop_med, loop_best = statistics.median(t_loop), min(t_loop)
    svd_med = statistics.median(t_svd)
    result = {
        "poses": args.poses,
        "repeat": args.repeat,
        "jacobian_seconds_median": med,
        "jacobian_seconds_best": best,
        "jacobian_seconds_worst": max(t_batch),
        "jacobian_poses_per_s_median": args.poses / med,
        "cond_loop_poses_per_s_median": 1 / loop_med,
        "ratio_vs_cond_loop_median": args.poses * loop_med / med,
        "ratio_vs_cond_loop_best": args.poses * loop_best / best,
        "lapack_svd_seconds_median": svd_med,
        "ratio_vs_lapack_svd_median": svd_med / med,
        "max_rel_error_singular_values": float(
            np.abs(jac.singular_values[:100_000] - sv_ref).max() / sv_ref.min()),
        "max_rel_error_condition": float(
            np.abs(jac.condition[:2000] / loop_cond - 1).max()),
    }
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"m.jacobian(X) on {args.poses} Orthoglide poses (IK, A, B, J, singular values, "
          f"condition, singularity class), {args.repeat} runs: median {med:.3f} s "
          f"({args.poses / med / 1e6:.2f} Mposes/s), best {best:.3f} s, worst {max(t_batch):.3f} s")
    print(f"numpy.linalg.cond pose by pose ({len(t_loop)} runs on {len(sub)} poses): median "
          f"{1 / loop_med:.0f} poses/s -> ratio {result['ratio_vs_cond_loop_median']:.0f}x "
          f"(medians), {result['ratio_vs_cond_loop_best']:.0f}x (bests)")
    print(f"numpy.linalg.svd batched on J alone: median {svd_med:.3f} s -> ratio "
          f"{result['ratio_vs_lapack_svd_median']:.1f}x")
    print(f"largest relative difference of the singular values vs LAPACK: "
          f"{result['max_rel_error_singular_values']:.1e}; of the condition numbers vs "
          f"numpy.linalg.cond: {result['max_rel_error_condition']:.1e}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
