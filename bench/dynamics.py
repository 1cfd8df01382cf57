"""Benchmark: inverse model, Jacobians and inverse dynamics along a 10⁶-sample linear-Delta
trajectory, against the same computation sample by sample (same process, same inputs).

Usage::

    python bench/dynamics.py [--samples 1000000] [--loop-samples 2000] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

import pkmkit
from pkmkit.dynamics import default_masses, inverse_dynamics
from pkmkit.motion import circle, joint_trajectory, plan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--loop-samples", type=int, default=2000)
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    m = pkmkit.machine("linear-delta-table-iv1")
    masses = default_masses(m)
    path = circle([0, 0, 0.2], 0.15)
    duration = plan(path, feed=0.12, accel=1.0, jerk=10.0, period=0.01).duration
    trajectory = plan(path, feed=0.12, accel=1.0, jerk=10.0,
                      period=duration / (args.samples - 1))
    n = len(trajectory.t)

    def batched():
        jt = joint_trajectory(m, trajectory)
        return inverse_dynamics(m, masses, jt.x, jt.xd, jt.xdd, jt.q, jt.qd, jt.qdd).force

    batched()
    times = []
    for _ in range(3):
        start = time.perf_counter()
        forces = batched()
        times.append(time.perf_counter() - start)
    t_batch = min(times)

    x, xd, xdd = trajectory.x, trajectory.xd, trajectory.xdd
    idx = np.linspace(0, n - 1, args.loop_samples).astype(int)

    def one(k: int) -> np.ndarray:
        q = m.ik(x[k], strokes="ignore")  # limits are the summary's business
        jac = m.jacobian(x[k], q=q)
        rates = m.jacobian_dot(x[k], xd[k], q=q)
        qdd = (jac.A @ xdd[k] + rates.A_dot @ xd[k] - np.diag(rates.B_dot) * rates.qd) / np.diag(
            jac.B)
        return inverse_dynamics(m, masses, x[k][None], xd[k][None], xdd[k][None], q[None],
                                rates.qd[None], qdd[None]).force[0]

    start = time.perf_counter()
    loop = np.array([one(k) for k in idx])
    t_loop = (time.perf_counter() - start) / len(idx)
    error = float(np.abs(loop - forces[idx]).max())
    result = {"samples": n, "batched_seconds": t_batch, "samples_per_s": n / t_batch,
              "loop_samples_per_s": 1 / t_loop, "ratio": t_loop * n / t_batch,
              "max_difference_N": error}
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"linear Delta (Table IV.1), Ø300 mm circle, {n} samples: IK + J + J̇ + q̇, q̈ + inverse "
          f"dynamics (carriages, 6 rods, platform, gravity) in {t_batch:.2f} s = "
          f"{n / t_batch / 1e6:.2f} Msamples/s")
    print(f"sample by sample: {1 / t_loop:.0f} samples/s -> ratio {result['ratio']:.0f}x; "
          f"largest difference {error:.1e} N")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
