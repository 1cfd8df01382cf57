"""A competing process for benchmarks: measure hot paths with another core busy.

Users run pkmkit beside other work and inside Dask workers; a figure taken on an idle machine
says little about that. :func:`competing_process` starts one separate Python process that keeps
one core busy — NumPy work on arrays far larger than the caches (element-wise operations and
sums, the memory traffic of a typical neighbour), plus a pure-Python spin — for at most
``seconds`` (it stops by itself) and is terminated, by its own process id, when the block exits.

    with competing_process():
        ...  # timings here are "loaded"
"""

from __future__ import annotations

import contextlib
import subprocess
import sys
import time

_WORKER = """
import os, sys, time
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np
deadline = time.monotonic() + float(sys.argv[1])
a = np.random.default_rng(0).random(4_000_000)
print("ready", flush=True)
while time.monotonic() < deadline:
    b = np.sqrt(a * 1.0001 + 0.5)      # 32 MB streams: a neighbour using memory bandwidth
    a[:] = b - 0.4999
    s = 0
    for k in range(200_000):           # and one using the core
        s += k
"""


@contextlib.contextmanager
def competing_process(seconds: float = 600.0):
    """Run one core-and-memory-bound process while the block runs (bounded by ``seconds``)."""
    proc = subprocess.Popen([sys.executable, "-c", _WORKER, str(seconds)],
                            stdout=subprocess.PIPE, text=True)
    try:
        proc.stdout.readline()  # wait until it is running
        time.sleep(0.2)
        yield proc
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def conditions(mode: str):
    """``[(label, context manager factory)]`` for ``--load none|busy|both``."""
    quiet = ("quiet", contextlib.nullcontext)
    busy = ("loaded", competing_process)
    return {"none": [quiet], "busy": [busy], "both": [quiet, busy]}[mode]
