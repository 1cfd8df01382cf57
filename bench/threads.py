"""Benchmark: one built machine called from several Python threads (docs/kinematics.md,
"Threads"; docs/testing.md, "Audit of threads, session 35").

The same work — ``calls`` one-pose ``m.ik(x)`` calls, or ``batches`` batch calls
``m.ik(X)`` of ``rows`` poses — done by one thread (the baseline) and split over ``threads``
Python threads sharing the machine, in the same process, interleaved over ``--rounds`` rounds
(each figure a median; the baseline and the threaded run see the same load). Printed: wall and
CPU time per call and the threaded/baseline ratio of wall time (below 1: the threads gain).
Batches run twice: with each call spread over the helper pool (``PKMKIT_THREADS`` default) and
with ``PKMKIT_THREADS=1`` (each call on its own thread: the parallelism is the caller's).

Usage::

    python bench/threads.py [--machines orthoglide,gough-stewart] [--threads 2]
        [--calls 20000] [--rows 65536] [--batches 40] [--rounds 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import threading
import time
import warnings

import numpy as np

import pkmkit
from pkmkit.exceptions import StrokeWarning


def timed(work, items: list, threads: int) -> tuple[float, float]:
    """Wall and process-CPU seconds of ``work(item)`` over ``items`` split over ``threads``
    threads (1: this thread)."""
    parts = [items[k::threads] for k in range(threads)]
    start = threading.Barrier(threads + 1) if threads > 1 else None

    def run(part):
        if start is not None:
            start.wait()
        for item in part:
            work(item)

    wall, cpu = time.perf_counter(), time.process_time()
    if threads == 1:
        run(items)
    else:
        pool = [threading.Thread(target=run, args=(p,)) for p in parts]
        for t in pool:
            t.start()
        wall, cpu = time.perf_counter(), time.process_time()
        start.wait()
        for t in pool:
            t.join()
    return time.perf_counter() - wall, time.process_time() - cpu


def compare(label: str, work, items: list, threads: int, rounds: int) -> None:
    base, split = [], []
    for _ in range(rounds):
        base.append(timed(work, items, 1))
        split.append(timed(work, items, threads))
    n = len(items)
    b_wall, b_cpu = (statistics.median(v[i] for v in base) for i in (0, 1))
    s_wall, s_cpu = (statistics.median(v[i] for v in split) for i in (0, 1))
    print(f"  {label:44s} 1 thread {b_wall / n * 1e6:9.2f} µs/call (CPU {b_cpu / n * 1e6:9.2f});"
          f" {threads} threads {s_wall / n * 1e6:9.2f} (CPU {s_cpu / n * 1e6:9.2f});"
          f" wall ratio {s_wall / b_wall:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--machines", default="orthoglide,gough-stewart")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--rows", type=int, default=1 << 16)
    parser.add_argument("--batches", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore", StrokeWarning)
    print(f"load average {os.getloadavg()[0]:.2f}; {len(os.sched_getaffinity(0))} cores")
    for name in args.machines.split(","):
        m = pkmkit.machine(name)
        q_home = np.asarray(m.ik(m.home_pose))
        rng = np.random.default_rng(0)
        q = q_home + rng.uniform(-5e-3, 5e-3, (args.rows, q_home.size))
        x = m.fk(q, strokes="ignore")
        one = [x[k].copy() for k in range(args.calls)]
        print(name)
        compare("ik one pose", m.ik, one, args.threads, args.rounds)
        batches = [x] * args.batches
        compare(f"ik {args.rows} rows, pool (default)", m.ik, batches, args.threads,
                args.rounds)
        before = os.environ.get("PKMKIT_THREADS")
        os.environ["PKMKIT_THREADS"] = "1"
        try:
            compare(f"ik {args.rows} rows, PKMKIT_THREADS=1", m.ik, batches, args.threads,
                    args.rounds)
        finally:
            if before is None:
                del os.environ["PKMKIT_THREADS"]
            else:
                os.environ["PKMKIT_THREADS"] = before
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
