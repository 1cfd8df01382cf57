"""Benchmark: what read-only record fields cost on the one-pose paths (session 34, trust3).

Every record hands out its arrays as read-only views (pkmkit.machines.lazy_records.read_only
and ReadOnlyFields; docs/kinematics.md, "Records are read-only"). This times, in one process,
one-pose calls that read record fields — ``m.jacobian(x).J`` (+ condition), ``m.ik(x,
full_output=True).q``, ``m.fk(q, full_output=True).pose`` — with the views (as shipped) and with
the baseline of handing out the kept arrays themselves (``read_only`` and
``ReadOnlyFields.__post_init__`` patched to do nothing, the code before session 34), the two
alternated round by round; it prints the per-call CPU time of each and their ratio.

    python bench/read_only_records.py [--calls 400] [--rounds 5]
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np

import pkmkit
from pkmkit.machines import chain_one_velocity, lazy_records, results, velocity, velocity_one

MACHINES = ("orthoglide", "delta", "gough-stewart", "tripteor-x7")
_USERS = (lazy_records, velocity, velocity_one, chain_one_velocity)


def _calls(m):
    x = np.array(m.home_pose, dtype=float) * 0.999 + 1e-4
    q = m.ik(x)
    return {
        "jacobian(x).J": lambda: m.jacobian(x).J,
        "jacobian(x).J + condition": lambda: (lambda r: (r.J, r.condition))(m.jacobian(x)),
        "ik(x, full_output).q": lambda: m.ik(x, full_output=True).q,
        "fk(q, full_output).pose": lambda: m.fk(q, full_output=True).pose,
    }


def _per_call(call, calls: int) -> float:
    start = time.process_time()
    for _ in range(calls):
        call()
    return (time.process_time() - start) / calls * 1e6


def _baseline(on: bool) -> None:
    """Hand out the kept arrays themselves (``on``) or read-only views (as shipped)."""
    same = (lambda value: value) if on else _SHIPPED[0]
    for module in _USERS:
        module.read_only = same
    results.ReadOnlyFields.__post_init__ = (lambda self: None) if on else _SHIPPED[1]


_SHIPPED = (lazy_records.read_only, lazy_records.ReadOnlyFields.__post_init__)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=400)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    print(f"load average {os.getloadavg()[0]:.2f}; CPU µs per call, best of {args.rounds} "
          f"alternated rounds of {args.calls} calls")
    for name in MACHINES:
        m = pkmkit.machine(name)
        for label, call in _calls(m).items():
            call()
            best = {False: np.inf, True: np.inf}
            for _ in range(args.rounds):
                for base in (True, False):
                    _baseline(base)
                    best[base] = min(best[base], _per_call(call, args.calls))
            _baseline(False)
            print(f"  {name:14s} {label:28s} read-only {best[False]:7.2f}  plain "
                  f"{best[True]:7.2f}  ratio {best[False] / best[True]:.3f}")
    print(f"load average after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
