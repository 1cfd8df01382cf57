"""Benchmark: the one-pose jacobian record's Python (issue 22 §1) — two versions of
``pkmkit/machines/chain_one_velocity.py`` side by side in one process, on the same C
answers: this tree's module and another copy given by path (e.g. main's, saved with
``git show main:src/pkmkit/machines/chain_one_velocity.py > /tmp/before.py``). Each version
makes the record of the same poses with its ``at_pose`` and reads ``J`` then ``condition``
(the fields' first reads: the views and the singular stage); rounds interleaved, CPU µs per
pose (the process's CPU time: the 2 cores are shared), the minimum and the median of the
rounds, and the ratio before / after. The fields of both records are checked equal bit for bit.

Usage::

    python bench/chain_jacobian_record.py BEFORE.py [--poses 300] [--rounds 15]
        [--machines tripteor-x7,trimule-600]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from chain_jacobian_split import rows_of

import pkmkit
from pkmkit.machines import chain_one_native
from pkmkit.machines import chain_one_velocity as after


def load(path: str):
    """The module at ``path`` under a name of its own (used on a machine object of its own:
    the pack is cached on the machine)."""
    spec = importlib.util.spec_from_file_location("chain_one_velocity_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def per_pose(module, m, c, xs) -> float:
    """CPU µs per pose: ``at_pose`` of ``module``, then the first reads of J and condition."""
    at_pose = module.at_pose
    start = time.process_time()
    for x in xs:
        r = at_pose(m, c, x, 1e-6)
        r.J  # noqa: B018 (the read is the work)
        r.condition  # noqa: B018
    return (time.process_time() - start) / len(xs) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("before")
    parser.add_argument("--poses", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    args = parser.parse_args()
    before = load(args.before)
    print(f"load average: {' '.join(f'{v:.1f}' for v in os.getloadavg())}")
    for name in args.machines.split(","):
        m, m_before = pkmkit.machine(name), pkmkit.machine(name)  # each its version's pack
        xs = rows_of(m, args.poses)
        c, c_before = chain_one_native.packed(m), chain_one_native.packed(m_before)
        pairs = [(before.at_pose(m_before, c_before, x, 1e-6), after.at_pose(m, c, x, 1e-6))
                 for x in xs]
        same = all(a is not None and a is not False and b is not None and b is not False
                   and all(np.array_equal(getattr(a, f), getattr(b, f))
                           for f in ("J", "J_homogeneous", "passive_rates", "singular_values",
                                     "condition", "q"))
                   for a, b in pairs)
        times = {"before": [], "after": []}
        for _ in range(args.rounds):
            times["before"].append(per_pose(before, m_before, c_before, xs))
            times["after"].append(per_pose(after, m, c, xs))
        b, a = (statistics.median(times[k]) for k in ("before", "after"))
        print(f"{name}: {len(xs)} poses; fields bit-identical {same}")
        print(f"  at_pose + J + condition, CPU µs min / median: before "
              f"{min(times['before']):.2f} / {b:.2f}, after {min(times['after']):.2f} / {a:.2f}"
              f" (x{b / a:.3f} by the medians)")
    print(f"load average: {' '.join(f'{v:.1f}' for v in os.getloadavg())}")


if __name__ == "__main__":
    main()
