"""Benchmark: one pose per call (issue 22 §1), quiet and with a competing process.

For each translational built-in machine, the cost of one call ``m.ik(x)`` from Python (the
plain-Python single-pose path), against, in the same process and on the same poses:

- the batch path with one row, ``m.ik(x[None])`` — what every single call cost before;
- the formula in plain Python for one pose, leg constants precomputed (slide legs) — the floor
  of any Python-level implementation;
- a compiled kernel called from Python on one preallocated row
  (:func:`pkmkit.machines.kernels.inverse`, slides and struts only) — what a user's Numba or C
  kernel costs per call.

Medians of interleaved repeats (each method sees the same load). Pinocchio is not a dependency
and is not installed here, so its 2.2 µs per forward-kinematics call (the issue's figure) is not
re-measured.

Usage::

    python bench/single_call.py [--calls 20000] [--load none|busy|both] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from load import conditions

import pkmkit
from pkmkit.machines import kernels
from pkmkit.machines.closed_form import BOUNDARY_TOL
from pkmkit.model.rods import CRANK, SLIDE


def per_call(fun, poses, repeats: int = 5) -> float:
    """Median over ``repeats`` of the mean time (µs) of ``fun(pose)`` over ``poses``."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for p in poses:
            fun(p)
        times.append((time.perf_counter() - start) / len(poses) * 1e6)
    return statistics.median(times)


def plain_formula(m):
    """The slide-leg inverse model of one pose in plain Python, constants precomputed once."""
    model = m.model
    dims = model.dims
    legs = [((model.leg_base[i] - model.leg_platform[i])[:dims].tolist(),
             model.leg_axis[i][:dims].tolist(), float(model.leg_length[i]) ** 2,
             float(model.leg_branch[i])) for i in range(model.n_legs)]

    def ik(pose):
        q = []
        for centre, axis, length_sq, branch in legs:
            w = [p - c for p, c in zip(pose, centre, strict=True)]
            along = sum(a * b for a, b in zip(w, axis, strict=True))
            q.append(along + branch * math.sqrt(length_sq - (sum(a * a for a in w)
                                                              - along * along)))
        return q

    return ik


def machine_rows(name: str, calls: int) -> dict:
    m = pkmkit.machine(name)
    lo, hi = m.default_box()
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    rng = np.random.default_rng(0)
    poses = centre + 0.3 * half * (2 * rng.random((calls, m.dims)) - 1)
    poses = poses[np.isfinite(m.ik(poses, strokes="ignore")).all(axis=1)]
    rows = [p for p in poses]
    ones = [p[None] for p in poses]
    closed = m._closed
    branch = np.asarray(m.model.leg_branch, dtype=float)
    out = np.empty((m.model.n_legs, 1))
    slide = m.model.leg_kind == SLIDE
    has_crank = bool((m.model.leg_kind == CRANK).any())
    m.ik(rows[0], strokes="ignore")
    figures = {"poses": len(rows)}
    for _ in range(2):  # interleaved: every method twice, the second round kept
        figures["ik one pose"] = per_call(lambda p: m.ik(p, strokes="ignore"), rows)
        figures["batch of one (before)"] = per_call(lambda p: m.ik(p, strokes="ignore"), ones)
        if (m.model.leg_kind == SLIDE).all():
            plain = plain_formula(m)
            lists = [p.tolist() for p in rows]
            figures["plain-Python formula"] = per_call(plain, lists)
        if not has_crank:
            figures["compiled kernel, one row"] = per_call(
                lambda p: kernels.inverse(p, closed.basis, closed.basis_offset,
                                          m.model.leg_length, slide, branch, BOUNDARY_TOL, out),
                ones)
    return figures


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20000)
    parser.add_argument("--load", default="both", choices=("none", "busy", "both"))
    parser.add_argument("--json")
    args = parser.parse_args()
    names = [n for n in ("orthoglide", "linear-delta", "five-bar", "delta")]
    report = {}
    for label, context in conditions(args.load):
        with context():
            report[label] = {n: machine_rows(n, args.calls) for n in names}
        print(f"== {label}")
        for n, f in report[label].items():
            base = f["batch of one (before)"]
            parts = [f"{k} {v:7.2f} µs" for k, v in f.items() if k != "poses"]
            print(f"  {n:14s} " + "; ".join(parts)
                  + f"; speed-up {base / f['ik one pose']:.0f}×")
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
