"""Vectorised predictor–corrector tracking of many solution paths of a homotopy ``H(x, t) = 0``.

Each path starts at a regular solution ``x(1)`` of the start system ``H(·, 1) = 0`` and is
followed to ``t = 0`` (the target system). All paths advance together (batch axis first, no
per-path Python loop); each keeps its own ``t`` and step size:

- **predictor**: classical Runge–Kutta (order 4) on the Davidenko equation
  ``ẋ = −H_x⁻¹ H_t``;
- **corrector**: Newton's method at the new ``t`` in complex arithmetic, at most
  ``max_newton`` iterations; the step is accepted when Newton converges (update below
  ``corrector_tol``) and contracts, and the first Newton update (the predictor's error) is below
  ``predictor_tol``;
- **adaptive step**: after an accepted step ``h ← h · min(2, 0.8 (predictor_tol / error)^{1/5})``,
  after a rejected one ``h ← h / 2``; a path whose step falls below ``min_step`` or whose step
  count exceeds ``max_steps`` *fails*;
- an optional ``stop(x, t)`` predicate ends paths early, e.g. paths that go to infinity (the
  translation of a pose in Study coordinates exceeding a bound) before their Jacobian becomes
  singular.

The homotopy is given by ``evaluate(x (k, n), t (k,), rows (k,)) → (H (k, n), H_x (k, n, n),
H_t (k, n))`` for the paths ``rows``; ``rows`` lets the caller find each path's own parameters.
The tangent at an accepted point comes from the corrector's last factorisation (one solve with
two right-hand sides), so a step costs three predictor evaluations plus the Newton iterations.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

Evaluate = Callable[
    [np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]
]
Stop = Callable[[np.ndarray, np.ndarray], np.ndarray]


class PathStatus(IntEnum):
    """Outcome of one tracked path."""

    #: reached t = 0.
    REACHED = 0
    #: ended early by the ``stop`` predicate (e.g. going to infinity).
    STOPPED = 1
    #: the step size fell below ``min_step`` or the step budget ran out.
    FAILED = 2
    #: the start point or an evaluation was not finite.
    NOT_FINITE = 3


@dataclass(frozen=True)
class TrackResult:
    """Paths followed by :func:`track_paths`.

    Attributes:
        x: ``(P, n)`` end points (where each path stopped).
        t: ``(P,)`` value of t where each path stopped (0 when it reached the target).
        status: ``(P,)`` :class:`PathStatus` codes.
        steps: ``(P,)`` accepted steps.
        rejected: ``(P,)`` rejected steps.
    """

    x: np.ndarray
    t: np.ndarray
    status: np.ndarray
    steps: np.ndarray
    rejected: np.ndarray


def solve_batch(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``jac (k, n, n) · y = rhs (k, n)``; rows with a singular matrix give NaN."""
    return solve_batch_multi(jac, rhs[:, :, None])[:, :, 0]


def _norm(v: np.ndarray) -> np.ndarray:
    return np.abs(v).max(axis=1)


def track_paths(
    evaluate: Evaluate,
    x_start: np.ndarray,
    *,
    stop: Stop | None = None,
    initial_step: float = 0.05,
    max_step: float = 0.25,
    min_step: float = 1e-12,
    predictor_tol: float = 1e-4,
    corrector_tol: float = 1e-9,
    max_newton: int = 3,
    max_steps: int = 2000,
) -> TrackResult:
    """Follow every path from ``t = 1`` to ``t = 0``.

    Args:
        evaluate: the homotopy (see the module docstring).
        x_start: ``(P, n)`` complex start solutions (one per path).
        stop: optional predicate ``(x (k, n), t (k,)) → (k,) bool`` that ends paths early.
        initial_step, max_step, min_step: step sizes in t.
        predictor_tol: largest accepted predictor error (first Newton update), relative to
            ``max(1, |x|∞)``.
        corrector_tol: Newton has converged when its update is below this (relative).
        max_newton: Newton iterations per step.
        max_steps: step budget per path (accepted plus rejected).

    Returns:
        :class:`TrackResult`.
    """
    x = np.array(x_start, dtype=complex, copy=True)
    n_paths = x.shape[0]
    t = np.ones(n_paths)
    h = np.full(n_paths, float(initial_step))
    steps = np.zeros(n_paths, dtype=int)
    rejected = np.zeros(n_paths, dtype=int)
    status = np.full(n_paths, int(PathStatus.REACHED))
    bad = ~np.isfinite(x).all(axis=1)
    status[bad] = PathStatus.NOT_FINITE
    active = ~bad
    all_rows = np.arange(n_paths)
    # tangent ẋ at the current point of every path (the predictor's first stage)
    velocity = np.zeros_like(x)
    if active.any():
        rows = all_rows[active]
        _, jac, d_t = evaluate(x[rows], t[rows], rows)
        velocity[rows] = -solve_batch(jac, d_t)

    def tangent(xk: np.ndarray, tk: np.ndarray, rows: np.ndarray) -> np.ndarray:
        _, jac, d_t = evaluate(xk, tk, rows)
        return -solve_batch(jac, d_t)

    while True:
        rows = all_rows[active]
        if rows.size == 0:
            break
        xr, tr = x[rows], t[rows]
        dt = np.minimum(h[rows], tr)
        half, full = (dt / 2)[:, None], dt[:, None]
        k1 = velocity[rows]
        k2 = tangent(xr - half * k1, tr - dt / 2, rows)
        k3 = tangent(xr - half * k2, tr - dt / 2, rows)
        k4 = tangent(xr - full * k3, tr - dt, rows)
        x_new = xr - (full / 6) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        t_new = tr - dt
        scale = np.maximum(1.0, _norm(xr))
        x_new, v_new, first, converged = _correct(
            evaluate, x_new, t_new, rows, scale, corrector_tol, max_newton
        )
        accept = converged & (first <= predictor_tol)
        acc, rej = rows[accept], rows[~accept]
        x[acc], t[acc] = x_new[accept], t_new[accept]
        velocity[acc] = -v_new[accept]
        steps[acc] += 1
        # step control from the predictor error ~ h⁵ (first Newton update)
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = 0.7 * (predictor_tol / np.maximum(first, 1e-300)) ** 0.2
        factor = np.nan_to_num(factor, nan=0.25)
        h[acc] = np.minimum(h[acc] * np.clip(factor[accept], 1.0, 2.0), max_step)
        shrink = np.where(converged, np.clip(factor, 0.1, 0.5), 0.5)[~accept]
        h[rej] *= shrink
        rejected[rej] += 1
        done = acc[t[acc] <= 0.0]
        active[done] = False
        if stop is not None and acc.size:
            gone = acc[stop(x[acc], t[acc]) & (t[acc] > 0.0)]
            status[gone] = PathStatus.STOPPED
            active[gone] = False
        failed = rows[(h[rows] < min_step) | (steps[rows] + rejected[rows] >= max_steps)]
        failed = failed[active[failed]]
        status[failed] = PathStatus.FAILED
        active[failed] = False
    return TrackResult(x=x, t=t, status=status, steps=steps, rejected=rejected)


def _correct(
    evaluate: Evaluate,
    x: np.ndarray,
    t: np.ndarray,
    rows: np.ndarray,
    scale: np.ndarray,
    tol: float,
    max_newton: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Newton's method at fixed t; each row stops once converged.

    A row has converged when its update is below ``tol · scale``, or when, contracting by a
    factor θ = |δ_k| / |δ_{k−1}| ≤ ½, the estimated remaining error ``θ |δ_k|`` is below it
    (Newton converges at least linearly from there). A row whose update stops contracting is
    abandoned.

    Returns the corrected points, ``H_x⁻¹ H_t`` from each row's last factorisation, the size of
    the first update (relative) and whether each row converged.
    """
    x = x.copy()
    v = np.full_like(x, np.nan)
    first = np.full(x.shape[0], np.inf)
    converged = np.zeros(x.shape[0], dtype=bool)
    live = np.arange(x.shape[0])
    last = np.full(0, np.inf)
    for k in range(max_newton):
        res, jac, d_t = evaluate(x[live], t[live], rows[live])
        delta, v[live] = _solve_two(jac, res, d_t)
        x[live] -= delta
        size = _norm(delta) / scale[live]
        size = np.where(np.isfinite(size), size, np.inf)
        if k == 0:
            first[live] = size
            ok, going = size <= tol, np.ones(live.size, dtype=bool)
        else:
            with np.errstate(invalid="ignore", divide="ignore"):
                theta = size / last  # inf / inf (a non-finite row): NaN, not going
            going = theta <= 0.5
            ok = (size <= tol) | (going & (theta * size <= tol))
        converged[live[ok]] = True
        keep = going & ~ok
        live, last = live[keep], size[keep]
        if live.size == 0:
            break
    return x, v, first, converged


def _solve_two(jac: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``jac y = a`` and ``jac z = b`` with one factorisation per matrix."""
    both = solve_batch_multi(jac, np.stack([a, b], axis=2))
    return both[:, :, 0], both[:, :, 1]


def solve_batch_multi(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``jac (k, n, n) · Y = rhs (k, n, r)``; rows with a singular matrix give NaN."""
    try:
        return np.linalg.solve(jac, rhs)
    except np.linalg.LinAlgError:
        out = np.full(rhs.shape, np.nan, dtype=np.result_type(jac, rhs))
        for i in range(jac.shape[0]):  # rare: isolate the singular rows
            try:
                out[i] = np.linalg.solve(jac[i], rhs[i])
            except np.linalg.LinAlgError:
                pass
        return out
