"""Benchmark (accuracy, not time): would the singular values of a joint-chain machine's
``J_homogeneous`` (6 × n) hold the one-pose path's contract — 1.5e-13 of the batch rows — if
taken as the square roots of the eigenvalues of the Gram matrix ``J_hᵀ J_h`` (issue 22 §1,
session 35's lever: a cheaper small SVD where only the values are needed)?

The batch path's records over random actuator configurations, 30 % beyond each end of every
stroke (nearer the singularities: the rows whose closure is singular or does not assemble are
left out), give ``J_homogeneous``, LAPACK's singular values and the condition number; the Gram
route is evaluated with LAPACK's symmetric eigenvalue solver (``numpy.linalg.eigvalsh``, its
best case: a hand-written Jacobi on the Gram matrix is no more accurate). Printed per band of
the condition number: the largest error of the singular values relative to σ_max, of σ_min
relative to itself, and of the condition number relative to itself; then the rows beyond
1.5e-13. The Gram route squares the condition: its σ_min carries ≈ eps κ² / 2 relative error.

Usage::

    python bench/chain_singular_gram.py [--rows 4000] [--machines tripteor-x7,trimule-600]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

import pkmkit

CONTRACT = 1.5e-13
BANDS = ((1, 10), (10, 100), (100, 1e3), (1e3, 1e4), (1e4, np.inf))


def study(name: str, rows: int) -> None:
    m = pkmkit.machine(name)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(5)
    q = lo + (hi - lo) * (-0.3 + 1.6 * rng.random((rows, len(act))))
    r = m.jacobian(q=q)
    ok = np.isfinite(r.condition)
    jh, sv, cond = r.J_homogeneous[ok], r.singular_values[ok], r.condition[ok]
    gram = np.einsum("nij,nik->njk", jh, jh)
    ev = np.sqrt(np.clip(np.linalg.eigvalsh(gram)[:, ::-1], 0.0, None))
    k = sv.shape[1]
    ev = ev[:, :k]
    err_sv = np.abs(ev - sv).max(axis=1) / sv[:, 0]
    err_min = np.abs(ev[:, -1] / sv[:, -1] - 1)
    err_cond = np.abs(ev[:, 0] / ev[:, -1] / cond - 1)
    print(f"{name}: {ok.sum()} of {rows} rows with a velocity model; condition "
          f"{cond.min():.3g} to {cond.max():.3g}")
    for low, high in BANDS:
        sel = (cond >= low) & (cond < high)
        if sel.any():
            print(f"  condition [{low:g}, {high:g}): {sel.sum():5d} rows; largest error: "
                  f"values / σ_max {err_sv[sel].max():.1e}, σ_min / σ_min "
                  f"{err_min[sel].max():.1e}, condition {err_cond[sel].max():.1e}")
    bad = (err_sv > CONTRACT) | (err_cond > CONTRACT) | (err_min > CONTRACT)
    lowest = f"{cond[bad].min():.3g}" if bad.any() else "-"
    print(f"  rows beyond {CONTRACT:g}: {bad.sum()} of {ok.sum()} (the lowest condition "
          f"among them {lowest})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=4000)
    parser.add_argument("--machines", default="tripteor-x7,trimule-600")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    for name in args.machines.split(","):
        study(name, args.rows)


if __name__ == "__main__":
    main()
