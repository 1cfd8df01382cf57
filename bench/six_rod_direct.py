"""Benchmark: every real direct-kinematic solution of general six-rod (6-6) platforms.

``six_rod_direct_all`` (Study-coordinate parameter homotopy, 40 paths per configuration)
against a baseline run in the same process on the same configurations: a multi-start
``scipy.optimize.least_squares`` (MINPACK ``lm``, analytic-free, the rod equations
``|p + R b_j − a_j| − ℓ_j``) from ``--starts`` random poses per configuration, keeping the
distinct converged solutions. The baseline is what one writes without an all-solutions
method; it finds *some* of the real solutions, the homotopy finds all of them (certified).

The homotopy runs twice on every input, in the same process: with the compiled path tracker
(:mod:`pkmkit.solve.six_rod_kernel`, the default) and with the NumPy reference tracker
(``compiled=False``, what ``PKMKIT_COMPILED=0`` selects); the two must give the same real
solutions (checked), and their ratio is printed for CPU and wall time (CPU time is the figure
to compare on a shared machine).

Printed:

- the first call of the compiled tracker (Numba's import and the cached kernel's load);
- single configurations, one call each (after loading the stored start system once), the two
  trackers alternated: median, best and worst wall time, median CPU time; their ratios, the
  count of real solutions and the worst rod-length residual;
- one batched call on ``--batch`` configurations per tracker: time per configuration;
- Dietmaier's 40-real-solution platform: time and count (both trackers), and what the baseline
  finds there;
- the baseline on the first ``--baseline`` configurations: time per configuration, the fraction
  of the homotopy's real solutions it found; ratios of times (medians);
- a faster multi-start for reference: pkmkit's own batched Levenberg–Marquardt engine started
  from ``--engine-starts`` random poses in one vectorised call per configuration: its time, the
  fraction of the real solutions it finds and how often it finds them all.

``--load`` starts one competing process (NumPy products in a loop) for the whole run, to see the
figures on a busy machine (the machines are shared: compare ratios, repeat, take medians).

Usage::

    python bench/six_rod_direct.py [--configs 30] [--batch 100] [--baseline 5] [--starts 100]
                                   [--engine-starts 200] [--load] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import platform
import statistics
import time

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.solve.least_squares import solve_least_squares
from pkmkit.solve.six_rod_direct import six_rod_direct_all
from pkmkit.solve.six_rod_start import load_start_system
from pkmkit.status import Status

DIETMAIER = (
    np.array([[0, 0, 0], [1.107915, 0, 0], [0.549094, 0.756063, 0],
              [0.735077, -0.223935, 0.525991], [0.514188, -0.526063, -0.368418],
              [0.590473, 0.094733, -0.205018]]),
    np.array([[0, 0, 0], [0.542805, 0, 0], [0.956919, -0.528915, 0],
              [0.665885, -0.353482, 1.402538], [0.478359, 1.158742, 0.107672],
              [-0.137087, -0.235121, 0.353913]]),
    np.array([1, 0.645275, 1.086284, 1.503439, 1.281933, 0.771071]),
)


def configurations(n: int, seed: int = 2026):
    """General 6-6 geometries (m) with a random pose each; rod lengths from the pose."""
    rng = np.random.default_rng(seed)
    base = rng.uniform(-0.8, 0.8, (n, 6, 3)) * [1.0, 1.0, 0.3]
    platform_pts = rng.uniform(-0.3, 0.3, (n, 6, 3))
    rot = Rotation.random(n, random_state=seed)
    rotvec = rot.as_rotvec() * rng.uniform(0.1, 0.6, (n, 1))
    position = rng.normal(0.0, 0.1, (n, 3)) + np.array([0.0, 0.0, 0.9])
    rb = np.einsum("nij,nkj->nki", Rotation.from_rotvec(rotvec).as_matrix(), platform_pts)
    lengths = np.linalg.norm(position[:, None] + rb - base, axis=2)
    return base, platform_pts, lengths


def multistart(base, platform_pts, lengths, starts: int, rng) -> np.ndarray:
    """Distinct real solutions found by least_squares from random starts."""
    reach = (np.linalg.norm(base, axis=1).max() + np.linalg.norm(platform_pts, axis=1).max()
             + lengths.max())
    found: list[np.ndarray] = []

    def residual(u):
        return np.linalg.norm(u[:3] + Rotation.from_rotvec(u[3:]).apply(platform_pts) - base,
                              axis=1) - lengths

    for rotvec in Rotation.random(starts, random_state=rng.integers(1 << 31)).as_rotvec():
        sol = least_squares(residual, np.r_[rng.uniform(-reach, reach, 3), rotvec],
                            method="lm", xtol=1e-12, ftol=1e-12)
        if np.abs(sol.fun).max() < 1e-9 and not any(_same(sol.x, f) for f in found):
            found.append(sol.x)
    return np.array(found).reshape(-1, 6)


def engine_multistart(base, platform_pts, lengths, starts: int, rng) -> np.ndarray:
    """Distinct real solutions found by pkmkit's batched Levenberg–Marquardt engine from
    ``starts`` random poses, all started in one vectorised call."""
    reach = (np.linalg.norm(base, axis=1).max() + np.linalg.norm(platform_pts, axis=1).max()
             + lengths.max())
    u0 = np.hstack([rng.uniform(-reach, reach, (starts, 3)),
                    Rotation.random(starts, random_state=rng.integers(1 << 31)).as_rotvec()])
    a, b = base.T[:, :, None], platform_pts.T[:, :, None]

    def evaluate(u, rows):
        rot = Rotation.from_rotvec(u[3:].T).as_matrix().transpose(1, 2, 0)
        rb = np.einsum("ijk,jmk->imk", rot, np.broadcast_to(b, (3, 6, u.shape[1])))
        d = u[:3, None] + rb - a
        dist = np.sqrt((d * d).sum(axis=0))
        unit = d / dist
        jac = np.concatenate([unit, np.cross(rb, unit, axis=0)], axis=0).transpose(1, 0, 2)
        return dist - lengths[:, None], jac

    def retract(u, step, rows):
        out = u + step
        out[3:] = (Rotation.from_rotvec(step[3:].T) * Rotation.from_rotvec(u[3:].T)).as_rotvec().T
        return out

    result = solve_least_squares(evaluate, u0, retract=retract, max_iter=100,
                                 compute_rank=False)
    found: list[np.ndarray] = []
    for u in result.u[result.status == Status.OK]:
        if not any(_same(u, f) for f in found):
            found.append(u)
    return np.array(found).reshape(-1, 6)


def _same(u, v, tol=1e-6) -> bool:
    angle = (Rotation.from_rotvec(u[3:]).inv() * Rotation.from_rotvec(v[3:])).magnitude()
    return bool(np.abs(u[:3] - v[:3]).max() <= tol and angle <= tol)


_NAME = {True: "compiled", False: "NumPy"}


def _ratio(times: dict, which: int) -> str:
    """``"3.1x"``: median of the NumPy tracker's times over the compiled one's."""
    return (f"{statistics.median(times[False][which]) / statistics.median(times[True][which]):.1f}"
            "x")


def _solution_gap(a, b, k=None) -> float:
    """Largest distance between the real solutions of two results (row ``k`` of batched ones);
    asserts that they have the same count and status."""
    if k is not None:
        a, b = (type(a)(**{f: getattr(r, f)[k] for f in r.__dataclass_fields__}) for r in (a, b))
    assert int(a.count) == int(b.count) and int(a.status) == int(b.status)
    n = int(a.count)
    if n == 0:
        return 0.0
    gaps = [[_gap(u, v) for v in b.poses[:n]] for u in a.poses[:n]]
    return float(np.max(np.min(gaps, axis=1)))


def _gap(u, v) -> float:
    angle = (Rotation.from_rotvec(u[3:]).inv() * Rotation.from_rotvec(v[3:])).magnitude()
    return float(max(np.abs(u[:3] - v[:3]).max(), angle))


def _burn(stop) -> None:  # the competing process
    a = np.random.default_rng(0).normal(size=(300, 300))
    while not stop.is_set():
        a = np.tanh(a @ a.T / 300.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", type=int, default=30)
    parser.add_argument("--batch", type=int, default=100)
    parser.add_argument("--baseline", type=int, default=5)
    parser.add_argument("--starts", type=int, default=100)
    parser.add_argument("--engine-starts", type=int, default=200)
    parser.add_argument("--load", action="store_true")
    parser.add_argument("--json")
    args = parser.parse_args()

    stop = multiprocessing.Event()
    burner = None
    if args.load:
        burner = multiprocessing.Process(target=_burn, args=(stop,), daemon=True)
        burner.start()
    try:
        report = run(args)
    finally:
        if burner is not None:
            stop.set()
            burner.join(5)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report, fh, indent=2)


def run(args) -> dict:
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}, load average "
          f"{os.getloadavg()[0]:.2f}{' + competing process' if args.load else ''}")
    start = time.perf_counter()
    load_start_system()
    print(f"start system loaded and checked in {1e3 * (time.perf_counter() - start):.1f} ms "
          "(once per process)")
    n = max(args.configs, args.batch, args.baseline)
    base, plat, lengths = configurations(n)
    start, start_cpu = time.perf_counter(), time.process_time()
    six_rod_direct_all(base[0], plat[0], lengths[0], compiled=True)
    print(f"first call of the compiled tracker: {time.perf_counter() - start:.2f} s "
          f"(CPU {time.process_time() - start_cpu:.2f} s: Numba import and kernel load, once "
          "per process)")

    # single calls, the two trackers alternated so that both see the same load
    single = {True: ([], []), False: ([], [])}
    counts, worst, gap = [], 0.0, 0.0
    for k in range(args.configs):
        got = {}
        for compiled in (True, False):
            wall, cpu = single[compiled]
            start, start_cpu = time.perf_counter(), time.process_time()
            got[compiled] = six_rod_direct_all(base[k], plat[k], lengths[k], compiled=compiled)
            wall.append(time.perf_counter() - start)
            cpu.append(time.process_time() - start_cpu)
            sols = got[compiled]
            assert sols.complete and sols.n_finite == 40
            worst = max(worst, float(np.nanmax(sols.residual)))
        counts.append(int(got[True].count))
        gap = max(gap, _solution_gap(got[True], got[False]))
    for compiled in (True, False):
        wall, cpu = single[compiled]
        print(f"single configuration, {_NAME[compiled]} tracker: median "
              f"{1e3 * statistics.median(wall):.1f} ms, best {1e3 * min(wall):.1f} ms, worst "
              f"{1e3 * max(wall):.1f} ms over {args.configs} (CPU time: median "
              f"{1e3 * statistics.median(cpu):.1f} ms)")
    med = statistics.median(single[True][0])
    print(f"ratio NumPy / compiled tracker, single: {_ratio(single, 1)} CPU, "
          f"{_ratio(single, 0)} wall; real solutions {min(counts)}–{max(counts)} (mean "
          f"{np.mean(counts):.1f}), the same from both (largest difference {gap:.1e}), worst "
          f"residual {worst:.1e} m")

    rows = slice(0, args.batch)
    timed = {True: ([], []), False: ([], [])}
    batches = {}
    for compiled in (True, False):
        start, start_cpu = time.perf_counter(), time.process_time()
        batches[compiled] = six_rod_direct_all(base[rows], plat[rows], lengths[rows],
                                               compiled=compiled)
        timed[compiled][0].append((time.perf_counter() - start) / args.batch)
        timed[compiled][1].append((time.process_time() - start_cpu) / args.batch)
    batch = batches[True]
    per_config = timed[True][0][0]
    gap = max(_solution_gap(batches[True], batches[False], k) for k in range(args.batch))
    for compiled in (True, False):
        print(f"batched, {args.batch} configurations, {_NAME[compiled]} tracker: "
              f"{1e3 * timed[compiled][0][0]:.1f} ms per configuration (CPU "
              f"{1e3 * timed[compiled][1][0]:.1f} ms), {batches[compiled].complete.sum()} "
              f"certified complete, worst residual {np.nanmax(batches[compiled].residual):.1e} m")
    print(f"ratio NumPy / compiled tracker, batched: {_ratio(timed, 1)} CPU, {_ratio(timed, 0)} "
          f"wall; the same real solutions (largest difference {gap:.1e})")

    dietmaier = {}
    for compiled in (True, False):
        start, start_cpu = time.perf_counter(), time.process_time()
        dietmaier[compiled] = (six_rod_direct_all(*DIETMAIER, compiled=compiled),
                               time.perf_counter() - start, time.process_time() - start_cpu)
    dm, t_dm, cpu_dm = dietmaier[True]
    dm_np, t_dm_np, cpu_dm_np = dietmaier[False]
    assert dm.complete and dm_np.complete and int(dm.count) == int(dm_np.count)
    rng = np.random.default_rng(1)
    start = time.perf_counter()
    dm_found = multistart(*DIETMAIER, args.starts, rng)
    t_dm_base = time.perf_counter() - start
    print(f"Dietmaier 1998: {int(dm.count)} real solutions of {int(dm.n_finite)} in "
          f"{1e3 * t_dm:.1f} ms (CPU {1e3 * cpu_dm:.1f} ms; NumPy tracker: "
          f"{int(dm_np.count)} in {1e3 * t_dm_np:.1f} ms, CPU {1e3 * cpu_dm_np:.1f} ms; the same "
          f"solutions to {_solution_gap(dm, dm_np):.1e}), worst residual "
          f"{np.nanmax(dm.residual):.1e} m; baseline "
          f"({args.starts} starts): {len(dm_found)} of them in {t_dm_base:.1f} s "
          f"({t_dm_base / t_dm:.0f}x the time)")

    base_times, fractions = [], []
    for k in range(args.baseline):
        start = time.perf_counter()
        found = multistart(base[k], plat[k], lengths[k], args.starts, rng)
        base_times.append(time.perf_counter() - start)
        ours = batch.poses[k, : batch.count[k]]
        hit = sum(any(_same(f, p, 1e-6) for p in ours) for f in found)
        assert hit == len(found), "the multi-start found a solution the homotopy missed"
        fractions.append(len(found) / batch.count[k])
    base_med = statistics.median(base_times)
    print(f"baseline multi-start least_squares ({args.starts} starts): median "
          f"{1e3 * base_med:.0f} ms per configuration, found {100 * np.mean(fractions):.0f}% "
          f"of the real solutions (min {100 * min(fractions):.0f}%), none the homotopy missed")
    print(f"ratio baseline / homotopy: {base_med / med:.1f}x (single), "
          f"{base_med / per_config:.1f}x (batched)")

    eng_times, eng_fractions = [], []
    for k in range(args.configs):
        start = time.perf_counter()
        found = engine_multistart(base[k], plat[k], lengths[k], args.engine_starts, rng)
        eng_times.append(time.perf_counter() - start)
        ours = batch.poses[k, : batch.count[k]]
        assert all(any(_same(f, p, 1e-6) for p in ours) for f in found)
        eng_fractions.append(len(found) / batch.count[k])
    eng_med = statistics.median(eng_times)
    start = time.perf_counter()
    dm_eng = engine_multistart(*DIETMAIER, args.engine_starts, rng)
    t_dm_eng = time.perf_counter() - start
    complete = np.mean(np.array(eng_fractions) == 1.0)
    print(f"vectorised multi-start, pkmkit LM engine ({args.engine_starts} starts in one call): "
          f"median {1e3 * eng_med:.1f} ms per configuration ({eng_med / med:.2f}x the homotopy),"
          f" found {100 * np.mean(eng_fractions):.0f}% of the real solutions, all of them in "
          f"{100 * complete:.0f}% of the configurations; Dietmaier: {len(dm_eng)} of 40 in "
          f"{1e3 * t_dm_eng:.0f} ms")
    return {
        "single_median_s": med, "single_best_s": min(single[True][0]),
        "single_cpu_median_s": statistics.median(single[True][1]),
        "numpy_single_median_s": statistics.median(single[False][0]),
        "numpy_single_cpu_median_s": statistics.median(single[False][1]),
        "batched_per_config_s": per_config, "batched_cpu_per_config_s": timed[True][1][0],
        "numpy_batched_per_config_s": timed[False][0][0],
        "numpy_batched_cpu_per_config_s": timed[False][1][0],
        "dietmaier_s": t_dm, "dietmaier_count": int(dm.count), "baseline_median_s": base_med,
        "dietmaier_baseline_s": t_dm_base, "dietmaier_baseline_count": len(dm_found),
        "baseline_found_fraction": float(np.mean(fractions)), "worst_residual_m": worst,
        "engine_multistart_median_s": eng_med,
        "engine_multistart_found_fraction": float(np.mean(eng_fractions)),
        "engine_multistart_complete_fraction": float(complete),
        "engine_multistart_dietmaier_count": len(dm_eng),
    }


if __name__ == "__main__":
    main()
