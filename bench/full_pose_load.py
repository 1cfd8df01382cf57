"""Benchmark: the hexapod's batch IK beside a competing process — threads, pieces, pages.

Issue 22 §2 asks the six-axis IK to stay within 3× of a copy of the same data into a
preallocated array also with a competing process on the machine. This bench takes the plain
call ``m.ik(X)`` on ``--poses`` hexapod poses apart, quiet and beside :mod:`load`'s competing
process, every variant interleaved round by round with the preallocated copy
(``np.copyto``) in the same process:

- **pages** — the output on fresh pages (``PKMKIT_RECYCLE=0``: ``numpy.empty``, which Linux
  maps and clears on every call) against the recycled output (``jit.batch_output``, the
  default) and against ``m.ik(X, out=Q)`` with ``Q`` reused;
- **threads** — 2 threads (the default on 2 cores) against 1 (``PKMKIT_THREADS=1``);
- **pieces** — the rows per piece drawn from the shared counter (``jit.THREAD_ROWS``: 2¹²,
  2¹⁴, 2¹⁶, and half the batch: two static halves) by :func:`jit.run_chunks`, the default
  until session 35;
- **the shared plan** (``jit.SHARED_INVERSE``, the default since session 35,
  ``native/inverse_shared.c``): every thread on one plan, a held slice computed again by an
  idle thread and written once, the call not waiting for a descheduled helper.

Per variant: the median wall time, the median of the per-round ratios to the same round's
preallocated copy with their range, the best CPU time per pose (process CPU), and minor page
faults per call. For the default variant the pieces are traced: how many each thread ran,
the page faults each thread took (``RUSAGE_THREAD``: who first-touches the fresh output) and
the tail — how long the first thread to run out of pieces waited for the other (a thread
descheduled in the middle of a piece holds the call that long); for the shared plan, how long
the helper ran on after the call had returned (what the pieces would have waited).

    python bench/full_pose_load.py [--poses 1000000] [--repeat 7] [--load none|busy|both]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))

from load import conditions

import pkmkit
from pkmkit.numerics import jit
from pkmkit.spatial import pose_from_angles


def _variants(n: int) -> dict:
    """``{label: (environment, THREAD_ROWS, uses out=, the shared plan)}``: the shared plan
    (``jit.SHARED_INVERSE``, session 35's default) or :func:`jit.run_chunks`' pieces."""
    default = jit.THREAD_ROWS
    return {
        "plain, shared plan (default)": ({}, default, False, True),
        "out=Q, shared plan": ({}, default, True, True),
        "plain, fresh pages, 2 threads": ({"PKMKIT_RECYCLE": "0"}, default, False, False),
        "plain, recycled, 2 threads": ({}, default, False, False),
        "out=Q, 2 threads": ({}, default, True, False),
        "plain, fresh pages, 1 thread": ({"PKMKIT_RECYCLE": "0", "PKMKIT_THREADS": "1"},
                                         default, False, False),
        "plain, recycled, 1 thread": ({"PKMKIT_THREADS": "1"}, default, False, False),
        "plain, recycled, pieces 2^12": ({}, 1 << 12, False, False),
        "plain, recycled, pieces 2^16": ({}, 1 << 16, False, False),
        "plain, recycled, two halves": ({}, -(-n // 2), False, False),
    }


def _call(m, poses, reused, setting) -> tuple[float, float, int]:
    """One call under ``setting``: wall s, process CPU s, minor page faults."""
    env, rows, use_out, shared = setting
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    jit.THREAD_ROWS = rows
    jit.SHARED_INVERSE = shared
    try:
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        cpu, wall = time.process_time(), time.perf_counter()
        q = m.ik(poses, out=reused) if use_out else m.ik(poses)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
        del q
    finally:
        jit.SHARED_INVERSE = True
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    return wall, cpu, faults


def _copy(poses, target) -> float:
    start = time.perf_counter()
    np.copyto(target, poses)
    return time.perf_counter() - start


def _trace_shared(m, poses, repeat: int) -> str:
    """The shared plan's calls: how long the helper ran on after the call returned (what a
    call that waits for its threads — the pieces — would have waited), over ``repeat``
    calls."""
    real = jit.run_together
    log: list = []

    def together(work):
        def timed(wait):
            try:
                work(wait)
            finally:
                log.append((wait, time.perf_counter()))
        real(timed)

    outlived = []
    jit.run_together = together
    try:
        for _ in range(repeat):
            log.clear()
            m.ik(poses)
            returned = time.perf_counter()
            jit._helper_pool(jit.thread_count() - 1).submit(lambda: None).result()  # idle
            helpers = [t for wait, t in log if not wait]
            outlived.append(max([0.0, *(t - returned for t in helpers)]) * 1e3)
    finally:
        jit.run_together = real
    return (f"the helper ran on after the call returned: {statistics.median(outlived):.2f} ms "
            f"median (range {min(outlived):.2f}–{max(outlived):.2f})")


def _trace(m, poses, repeat: int, fresh: bool) -> str:
    """Pieces per thread, faults per thread and the tail of ``repeat`` calls on
    :func:`jit.run_chunks`' pieces (``jit.SHARED_INVERSE`` off)."""
    jit.SHARED_INVERSE = False
    real = jit.kernel
    log: list = []

    def kernel(module, name):
        fun = real(module, name)
        if name != "inverse_poses":
            return fun

        def traced(x, *rest):
            f0 = resource.getrusage(resource.RUSAGE_THREAD).ru_minflt
            t0 = time.perf_counter()
            fun(x, *rest)
            log.append((threading.get_ident(), t0, time.perf_counter(),
                        resource.getrusage(resource.RUSAGE_THREAD).ru_minflt - f0))
        return traced

    tails, counts, faults = [], [], []
    jit.kernel = kernel
    if fresh:
        os.environ["PKMKIT_RECYCLE"] = "0"
    try:
        for _ in range(repeat):
            log.clear()
            m.ik(poses)
            me = threading.get_ident()
            ends = {}
            for ident, _, end, _ in log:
                ends[ident] = max(ends.get(ident, 0.0), end)
            tails.append((max(ends.values()) - min(ends.values())) * 1e3)
            counts.append("/".join(str(sum(1 for e in log if e[0] == ident))
                                   for ident in sorted(ends, key=lambda i: i != me)))
            faults.append("/".join(str(sum(e[3] for e in log if e[0] == ident))
                                   for ident in sorted(ends, key=lambda i: i != me)))
    finally:
        jit.kernel = real
        jit.SHARED_INVERSE = True
        os.environ.pop("PKMKIT_RECYCLE", None)
    return (f"pieces (calling thread/helper) {', '.join(counts)}; page faults in the pieces "
            f"{', '.join(faults)}; tail {statistics.median(tails):.2f} ms median "
            f"(range {min(tails):.2f}–{max(tails):.2f})")


def load_rows(m, poses: np.ndarray, repeat: int) -> None:
    n = len(poses)
    variants = _variants(n)
    target = np.empty_like(poses)
    np.copyto(target, poses)
    reused = m.ik(poses)
    saved_rows = jit.THREAD_ROWS
    runs: dict = {label: [] for label in variants}
    copies = []
    try:
        for setting in variants.values():  # warm every path once
            _call(m, poses, reused, setting)
        for _ in range(repeat):
            for label, setting in variants.items():
                copy = _copy(poses, target)
                runs[label].append((*_call(m, poses, reused, setting), copy))
                copies.append(copy)
    finally:
        jit.THREAD_ROWS = saved_rows
    print(f"  preallocated copy: {statistics.median(copies) * 1e3:.2f} ms median "
          f"(best {min(copies) * 1e3:.2f})")
    for label, rows in runs.items():
        ratios = sorted(wall / copy for wall, _, _, copy in rows)
        print(f"  {label:<31} wall {statistics.median(r[0] for r in rows) * 1e3:6.1f} ms, "
              f"/ copy {statistics.median(ratios):4.1f} (rounds {ratios[0]:.1f}–"
              f"{ratios[-1]:.1f}), CPU {min(r[1] for r in rows) / n * 1e9:5.1f} ns per pose "
              f"(best), {statistics.median(r[2] for r in rows):.0f} faults per call")
    print(f"  traced, pieces, fresh pages: {_trace(m, poses, repeat, True)}")
    print(f"  traced, pieces, recycled:    {_trace(m, poses, repeat, False)}")
    print(f"  traced, shared plan:         {_trace_shared(m, poses, repeat)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--load", choices=("none", "busy", "both"), default="both")
    args = parser.parse_args()
    print(f"pkmkit {pkmkit.__version__}, numpy {np.__version__}, {os.cpu_count()} CPUs, "
          f"{jit.thread_count()} threads by default")
    rng = np.random.default_rng(0)
    hexapod = pkmkit.machine("gough-stewart")
    poses = pose_from_angles(hexapod.home_pose[:3] + rng.uniform(-0.1, 0.1, (args.poses, 3)),
                             rng.uniform(-8, 8, (args.poses, 3)), "xyz", degrees=True)
    hexapod.ik(poses[:5000])
    for label, context in conditions(args.load):
        print(f"{label} (load average {os.getloadavg()[0]:.2f} before):")
        with context():
            load_rows(hexapod, poses, args.repeat)
        print(f"  (load average {os.getloadavg()[0]:.2f} after)")


if __name__ == "__main__":
    main()
