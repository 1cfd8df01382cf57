"""Benchmark of the identification (issues 11 §7 and 22 §7): time per calibration, quiet and with
a competing process, against ``scipy.optimize.least_squares`` with finite-difference Jacobians
on the same residual, in one process on the same inputs.

Problems (synthetic, seeded; tracker noise):

- **Tripteor X7**, seed 002's protocol: 107 poses (platform-only and wrist-only moves, two
  tools), the measurement frame identified jointly: 47 compatible defects that move the tool
  point + 6 frame parameters = 53 unknowns (the class of the thesis's 52), priors at the
  tolerances, every residual evaluation closing the legs in least squares (the "closure
  inside").
- **Gough–Stewart hexapod**, 50 full poses, the 42 identifiable rod parameters (no priors).

Rows, for each condition (``quiet``; ``loaded``: one process keeping a core and the memory bus
busy, :mod:`load`), medians of ``--repeat`` runs, wall and CPU time of this process:

- ``pkmkit calibrate`` — the whole ``calibrate()`` call (set-up fit, compatibility,
  identifiability, solve, uncertainties);
- ``NumPy closures`` — the same call with ``PKMKIT_COMPILED=0``: every closure through the
  batched NumPy engine, as before the compiled closure kernels (:mod:`pkmkit.solve.chain_kernel`);
- ``scipy least_squares (FD)`` — ``least_squares(method="trf", jac="2-point")`` on the whitened
  residual ``identification_problem(...).residual`` (the function the identification evaluates,
  its closures compiled and warm-started too) from the same start, once per condition; the
  ratio is its time over ``calibrate``'s; ``same answer`` compares the optimum in units of the
  parameters' standard deviations and the two costs.

Run: ``python bench/calibration.py [--repeat 5] [--load none|busy|both] [--skip-scipy]``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import statistics
import time

import numpy as np
import scipy
from load import conditions
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


@contextlib.contextmanager
def numpy_closures():
    """``PKMKIT_COMPILED=0`` inside the block (read at every call)."""
    before = os.environ.get("PKMKIT_COMPILED")
    os.environ["PKMKIT_COMPILED"] = "0"
    try:
        yield
    finally:
        if before is None:
            del os.environ["PKMKIT_COMPILED"]
        else:
            os.environ["PKMKIT_COMPILED"] = before


def timed(func, repeat: int) -> tuple[float, float, object]:
    """Median wall and CPU time over ``repeat`` runs, and the last result."""
    walls, cpus, out = [], [], None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = func()
        cpus.append(time.process_time() - c)
        walls.append(time.perf_counter() - t)
    return statistics.median(walls), statistics.median(cpus), out


def interleaved(funcs: dict, repeat: int) -> dict:
    """``{name: (wall, cpu, last result)}``: the functions run in turn, ``repeat`` rounds (a
    change of load falls on all of them), medians."""
    runs = {name: ([], [], None) for name in funcs}
    for _ in range(repeat):
        for name, func in funcs.items():
            walls, cpus, _ = runs[name]
            wall, cpu, out = timed(func, 1)
            walls.append(wall)
            cpus.append(cpu)
            runs[name] = (walls, cpus, out)
    return {name: (statistics.median(w), statistics.median(c), out)
            for name, (w, c, out) in runs.items()}


def scipy_baseline(problem):
    from scipy.optimize import least_squares

    with threadpool_limits(1, "blas"):
        return least_squares(problem.residual, problem.u0, jac="2-point", method="trf",
                             x_scale=1.0, xtol=1e-10, ftol=1e-12, gtol=1e-10)


def problem_rows(title: str, m, data, options: dict, repeat: int, skip_scipy: bool,
                 seed_ratio: bool = False) -> None:
    def ours():
        return calibrate(m, data, **options)

    def numpy_path():
        with numpy_closures():
            return calibrate(m, data, **options)

    runs = interleaved({"ours": ours, "numpy": numpy_path}, repeat)
    wall, cpu, res = runs["ours"]
    unknowns = len(res.names) + len(res.setup_names)
    print(f"  {title}, {len(data)} poses, {unknowns} unknowns ({len(res.names)} machine + "
          f"{len(res.setup_names)} set-up):")
    seed = f"   {SEED_SECONDS / wall:,.0f}× the seed's 266.72 min" if seed_ratio else ""
    print(f"    pkmkit calibrate          {wall:7.3f} s wall {cpu:7.3f} s CPU  "
          f"({res.iterations} iterations, RMS {res.before.rms * 1e3:.4f} → "
          f"{res.after.rms * 1e3:.4f} mm){seed}")
    n_wall, n_cpu, old = runs["numpy"]
    same = np.abs(np.concatenate([res.values - old.values, res.setup_values - old.setup_values])
                  / np.concatenate([old.std, old.setup_std])).max()
    print(f"    NumPy closures            {n_wall:7.3f} s wall {n_cpu:7.3f} s CPU  "
          f"(×{n_wall / wall:.1f} wall, ×{n_cpu / cpu:.1f} CPU; max |Δ| {same:.1e} σ)")
    if skip_scipy:
        return
    problem = identification_problem(m, data, **options)
    s_wall, s_cpu, sp = timed(lambda: scipy_baseline(problem), 1)
    ours_u = np.concatenate([res.values, res.setup_values]) / problem.scale
    std = np.concatenate([res.std, res.setup_std]) / problem.scale
    diff = np.abs(ours_u - sp.x) / std
    cost = 0.5 * float(np.sum(problem.residual(ours_u) ** 2))
    print(f"    scipy least_squares (FD)  {s_wall:7.3f} s wall {s_cpu:7.3f} s CPU  "
          f"({sp.nfev} evaluations)   ratio {s_wall / wall:.0f}× wall, {s_cpu / cpu:.0f}× CPU")
    print(f"    same answer: max |Δ| = {diff.max():.2e} σ, cost {cost:.6f} vs {sp.cost:.6f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--load", choices=("none", "busy", "both"), default="both")
    parser.add_argument("--skip-scipy", action="store_true")
    args = parser.parse_args()
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, scipy {scipy.__version__}, "
          f"Python {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores")
    tripteor = tripteor_data()
    hexapod = hexapod_data()
    for m, data, options in ((*tripteor, {"frame": "identify", "prior": True}),
                             (*hexapod, {"prune": False})):
        calibrate(m, data, **options)  # compiled kernels loaded, caches warm
    for label, context in conditions(args.load):
        print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
        with context():
            problem_rows("Tripteor X7 (two tools, frame identified, closure inside)", *tripteor,
                         {"frame": "identify", "prior": True}, args.repeat, args.skip_scipy,
                         seed_ratio=True)
            problem_rows("Gough–Stewart, full poses", *hexapod, {"prune": False}, args.repeat,
                         args.skip_scipy)


if __name__ == "__main__":
    main()
