"""Agreement of ``m.jacobian(x)`` of one pose of a joint-chain machine (the C kernel at the
inverse solution, :mod:`pkmkit.machines.chain_one_velocity`) with the batch row
(``m.jacobian(X)`` with X of one row: the direct model solved again, LAPACK's pseudo-inverse
and SVD) over random workspace poses (actuators uniform over 2–98 % of their strokes): how many
calls took the C kernel, and per field the largest difference relative to the field's largest
entry (q: the largest absolute difference; the C inverse's q agrees to rounding, not to the
bit); statuses and ranks must be equal.

Usage::

    python bench/chain_jacobian_agreement.py [--poses 1000] [--machines tripteor-x7,trimule-600]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one
from pkmkit.machines import chain_one_velocity as cov

FIELDS = ("J", "J_homogeneous", "singular_values", "condition", "passive_rates")


def agreement(name: str, n: int) -> tuple[int, int, dict, int]:
    """``(poses, calls through the C kernel, field -> largest relative difference (q: the
    largest absolute one: the C inverse's q is the batch row's to rounding, not to the bit),
    mismatched statuses or ranks)``."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(5)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    x = m.fk(lo + (hi - lo) * (0.02 + 0.96 * rng.random((n, len(act)))), strokes="ignore")
    x = x[np.isfinite(x).all(axis=1)]
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
    worst = dict.fromkeys((*FIELDS, "q (m, rad)"), 0.0)
    through, wrong = 0, 0
    for pose in x:
        one = m.jacobian(pose)
        if not isinstance(one, cov.OnePoseChainJacobians):
            continue
        through += 1
        ref = m.jacobian(pose[None])
        for field in FIELDS:
            a, b = np.asarray(getattr(one, field)), np.asarray(getattr(ref, field))[0]
            worst[field] = max(worst[field], float(np.abs(a - b).max() / np.abs(b).max()))
        wrong += not (one.status == ref.status[0] and one.closure_rank == ref.closure_rank[0]
                      and one.expected_rank == ref.expected_rank)
        worst["q (m, rad)"] = max(worst["q (m, rad)"], float(np.abs(one.q - ref.q[0]).max()))
    return len(x), through, worst, wrong


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1000)
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    args = parser.parse_args()
    warnings.simplefilter("ignore", StrokeWarning)
    for name in args.machines.split(","):
        n, through, worst, wrong = agreement(name, args.poses)
        print(f"{name}: {through} of {n} poses through the C kernel; statuses or ranks "
              f"different: {wrong}")
        print("  largest difference / the field's largest entry: "
              + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()))


if __name__ == "__main__":
    main()
