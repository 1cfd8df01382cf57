"""Why a calibration failed: cheap alternative hypotheses tried on the measurements, and the
verdict (:mod:`pkmkit.calibration.verdict`) that names the ones that explain the misfit.

Hypotheses (each an :class:`~pkmkit.calibration.verdict.Alternative` with what it gives):

- **frame** (point and pose readings taken without ``frame``): the best rigid motion of the
  measured points onto the nominal machine's tool points (Kabsch, one SVD). If it leaves a
  residual many times smaller than the identification did, the readings are in another frame.
- **unit**: the readings (or the whole file: readings, pivots, commanded paths, tool lengths
  and length actuators; a machined part's readings only) multiplied by 10⁻³, 10³, 10⁻⁶, 10⁶,
  25.4 or 1/25.4, the nominal machine with its set-up fitted alone (for the two factors that
  fit best before the set-up is fitted). The best factor counts only when it fits ten times
  better than readings set to zero (readings shrunk to nothing are fitted by any bed plane);
  if it fits many times better than the readings as read, the file is in another unit.
- **noise stated in another unit's terms** (a passed verdict whose a-posteriori noise is many
  times *below* the assumed one): readings in inches in a millimetre file shrink the errors
  and their noise 25.4 times alike, and a machine fits them "too well". When a unit factor
  brings the ratio back to about 1 and the calibration of the rescaled readings confirms it,
  the verdict fails with a ``unit`` check naming the unit (or a noise stated that many times
  too large).
- **weak parameters**: when parameters were dropped as weakly identifiable (and neither of
  the above explains the misfit), the calibration run again keeping them (``prune=False``,
  the CLI's ``--keep-weak``): if its a-posteriori noise matches the assumed one, the dropped
  parameters explain the residual.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from pkmkit.calibration import identify
from pkmkit.calibration.divergence import machine_size, setup_failure_result
from pkmkit.calibration.results import residual_stats
from pkmkit.calibration.unit_screen import (
    NAMED_UNITS,
    UNIT_FACTORS,
    scaled_readings,
    screen_units,
    unit_guess,
    unit_named,
)
from pkmkit.calibration.verdict import RATIO_MAX, Alternative, Cause, Check, Verdict, judge
from pkmkit.exceptions import IdentificationDivergedError, InputError, PkmError
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.model.parameters import length_scale

__all__ = ["NAMED_UNITS", "UNIT_FACTORS", "calibrate", "judge_calibration"]


def calibrate(machine, data: MeasurementSet, *, file_unit: str | None = None,
              **options: Any):
    """:func:`pkmkit.calibration.identify.calibrate` (same arguments) with its verdict as
    ``result.verdict`` (:func:`judge_calibration`; the weak-parameter hypothesis reruns the
    calibration with ``prune=False`` when it applies). This is
    :func:`pkmkit.calibration.calibrate`. An identification that does not converge is judged
    too (:mod:`pkmkit.calibration.divergence`): the result then has ``converged`` False, the
    nominal machine's fit and a failed verdict naming the likely cause.

    Readings in another unit are checked first (:func:`pkmkit.calibration.unit_screen.\
screen_units`): when the nominal machine does not assemble at most rows as read but does
    rescaled, an :class:`~pkmkit.exceptions.InputError` names the unit; when it misses them
    by more than any built machine errs and a rescale fits them, the identification is skipped
    and the result is the nominal machine's, with a failed verdict naming the unit.

    Args:
        file_unit: the length unit the measurement file was read in (messages of the
            verdict's unit hypothesis), or None.

    Raises:
        InputError: as :func:`pkmkit.calibration.identify.calibrate`, and readings the
            nominal machine cannot reach as read but can in another unit (the message names
            it).
    """
    skipped = _screened(machine, data, file_unit, options)
    if skipped is not None:
        return skipped
    try:
        result = identify.calibrate(machine, data, **options)
    except IdentificationDivergedError as exc:  # judged all the same: never a hidden verdict
        if exc.result is None:
            raise
        result = exc.result
    prune = (options.get("prune", True) and not options.get("prior", False)
             and result.converged)

    def keep_weak():
        return identify.calibrate(machine, data, **{**options, "prune": False,
                                                    "validation": None, "progress": False})

    def rescaled(scaled: MeasurementSet):
        return identify.calibrate(machine, scaled, **{**options, "validation": None,
                                                       "progress": False})

    with identify.single_threaded_blas():
        verdict = judge_calibration(machine, data, result, rerun=keep_weak if prune else None,
                                    file_unit=file_unit, recalibrate=rescaled)
    return replace(result, verdict=verdict)


def _screened(machine, data: MeasurementSet, file_unit: str | None, options: dict):
    """The unit screen before the identification (:func:`calibrate`): None to go on, a
    judged nominal result when the readings are in another unit; raises when the nominal
    machine does not assemble at most rows as read."""
    if options.get("frame") is not None:
        return None  # readings in an instrument frame: the frame's registration first
    sigma = options.get("sigma")
    sigma = identify.DEFAULT_SIGMA[data.kind] if sigma is None else float(sigma)
    if not (np.isfinite(sigma) and sigma > 0):
        return None  # refused with its message by the identification
    identify.check_measurements(machine, data)
    rows = identify.sigma_rows(data.kind, machine, sigma)
    suspect = screen_units(machine, data, rows, file_unit=file_unit)
    if suspect is None:
        return None
    if not np.isfinite(suspect.rms_read):
        raise InputError(f"{data.source}: the nominal machine does not assemble (or cannot "
                         f"reach the measured point) at most rows; {suspect.hint()}")
    from pkmkit.calibration.models import make_model
    from pkmkit.geometric_errors.model import defect_set

    parameters = options.get("parameters", "auto")
    candidates = (len(defect_set(machine)) if isinstance(parameters, str)
                  else len(parameters))
    model = make_model(machine, data, rows, registration=None, identify_frame=False)
    result = setup_failure_result(
        machine, data, model, "identification not run (it cannot converge to a plausible "
        "machine): the nominal machine misses the readings by more than any built machine "
        "errs, and they fit in another unit",
        sigma=sigma, frame=None, candidates=candidates, t_start=time.perf_counter())
    if not result.singular_values.size:  # no set-up parameter: nothing to condition
        result = replace(result, condition=1.0)
    alt = Alternative("unit", suspect.hint(), rms=suspect.rms_scaled)
    return replace(result, verdict=judge_calibration(machine, data, result,
                                                     file_unit=file_unit,
                                                     alternatives=[alt]))


def judge_calibration(machine, data: MeasurementSet, result, *,
                      rerun: Callable[[], Any] | None = None,
                      file_unit: str | None = None,
                      alternatives: list[Alternative] | None = None,
                      recalibrate: Callable[[MeasurementSet], Any] | None = None) -> Verdict:
    """The verdict on ``result`` (a :class:`~pkmkit.calibration.identify.CalibrationResult`
    of ``machine`` from ``data``), with the alternatives of the module docstring tried when it
    fails.

    Args:
        rerun: a callable returning the same calibration with the weak parameters kept, or
            None (the weak-parameter hypothesis is then not tried).
        file_unit: the unit the measurement file was read in (for the unit hypothesis's
            message), or None.
        alternatives: hypotheses already tried (the unit screen's): the others are then
            not tried.
        recalibrate: a callable returning the same calibration of other measurements (the
            readings rescaled), or None (a passed verdict is then not questioned).
    """
    args = dict(chi2=result.chi2, dof=result.dof, sigma=result.sigma,
                condition=(result.condition_with_priors
                           if np.isfinite(result.condition_with_priors) else result.condition),
                names=result.names, values=result.values,
                units=result.units, tolerances=result.tolerance,
                machine_size=machine_size(machine), rms=result.after.rms,
                length_unit=file_unit or "m",
                convergence=None if result.converged else result.convergence)
    first = judge(**args)
    if first.passed:
        return _noise_in_another_unit(data, result, first, recalibrate, file_unit)
    if alternatives is not None:
        return judge(**args, alternatives=alternatives)
    alternatives = []
    for test in (_frame_alternative, _unit_alternative):
        try:
            alt = test(machine, data, result, file_unit)
        except (PkmError, np.linalg.LinAlgError, ValueError):
            alt = None
        if alt is not None:
            alternatives.append(alt)
    cheap = judge(**args, alternatives=alternatives)
    explained = any(c.cause in ("frame", "unit") for c in cheap.causes)
    if rerun is not None and not explained and not first.checks[0].passed and any(
            r.startswith("weakly identifiable") for r in result.unidentifiable.values()):
        alt = _weak_alternative(result, rerun, file_unit or "m")
        if alt is not None:
            alternatives.append(alt)
    return judge(**args, alternatives=alternatives)


def _noise_in_another_unit(data: MeasurementSet, result, verdict: Verdict,
                           recalibrate: Callable[[MeasurementSet], Any] | None,
                           file_unit: str | None) -> Verdict:
    """A passed ``verdict`` whose a-posteriori noise is far below the assumed one, questioned
    (module docstring): failed with a ``unit`` check when a unit factor f > 1 brings the noise
    ratio within [1/RATIO_MAX, RATIO_MAX] and the calibration of the readings rescaled by f
    (``recalibrate``) converges with a noise ratio in that range too."""
    noise = verdict.checks[0]
    ratio = noise.value
    if recalibrate is None or not (noise.warning and 0 < ratio < 1.0 / RATIO_MAX):
        return verdict
    for factor in sorted(f for f in UNIT_FACTORS if f > 1.0):
        if not 1.0 / RATIO_MAX <= ratio * factor <= RATIO_MAX:
            continue
        try:
            alt = recalibrate(scaled_readings(data, factor))
        except PkmError:
            continue
        alt_ratio = alt.sigma_posterior / alt.sigma
        if not (alt.converged and 1.0 / RATIO_MAX <= alt_ratio <= RATIO_MAX):
            continue
        unit = file_unit or "m"
        message = (f"wrong unit: {unit_guess(factor, unit)}: as read, the a-posteriori "
                   f"noise is {ratio:.3g}× the assumed one; "
                   f"rescaled ×{factor:g} the calibration gives {alt_ratio:.3g}× (RMS "
                   f"{alt.after.rms / length_scale(unit):.4g} {unit}). Fix the file's "
                   "'# units:' line or give --units (or, if the file is right, the stated "
                   f"noise is {factor:.4g}× too large: give the instrument's σ with --sigma)")
        check = Check("unit", False, factor, 1.0,
                      f"a-posteriori noise {ratio:.3g}× the assumed one, about 1/{factor:.4g}: "
                      f"the readings rescaled ×{factor:g} give {alt_ratio:.3g}×")
        return replace(verdict, checks=(*verdict.checks, check),
                       causes=(Cause("unit", message),))
    return verdict


def _frame_alternative(machine, data, result, file_unit) -> Alternative | None:
    from pkmkit.calibration.registration import register_points
    from pkmkit.spatial.rotation import matrix_to_rotvec

    if data.kind not in ("point", "pose") or result.frame is not None:
        return None
    if result.residuals_before is None:
        return None
    measured = data.values[:, :3]
    predicted = measured + result.residuals_before[:, :3]
    if not np.isfinite(predicted).all() or len(measured) < 3:
        return None
    reg = register_points(measured, predicted)
    angle = float(np.degrees(np.linalg.norm(matrix_to_rotvec(reg.rotation))))
    unit = file_unit or "m"
    s = length_scale(unit)
    return Alternative(
        "frame",
        f"the readings look like they are in another frame: a rigid motion alone (rotation "
        f"{angle:.3g}°, translation {np.linalg.norm(reg.translation) / s:.4g} {unit}) brings "
        f"them to RMS {reg.rms / s:.4g} {unit} of the nominal machine, against "
        f"{result.after.rms / s:.4g} {unit} {_after(result)}. Register the frame "
        "(pkmkit register) and calibrate with --frame FILE --identify-frame, or use "
        "--frame identify when the frames are close",
        rms=reg.rms)


def _scaled(data: MeasurementSet, machine, factor: float, whole_file: bool) -> MeasurementSet:
    values = data.values.copy()
    values[:, :3 if data.kind in ("point", "pose", "part") else 1] *= factor
    if not whole_file:
        return replace(data, values=values)
    q = data.q
    if q is not None:
        q = np.where(machine.angular_actuators[None, :], q, q * factor)

    def times(a):
        return None if a is None else a * factor

    return replace(data, values=values, q=q, pivot=times(data.pivot),
                   tool_length=times(data.tool_length), commanded=times(data.commanded))


def _unit_alternative(machine, data, result, file_unit) -> Alternative | None:
    from pkmkit.calibration.models import make_model

    identify_frame = bool(result.frame is not None and data.kind in ("point", "pose"))

    def model_of(factor: float, whole: bool):
        scaled = _scaled(data, machine, factor, whole)
        if whole:
            identify.check_measurements(machine, scaled)
        return make_model(machine, scaled, identify.sigma_rows(data.kind, machine,
                                                                result.sigma),
                          registration=None, identify_frame=identify_frame)

    def rms_of(model, setup) -> float:
        r, _, _ = model.residuals(machine, setup, jacobian=False)
        return residual_stats(model, r).rms if np.isfinite(r).all() else np.inf

    # a machined part's commanded paths are the program's, sampled at a fixed step: scaled
    # they would be sampled a million times finer; only its readings are tried
    modes = (False,) if data.kind == "part" else (False, True)
    screened = []
    for factor in UNIT_FACTORS:
        for whole in modes:
            try:
                model = model_of(factor, whole)
                screened.append((rms_of(model, model.setup.initial), factor, whole, model))
            except (PkmError, np.linalg.LinAlgError, ValueError):
                continue
    # the set-up fitted for the two most promising factors only, and for readings set to zero:
    # readings shrunk to nothing are "fitted" by any bed plane, so a rescale must fit them
    # many times better than zeros do
    best = None
    for rms0, factor, whole, model in sorted(screened, key=lambda t: t[0])[:2]:
        if not np.isfinite(rms0):
            continue
        try:
            rms = rms_of(model, identify.fit_setup(machine, model))
        except (PkmError, np.linalg.LinAlgError, ValueError):
            continue
        if best is None or rms < best[0]:
            best = (rms, factor, whole)
    if best is None:
        return None
    try:
        zero = model_of(0.0, False)
        rms_zero = rms_of(zero, identify.fit_setup(machine, zero))
    except (PkmError, np.linalg.LinAlgError, ValueError):
        rms_zero = np.inf
    if not best[0] * 10.0 <= rms_zero:
        return None
    if best is None:
        return None
    rms, factor, whole = best
    unit = file_unit or "m"
    true_unit = unit_named(length_scale(unit) * factor)
    what = "the file" if whole else "the readings"
    guess = (f"{what} look like they are in {true_unit}, not {unit}" if true_unit else
             f"{what} fit when multiplied by {factor:g}")
    fix = ("fix the file's '# units:' line or give --units" if whole else
           "convert the reading column(s) to the file's unit")
    s = length_scale(unit)
    return Alternative(
        "unit",
        f"wrong unit: {guess} — rescaled ×{factor:g}, the nominal machine fits them to RMS "
        f"{rms / s:.4g} {unit} against {result.after.rms / s:.4g} {unit} {_after(result)} "
        f"as read; {fix}",
        rms=rms)


def _after(result) -> str:
    """What the result's residual is: after identification, or the nominal machine's."""
    return ("after identification" if result.converged else
            "with the nominal machine (the identification did not converge)")


def _weak_alternative(result, rerun, unit: str) -> Alternative | None:
    weak = [n for n, r in result.unidentifiable.items() if r.startswith("weakly identifiable")]
    try:
        alt = rerun()
    except PkmError:
        return None
    ratio = alt.sigma_posterior / result.sigma
    more = ("; the readings are also more precise than the stated noise: give the "
            "instrument's σ with --sigma" if ratio < 0.5 else "")
    return Alternative(
        "weak-parameters",
        f"{len(weak)} parameter(s) dropped as weakly identifiable with the stated noise ("
        + ", ".join(weak[:10]) + (" …" if len(weak) > 10 else "")
        + f") explain the residual: identifying them (--keep-weak) gives RMS "
        f"{alt.after.rms / length_scale(unit):.4g} {unit} and an a-posteriori noise "
        f"{ratio:.3g}× the assumed one"
        + more,
        rms=alt.after.rms, sigma_posterior=alt.sigma_posterior)
