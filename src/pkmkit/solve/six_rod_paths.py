"""The 40 homotopy paths of six-rod direct kinematics: tracking, end-point classes, checks.

For C target configurations (normalised, see :mod:`pkmkit.solve.six_rod_direct`) the 40
solutions of the stored generic start system (:mod:`pkmkit.solve.six_rod_start`) are followed
to each target by the coefficient-parameter homotopy of :mod:`pkmkit.solve.study_rods`, all
``40 C`` paths in one batch. Each path's end is then classified:

``REGULAR``
    reached t = 0 at a finite point with a well-conditioned Jacobian: an isolated solution;
``SINGULAR``
    a finite end point with a (nearly) singular Jacobian: a multiple solution (several paths
    meet there: the configuration is at or very near a direct-kinematic singularity) or a point
    of a positive-dimensional solution set (degenerate geometry). Paths whose step size
    collapsed within ``t ≤ 10⁻⁶`` of the target are in this class too, with their last point;
``INFINITE``
    the translation diverges: ``|g|/|e|`` (half the normalised translation) exceeds 10⁷ at any
    t, or 10⁴ at the end (``t < 10⁻⁶``, or where the steps collapsed after ``t = 10⁻³``), or
    10² while tending to the null quadric below (e → 0). A real assembly has ``|g|/|e| ≤ 1.5``
    (centred joints, unit characteristic length: ``|p| ≤ ℓ + |a| + |b| ≤ 3``), so no real
    solution is lost;
``EXCEPTIONAL``
    the rotation part tends to the null quadric ``e·e = 0`` (relative ``|e·e|/‖e‖²`` below
    10⁻⁶ at a regular end, 10⁻⁴ at a singular or collapsed one): spurious solutions of the
    Study formulation, not rigid displacements (a real rotation has ``e·e = ‖e‖²``, ratio 1).
    They appear for special geometries, e.g. coincident joints (3-3, 6-3 platforms), whose extra
    paths converge there slowly;
``FAILED``
    the step size collapsed (or the step budget ran out) before ``t = 10⁻⁶`` at a point of
    none of the classes above.

Completeness checks per configuration (a configuration passing them is *certified*):
no ``FAILED`` path; no two ``REGULAR`` end points coincide (two paths that jumped onto one
solution would leave another solution unfound); the complex conjugate of every ``REGULAR`` end
point is also an end point (the target system is real, so its solution set is closed under
conjugation; a missing conjugate betrays a lost path). Configurations that fail a check are
tracked again with a 100× tighter predictor tolerance.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from pkmkit.numerics import jit
from pkmkit.solve.path_tracking import PathStatus, TrackResult, track_paths
from pkmkit.solve.six_rod_start import GENERIC_COUNT, StartSystem
from pkmkit.solve.study_rods import BASIS_INDEX, BASIS_SCALE, RodParameters, StudyHomotopy

#: ``|g|/|e|`` beyond which a path is stopped at infinity at any t.
DIVERGED_RATIO = 1e7
#: Below ``LATE_T`` a path is stopped when ``|g|/|e| > LARGE_RATIO`` (at infinity) or
#: ``|e·e|/‖e‖² < NULL_STOP`` (on the exceptional quadric).
LATE_T, LARGE_RATIO, NULL_STOP = 1e-6, 1e4, 1e-6
#: A path whose steps collapse below ``ENDGAME_T`` ends at a degenerate point: at infinity if
#: ``|g|/|e| > LARGE_RATIO``, exceptional if ``|e·e|/‖e‖² < NULL_END`` (at infinity if also
#: ``|g|/|e| > NULL_FAR``), else singular when ``t ≤ SINGULAR_T`` (its last point is an
#: approximation of a multiple solution) and failed otherwise.
ENDGAME_T, NULL_END, NULL_FAR, SINGULAR_T = 1e-3, 1e-4, 1e2, 1e-6
#: Jacobian condition number above which an end point reached at t = 0 is singular.
SINGULAR_CONDITION = 1e10
#: Options of the path tracker (both implementations); ``predictor_tol`` comes from the caller.
TRACKER_OPTIONS = {"initial_step": 0.05, "max_step": 0.2, "min_step": 1e-12,
                   "corrector_tol": 1e-9, "max_newton": 3, "max_steps": 2000}


class EndKind(IntEnum):
    """Class of a path's end point (see the module docstring)."""

    REGULAR = 0
    SINGULAR = 1
    INFINITE = 2
    EXCEPTIONAL = 3
    FAILED = 4


@dataclass
class EndPoints:
    """Path end points of C configurations (40 paths each).

    Attributes:
        x: ``(C, 40, 8)`` complex Study points on the start system's patch (NaN unless the
            end point is finite: ``REGULAR`` or ``SINGULAR``).
        normal: ``(C, 40, 8)`` the same points divided by their largest rotation component
            (a representative independent of the patch, used for comparisons and for the real
            test).
        kind: ``(C, 40)`` :class:`EndKind` codes.
        certified: ``(C,)`` every completeness check passed.
        steps: ``(C,)`` accepted predictor–corrector steps summed over the 40 paths.
    """

    x: np.ndarray
    normal: np.ndarray
    kind: np.ndarray
    certified: np.ndarray
    steps: np.ndarray


#: Configurations tracked together (40 paths each): large enough to amortise NumPy's per-call
#: overhead, small enough for the working arrays to stay in cache (bench/six_rod_direct.py).
CHUNK = 16


def use_compiled_tracker(n_conf: int = 1) -> bool:
    """Whether the compiled tracker (:mod:`pkmkit.solve.six_rod_kernel`) runs by default on
    ``n_conf`` configurations: the rule of :func:`pkmkit.numerics.jit.use_compiled_solver` on
    their 40 paths each — from two configurations, or at any size once Numba is imported, never
    under ``PKMKIT_COMPILED=0`` or without Numba. The first lone configuration of a process in
    which Numba is not imported yet takes the NumPy tracker (≈ 0.1 s, where importing Numba and
    loading the kernel cost ≈ 0.4 s: a one-shot ``pkmkit fk --all`` stays on NumPy); the next
    call imports it (a loop of single calls runs compiled from its second call)."""
    if jit.use_compiled_solver(GENERIC_COUNT * n_conf):
        return True
    return jit.compiled_from_second_call(sys.modules[__name__], "tracker")


def track_configurations(
    start: StartSystem,
    target: RodParameters,
    predictor_tol: float = 1e-3,
    retries: int = 1,
    compiled: bool | None = None,
) -> EndPoints:
    """Track the start solutions to every target configuration and classify the ends.

    Args:
        start: the generic start system.
        target: C normalised target configurations.
        predictor_tol: relative predictor error accepted per step.
        retries: re-tracking rounds (each 100× tighter) for configurations not certified.
        compiled: the compiled tracker (True), the NumPy one (False) or the default
            (None: :func:`use_compiled_tracker`); both follow the same rules.
    """
    if compiled is None:
        compiled = use_compiled_tracker(target.offset.shape[1])
    ends = _track_in_chunks(start, target, predictor_tol, compiled)
    tol = predictor_tol
    for _ in range(retries):
        redo = np.flatnonzero(~ends.certified)
        if redo.size == 0:
            break
        tol *= 0.01
        again = _track_in_chunks(start, target.take(redo), tol, compiled)
        fails_before = (ends.kind[redo] == EndKind.FAILED).sum(axis=1)
        better = again.certified | ((again.kind == EndKind.FAILED).sum(axis=1) <= fails_before)
        for name in ("x", "normal", "kind", "certified"):
            getattr(ends, name)[redo[better]] = getattr(again, name)[better]
        ends.steps[redo] += again.steps
    return ends


def _track_in_chunks(start: StartSystem, target: RodParameters, tol: float,
                     compiled: bool) -> EndPoints:
    n_conf = target.offset.shape[1]
    if n_conf <= CHUNK:
        return _track(start, target, tol, compiled)
    parts = [_track(start, target.take(np.arange(i, min(i + CHUNK, n_conf))), tol, compiled)
             for i in range(0, n_conf, CHUNK)]
    return EndPoints(*(np.concatenate([getattr(p, f) for p in parts])
                       for f in ("x", "normal", "kind", "certified", "steps")))


def translation_ratio(x: np.ndarray) -> np.ndarray:
    """``|g| / |e|`` of Study points ``(..., 8)``: half the normalised translation."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.linalg.norm(x[..., 4:], axis=-1) / np.linalg.norm(x[..., :4], axis=-1)


def null_rotation(x: np.ndarray) -> np.ndarray:
    """``|e·e| / ‖e‖²`` of Study points ``(..., 8)``: 1 for real rotations, 0 on the null
    quadric."""
    e = x[..., :4]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.abs((e * e).sum(axis=-1)) / (np.abs(e) ** 2).sum(axis=-1)


def _stop(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    ratio = translation_ratio(x)
    late = t < LATE_T
    return (ratio > DIVERGED_RATIO) | (late & ((ratio > LARGE_RATIO)
                                               | (null_rotation(x) < NULL_STOP)))


def classify(x: np.ndarray, t: np.ndarray, status: np.ndarray, cond: np.ndarray) -> np.ndarray:
    """:class:`EndKind` of path ends ``x (P, 8)`` where tracking stopped at ``t (P,)`` with
    :class:`~pkmkit.solve.path_tracking.PathStatus` ``status``; ``cond`` is the Jacobian
    condition number of the ends that reached t = 0 (polished)."""
    ratio, null = translation_ratio(x), null_rotation(x)
    reached = status == PathStatus.REACHED
    stuck = (status == PathStatus.FAILED) & (t <= ENDGAME_T)
    ended = reached | stuck | (status == PathStatus.STOPPED)
    singular = reached & ~(cond <= SINGULAR_CONDITION)
    # on (or converging to) the null quadric: exact at t = 0, looser for degenerate ends
    near_null = np.where(reached & ~singular, null < NULL_STOP, null < NULL_END)
    infinite = ended & ((ratio > LARGE_RATIO) | (near_null & (ratio > NULL_FAR)))
    exceptional = ended & ~infinite & near_null
    kind = np.full(x.shape[0], int(EndKind.FAILED))
    kind[reached & ~singular] = EndKind.REGULAR
    kind[singular | (stuck & (t <= SINGULAR_T))] = EndKind.SINGULAR
    kind[infinite] = EndKind.INFINITE
    kind[exceptional] = EndKind.EXCEPTIONAL
    return kind


def _track(start: StartSystem, target: RodParameters, predictor_tol: float,
           compiled: bool = False) -> EndPoints:
    n_conf = target.offset.shape[1]
    n_paths = start.solutions.shape[0]
    homotopy = StudyHomotopy.between(start.parameters, target, start.patch)
    cols = np.repeat(np.arange(n_conf), n_paths)
    single = n_conf == 1
    if compiled:
        result = _track_compiled(homotopy, start.solutions, n_conf, predictor_tol)
    else:
        def evaluate(x, t, rows):
            return homotopy.evaluate(x, t, None if single else cols[rows])

        result = track_paths(evaluate, np.tile(start.solutions, (n_conf, 1)), stop=_stop,
                             predictor_tol=predictor_tol, **TRACKER_OPTIONS)
    x = result.x
    cond = np.full(x.shape[0], np.inf)
    idx = np.flatnonzero(result.status == PathStatus.REACHED)
    if idx.size:
        x[idx], cond[idx] = _polish(homotopy, x[idx], None if single else cols[idx])
    kind = classify(x, result.t, result.status, cond)
    finite = (kind == EndKind.REGULAR) | (kind == EndKind.SINGULAR)
    x = np.where(finite[:, None], x, np.nan)
    kind = kind.reshape(n_conf, n_paths)
    x = x.reshape(n_conf, n_paths, -1)
    normal = projective_normal(x)
    certified = ~(kind == EndKind.FAILED).any(axis=1)
    certified &= distinct_regular(normal, kind) & closed_under_conjugation(normal, kind)
    steps = result.steps.reshape(n_conf, n_paths).sum(axis=1)
    return EndPoints(x, normal, kind, certified, steps)


def _track_compiled(homotopy: StudyHomotopy, start: np.ndarray, n_conf: int,
                    predictor_tol: float) -> TrackResult:
    """The compiled tracker (:mod:`pkmkit.solve.six_rod_kernel`) on every path of ``n_conf``
    configurations (path ``p``: configuration ``p // 40``, start ``p % 40``)."""
    from pkmkit.solve import six_rod_kernel as kernel

    values = {**TRACKER_OPTIONS, "predictor_tol": predictor_tol, "diverged": DIVERGED_RATIO,
              "late_t": LATE_T, "large": LARGE_RATIO, "null_stop": NULL_STOP}
    opts = np.array([values[name] for name in kernel.OPTION_NAMES], dtype=float)
    n = n_conf * start.shape[0]
    x, t = np.empty((n, start.shape[1]), dtype=complex), np.empty(n)
    status, steps, rejected = (np.empty(n, dtype=np.int64) for _ in range(3))
    kernel.track_range(np.ascontiguousarray(start), n_conf,
                       np.ascontiguousarray(homotopy.coeffs), homotopy.patch, BASIS_INDEX,
                       BASIS_SCALE, opts, 0, n, x, t, status, steps, rejected)
    return TrackResult(x=x, t=t, status=status, steps=steps, rejected=rejected)


def _polish(homotopy: StudyHomotopy, x: np.ndarray, cols, iterations: int = 3):
    """Newton at t = 0; returns the points and the condition numbers of their Jacobians."""
    t0 = np.zeros(x.shape[0])
    for _ in range(iterations):
        res, jac, _ = homotopy.evaluate(x, t0, cols)
        try:
            step = np.linalg.solve(jac, res[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            break
        x = np.where(np.isfinite(step).all(axis=1)[:, None], x - step, x)
    _, jac, _ = homotopy.evaluate(x, t0, cols)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        cond = np.linalg.cond(jac)
    return x, np.nan_to_num(cond, nan=np.inf)


def projective_normal(x: np.ndarray) -> np.ndarray:
    """``x / e_k`` with ``e_k`` the largest rotation component of each point ``(..., 8)``
    (NaN points stay NaN)."""
    e = x[..., :4]
    k = np.argmax(np.nan_to_num(np.abs(e), nan=-1.0), axis=-1)
    pivot = np.take_along_axis(e, k[..., None], axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return x / pivot


def pair_distance(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``(C, P, Q)`` largest component difference between rows of ``u (C, P, 8)`` and
    ``v (C, Q, 8)``, relative to ``max(1, |u|∞)``; NaN rows give +inf."""
    scale = np.maximum(1.0, np.nan_to_num(np.abs(u).max(axis=2), nan=1.0))
    with np.errstate(invalid="ignore"):
        dist = np.abs(u[:, :, None, :] - v[:, None, :, :]).max(axis=3) / scale[:, :, None]
    return np.nan_to_num(dist, nan=np.inf)


def distinct_regular(normal: np.ndarray, kind: np.ndarray, tol: float = 1e-7) -> np.ndarray:
    """``(C,)``: no two regular end points coincide (no path jumping)."""
    reg = np.where((kind == EndKind.REGULAR)[..., None], normal, np.nan)
    dist = pair_distance(reg, reg)
    n = normal.shape[1]
    dist[:, np.arange(n), np.arange(n)] = np.inf
    return ~(dist <= tol).any(axis=(1, 2))


def closed_under_conjugation(normal: np.ndarray, kind: np.ndarray,
                             tol: float = 1e-6) -> np.ndarray:
    """``(C,)``: the conjugate of every regular end point is a finite end point."""
    reg = kind == EndKind.REGULAR
    dist = pair_distance(np.conj(normal), normal)  # NaN (not finite) ends never match
    found = dist.min(axis=2) <= tol
    return (found | ~reg).all(axis=1)
