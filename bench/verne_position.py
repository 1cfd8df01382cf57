"""Benchmark: the Verne module's position inverse, ``m.ik(P)`` and ``m.ik(P,
full_output=True)``, by the paired Newton solve from its start table (default, session 35)
against the same solve from the first-order start (``PKMKIT_POSITION_TABLE=0``) and the former
Levenberg–Marquardt solve of every row (``PKMKIT_POSITION_PAIRED=0``), all in this process,
alternated, on the same positions (issue 22 §5, sessions 34–35).

Two sets of ``--rows`` positions: ``cli`` — home ± 0.05 m per axis, the table of
``bench/cli_io.py --six-axis verne``; ``box`` — the machine's default box (± 0.2 m). Per
call: the median wall time and the median CPU time (user + system, both threads) of
``--repeat`` runs, and the ratios former / table and first-order / table. On a loaded
machine compare the ratios and the CPU times.

Usage::

    python bench/verne_position.py [--rows 1000000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings

import numpy as np

import pkmkit


def timed(func) -> tuple[float, float]:
    """(wall s, CPU s) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    func()
    return time.perf_counter() - wall, time.process_time() - cpu


#: The paths compared: their environment.
PATHS = {"former": {"PKMKIT_POSITION_PAIRED": "0"},
         "first": {"PKMKIT_POSITION_PAIRED": "1", "PKMKIT_POSITION_TABLE": "0"},
         "table": {"PKMKIT_POSITION_PAIRED": "1", "PKMKIT_POSITION_TABLE": "1"}}


def compare(m, p: np.ndarray, full_output: bool, repeat: int) -> dict[str, tuple[float, float]]:
    """Median (wall, CPU) of ``m.ik(p, full_output=...)`` per path, the paths alternated."""
    runs: dict[str, list[tuple[float, float]]] = {path: [] for path in PATHS}
    for _ in range(repeat):
        for path, env in PATHS.items():
            os.environ.update(env)
            runs[path].append(timed(lambda: m.ik(p, full_output=full_output)))
    for name in ("PKMKIT_POSITION_PAIRED", "PKMKIT_POSITION_TABLE"):
        os.environ.pop(name, None)
    return {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v))
            for k, v in runs.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # rows beyond a stroke
    m = pkmkit.machine("verne")
    rng = np.random.default_rng(0)
    sets = {"cli": np.round(m.home_pose[:3] + rng.uniform(-0.05, 0.05, (args.rows, 3)), 6),
            "box": rng.uniform(-0.2, 0.2, (args.rows, 3))}
    m.ik(sets["cli"][:1000], full_output=True)  # warm: kernels loaded
    print(f"Verne position inverse, {args.rows} rows, median of {args.repeat} "
          f"(load average {' '.join(f'{v:.2f}' for v in os.getloadavg())})")
    print(f"{'positions':<10} {'call':<26} {'former s':>8} {'first s':>8} {'table s':>8} "
          f"{'xformer':>7} {'xfirst':>6} {'former cpu':>10} {'first cpu':>9} {'table cpu':>9} "
          f"{'xformer':>7} {'xfirst':>6}")
    for name, p in sets.items():
        for full_output in (False, True):
            r = compare(m, p, full_output, args.repeat)
            call = "m.ik(P, full_output=True)" if full_output else "m.ik(P)"
            (fw, fc), (sw, sc), (tw, tc) = r["former"], r["first"], r["table"]
            print(f"{name:<10} {call:<26} {fw:8.3f} {sw:8.3f} {tw:8.3f} {fw / tw:7.2f} "
                  f"{sw / tw:6.2f} {fc:10.3f} {sc:9.3f} {tc:9.3f} {fc / tc:7.2f} {sc / tc:6.2f}")
    print(f"(load average after: {' '.join(f'{v:.2f}' for v in os.getloadavg())})")


if __name__ == "__main__":
    main()
