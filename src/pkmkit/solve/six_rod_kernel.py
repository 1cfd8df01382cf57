"""Compiled (Numba) path tracker of the six-rod homotopy: one path at a time, the NumPy
tracker's rules.

:func:`pkmkit.solve.path_tracking.track_paths` driven by
:meth:`pkmkit.solve.study_rods.StudyHomotopy.evaluate` and the stop rule of
:mod:`pkmkit.solve.six_rod_paths` is the reference this kernel is tested against. The NumPy
tracker advances every path in lock-step (the slowest path sets the number of batched
iterations, each paying NumPy's per-call overhead on a few rows); here each path is followed
on its own, to its end, with the same rules:

- homotopy ``H(x, t)``, ``∂H/∂x`` and ``∂H/∂t`` as :class:`~pkmkit.solve.study_rods.
  StudyHomotopy`: ``Q_j x = Σ_m c_jm(t) Z_m(x)`` with the 17 signed permutations ``Z_m``
  (``index``, ``scale``), ``c_j(t) = c⁰ + t (c¹ + t c²)``, the Study quadric and the patch;
- predictor: classical Runge–Kutta on ``ẋ = −H_x⁻¹ H_t``, the first stage being the tangent
  from the corrector's last factorisation;
- corrector: at most ``max_newton`` Newton iterations, converged when the update is below
  ``corrector_tol · max(1, |x|∞)`` or, contracting by θ ≤ ½, when ``θ |δ|`` is; abandoned when
  it stops contracting (θ > ½, or a non-finite update);
- acceptance when converged with a first update (the predictor's error) ≤ ``predictor_tol``;
  step ``h ← min(h · clip(f, 1, 2), max_step)`` after an accepted step, ``h ← h · clip(f, 0.1,
  0.5)`` after a rejected converged one and ``h / 2`` otherwise, ``f = 0.7 (predictor_tol /
  first)^{1/5}``;
- end: REACHED at t = 0; STOPPED (after an accepted step with t > 0) when ``|g|/|e|`` exceeds
  ``diverged`` or, for ``t < late_t``, exceeds ``large`` or ``|e·e|/‖e‖²`` falls below
  ``null_stop``; FAILED when the step falls below ``min_step`` or the step budget
  ``max_steps`` (accepted plus rejected) runs out; NOT_FINITE for a non-finite start.

The 8×8 complex systems are solved by LU with partial pivoting (largest ``|Re| + |Im|``, as
LAPACK's ``izamax``) written here; an exactly zero pivot is a singular matrix (NaN solution, as
the NumPy tracker's ``solve_batch``). Every working array is allocated once per call of
:func:`track_range`, none per step; no BLAS, single-threaded, the GIL released.

Options ``opts (11,)``: initial_step, max_step, min_step, predictor_tol, corrector_tol,
max_newton, max_steps, diverged, late_t, large, null_stop (:data:`OPTION_NAMES`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.solve.path_tracking import PathStatus
from pkmkit.solve.study_rods import BASIS_INDEX

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

OPTION_NAMES = ("initial_step", "max_step", "min_step", "predictor_tol", "corrector_tol",
                "max_newton", "max_steps", "diverged", "late_t", "large", "null_stop")
REACHED, STOPPED, FAILED, NOT_FINITE = (int(PathStatus.REACHED), int(PathStatus.STOPPED),
                                        int(PathStatus.FAILED), int(PathStatus.NOT_FINITE))
N = 8  # unknowns and equations

#: Rows where each map ``Z_m`` has entries (m = 0–5: a_k, b_k, all 8; 6–15: a_k b_l and d, the
#: e rows 0–3; 16: the constant, the g rows 4–7): :func:`evaluate` skips the others.
_ROWS = np.zeros((len(BASIS_INDEX), N), dtype=bool)
_ROWS[:6] = True
_ROWS[6:16, :4] = True
_ROWS[16, 4:] = True
if not np.array_equal(_ROWS, BASIS_INDEX < N):  # pragma: no cover - guards study_rods' order
    raise RuntimeError("study_rods' maps Z_m changed: update six_rod_kernel.evaluate")


@njit(**_OPTIONS)
def evaluate(x, t, coeffs, conf, patch, index, scale, work, res, jac, d_t):  # pragma: no cover
    """``H``, ``∂H/∂x``, ``∂H/∂t`` at ``x (8,)``, ``t`` for configuration ``conf`` into
    ``res (8,)``, ``jac (8, 8)``, ``d_t (8,)``. ``coeffs (3, C, 6, 17)``: coefficients of t⁰,
    t¹, t² (:class:`~pkmkit.solve.study_rods.StudyHomotopy`); ``index``, ``scale (17, 8)``: the
    maps ``Z_m``, whose zero entries (:data:`_ROWS`) are skipped: the sums keep the order of the
    full products and lose only exact zeros; ``work (22, 17)`` complex scratch (rows 0–7:
    ``Z_mᵀ``, 8–13: ``c_j(t)``, 14: ``x·Z_m(x)``, 15–20: ``ċ_j(t)``; ``work[21, 0] = t + i·conf``
    of the coefficients held, NaN for none: the Runge–Kutta stages and the Newton iterations of a
    step share their t, so the coefficients are formed about twice per step)."""
    n_maps = index.shape[0]
    for m in range(n_maps):  # Z_m has entries in rows lo…hi−1 only (see _ROWS)
        lo, hi = (0, N) if m < 6 else ((0, 4) if m < 16 else (4, N))
        acc = 0j
        for r in range(lo, hi):
            v = scale[m, r] * x[index[m, r]]
            work[r, m] = v
            acc += v * x[r]
        work[14, m] = acc
    key = complex(t, conf)
    if work[21, 0] != key:  # c_j(t), ċ_j(t) of another t (or configuration): recompute
        for j in range(6):
            for m in range(n_maps):
                c1, c2 = coeffs[1, conf, j, m], coeffs[2, conf, j, m]
                work[8 + j, m] = coeffs[0, conf, j, m] + t * (c1 + t * c2)
                work[15 + j, m] = c1 + (2.0 * t) * c2
        work[21, 0] = key
    for j in range(6):
        rj, tj = 0j, 0j
        for m in range(n_maps):
            rj += work[8 + j, m] * work[14, m]
            tj += work[15 + j, m] * work[14, m]
        res[j] = rj
        d_t[j] = tj
        for r in range(4):  # e columns: maps 0–15
            acc = 0j
            for m in range(16):
                acc += work[8 + j, m] * work[r, m]
            jac[j, r] = 2.0 * acc
        for r in range(4, N):  # g columns: maps 0–5 and 16
            acc = 0j
            for m in range(6):
                acc += work[8 + j, m] * work[r, m]
            acc += work[8 + j, 16] * work[r, 16]
            jac[j, r] = 2.0 * acc
    study, lin = 0j, 0j
    for k in range(4):
        study += x[k] * x[k + 4]
        jac[6, k] = x[k + 4]
        jac[6, k + 4] = x[k]
    for k in range(N):
        lin += x[k] * patch[k]
        jac[7, k] = patch[k]
    res[6] = study
    res[7] = lin - 1.0
    d_t[6] = 0j
    d_t[7] = 0j


@njit(**_OPTIONS)
def lu_solve(a, b, n_rhs):  # pragma: no cover
    """Solve ``a (8, 8) · Y = b[:, :n_rhs]`` in place (``a`` becomes its LU factors, ``b`` the
    solution): partial pivoting on the largest ``|Re| + |Im|``. Returns False (``b`` left
    partly eliminated) on an exactly zero pivot."""
    for k in range(N):
        p = k
        best = abs(a[k, k].real) + abs(a[k, k].imag)
        for i in range(k + 1, N):
            size = abs(a[i, k].real) + abs(a[i, k].imag)
            if size > best:
                p, best = i, size
        if best == 0.0:
            return False
        if p != k:
            for j in range(N):
                a[k, j], a[p, j] = a[p, j], a[k, j]
            for r in range(n_rhs):
                b[k, r], b[p, r] = b[p, r], b[k, r]
        inv = 1.0 / a[k, k]
        for i in range(k + 1, N):
            f = a[i, k] * inv
            a[i, k] = f
            for j in range(k + 1, N):
                a[i, j] -= f * a[k, j]
            for r in range(n_rhs):
                b[i, r] -= f * b[k, r]
    for i in range(N - 1, -1, -1):
        for r in range(n_rhs):
            v = b[i, r]
            for j in range(i + 1, N):
                v -= a[i, j] * b[j, r]
            b[i, r] = v / a[i, i]
    return True


@njit(**_OPTIONS)
def _tangent(x, t, coeffs, conf, patch, index, scale, work, res, jac, d_t, rhs,
             out):  # pragma: no cover
    """``out = −H_x⁻¹ H_t`` at ``(x, t)`` (NaN where ``H_x`` is singular)."""
    evaluate(x, t, coeffs, conf, patch, index, scale, work, res, jac, d_t)
    for k in range(N):
        rhs[k, 0] = d_t[k]
    ok = lu_solve(jac, rhs, 1)
    for k in range(N):
        out[k] = -rhs[k, 0] if ok else complex(np.nan, np.nan)


@njit(**_OPTIONS)
def _stop(x, t, opts):  # pragma: no cover
    """The six-rod stop rule (:func:`pkmkit.solve.six_rod_paths._stop`)."""
    ee, gg, dot = 0.0, 0.0, 0j
    for k in range(4):
        ee += x[k].real ** 2 + x[k].imag ** 2
        gg += x[k + 4].real ** 2 + x[k + 4].imag ** 2
        dot += x[k] * x[k]
    ratio = math.sqrt(gg) / math.sqrt(ee)
    if ratio > opts[7]:
        return True
    return t < opts[8] and (ratio > opts[9] or abs(dot) / ee < opts[10])


@njit(**_OPTIONS)
def _max_abs(v):  # pragma: no cover
    out = 0.0
    for k in range(v.shape[0]):
        a = abs(v[k])
        if not a <= out:  # NaN propagates, as NumPy's max
            out = a
    return out


@njit(**_OPTIONS)
def _predict(x, t, dt, coeffs, conf, patch, index, scale, w, jac, rhs, vec):  # pragma: no cover
    """Runge–Kutta 4 from ``(x, t)`` over ``dt`` into ``vec[7]`` (the tangent ``vec[2]`` at
    ``x`` given; ``vec``'s rows as :func:`_track_path`)."""
    res, d_t, k1, k2, k3, k4, xs, xn = (vec[0], vec[1], vec[2], vec[3], vec[4], vec[5],
                                        vec[6], vec[7])
    half = dt / 2
    for k in range(N):
        xs[k] = x[k] - half * k1[k]
    _tangent(xs, t - dt / 2, coeffs, conf, patch, index, scale, w, res, jac, d_t, rhs, k2)
    for k in range(N):
        xs[k] = x[k] - half * k2[k]
    _tangent(xs, t - dt / 2, coeffs, conf, patch, index, scale, w, res, jac, d_t, rhs, k3)
    for k in range(N):
        xs[k] = x[k] - dt * k3[k]
    _tangent(xs, t - dt, coeffs, conf, patch, index, scale, w, res, jac, d_t, rhs, k4)
    for k in range(N):
        xn[k] = x[k] - (dt / 6) * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k])


@njit(**_OPTIONS)
def _correct(xn, t, sc, coeffs, conf, patch, index, scale, opts, w, jac, rhs,
             vec):  # pragma: no cover
    """Newton at ``t`` from ``xn`` (updated in place), updates relative to ``sc``; ``rhs[:, 1]``
    is left with ``H_x⁻¹ H_t`` of the last factorisation. Returns ``(first update size,
    converged)``."""
    res, d_t = vec[0], vec[1]
    corrector_tol, max_newton = opts[4], int(opts[5])
    first, last = np.inf, np.inf
    for it in range(max_newton):
        evaluate(xn, t, coeffs, conf, patch, index, scale, w, res, jac, d_t)
        for k in range(N):
            rhs[k, 0] = res[k]
            rhs[k, 1] = d_t[k]
        size = np.inf
        if lu_solve(jac, rhs, 2):
            for k in range(N):
                xn[k] -= rhs[k, 0]
            size = _max_abs(rhs[:, 0]) / sc
            if not math.isfinite(size):
                size = np.inf
        if it == 0:
            first = size
            ok, going = size <= corrector_tol, True
        else:
            theta = size / last
            going = theta <= 0.5
            ok = size <= corrector_tol or (going and theta * size <= corrector_tol)
        if ok:
            return first, True
        if not going or size == np.inf:  # an infinite update never recovers
            return first, False
        last = size
    return first, False


@njit(**_OPTIONS)
def _track_path(x, conf, coeffs, patch, index, scale, opts, w, jac, rhs, vec):  # pragma: no cover
    """Follow one path from ``x`` (overwritten with its end) at t = 1.

    Scratch: ``w (22, 17)`` (:func:`evaluate`), ``jac (8, 8)``, ``rhs (8, 2)``, ``vec (8, 8)``
    (rows: H, H_t, the tangent k1, k2, k3, k4, the trial point, the corrected point).
    Returns ``(t, status, accepted steps, rejected steps)``."""
    h, max_step, min_step = opts[0], opts[1], opts[2]
    predictor_tol, max_steps = opts[3], int(opts[6])
    k1, xn = vec[2], vec[7]
    t, steps, rejected = 1.0, 0, 0
    for k in range(N):
        if not (math.isfinite(x[k].real) and math.isfinite(x[k].imag)):
            return t, NOT_FINITE, steps, rejected
    _tangent(x, t, coeffs, conf, patch, index, scale, w, vec[0], jac, vec[1], rhs, k1)
    while True:
        dt = min(h, t)
        _predict(x, t, dt, coeffs, conf, patch, index, scale, w, jac, rhs, vec)
        t_new = t - dt
        first, converged = _correct(xn, t_new, max(1.0, _max_abs(x)), coeffs, conf, patch,
                                    index, scale, opts, w, jac, rhs, vec)
        accept = converged and first <= predictor_tol
        factor = 0.7 * (predictor_tol / max(first, 1e-300)) ** 0.2
        if math.isnan(factor):
            factor = 0.25
        if accept:
            for k in range(N):
                x[k] = xn[k]
                k1[k] = -rhs[k, 1]  # the next tangent, from the corrector's factorisation
            t = t_new
            steps += 1
            h = min(h * min(max(factor, 1.0), 2.0), max_step)
            if t <= 0.0:
                return t, REACHED, steps, rejected
            if _stop(x, t, opts):
                return t, STOPPED, steps, rejected
        else:
            h *= min(max(factor, 0.1), 0.5) if converged else 0.5
            rejected += 1
        if h < min_step or steps + rejected >= max_steps:
            return t, FAILED, steps, rejected


@njit(**_OPTIONS)
def track_range(start, n_conf, coeffs, patch, index, scale, opts, lo, hi,
                x_out, t_out, status, steps, rejected):  # pragma: no cover
    """Paths ``lo ≤ p < hi`` of ``n_conf`` configurations × ``P0`` start solutions
    ``start (P0, 8)`` (path ``p``: configuration ``p // P0``, start ``p % P0``), into
    ``x_out (P, 8)``, ``t_out``, ``status``, ``steps``, ``rejected (P,)``."""
    n_start = start.shape[0]
    w = np.empty((22, index.shape[0]), dtype=np.complex128)
    w[21, 0] = complex(np.nan, np.nan)
    jac = np.empty((N, N), dtype=np.complex128)
    rhs = np.empty((N, 2), dtype=np.complex128)
    vec = np.empty((8, N), dtype=np.complex128)
    x = np.empty(N, dtype=np.complex128)
    for p in range(lo, hi):
        conf = p // n_start
        for k in range(N):
            x[k] = start[p % n_start, k]
        t, code, acc, rej = _track_path(x, conf, coeffs, patch, index, scale, opts, w, jac, rhs,
                                          vec)
        for k in range(N):
            x_out[p, k] = x[k]
        t_out[p] = t
        status[p] = code
        steps[p] = acc
        rejected[p] = rej
    return n_conf
