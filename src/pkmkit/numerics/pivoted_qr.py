"""QR with column pivoting whose choice of columns does not depend on rounding.

LAPACK's pivoted QR (``scipy.linalg.qr(..., pivoting=True)``) takes, at each step, the column
of largest remaining norm. Where several columns tie — parameters with the same effect on the
measurements (an actuator offset and a slide's position along it), symmetric legs — the choice
is made by the last bits of the norms, so the same problem computed along two paths that round
differently (a compiled and a NumPy inverse model, 1e-12 apart) can select different parameters
to identify. Here a column whose remaining norm is within a relative ``tie`` of the largest
counts as tied, and among tied columns the one given first wins: the same selection for every
rounding, and the caller's order (a priority) decides between equivalent parameters.

Householder reflections on a copy, the norms recomputed at every step (no downdating): for
the calibration's and the error analysis's matrices, up to a few thousand rows and ~100
columns.
"""

from __future__ import annotations

import math

import numpy as np

#: Remaining column norms within this relative distance of the largest are tied.
TIE = 1e-6


def pivoted_qr(a: np.ndarray, *, tie: float = TIE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(q, r, piv)`` with ``a[:, piv] = q @ r`` — ``q (M, K)`` orthonormal columns, ``r (K,
    p)`` upper triangular, ``K = min(M, p)``, ``piv (p,)`` — as
    ``scipy.linalg.qr(a, pivoting=True, mode="economic")``, with ties broken by column order
    (module docstring). ``|diag(r)|`` does not increase."""
    work = np.array(a, dtype=float, copy=True)
    if work.ndim != 2:
        raise ValueError(f"pivoted_qr needs a matrix, got shape {work.shape}")
    m, p = work.shape
    k_max = min(m, p)
    piv = np.arange(p)
    reflectors = []
    for k in range(k_max):
        rest = work[k:, k:]
        norms = np.sqrt(np.einsum("ij,ij->j", rest, rest))
        top = float(norms.max())
        tied = np.flatnonzero(norms >= top * (1.0 - tie))
        j = k + int(tied[np.argmin(piv[k + tied])])
        if j != k:
            work[:, [k, j]] = work[:, [j, k]]
            piv[[k, j]] = piv[[j, k]]
        x = work[k:, k]
        alpha = -math.copysign(float(np.sqrt(x @ x)), float(x[0]))
        v = x.copy()
        v[0] -= alpha
        length = float(np.sqrt(v @ v))
        if length == 0.0:  # a zero column: nothing to reflect
            reflectors.append(None)
            continue
        v /= length
        work[k:, k:] -= 2.0 * np.outer(v, v @ work[k:, k:])
        work[k + 1:, k] = 0.0
        reflectors.append(v)
    r = np.triu(work[:k_max, :])
    q = np.eye(m, k_max)
    for k in range(len(reflectors) - 1, -1, -1):
        v = reflectors[k]
        if v is not None:
            q[k:, :] -= 2.0 * np.outer(v, v @ q[k:, :])
    return q, r, piv
