"""Benchmark: batched closure + complete direct model of the Tripteor X7 on 10⁴ configurations
against a per-configuration ``scipy.optimize.least_squares`` on the same residual.

- pkmkit: ``m.fk(Q, full_output=True)`` on ``--configs`` random actuator vectors (Table 5.3
  ranges widened by 10 mm and 5°): the least-squares closure of the three legs on the platform
  (16 unknowns, 18 equations, the batched engine) then the head and the tool point, every
  passive joint and the closure residual.
- baseline: the thesis's approach (MATLAB ``lsqnonlin``, one call per pose), i.e. SciPy's
  ``least_squares`` (MINPACK Levenberg–Marquardt) called configuration by configuration on the
  same closure residual and analytic Jacobian (:func:`pkmkit.solve.chains.closure` at one
  configuration; the platform rotation parametrised by its rotation vector, with the SO(3) left
  Jacobian), from the same start, then the same head; on the first ``--scipy-configs``
  configurations. The answers of the two are compared.

Both run in the same process on the same inputs, interleaved, ``--repeat`` times, first on the
machine as it is ("quiet": other users' work included, see the load average printed), then with
a competing process started by this script (a NumPy loop on one core, single-threaded BLAS) —
the ratios are what to compare across runs. The processor time of the batched call (``CPU µs``)
is printed as well: it is what the call costs whatever else shares the cores.

Usage::

    python bench/chains.py [--configs 10000] [--scipy-configs 300] [--repeat 5] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np
from scipy.optimize import least_squares

import pkmkit
from pkmkit.solve.chains import closure, tool_frame
from pkmkit.spatial.rotation import rotvec_to_matrix, skew

COMPETITOR = """
import numpy as np
a = np.random.default_rng(0).normal(size=(400, 400))
while True:
    a = np.tanh(a @ a.T / 400.0)
"""


def configurations(m, n: int, seed: int = 2026) -> np.ndarray:
    """Random actuator vectors in the Table 5.3 ranges, widened by 10 mm and 5°."""
    rng = np.random.default_rng(seed)
    lo = np.array([0.965, 1.045, 0.965, np.radians(-20.0), np.radians(-5.0)])
    hi = np.array([1.005, 1.085, 1.005, np.radians(20.0), np.radians(60.0)])
    return lo + (hi - lo) * rng.random((n, len(lo)))


def path(n: int) -> np.ndarray:
    """A smooth joint-space path of n samples through the measured ranges (a Lissajous curve)."""
    t = np.linspace(0.0, 2 * np.pi, n)
    return np.stack([0.985 + 0.01 * np.sin(t), 1.065 + 0.01 * np.sin(2 * t + 1.0),
                     0.985 + 0.01 * np.sin(3 * t + 2.0), np.radians(15.0) * np.sin(t + 0.5),
                     np.radians(27.5) * (1 + np.sin(2 * t))], axis=1)


def left_jacobian(phi: np.ndarray) -> np.ndarray:
    """SO(3) left Jacobian: ``d exp(φ) = [J_l(φ) dφ]× exp(φ)``."""
    theta = float(np.linalg.norm(phi))
    k = skew(phi)
    if theta < 1e-8:
        return np.eye(3) + 0.5 * k
    return (np.eye(3) + (1 - np.cos(theta)) / theta**2 * k
            + (theta - np.sin(theta)) / theta**3 * (k @ k))


def scipy_direct(m, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-configuration SciPy least squares on the library's closure residual, then the head;
    returns tool poses (N, 6) and passive joints (N, 10)."""
    model = m.model
    act, passive = m._actuated, m._passive
    home_values = m._home["values"]
    u0 = np.concatenate([m._home["platform"], home_values[passive]])
    lengths = m.tool_length

    def split(u, q):
        values = home_values.copy()
        values[act] = q
        values[passive] = u[6:]
        rot = rotvec_to_matrix(u[3:6])[0][:, :, None]
        return values[:, None], rot, u[:3, None]

    def residual(u, q):
        values, rot, p = split(u, q)
        return closure(model, rot, p, values).residual[:, 0]

    def jacobian(u, q):
        values, rot, p = split(u, q)
        c = closure(model, rot, p, values)
        jac = np.concatenate([c.platform[:, :, 0], c.variables[:, passive, 0]], axis=1)
        jac[:, 3:6] = jac[:, 3:6] @ left_jacobian(u[3:6])
        return jac

    poses = np.empty((len(qs), 6))
    passives = np.empty((len(qs), len(passive)))
    for i, q in enumerate(qs):
        sol = least_squares(residual, u0, jac=jacobian, args=(q,), method="lm",
                            xtol=1e-15, ftol=1e-15, gtol=1e-15)
        values, rot, p = split(sol.x, q)
        tool = tool_frame(model, rot, p, values)
        axis = tool.R[:, 2, 0]
        poses[i] = np.concatenate([tool.p[:, 0] + lengths * axis, axis])
        passives[i] = sol.x[6:]
    return poses, passives


def timed(func) -> float:
    start = time.perf_counter()
    func()
    return time.perf_counter() - start


def cpu_timed(func) -> float:
    """Processor time of this process (s): what the call costs whatever else runs."""
    start = time.process_time()
    func()
    return time.process_time() - start


def measure(m, qs, n_scipy: int, repeat: int) -> dict:
    sub = qs[:n_scipy]
    t_batch, t_scipy, t_cpu = [], [], []
    for _ in range(repeat):  # interleaved: both see the same load
        t_batch.append(timed(lambda: m.fk(qs, full_output=True)))
        t_cpu.append(cpu_timed(lambda: m.fk(qs, full_output=True)))
        t_scipy.append(timed(lambda: scipy_direct(m, sub)) / len(sub))
    med, best = statistics.median(t_batch), min(t_batch)
    s_med, s_best = statistics.median(t_scipy), min(t_scipy)
    return {
        "batched_seconds_median": med,
        "batched_seconds_best": best,
        "batched_us_per_config_median": med / len(qs) * 1e6,
        "batched_us_per_config_best": best / len(qs) * 1e6,
        "batched_cpu_us_per_config_median": statistics.median(t_cpu) / len(qs) * 1e6,
        "scipy_us_per_config_median": s_med * 1e6,
        "scipy_us_per_config_best": s_best * 1e6,
        "ratio_median": s_med * len(qs) / med,
        "ratio_best": s_best * len(qs) / best,
        "load_average": os.getloadavg()[0],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", type=int, default=10_000)
    parser.add_argument("--scipy-configs", type=int, default=300)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--no-load", action="store_true", help="skip the competing-process run")
    parser.add_argument("--json", help="also write the results to this JSON file")
    args = parser.parse_args()

    m = pkmkit.machine("tripteor-x7")
    qs = configurations(m, args.configs)
    m.fk(qs[:200])
    direct = m.fk(qs, full_output=True)
    n_check = min(args.scipy_configs, 300)
    ref_pose, ref_passive = scipy_direct(m, qs[:n_check])
    result = {
        "configs": args.configs,
        "scipy_configs": args.scipy_configs,
        "all_closed": bool((direct.status == 0).all()),
        "largest_closure_residual_m": float(direct.closure_residual.max()),
        "iterations_max": int(direct.iterations.max()),
        "iterations_mean": float(direct.iterations.mean()),
        "max_pose_difference_vs_scipy": float(np.abs(direct.pose[:n_check] - ref_pose).max()),
        "max_passive_difference_vs_scipy_rad": float(
            np.abs(direct.passive[:n_check] - ref_passive).max()),
        "quiet": measure(m, qs, args.scipy_configs, args.repeat),
    }
    # along a path, each sample warm-started from the solution at the previous one
    along = path(args.configs)
    first = m.fk(along, full_output=True)
    start = np.concatenate([first.platform, first.passive], axis=1)
    start = np.vstack([start[:1], start[:-1]])
    warm = m.fk(along, start=start, full_output=True)
    t_cold = statistics.median(timed(lambda: m.fk(along)) for _ in range(args.repeat))
    t_warm = statistics.median(timed(lambda: m.fk(along, start=start))
                               for _ in range(args.repeat))
    result["path"] = {
        "cold_us_per_config_median": t_cold / args.configs * 1e6,
        "warm_us_per_config_median": t_warm / args.configs * 1e6,
        "cold_iterations_mean": float(first.iterations.mean()),
        "warm_iterations_mean": float(warm.iterations.mean()),
        "max_difference": float(np.abs(warm.pose - first.pose).max()),
    }
    if not args.no_load:
        competitor = subprocess.Popen([sys.executable, "-c", COMPETITOR],
                                      env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        try:
            time.sleep(1.0)
            result["competing_process"] = measure(m, qs, args.scipy_configs, args.repeat)
        finally:
            competitor.kill()
            competitor.wait()

    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    print(f"Tripteor X7 direct model (closure of 3 legs on the platform, 16 unknowns / 18 "
          f"equations, then the head) on {args.configs} configurations, {args.repeat} runs; "
          f"baseline scipy.optimize.least_squares (lm) per configuration on "
          f"{args.scipy_configs}")
    print(f"all closed: {result['all_closed']} (largest closure residual "
          f"{result['largest_closure_residual_m']:.1e} m, {result['iterations_mean']:.2f} "
          f"iterations on average, at most {result['iterations_max']}); largest difference "
          f"from SciPy: tool pose {result['max_pose_difference_vs_scipy']:.1e}, passive joints "
          f"{result['max_passive_difference_vs_scipy_rad']:.1e} rad")
    header = (f"{'run':<18}{'load':>6}{'µs/config med':>15}{'best':>8}{'CPU µs':>8}"
              f"{'scipy µs med':>14}{'ratio med':>11}{'best':>7}")
    print(header)
    for name in ("quiet", "competing_process"):
        if name not in result:
            continue
        r = result[name]
        print(f"{name:<18}{r['load_average']:>6.1f}{r['batched_us_per_config_median']:>15.1f}"
              f"{r['batched_us_per_config_best']:>8.1f}"
              f"{r['batched_cpu_us_per_config_median']:>8.1f}{r['scipy_us_per_config_median']:>14.0f}"
              f"{r['ratio_median']:>11.0f}{r['ratio_best']:>7.0f}")
    p = result["path"]
    print(f"along a path of {args.configs} samples: default start "
          f"{p['cold_us_per_config_median']:.1f} µs/config "
          f"({p['cold_iterations_mean']:.2f} iterations), warm-started from the "
          f"previous sample {p['warm_us_per_config_median']:.1f} µs/config "
          f"({p['warm_iterations_mean']:.2f} iterations); largest difference "
          f"{p['max_difference']:.1e}")
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(result, handle, indent=2)


if __name__ == "__main__":
    main()
