"""An identification that does not converge still gets a verdict.

Readings in the wrong unit or frame, or from another machine, may have no set of plausible
defects that fits them: the least-squares solve then walks the defects away (metres, axes
tilted past 45°) until its iteration limit, or until the machine stops assembling. That is not
a calibration, but it is not a reason to hide what a verdict can say either: the
:class:`~pkmkit.calibration.results.CalibrationResult` built here is the nominal machine with
its set-up fitted alone (nothing identified, ``converged`` False, the reason in
``convergence``); :func:`pkmkit.calibration.calibrate` judges it (its ``convergence`` check
fails) and tries the frame and unit hypotheses on it, and the CLI exits with status 3 and
writes no calibrated machine file.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from pkmkit.calibration.results import CalibrationResult, residual_stats
from pkmkit.geometric_errors.model import defect_set
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.status import Status

#: An identification has diverged once an accepted iterate holds a length defect beyond this
#: many times the machine's size, or a direction component or angle beyond this many rad (a
#: half-turn). Far beyond the verdict's plausibility bounds (5 % of the size, 0.1 rad) on
#: purpose: a fit that settles on absurd defects (readings in another frame: metres) still
#: converges and is judged as such; one that keeps walking them away is stopped.
DIVERGED_SIZE = 10.0
DIVERGED_ANGLE = np.pi


def machine_size(machine) -> float:
    """A machine's size (m): the largest of the distances from the origin to the corners of its
    default region and of that region's diagonal."""
    lo, hi = (np.asarray(v, dtype=float)[:3] for v in machine.default_box())
    return float(max(np.linalg.norm(lo), np.linalg.norm(hi), np.linalg.norm(hi - lo)))


def divergence_bounds(machine, units: Sequence[str]) -> np.ndarray:
    """``(p,)`` the |value| (SI) beyond which identified machine parameters of these units
    (``"m"``, ``"1"``, ``"rad"``) mean a diverged identification (:data:`DIVERGED_SIZE`,
    :data:`DIVERGED_ANGLE`)."""
    size = machine_size(machine)
    return np.array([DIVERGED_SIZE * size if u == "m" else DIVERGED_ANGLE for u in units])


def divergence_message(prep: Any, sol: Any, iterations: int) -> str:
    """Why an identification stopped without converging (one sentence): ``prep`` the prepared
    problem of :mod:`pkmkit.calibration.identify`, ``sol`` the solver's last
    :class:`~pkmkit.calibration.solver.Solution`."""
    model, problem = prep.model, prep.problem
    text = (f"the identification did not converge ({Status(sol.status).label} after "
            f"{iterations} {'evaluations' if sol.r is None else 'iterations'}")
    if sol.r is not None and not np.isfinite(sol.r).all():
        bad = np.flatnonzero(~np.isfinite(sol.r).all(axis=1))
        text += (", the machine being identified no longer assembling at "
                 + ", ".join(model.data.labels[i] for i in bad[:5])
                 + (f" and {bad.size - 5} more" if bad.size > 5 else ""))
    elif sol.u is not None and problem.n_machine and np.isfinite(sol.u).all():
        u = np.abs(sol.u[:problem.n_machine])
        k = int(np.argmax(u))
        name = prep.cand_names[int(prep.mach_sel[k])]
        unit = prep.dset.units[prep.dset.names.index(name)]
        value = sol.u[k] * problem.scale[k]
        text += (f", the defects grown to {u[k]:.3g} times their tolerance: {name} = "
                 + (f"{value * 1e3:.4g} mm" if unit == "m" else
                    f"{np.degrees(value):.3g}°" if unit == "rad" else f"{value:.3g}"))
    return (text + "): the measurements may not come from this machine (another machine, "
            "frame or unit), or its defects are too large for the starting geometry")


def unconverged_result(prep: Any, machine, data: MeasurementSet, message: str,
                       iterations: int, counts: dict[str, int]) -> CalibrationResult:
    """The result of an identification that did not converge (module docstring): ``prep``
    the prepared problem of :mod:`pkmkit.calibration.identify` (its state at the nominal
    machine), ``message`` why, ``counts`` the parameter counts."""
    model = prep.model
    rw0, jw0, _ = prep.start
    meas = rw0[:prep.readings]
    chi2 = float(meas @ meas)
    dof = max(prep.readings - prep.setup_sel.size, 1)  # the set-up alone was fitted
    sv = (np.linalg.svd(jw0[:prep.readings], compute_uv=False) if jw0.size
          else np.zeros(0))
    condition = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
    frame = (model.frame(prep.setup0) if prep.registration is not None or prep.identify_frame
             else None)
    unidentifiable = {**prep.unidentifiable,
                      **{n: f"set-up parameter not identifiable: {r}"
                         for n, r in prep.setup_unid.items()}}
    stats = residual_stats(model, prep.r_before)
    empty = np.zeros(0)
    return CalibrationResult(
        machine=machine, nominal=machine, kind=data.kind, names=(), units=(), values=empty,
        std=empty, setup_names=(), setup_units=(), setup_values=empty, setup_std=empty,
        correlation=np.zeros((0, 0)), defects=np.zeros(len(prep.dset)),
        defect_names=prep.dset.names, before=stats, after=stats, validation=None,
        rank=prep.rank, condition=condition, candidates=len(prep.cand_names),
        unidentifiable=unidentifiable, outliers=[], sigma=prep.sigma,
        sigma_posterior=float(np.sqrt(chi2 / dof)) * prep.sigma, frame=frame,
        iterations=iterations, seconds=time.perf_counter() - prep.t_start,
        residuals=prep.r_before, weights=prep.problem.weights.copy(), singular_values=sv,
        tolerance=empty, chi2=chi2, dof=int(dof), residuals_before=prep.r_before,
        covariance=np.zeros((0, 0)), counts=dict(counts), converged=False,
        convergence=message)


def setup_failure_result(machine, data: MeasurementSet, model: Any, message: str, *,
                         sigma: float, frame: Any, candidates: int,
                         t_start: float) -> CalibrationResult:
    """The result when even the set-up (part placement, pivots, bed plane, frame) cannot be
    fitted on the nominal machine: its residuals at the set-up's initial values, nothing
    identified, the condition of the set-up alone there, ``converged`` False with
    ``message``. ``model`` is the :class:`~pkmkit.calibration.models.ResidualModel`, ``frame``
    the given registration or None."""
    r, _, js = model.residuals(machine, model.setup.initial, jacobian=True)
    w = 1.0 / model.sigma
    meas = (r * w).reshape(-1)
    chi2 = float(meas @ meas) if np.isfinite(meas).all() else float("inf")
    dof = max(meas.size, 1)
    jw = (js * w[:, :, None]).reshape(meas.size, -1)
    sv = (np.linalg.svd(jw, compute_uv=False) if jw.size and np.isfinite(jw).all()
          else np.zeros(0))
    condition = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
    stats = residual_stats(model, r)
    empty = np.zeros(0)
    dset = defect_set(machine)
    return CalibrationResult(
        machine=machine, nominal=machine, kind=data.kind, names=(), units=(), values=empty,
        std=empty, setup_names=(), setup_units=(), setup_values=empty, setup_std=empty,
        correlation=np.zeros((0, 0)), defects=np.zeros(len(dset)),
        defect_names=dset.names, before=stats, after=stats, validation=None, rank=0,
        condition=condition, candidates=candidates, unidentifiable={}, outliers=[],
        sigma=sigma, sigma_posterior=float(np.sqrt(chi2 / dof)) * sigma, frame=frame,
        iterations=0, seconds=time.perf_counter() - t_start, residuals=r,
        weights=np.ones(len(data)), singular_values=sv, tolerance=empty, chi2=chi2,
        dof=int(dof), residuals_before=r, covariance=np.zeros((0, 0)),
        counts={"candidates": int(candidates), "identified": 0}, converged=False,
        convergence=message)
