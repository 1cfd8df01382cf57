"""Benchmark: peak memory of the batch calls of the machine protocol against their data.

Each call runs in its own subprocess (so that one call's high-water mark does not hide another's):
the process imports pkmkit, warms the call up on a few rows (compiling the Numba kernels), records
its peak resident set size (``ru_maxrss``), builds the input, makes the call once, reads every
field of the result (a lazy velocity model computes them all) and records the peak again. The
figure is the rise of the peak per row against the bytes per row of the input plus the output
(every array of the result); the machine protocol chunks its batches so that this rise stays
within about twice the input plus the output (column ``ratio`` ≤ 2).

    python bench/memory.py [--rows 1000000] [--chain-rows 20000] [--only NAME]

Machines: ``linear-delta`` (translational, closed forms), ``gough-stewart`` (full-pose hexapod:
closed-form ik, compiled engine fk) and ``tripteor-x7`` (joint chain: iterative engine, hence
fewer rows; chunked as well, ``PKMKIT_COMPILED=0`` measures its NumPy engine).

The figure is the rise above the peak the warm-up left: a chunked call reuses the memory the
warm-up's chunks freed, so a small rise (or 0) is a floor, not an exact working set.
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

CALLS = {  # name: (machine id, call, input kind)
    "delta ik": ("linear-delta", "ik", "pose"),
    "delta ik full": ("linear-delta", "ik_full", "pose"),
    "delta fk": ("linear-delta", "fk", "q"),
    "delta fk full": ("linear-delta", "fk_full", "q"),
    "delta jacobian": ("linear-delta", "jacobian", "pose"),
    "hexapod ik": ("gough-stewart", "ik", "pose"),
    "hexapod ik full": ("gough-stewart", "ik_full", "pose"),
    "hexapod fk": ("gough-stewart", "fk", "q"),
    "hexapod fk full": ("gough-stewart", "fk_full", "q"),
    "hexapod jacobian": ("gough-stewart", "jacobian", "pose"),
    "chain ik": ("tripteor-x7", "ik", "pose"),
    "chain ik full": ("tripteor-x7", "ik_full", "pose"),
    "chain fk": ("tripteor-x7", "fk", "q"),
    "chain fk full": ("tripteor-x7", "fk_full", "q"),
    "chain jacobian": ("tripteor-x7", "jacobian", "pose"),
}

CHILD = r"""
import json, resource, sys
import numpy as np
import pkmkit

ident, call, kind, rows, path = sys.argv[1:4] + [int(sys.argv[4]), sys.argv[5]]
m = pkmkit.machine(ident)
rng = np.random.default_rng(0)

def inputs(n):
    # reachable poses (positions in the middle of the default box; a hexapod turned by up
    # to 0.05 rad, a joint chain's tool axis that of home) or their actuator values
    lo, hi = m.default_box()
    x = np.tile(np.asarray(m.home_pose, dtype=float), (n, 1))
    x[:, :3] = lo + (hi - lo) * (0.25 + 0.5 * rng.random((n, 3)))
    if x.shape[1] == 6 and not ident.startswith("tripteor"):
        x[:, 3:] += 0.05 * (2.0 * rng.random((n, 3)) - 1.0)
    if kind == "q":
        x = m.ik(x, strokes="ignore")
    return np.ascontiguousarray(x)

if call == "prepare":  # in its own process: its temporaries stay out of the measure
    np.save(path, inputs(rows))
    sys.exit(0)

def run(x):
    if call == "ik":
        return m.ik(x, strokes="ignore")
    if call == "ik_full":
        return m.ik(x, strokes="ignore", full_output=True)
    if call == "fk":
        return m.fk(x, strokes="ignore")
    if call == "fk_full":
        return m.fk(x, strokes="ignore", full_output=True)
    return m.jacobian(x)

def arrays(result, seen=None):
    seen = set() if seen is None else seen
    if id(result) in seen:
        return 0
    seen.add(id(result))
    if isinstance(result, np.ndarray):
        return result.nbytes
    if hasattr(result, "__dataclass_fields__"):
        return sum(arrays(getattr(result, f), seen) for f in result.__dataclass_fields__)
    return 0

def peak():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0

arrays(run(inputs(8192)))  # warm-up: compiled kernels (from 4096 rows) loaded, threads started
x = np.load(path)
before = peak()
out = run(x)
size = x.nbytes + arrays(out)
print(json.dumps({"rise": peak() - before, "data": size}))
"""


def measure(ident: str, call: str, kind: str, rows: int) -> dict:
    """Peak rise and data size (bytes) of one call in a fresh process (its input prepared by
    another process and loaded from a file)."""
    with tempfile.TemporaryDirectory() as folder:
        path = str(Path(folder) / "input.npy")
        for step in ("prepare", call):
            done = subprocess.run([sys.executable, "-c", CHILD, ident, step, kind, str(rows),
                                   path], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=int, default=1_000_000)
    parser.add_argument("--chain-rows", type=int, default=20_000)
    parser.add_argument("--only", default="", help="run only the calls whose name contains this")
    args = parser.parse_args()
    print(f"# peak RSS rise per row, Python {platform.python_version()}, {platform.machine()}")
    print(f"{'call':<18} {'rows':>9} {'peak B/row':>11} {'in+out B/row':>13} {'ratio':>6}")
    for name, (ident, call, kind) in CALLS.items():
        if args.only not in name:
            continue
        rows = args.chain_rows if ident.startswith("tripteor") else args.rows
        # the input is built before the mark: the rise counts the output and the temporaries
        r = measure(ident, call, kind, rows)
        print(f"{name:<18} {rows:>9} {r['rise'] / rows:>11.0f} {r['data'] / rows:>13.0f} "
              f"{r['rise'] / r['data']:>6.2f}")


if __name__ == "__main__":
    main()
