"""Benchmark: elastostatics of many poses, quiet and with a competing process.

For each condition (``quiet``; ``loaded`` with one process keeping a core and the memory bus
busy, :mod:`load`) the median of ``--repeat`` runs of each figure, with its baselines measured in
the same run on the same inputs:

- **stiffness map of a 3-DOF machine** — ``stiffness_figures(orthoglide, X)`` (the smallest
  translational stiffness, the index of ``pkmkit map --index stiffness``) on ``--poses`` poses:
  seconds for the whole map, against the per-pose Python baseline (``pkmkit.stiffness.stiffness``
  called pose by pose, on a sample, scaled) and against the NumPy batch path
  (``PKMKIT_COMPILED=0``, on a sample, scaled);
- **hexapod 6×6 stiffness** — ``rod_leg_stiffness(gough_stewart, P, compliance=False)`` (K at
  the platform reference point) on ``--poses`` full poses: poses/s, the same two baselines;
- **Tripteor VJM** — ``chain_compliance(tripteor, Q)`` (forward model for the passive joints,
  closure assembly, null-space compliance) on ``--configurations`` actuator configurations:
  configurations/s, the per-configuration ``stiffness(tripteor, q=q)`` and the SVD-only batch
  path (``PKMKIT_COMPILED=0``); and the compliance of the already assembled closures alone.

Each row prints the largest difference to its baseline (relative, Frobenius norm per matrix)
and the CPU time per pose (all threads: what a loaded machine does not inflate as much).

    python bench/stiffness.py [--poses 1000000] [--configurations 20000] [--repeat 3]
                              [--load none|busy|both]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from load import conditions

import pkmkit
from pkmkit.numerics import jit
from pkmkit.spatial import pose_from_angles
from pkmkit.stiffness import default_data, rod_leg_stiffness, stiffness
from pkmkit.stiffness.indices import stiffness_figures
from pkmkit.stiffness.joint_chains import assemble, chain_compliance, system_compliance

#: Poses of the per-pose Python baseline (scaled to the batch).
LOOP_SAMPLE = 1000


def _time(fun, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fun()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _cpu(fun) -> float:
    start = time.process_time()
    fun()
    return time.process_time() - start


def _numpy_path(fun):
    os.environ["PKMKIT_COMPILED"] = "0"
    try:
        start = time.perf_counter()
        out = fun()
        return time.perf_counter() - start, out
    finally:
        del os.environ["PKMKIT_COMPILED"]


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(a).all(axis=(1, 2)) & np.isfinite(b).all(axis=(1, 2))
    return float((np.linalg.norm(a[ok] - b[ok], axis=(1, 2))
                  / np.linalg.norm(b[ok], axis=(1, 2))).max(initial=0.0))


def map_rows(m, x: np.ndarray, repeat: int) -> None:
    stiffness_figures(m, x[:5000])  # compile / warm up
    sample = x[:LOOP_SAMPLE]
    t_api = _time(lambda: stiffness_figures(m, x), repeat)
    cpu = _cpu(lambda: stiffness_figures(m, x)) / len(x)
    start = time.perf_counter()
    loop = np.array([stiffness(m, p).translational[0] for p in sample])
    t_loop = (time.perf_counter() - start) * len(x) / len(sample)
    big = x[:100_000]
    t_numpy, ref = _numpy_path(lambda: stiffness_figures(m, big).smallest)
    t_numpy *= len(x) / len(big)
    fast = stiffness_figures(m, big).smallest
    gap = np.nanmax(np.abs(fast - ref) / ref)
    gap_loop = np.max(np.abs(fast[:LOOP_SAMPLE] - loop) / loop)
    print(f"  map {m.id:<12} {len(x):,} poses in {t_api:6.3f} s ({len(x) / t_api / 1e6:5.2f} "
          f"Mposes/s, {jit.thread_count()} threads, {cpu * 1e9:.0f} ns CPU per pose)   "
          f"×per-pose {t_loop / t_api:7.0f}   "
          f"×NumPy batch {t_numpy / t_api:5.1f}   (largest relative difference {gap_loop:.1e} "
          f"per-pose, {gap:.1e} NumPy)")


def hexapod_rows(m, x: np.ndarray, repeat: int) -> None:
    rod_leg_stiffness(m, x[:5000])
    sample = x[:LOOP_SAMPLE]
    t_api = _time(lambda: rod_leg_stiffness(m, x, compliance=False), repeat)
    cpu = _cpu(lambda: rod_leg_stiffness(m, x, compliance=False)) / len(x)
    start = time.perf_counter()
    loop = np.array([stiffness(m, p).stiffness for p in sample])
    t_loop = (time.perf_counter() - start) * len(x) / len(sample)
    big = x[:100_000]
    t_numpy, ref = _numpy_path(lambda: rod_leg_stiffness(m, big)[1])
    t_numpy *= len(x) / len(big)
    k, c, _ = rod_leg_stiffness(m, big)
    print(f"  6×6 {m.id:<12} {len(x) / t_api / 1e6:5.2f} Mposes/s ({jit.thread_count()} threads, "
          f"{cpu * 1e9:.0f} ns CPU per pose)"
          f"   ×per-pose {t_loop / t_api:7.0f}   ×NumPy batch {t_numpy / t_api:5.1f}   (largest "
          f"relative difference: K {_gap(k[:LOOP_SAMPLE], loop):.1e} per-pose (its K from C's "
          f"eigenvectors), C {_gap(c, ref):.1e} NumPy)")


def chain_rows(m, q: np.ndarray, repeat: int) -> None:
    data = default_data(m)
    chain_compliance(m, q[:200], data)
    sample = q[:200]
    t_api = _time(lambda: chain_compliance(m, q, data), repeat)
    cpu = _cpu(lambda: chain_compliance(m, q, data)) / len(q)
    start = time.perf_counter()
    loop = np.array([stiffness(m, q=row).compliance for row in sample])
    t_loop = (time.perf_counter() - start) * len(q) / len(sample)
    t_numpy, ref = _numpy_path(lambda: chain_compliance(m, q, data)[0])
    c, _, system = chain_compliance(m, q, data)
    args = (system.G, system.H, system.T, system.status, system.columns,
            1.0 / data.actuator_stiffness)
    t_solve = _time(lambda: system_compliance(*args), repeat)
    t_asm = _time(lambda: assemble(m, q, data), 1)
    print(f"  VJM {m.id:<12} {len(q) / t_api / 1e3:6.1f} kconfigurations/s ({cpu * 1e6:.0f} µs "
          f"CPU each)   ×per-pose "
          f"{t_loop / t_api:5.0f}   ×SVD batch {t_numpy / t_api:4.1f}   (of which forward model "
          f"and assembly {t_asm / t_api:.0%}; the compliance of assembled closures alone "
          f"{len(q) / t_solve / 1e3:.0f} k/s; largest relative difference "
          f"{_gap(c[:len(sample)], loop):.1e} per-pose, {_gap(c, ref):.1e} SVD)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--configurations", type=int, default=20_000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--load", choices=("none", "busy", "both"), default="both")
    args = parser.parse_args()
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, Python "
          f"{platform.python_version()}, {platform.machine()}")
    rng = np.random.default_rng(0)
    ortho = pkmkit.machine("orthoglide")
    x3 = ortho.home_pose + rng.uniform(-0.1, 0.1, (args.poses, 3))
    hexapod = pkmkit.machine("gough-stewart")
    x6 = pose_from_angles(hexapod.home_pose[:3] + rng.uniform(-0.1, 0.1, (args.poses, 3)),
                          rng.uniform(-8, 8, (args.poses, 3)), "xyz", degrees=True)
    tripteor = pkmkit.machine("tripteor-x7")
    q = tripteor.home_q + rng.uniform(-0.05, 0.05, (args.configurations, tripteor.n_actuators))
    for label, context in conditions(args.load):
        print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
        with context():
            map_rows(ortho, x3, args.repeat)
            hexapod_rows(hexapod, x6, args.repeat)
            chain_rows(tripteor, q, args.repeat)


if __name__ == "__main__":
    main()
