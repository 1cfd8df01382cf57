"""Benchmark of the identification (issue 11 §7): time per calibration and the ratio to
``scipy.optimize.least_squares`` with finite-difference Jacobians on the same residual.

Problems (synthetic, seeded; tracker/realistic noise):

- **Tripteor X7**, seed 002's protocol: 107 poses (platform-only and wrist-only moves, two
  tools), the measurement frame identified jointly: 47 compatible defects that move the tool
  point + 6 frame parameters = 53 unknowns (the class of the thesis's 52), priors at the
  tolerances, every residual evaluation closing the legs in least squares (the "closure
  inside"). Baseline: scipy ``least_squares`` (TRF, ``jac="2-point"``) on the same whitened
  residual from the same start, to the same optimum (compared in units of the parameters'
  standard deviations).
- **Gough–Stewart hexapod**, 50 full poses, the 42 identifiable rod parameters (no priors).

Run: ``python bench/calibration.py [--repeat 3] [--skip-scipy]``. Prints the medians.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np
from threadpoolctl import threadpool_limits

import pkmkit
from pkmkit.calibration.identify import calibrate, identification_problem
from pkmkit.calibration.simulate import default_configurations, random_defects, simulate

#: The seed's run time (MATLAB lsqnonlin, 52 parameters, 107 poses): 266.72 min.
SEED_SECONDS = 266.72 * 60


def tripteor_data(seed: int = 7):
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(seed)
    true = m.with_defects(random_defects(m, rng))
    q = default_configurations(m, 107, rng)
    return m, simulate(true, m, "point", len(q), rng, q=q, noise="tracker")


def hexapod_data(seed: int = 3):
    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(seed)
    true = m.with_defects(random_defects(m, rng))
    return m, simulate(true, m, "pose", 50, rng)


def timed(func, repeat: int) -> tuple[float, object]:
    """Median wall time over ``repeat`` runs (and the last result)."""
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = func()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def cpu_timed(func) -> float:
    """CPU time of this process for one run (less sensitive to other processes)."""
    t = time.process_time()
    func()
    return time.process_time() - t


def scipy_baseline(problem):
    from scipy.optimize import least_squares

    with threadpool_limits(1, "blas"):
        return least_squares(problem.residual, problem.u0, jac="2-point", method="trf",
                             x_scale=1.0, xtol=1e-10, ftol=1e-12, gtol=1e-10)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--skip-scipy", action="store_true")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")

    m, data = tripteor_data()
    options = {"frame": "identify", "prior": True}
    t_ours, res = timed(lambda: calibrate(m, data, **options), args.repeat)
    cpu = cpu_timed(lambda: calibrate(m, data, **options))
    unknowns = len(res.names) + len(res.setup_names)
    print(f"Tripteor X7, {len(data)} poses (two tools), {unknowns} unknowns "
          f"({len(res.names)} defects + {len(res.setup_names)} frame), closure inside:")
    print(f"  pkmkit calibrate          {t_ours:8.3f} s  ({res.iterations} iterations, RMS "
          f"{res.before.rms * 1e3:.3f} → {res.after.rms * 1e3:.4f} mm; CPU {cpu:.3f} s)   "
          f"{SEED_SECONDS / t_ours:,.0f}× the seed's 266.72 min")
    if not args.skip_scipy:
        problem = identification_problem(m, data, **options)
        t_sp, sp = timed(lambda: scipy_baseline(problem), 1)
        ours = np.concatenate([res.values, res.setup_values]) / problem.scale
        std = np.concatenate([res.std, res.setup_std]) / problem.scale
        theirs = sp.x.copy()
        # rotation parameters compose on the left in ours, add in scipy's: compare the points
        diff = np.abs(ours - theirs) / std
        cost_ours = 0.5 * float(np.sum(problem.residual(ours) ** 2))
        print(f"  scipy least_squares (FD)  {t_sp:8.3f} s  ({sp.nfev} evaluations)   ratio "
              f"{t_sp / t_ours:.1f}×")
        print(f"  same answer: max |Δ| = {diff.max():.2e} σ, cost {cost_ours:.6f} vs "
              f"{sp.cost:.6f}")

    m6, data6 = hexapod_data()
    t6, res6 = timed(lambda: calibrate(m6, data6, prune=False), args.repeat)
    cpu6 = cpu_timed(lambda: calibrate(m6, data6, prune=False))
    print(f"Gough–Stewart, {len(data6)} full poses, {len(res6.names)} parameters:")
    print(f"  pkmkit calibrate          {t6:8.3f} s  ({res6.iterations} iterations, RMS "
          f"{res6.before.rms * 1e3:.4f} → {res6.after.rms * 1e3:.4f} mm; CPU {cpu6:.3f} s)")


if __name__ == "__main__":
    main()
