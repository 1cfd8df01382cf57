"""Benchmark: the joint-chain one-pose velocity kernel (``chain_one_velocity``,
native/chain_one_velocity.c) of this tree against another build of the extension, in the same
process (issue 22 §1): a change to the C kernel measured as a ratio free of the load.

Build the baseline first (the base commit's ``native/chain_one_velocity.c`` built with
``python setup.py build_ext --inplace``, its ``kernels*.so`` copied aside) and pass its path. Both
builds get their own pack of the same machine and are timed in turn on the same inverse
solutions (CPU µs per call, the median of 3 rounds of 7 repeats each); the baseline's call is
the full one (3 arguments), this tree's also without the singular stage (``False``); and the
per-call step of ``m.jacobian(x)`` after the inverse, where the baseline has no
``chain_one_jacobian``: the baseline's record step (the solution's ``tolist()``, ``np.empty``,
the call without the singular stage) against ``chain_one_jacobian`` on the solution array.

Usage::

    python bench/chain_velocity_builds.py BASELINE_SO [--machines tripteor-x7,trimule-600]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import time
import warnings

import numpy as np

import pkmkit
from pkmkit.machines import chain_one
from pkmkit.machines import chain_one_velocity as cov


def load(path: str):
    """The extension module built at ``path`` (its init function is ``PyInit_kernels``)."""
    spec = importlib.util.spec_from_file_location("kernels", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def solutions(name: str, count: int = 300):
    """``(machine, inverse solutions u)`` of random configurations within the strokes."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(2)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.1 + 0.8 * rng.random((count, len(act))))
    poses = m.fk(q, strokes="ignore")
    rows = [x for x in poses if np.isfinite(x).all()]
    m.jacobian(rows[0])  # the constants, past the first (batch) call
    chain_one.usable(m, "chain_jacobian")
    c = chain_one.constants(m, "chain_jacobian")
    found = [chain_one._inverse_values(c, list(map(float, x))) for x in rows]
    return m, [f[1] for f in found if f is not None]


def cpu_per_call(fun, items, repeats: int = 7) -> float:
    times = []
    for _ in range(repeats):
        start = time.process_time()
        for item in items:
            fun(item)
        times.append((time.process_time() - start) / len(items) * 1e6)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("baseline")
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    base = load(args.baseline)
    from pkmkit.native import kernels as here
    print(f"load average {os.getloadavg()[0]:.2f}")
    for name in args.machines.split(","):
        m, us = solutions(name)
        old, new = cov.VelocityPack(m, base), cov.VelocityPack(m, here)
        out = np.empty(new.size)
        arrays = [np.array(u) for u in us]  # as chain_one_ik returns the solution
        calls = {"baseline": lambda u, p=old, o=out: p.call(p.pack, u, o),
                 "this tree": lambda u, p=new, o=out: p.call(p.pack, u, o),
                 "this tree, no singular stage":
                     lambda u, p=new, o=out: p.call(p.pack, u, o, False)}
        # the per-call step of m.jacobian(x) after the inverse: before, the record's
        # tolist(), np.empty and the 4-argument call; now chain_one_jacobian on the array
        steps = {"baseline, the record's step (tolist, np.empty, call)":
                     lambda a, p=old: p.call(p.pack, a.tolist(), np.empty(p.size), False),
                 "this tree, chain_one_jacobian":
                     lambda a, p=new: p.jacobian(p.pack, a, 2e-6)}
        rounds = {k: [] for k in (*calls, *steps)}
        for _ in range(3):
            for k, fun in calls.items():
                rounds[k].append(cpu_per_call(fun, us))
            if new.jacobian is not None and old.jacobian is None:
                for k, fun in steps.items():
                    rounds[k].append(cpu_per_call(fun, arrays))
        med = {k: statistics.median(v) for k, v in rounds.items() if v}
        print(f"{name} ({len(us)} solutions), CPU µs per call: " + ", ".join(
            f"{k} {v:.2f}" for k, v in med.items() if k in calls))
        lazy = med["this tree, no singular stage"]
        print(f"  this tree / baseline {med['this tree'] / med['baseline']:.3f}; without the "
              f"singular stage / baseline {lazy / med['baseline']:.3f}")
        step = [k for k in steps if k in med]
        if step:
            print(f"  {step[0]} {med[step[0]]:.2f}, {step[1]} {med[step[1]]:.2f}: ratio "
                  f"{med[step[1]] / med[step[0]]:.3f}")
    print(f"load average {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
