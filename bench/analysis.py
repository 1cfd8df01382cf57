"""Benchmark: singular values and condition number of J for 10⁶ Orthoglide poses.

``m.jacobian(X)`` (inverse model, A, B, J, singular values, condition, singularity class, all
batched) against baselines run in the same process on the same poses:

- ``numpy.linalg.cond`` called pose by pose on J (the loop a user would write), on the first
  ``--loop-poses`` poses, throughputs compared;
- ``numpy.linalg.svd`` batched over all the J matrices (LAPACK), for reference.

Usage::

    python bench/analysis.py [--poses 1000000] [--loop-poses 20000] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import pkmkit


def best_time(func, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--loop-poses", type=int, default=20_000)
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    m = pkmkit.machine("orthoglide")
    rng = np.random.default_rng(2026)
    poses = rng.uniform(-0.1, 0.07, (args.poses, 3))  # the prescribed cube and around
    m.jacobian(poses[:1000])
    t_batch = best_time(lambda: m.jacobian(poses), 3)
    jac = m.jacobian(poses)
    j = np.ascontiguousarray(jac.J)
    sub = j[: args.loop_poses]
    t_loop = best_time(lambda: [np.linalg.cond(x) for x in sub], 1) / len(sub)
    loop_cond = np.array([np.linalg.cond(x) for x in sub[:2000]])
    t_svd = best_time(lambda: np.linalg.svd(j, compute_uv=False), 1)
    sv_ref = np.linalg.svd(j[:100_000], compute_uv=False)

    rate = args.poses / t_batch
    result = {
        "poses": args.poses,
        "jacobian_seconds": t_batch,
        "jacobian_poses_per_s": rate,
        "cond_loop_poses_per_s": 1 / t_loop,
        "ratio_vs_cond_loop": rate * t_loop,
        "lapack_svd_seconds": t_svd,
        "ratio_vs_lapack_svd": t_svd / t_batch,
        "max_rel_error_singular_values": float(
            np.abs(jac.singular_values[:100_000] - sv_ref).max() / sv_ref.min()),
        "max_rel_error_condition": float(
            np.abs(jac.condition[:2000] / loop_cond - 1).max()),
    }
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"m.jacobian(X) on {args.poses} Orthoglide poses (IK, A, B, J, singular values, "
          f"condition, singularity class): {t_batch:.3f} s = {rate / 1e6:.2f} Mposes/s")
    print(f"numpy.linalg.cond pose by pose: {1 / t_loop:.0f} poses/s -> ratio "
          f"{result['ratio_vs_cond_loop']:.0f}x")
    print(f"numpy.linalg.svd batched on J alone: {t_svd:.3f} s -> ratio "
          f"{result['ratio_vs_lapack_svd']:.1f}x")
    print(f"largest relative difference of the singular values vs LAPACK: "
          f"{result['max_rel_error_singular_values']:.1e}; of the condition numbers vs "
          f"numpy.linalg.cond: {result['max_rel_error_condition']:.1e}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
