"""Identification of a machine's geometric defects from measurements: nonlinear least squares over
the identifiable parameters, with analytic Jacobians, validation and uncertainties.

:func:`calibrate` runs the whole procedure:

1. checks the measurements against the machine (strokes, assembly of the nominal machine),
   naming the rows that fail;
2. fits the set-up parameters alone on the nominal machine (measurement frame, part placement,
   ball-bar pivots, bed plane: :mod:`pkmkit.calibration.models`) — the **before** state;
3. for a hyperstatic machine, restricts the defects to the **compatible** subspace (the legs
   close exactly; :func:`~pkmkit.calibration.identifiability.compatible_directions`: the
   incompatible directions are named and fixed), unless ``compatible=False`` (then the forward
   model closes the legs in least squares, as seed 002 did);
4. selects the **identifiable** parameters on the whitened, tolerance-scaled Jacobian at the
   nominal machine (QR with column pivoting; set-up parameters first, so that the machine
   defects that only move the machine rigidly with respect to the instrument are reported as
   gauges), then drops those the measurement noise cannot determine better than their tolerance
   (``prune=True``); every parameter left at its nominal value is reported with the reason;
5. solves ``min Σ w_i ‖r_i / σ_i‖² (+ Σ (δ_j / tol_j)² with priors)`` with the analytic
   Jacobians of the residual models, the machine with defects rebuilt exactly at every step
   (inner closures included): a chord stage (the batched engine's Levenberg–Marquardt on a
   Jacobian frozen for a few iterations), then MINPACK's Levenberg–Marquardt (SciPy) if the
   gradient is not yet orthogonal to every column (:func:`solve_scaled`); with ``robust=True`` the
   weights w_i follow Huber's loss on each observation's normalised error (iteratively
   reweighted) and the observations beyond 3 robust standard deviations are reported;
6. reports the identified values with standard deviations (``σ̂² (JᵀJ)⁻¹``, σ̂² the a-posteriori
   variance factor) and correlations, the residuals before and after (mean, RMS, max, per
   observation), the rank and condition of the identified problem, and the residuals of a
   held-out validation set before and after.

Units: SI inside (m, rad, and dimensionless direction components); :meth:`CalibrationResult.
to_json` converts lengths to the caller's unit and angles (``"rad"`` parameters) to degrees.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.calibration.divergence import (
    divergence_bounds,
    divergence_message,
    setup_failure_result,
    unconverged_result,
)
from pkmkit.calibration.identifiability import (
    RCOND,
    CompatibleDirections,
    compatible_directions,
    identifiable_parameters,
    prune_weak,
)
from pkmkit.calibration.models import ResidualModel, make_model
from pkmkit.calibration.registration import Registration
from pkmkit.calibration.results import (
    CalibrationResult,
    Validation,
    residual_stats,
)
from pkmkit.calibration.solver import (
    ScaledProblem,
    fit_setup,
    problem_rows,
    solve_scaled,
)
from pkmkit.calibration.uncertainty import Propagation, tool_point_uncertainty
from pkmkit.exceptions import (
    ConvergenceError,
    IdentificationDivergedError,
    InputError,
    ParameterError,
    PkmError,
)
from pkmkit.geometric_errors.blas_threads import one_blas_thread
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity
from pkmkit.machines.strokes import signed_excess, stroke_limits
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.status import Status

#: Default standard deviation of one reading per measurement type (m): a laser tracker
#: (≈ ±15 µm + 6 µm/m as a 2σ bound at 2–3 m), a ball-bar (±1 µm), a touch probe, a CMM.
DEFAULT_SIGMA = {"point": 1.5e-5, "pose": 1.5e-5, "ballbar": 1e-6, "height": 2e-6,
                 "part": 2e-6}
#: Standard deviation of a measured orientation (rad) for ``pose`` measurements.
DEFAULT_SIGMA_ROTATION = 3e-5
#: Default tolerance (typical magnitude) of a defect by unit: m, direction component, rad.
DEFAULT_TOLERANCE = {"m": 1e-4, "1": 5e-3, "rad": 5e-3}
#: Huber threshold on an observation's normalised error (robust loss).
HUBER = 2.0
#: Observations beyond this many robust standard deviations are reported as outliers.
OUTLIER = 3.0


def default_tolerances(names: Sequence[str], units: Sequence[str],
                       tolerances: Mapping[str, float] | None = None) -> np.ndarray:
    """Tolerance (typical magnitude, SI) of each defect: ``tolerances[name]`` or the default of
    its unit (:data:`DEFAULT_TOLERANCE`)."""
    tolerances = dict(tolerances or {})
    unknown = sorted(set(tolerances) - set(names))
    if unknown:
        raise ParameterError(f"tolerances given for unknown defects: {', '.join(unknown)}",
                             unknown[0])
    out = np.array([float(tolerances.get(n, DEFAULT_TOLERANCE[u])) for n, u in
                    zip(names, units, strict=True)])
    if not (np.isfinite(out).all() and (out > 0).all()):
        raise ParameterError("tolerances must be positive numbers")
    return out


def check_measurements(machine, data: MeasurementSet) -> None:
    """Typed errors for rows outside the strokes or where the nominal machine does not
    assemble, naming the rows (file lines) and actuator columns.

    Raises:
        InputError: the rows and columns at fault (up to ten listed).
    """
    if data.q is None:
        return
    q = data.q
    if q.shape[1] != machine.n_actuators:
        raise InputError(f"{data.source}: {q.shape[1]} actuator columns for a machine with "
                         f"{machine.n_actuators} actuators")
    if not np.isfinite(q).all():
        i = int(np.flatnonzero(~np.isfinite(q).all(axis=1))[0])
        raise InputError(f"{data.labels[i]}: actuator values are not finite")
    lo, hi = stroke_limits(machine)
    angle = machine.angular_actuators
    excess = signed_excess(q, lo, hi)
    bad = []
    for k, name in enumerate(machine.actuator_names):
        rows = np.flatnonzero(excess[:, k] != 0)
        for i in rows:
            f = (np.degrees if angle[k] else (lambda v: v))
            bad.append(f"{data.labels[i]} column {name}: {f(q[i, k]):.6g} outside the stroke "
                       f"[{f(lo[k]):.6g}, {f(hi[k]):.6g}] ({'deg' if angle[k] else 'm'})")
    if bad:
        more = f" (and {len(bad) - 10} more)" if len(bad) > 10 else ""
        raise InputError("rows out of stroke: " + "; ".join(bad[:10]) + more)


def calibrate(machine, data: MeasurementSet, *, validation: MeasurementSet | None = None,
              parameters: str | Sequence[str] = "auto", frame: Any = None,
              robust: bool = False, prior: bool = False,
              tolerances: Mapping[str, float] | None = None, sigma: float | None = None,
              compatible: bool = True, rcond: float = RCOND, prune: bool = True,
              max_iter: int = 60, progress: bool = False) -> CalibrationResult:
    """Identify ``machine``'s defects from ``data`` (see the module docstring).

    Args:
        machine: the nominal machine (whose controller produced the commands).
        data: identification measurements.
        validation: held-out measurements of the same kind, or None.
        parameters: ``"auto"`` (every defect, the identifiable ones selected) or defect names
            (candidates; the identifiable ones among them are selected).
        frame: for point and pose measurements: None (readings in the machine frame), a
            :class:`Registration` (fixed), or ``"identify"`` (6 frame parameters identified
            with the machine).
        robust: Huber loss on each observation (iteratively reweighted), outliers reported.
        prior: add the tolerances as priors (Tikhonov rows δ/tol): every candidate the
            measurements see is kept, weighted against its tolerance.
        tolerances: defect name → tolerance (SI); default by unit (:data:`DEFAULT_TOLERANCE`).
        sigma: standard deviation of one reading (m); default by type (:data:`DEFAULT_SIGMA`).
        compatible: restrict a hyperstatic machine's defects to its compatible subspace.
        rcond: relative rank threshold of the selection.
        prune: drop the parameters the noise determines worse than their tolerance.
        max_iter: iteration limit of each least-squares solve.
        progress: show a progress counter of model evaluations on stderr (terminals only).

    Raises:
        InputError: measurements the machine cannot have produced (rows out of stroke, no
            assembly), too few independent measurements, mismatched kinds.
        ParameterError: unknown parameter names or tolerances.
        IdentificationDivergedError: the identification did not converge (a
            :class:`~pkmkit.exceptions.ConvergenceError`); its ``result`` is the nominal
            machine's fit, which :func:`pkmkit.calibration.calibrate` still judges
            (:mod:`pkmkit.calibration.divergence`).
    """
    # small dense problems: a multi-threaded BLAS only loses time, and collapses when another
    # process holds a core (docs/benchmarks.md)
    from tqdm import tqdm

    with single_threaded_blas(), tqdm(desc="identification", unit=" evaluations",
                                      disable=None if progress else True, leave=False) as bar:
        return _calibrate(machine, data, validation=validation, parameters=parameters,
                          frame=frame, robust=robust, prior=prior, tolerances=tolerances,
                          sigma=sigma, compatible=compatible, rcond=rcond, prune=prune,
                          max_iter=max_iter, progress=bar if progress else None)


def single_threaded_blas():
    """A context in which BLAS/LAPACK run on one thread (the one limiter,
    :func:`pkmkit.geometric_errors.blas_threads.one_blas_thread`)."""
    return one_blas_thread()


@dataclass
class _Prepared:
    """Everything :func:`calibrate` sets up before solving (see :func:`identification_problem`
    for the public face)."""

    problem: ScaledProblem
    u0: np.ndarray
    start: tuple
    model: ResidualModel
    dset: Any
    setup0: np.ndarray
    r_before: np.ndarray
    unidentifiable: dict[str, str]
    setup_unid: dict[str, str]
    cand_names: list[str]
    mach_sel: np.ndarray
    setup_sel: np.ndarray
    readings: int
    rank: int
    sigma: float
    registration: Registration | None
    identify_frame: bool
    t_start: float
    n_candidates: int = 0


def _prepare(machine, data, *, validation, parameters, frame, prior, tolerances, sigma,
             compatible, rcond, prune) -> _Prepared:
    t_start = time.perf_counter()
    if validation is not None and validation.kind != data.kind:
        raise InputError(f"validation measurements are {validation.kind!r}, identification "
                         f"ones {data.kind!r}")
    check_measurements(machine, data)
    if validation is not None:
        check_measurements(machine, validation)
    sig = DEFAULT_SIGMA[data.kind] if sigma is None else float(sigma)
    if not (np.isfinite(sig) and sig > 0):
        raise InputError(f"sigma must be a positive length, got {sigma!r}")
    registration, identify_frame = _frame_option(frame)
    model = make_model(machine, data, sigma_rows(data.kind, machine, sig),
                       registration=registration, identify_frame=identify_frame)
    dset = defect_set(machine)
    d = len(dset)
    tol = default_tolerances(dset.names, dset.units, tolerances)
    candidates = _candidates(dset, parameters)

    # ---- before: the nominal machine, set-up fitted alone
    r_nom, _, _ = model.residuals(machine, model.setup.initial, jacobian=False)
    _raise_unassembled(model, r_nom, "the nominal machine")
    try:
        setup0 = fit_setup(machine, model)
    except ConvergenceError as exc:  # readings no placement of the set-up fits: judged too
        raise IdentificationDivergedError(str(exc), result=setup_failure_result(
            machine, data, model, str(exc), sigma=sig, frame=registration,
            candidates=len(candidates), t_start=t_start)) from None
    r_before, jd0, js0 = model.residuals(machine, setup0, jacobian=True)
    _raise_unassembled(model, r_before, "the nominal machine")

    # ---- compatible subspace (hyperstatic joint chains)
    unidentifiable: dict[str, str] = {}
    compat: CompatibleDirections | None = None
    basis = np.eye(d)[:, candidates]
    if compatible and machine.incompatible_defects:
        compat = _compatibility(machine, data, tol, model.sensitivity(machine))
        basis = compat.basis
        free = [int(i) for i in compat.free if i in set(candidates)]
        dependents = [int(k) for k in compat.dependent]
        for k in dependents:
            if k in set(candidates):
                unidentifiable[dset.names[k]] = compat.describe(dset.names[k])
        keep = [list(compat.free).index(i) for i in free]
        basis = basis[:, keep]
        cand_names = [dset.names[i] for i in free]
        cand_tol = tol[free]
    else:
        cand_names = [dset.names[i] for i in candidates]
        cand_tol = tol[candidates]
    for i in range(d):
        if i not in set(candidates) and parameters != "auto":
            unidentifiable[dset.names[i]] = "not among the requested parameters"

    # ---- identifiability on the whitened, scaled Jacobian at the nominal machine
    w = 1.0 / model.sigma
    jm = (jd0 @ basis) * w[:, :, None]
    jsw = js0 * w[:, :, None]
    full = np.concatenate([jsw, jm], axis=2).reshape(-1, len(model.setup) + basis.shape[1])
    names_all = list(model.setup.names) + cand_names
    scale_all = np.concatenate([model.setup.scale, cand_tol])
    groups = [0] * len(model.setup) + [1] * len(cand_names)
    group_labels = {0: _setup_label(data.kind, identify_frame), 1: "machine defects"}
    ident = identifiable_parameters(full, names_all, scale_all, groups=groups, rcond=rcond,
                                    group_labels=group_labels)
    unidentifiable.update({n: r for n, r in ident.reasons.items()
                           if n not in model.setup.names})
    setup_unid = {n: r for n, r in ident.reasons.items() if n in model.setup.names}
    sel = ident.selected
    s_count = len(model.setup)
    setup_sel = np.array([i for i in sel if i < s_count], dtype=int)
    mach_sel = np.array([i - s_count for i in sel if i >= s_count], dtype=int)
    if prior:  # the priors make every parameter the measurements see determinate
        seen = [k for k, n in enumerate(cand_names)
                if not ident.reasons.get(n, "").startswith("no effect")]
        mach_sel = np.array(seen, dtype=int)
        for n in cand_names:
            if not ident.reasons.get(n, "no effect").startswith("no effect"):
                unidentifiable.pop(n, None)
    if prune and not prior and mach_sel.size:
        cols = np.concatenate([setup_sel, s_count + mach_sel])
        weak = prune_weak(full[:, cols], scale_all[cols], sigma=1.0,
                          keep=range(setup_sel.size))
        kept = weak.kept
        for idx, (std, tl) in weak.dropped.items():
            name = names_all[cols[idx]]
            unit = dset.units[dset.names.index(name)]
            unidentifiable[name] = (f"weakly identifiable: these measurements would determine "
                                    f"it to ±{_quantity(std, unit)}, worse than its tolerance "
                                    f"{_quantity(tl, unit)}")
        kept_cols = cols[kept]
        mach_sel = np.array([c - s_count for c in kept_cols if c >= s_count], dtype=int)
    readings = len(data) * model.width
    n_unknown = mach_sel.size + setup_sel.size
    if readings <= n_unknown:
        raise InputError(f"too few independent measurements: {len(data)} {data.kind} rows give "
                         f"{readings} readings for {n_unknown} identifiable parameters "
                         f"({mach_sel.size} of the machine, {setup_sel.size} of the set-up); "
                         "add measurements")

    # ---- nonlinear least squares (robust: iteratively reweighted)
    problem = ScaledProblem(machine=machine, model=model, basis=basis[:, mach_sel],
                       setup_index=setup_sel, setup_base=setup0.copy(),
                       scale=np.concatenate([cand_tol[mach_sel], model.setup.scale[setup_sel]]),
                       prior=prior, weights=np.ones(len(data)),
                       bound=divergence_bounds(machine, [dset.units[dset.names.index(
                           cand_names[i])] for i in mach_sel]))
    u = np.concatenate([np.zeros(mach_sel.size), setup0[setup_sel] / model.setup.scale[
        setup_sel]])
    return _Prepared(problem=problem, u0=u, start=problem.assemble(u, r_before, jd0, js0),
                     model=model, dset=dset, setup0=setup0, r_before=r_before,
                     unidentifiable=unidentifiable, setup_unid=setup_unid,
                     cand_names=cand_names, mach_sel=mach_sel, setup_sel=setup_sel,
                     readings=readings, rank=ident.rank if prior else int(
                         mach_sel.size + setup_sel.size), sigma=sig, registration=registration,
                     identify_frame=identify_frame, t_start=t_start,
                     n_candidates=len(candidates))


@dataclass(frozen=True)
class IdentificationProblem:
    """The least-squares problem :func:`calibrate` solves, exposed for independent solvers
    (benchmarks, tests): unknowns ``u`` are the identified parameters divided by their scales
    (machine defects first, then set-up parameters), the residual is whitened (and has the
    prior rows with ``prior=True``).

    Attributes:
        names: ``(p,)`` parameter names. scale: ``(p,)`` SI per unit of u. u0: ``(p,)`` start.
    """

    names: tuple[str, ...]
    scale: np.ndarray
    u0: np.ndarray
    _problem: Any = field(repr=False)

    def residual(self, u: np.ndarray) -> np.ndarray:
        """Whitened residual ``(M,)`` (NaN where the machine does not assemble)."""
        rw, _, _ = self._problem.evaluate(np.asarray(u, dtype=float), jacobian=False)
        return rw if rw is not None else np.full(len(self._problem_rows()), np.nan)

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """Analytic Jacobian ``(M, p)`` of :meth:`residual`."""
        return self._problem.evaluate(np.asarray(u, dtype=float), jacobian=True)[1]

    def _problem_rows(self):
        return np.zeros(problem_rows(self._problem))


def identification_problem(machine, data: MeasurementSet, *,
                           parameters: str | Sequence[str] = "auto", frame: Any = None,
                           prior: bool = False, tolerances: Mapping[str, float] | None = None,
                           sigma: float | None = None, compatible: bool = True,
                           rcond: float = RCOND, prune: bool = True,
                           closure_options: dict | None = None) -> IdentificationProblem:
    """The problem :func:`calibrate` would solve with these options (same arguments);
    ``closure_options`` are engine options of the residual's inner closures (joint chains),
    e.g. ``{"xtol": 1e-6}`` to emulate an inexact inner solver."""
    with single_threaded_blas():
        prep = _prepare(machine, data, validation=None, parameters=parameters, frame=frame,
                        prior=prior, tolerances=tolerances, sigma=sigma, compatible=compatible,
                        rcond=rcond, prune=prune)
    prep.model.closure_options = dict(closure_options or {})
    names = (tuple(prep.cand_names[i] for i in prep.mach_sel)
             + tuple(prep.model.setup.names[i] for i in prep.setup_sel))
    return IdentificationProblem(names=names, scale=prep.problem.scale.copy(),
                                 u0=prep.u0.copy(), _problem=prep.problem)


def _calibrate(machine, data, *, validation, parameters, frame, robust, prior, tolerances,
               sigma, compatible, rcond, prune, max_iter, progress=None) -> CalibrationResult:
    prep = _prepare(machine, data, validation=validation, parameters=parameters, frame=frame,
                    prior=prior, tolerances=tolerances, sigma=sigma, compatible=compatible,
                    rcond=rcond, prune=prune)
    problem, u, model, dset = prep.problem, prep.u0, prep.model, prep.dset
    problem.progress = progress
    setup0, r_before, unidentifiable = prep.setup0, prep.r_before, prep.unidentifiable
    setup_unid, cand_names = prep.setup_unid, prep.cand_names
    mach_sel, setup_sel, readings, sig = prep.mach_sel, prep.setup_sel, prep.readings, prep.sigma
    registration, identify_frame, t_start = prep.registration, prep.identify_frame, prep.t_start
    n_unknown = mach_sel.size + setup_sel.size
    iterations = 0
    start = prep.start
    for _ in range(8 if robust else 1):
        sol = solve_scaled(problem, u, max_iter, start)
        iterations += sol.iterations
        if sol.status not in (Status.OK, Status.INCONSISTENT):
            message = divergence_message(prep, sol, iterations)
            raise IdentificationDivergedError(message, result=unconverged_result(
                prep, machine, data, message, iterations,
                counts={**_counts(prep, prep.unidentifiable), "identified": 0}))
        u = sol.u
        if not robust:
            break
        new = _huber_weights(model, sol.r)
        converged = np.allclose(new, problem.weights, atol=1e-3)
        problem.weights = new
        start = problem.evaluate(u, jacobian=True)
        if converged:
            break
    rw, jw, r_after = start if robust else (sol.rw, sol.jw, sol.r)
    delta, setup = problem.unpack(u)
    m_id = problem.machine_at(delta)

    # ---- uncertainties
    m_rows = readings
    dof = max(m_rows - n_unknown, 1)
    meas = rw[:m_rows]
    factor = float(meas @ meas) / dof
    jtj = jw.T @ jw
    cov_u = np.linalg.pinv(jtj) * factor
    cov = cov_u * np.outer(problem.scale, problem.scale)
    std = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    # the pseudo-inverse drops the directions the data do not determine, which would give
    # those parameters a standard deviation of 0: they are undetermined (inf)
    null_scaled = _null_directions(jw)
    undetermined = (null_scaled ** 2).sum(axis=0) > 1e-6
    null = null_scaled * problem.scale[None, :]
    uncertainty = _tool_uncertainty(m_id, data, model.sensitivity(m_id),
                                    problem.basis, cov[:mach_sel.size, :mach_sel.size],
                                    null[:, :mach_sel.size], model.rigid_motion_free)
    std[undetermined] = np.inf
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, np.where(undetermined, np.nan, 1.0))
    cov[undetermined, :] = np.nan
    cov[:, undetermined] = np.nan
    cov[undetermined, undetermined] = np.inf
    sv = np.linalg.svd(jw[:m_rows], compute_uv=False)
    condition = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")

    p = mach_sel.size
    theta = u * problem.scale
    outliers = _outliers(model, r_after, problem.weights) if robust else []

    # ---- validation
    val = None
    final_frame = (model.frame(setup) if registration is not None or identify_frame
                   else None)
    if validation is not None:
        frames = ((model.frame(setup0), final_frame) if final_frame is not None
                  else (None, None))  # the frame fitted with each machine
        val = _validate(machine, m_id, validation, frames, sig)

    unidentifiable.update({n: f"set-up parameter not identifiable: {r}" for n, r in
                           setup_unid.items()})
    return CalibrationResult(
        machine=m_id, nominal=machine, kind=data.kind,
        names=tuple(cand_names[i] for i in mach_sel),
        units=tuple(dset.units[dset.names.index(cand_names[i])] for i in mach_sel),
        values=theta[:p], std=std[:p],
        setup_names=tuple(model.setup.names[i] for i in setup_sel),
        setup_units=tuple(model.setup.units[i] for i in setup_sel),
        setup_values=setup[setup_sel], setup_std=std[p:], correlation=corr,
        defects=delta, defect_names=dset.names,
        before=residual_stats(model, r_before), after=residual_stats(model, r_after),
        validation=val,
        rank=prep.rank, condition=condition, candidates=len(cand_names),
        unidentifiable=unidentifiable, outliers=outliers, sigma=sig,
        sigma_posterior=float(np.sqrt(factor)) * sig, frame=final_frame,
        iterations=iterations, seconds=time.perf_counter() - t_start,
        residuals=r_after, weights=problem.weights.copy(), singular_values=sv,
        tolerance=problem.scale[:p].copy(), chi2=float(meas @ meas), dof=int(dof),
        residuals_before=r_before, covariance=cov, counts=_counts(prep, unidentifiable),
        condition_with_priors=_condition(jw) if problem.prior else float("nan"),
        **uncertainty)


def _condition(jw: np.ndarray) -> float:
    s = np.linalg.svd(jw, compute_uv=False)
    return float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")


def _undetermined(jw: np.ndarray) -> np.ndarray:
    """``(p,)`` True for the parameters with a component along a direction the data do not
    determine (singular value of the whitened Jacobian below :data:`RCOND` of the largest)."""
    if jw.size == 0:
        return np.zeros(jw.shape[1], dtype=bool)
    return (_null_directions(jw) ** 2).sum(axis=0) > 1e-6


def _null_directions(jw: np.ndarray) -> np.ndarray:
    """``(k, p)`` unit directions (in the scaled unknowns) that ``jw (M, p)`` does not
    determine: right singular vectors of singular values below :data:`RCOND` of the largest,
    and those beyond its rank."""
    p = jw.shape[1]
    if jw.size == 0:
        return np.eye(p)
    # every right singular vector; the left ones are not needed beyond the first p
    _, s, vt = np.linalg.svd(jw, full_matrices=jw.shape[0] < p)
    small = np.ones(p, dtype=bool)
    small[:s.size] = s < RCOND * s[0] if s[0] > 0 else True
    return vt[small]


def _counts(prep, unidentifiable: Mapping[str, str]) -> dict[str, int]:
    """Parameter counts of a calibration (see :class:`CalibrationResult`)."""
    reasons = [r for n, r in unidentifiable.items() if n in set(prep.dset.names)]
    return {"candidates": int(prep.n_candidates), "compatible": len(prep.cand_names),
            "identified": int(prep.mach_sel.size),
            "gauges": sum(r.startswith("gauge") for r in reasons),
            "weak": sum(r.startswith("weakly") for r in reasons),
            "no_effect": sum(r.startswith("no effect") for r in reasons),
            "combinations": sum(r.startswith("a combination") for r in reasons)}


def _tool_uncertainty(machine, data: MeasurementSet, sens: Any, basis: np.ndarray,
                      cov: np.ndarray, null: np.ndarray, rigid_motion_free: Any
                      ) -> dict[str, Any]:
    """Nominal tool points and the k = 2 uncertainty of the identified machine's tool point
    at the measured configurations (:mod:`pkmkit.calibration.uncertainty`): ``cov (p, p)`` the
    machine block of the joint covariance (finite), ``null (k, p)`` undetermined directions
    (SI), ``basis (d, p)`` identified parameters → defect vector, ``rigid_motion_free`` the
    free rigid motions (bool or ``(6,)`` mask), ``sens`` the tool sensitivity of ``machine``
    at ``data.q`` if already computed (the identification's last Jacobian), else None."""
    tl = None if data.tool_length is None else float(np.asarray(data.tool_length).flat[0])
    removed = bool(np.any(rigid_motion_free))
    out = {"tool_points": None, "tool_uncertainty": None,
           "tool_uncertainty_rigid_removed": removed,
           "propagation": Propagation(basis=basis, cov=np.array(cov), null=null,
                                      rigid_motion_free=rigid_motion_free, tool_length=tl)}
    if data.q is None:
        return out
    try:
        if sens is None:
            sens = tool_sensitivity(machine, data.q, tool_length=data.tool_length,
                                    compiled=True)
    except (PkmError, np.linalg.LinAlgError):
        return out
    points = np.asarray(sens.pose)[:, :3]
    u = tool_point_uncertainty(points, sens.point @ basis, cov,
                               rigid_motion_free=rigid_motion_free, null=null)
    return {**out, "tool_points": points, "tool_uncertainty": u}


def _quantity(value: float, unit: str) -> str:
    if unit == "m":
        return f"{value * 1e3:.3g} mm"
    if unit == "rad":
        return f"{np.degrees(value):.3g}°"
    return f"{value:.3g}"


def _frame_option(frame: Any) -> tuple[Registration | None, bool]:
    if frame is None:
        return None, False
    if isinstance(frame, str):
        if frame == "identify":
            return None, True
        raise InputError(f"frame must be None, a Registration or 'identify', got {frame!r}")
    if isinstance(frame, Registration):
        return frame, False
    if isinstance(frame, tuple) and len(frame) == 2 and frame[1] == "identify":
        return frame[0], True
    raise InputError(f"frame must be None, a Registration or 'identify', got {frame!r}")


def sigma_rows(kind: str, machine, sigma: float) -> np.ndarray:
    """``(w,)`` the standard deviation of each component of one observation of ``kind``
    (m; rad for a pose's rotation, scaled with ``sigma`` from :data:`DEFAULT_SIGMA_ROTATION`)
    for a reading noise ``sigma`` (m)."""
    if kind == "pose":
        return np.array([sigma] * 3 + [DEFAULT_SIGMA_ROTATION * sigma / DEFAULT_SIGMA["pose"]] * 3)
    if kind == "part":
        return np.full(machine.n_actuators, sigma)
    return np.array([sigma])


def _setup_label(kind: str, identify_frame: bool) -> str:
    return {"point": "the measurement frame", "pose": "the measurement frame",
            "ballbar": "the pivot positions", "height": "the bed plane",
            "part": "the part placement"}[kind]


def _candidates(dset, parameters) -> list[int]:
    if isinstance(parameters, str):
        if parameters == "auto":
            return list(range(len(dset)))
        parameters = [p.strip() for p in parameters.split(",") if p.strip()]
    out = []
    for name in parameters:
        out.append(dset.index(name))
    if not out:
        raise ParameterError("no parameter to identify")
    return sorted(set(out))


def _compatibility(machine, data: MeasurementSet, tol: np.ndarray,
                   known: Any = None) -> CompatibleDirections:
    """The compatible directions seen at (up to 60 distinct) measured configurations and the
    machine's reference ones; ``known``: the machine's sensitivity at ``data.q`` if already
    computed (its closure rows do not depend on the tool)."""
    _, first = np.unique(np.round(data.q, 12), axis=0, return_index=True)
    rows = np.sort(first)
    if len(rows) > 60:
        rows = rows[np.linspace(0, len(rows) - 1, 60).astype(int)]
    extra = np.array(list(machine.reference_poses().values()), dtype=float)
    if known is not None and known.closure_defect is not None:
        closure = np.concatenate([known.closure_defect[rows], tool_sensitivity(
            machine, extra, compiled=True).closure_defect])
    else:
        closure = tool_sensitivity(machine, np.concatenate([data.q[rows], extra]),
                                   compiled=True).closure_defect
    return compatible_directions(closure, defect_set(machine).names, tol)


def _raise_unassembled(model: ResidualModel, r: np.ndarray, what: str) -> None:
    bad = np.flatnonzero(~np.isfinite(r).all(axis=1))
    if bad.size:
        rows = ", ".join(model.data.labels[i] for i in bad[:10])
        more = f" (and {bad.size - 10} more)" if bad.size > 10 else ""
        raise InputError(f"{what} does not assemble (or cannot reach the measured point) at "
                         f"{rows}{more}")


def _huber_weights(model: ResidualModel, r: np.ndarray) -> np.ndarray:
    e = np.linalg.norm(r / model.sigma, axis=1) / np.sqrt(model.width)
    scale = max(1.4826 * float(np.median(e)), 1e-12)
    z = e / scale
    return np.where(z <= HUBER, 1.0, HUBER / np.maximum(z, 1e-300))


def _outliers(model: ResidualModel, r: np.ndarray, weights: np.ndarray
              ) -> list[tuple[str, float, float]]:
    e = np.linalg.norm(r / model.sigma, axis=1) / np.sqrt(model.width)
    scale = max(1.4826 * float(np.median(e)), 1e-12)
    err = model.errors(r)
    return [(model.data.labels[i], float(err[i]), float(weights[i]))
            for i in np.flatnonzero(e > OUTLIER * scale)]


def _validate(nominal, identified, data: MeasurementSet,
              frames: tuple[Registration | None, Registration | None], sigma: float
              ) -> Validation:
    """Held-out residuals: the instrument frame carries over (the one fitted with each
    machine); an artefact's set-up (part placement, pivots, bed) is refitted for each
    machine."""
    out = []
    for m, frame in zip((nominal, identified), frames, strict=True):
        vm = make_model(nominal, data, sigma_rows(data.kind, nominal, sigma),
                        registration=frame)
        setup = fit_setup(m, vm) if vm.refit_setup_for_validation() else vm.setup.initial
        r, _, _ = vm.residuals(m, setup, jacobian=False)
        _raise_unassembled(vm, r, "the validation set")
        out.append(residual_stats(vm, r))
    return Validation(before=out[0], after=out[1])
