"""The result of a calibration: residual statistics, validation, identified values with their
uncertainties and correlations (:class:`CalibrationResult`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.calibration.registration import Registration
from pkmkit.exceptions import ParameterError


@dataclass(frozen=True)
class ResidualStats:
    """Error magnitudes of N observations (SI): ``per_pose (N,)``, with their mean, RMS, max."""

    per_pose: np.ndarray
    labels: tuple[str, ...]

    @property
    def mean(self) -> float:
        return float(np.mean(self.per_pose)) if self.per_pose.size else float("nan")

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.per_pose**2))) if self.per_pose.size else float("nan")

    @property
    def max(self) -> float:
        return float(np.max(self.per_pose)) if self.per_pose.size else float("nan")

    def to_dict(self, scale: float = 1.0) -> dict[str, Any]:
        return {"mean": self.mean / scale, "rms": self.rms / scale, "max": self.max / scale}


def residual_stats(model: Any, r: np.ndarray) -> ResidualStats:
    """The error magnitudes of a residual model's observations
    (:class:`~pkmkit.calibration.models.ResidualModel`) from its residual rows ``r (N, w)``
    (SI), labelled by the measurement file's rows."""
    return ResidualStats(model.errors(r), tuple(model.data.labels))


@dataclass(frozen=True)
class Validation:
    """Residuals of a held-out set before (nominal machine) and after (identified machine)."""

    before: ResidualStats
    after: ResidualStats


@dataclass(frozen=True)
class CalibrationResult:
    """Outcome of :func:`calibrate` (SI units; see :meth:`to_json` for output units).

    Attributes:
        machine: the identified machine (nominal with :attr:`defects` applied).
        nominal: the machine calibrated.
        kind: measurement type.
        names, units, values, std: the identified machine parameters (defect names).
        setup_names, setup_units, setup_values, setup_std: the identified set-up parameters.
        correlation: ``(p + s, p + s)`` correlations of every identified parameter (machine
            first, then set-up).
        defects: ``(d,)`` the identified machine's full defect vector (dependent defects of a
            hyperstatic machine follow their free ones; unidentified ones 0).
        defect_names: ``(d,)``.
        before, after: residuals of the identification set with the nominal and identified
            machines (set-up fitted in both).
        validation: held-out residuals, or None.
        rank, condition: of the identified problem (whitened, tolerance-scaled Jacobian).
        candidates: number of candidate machine parameters.
        unidentifiable: name → why it was left at its nominal value.
        outliers: ``(label, error (m), weight)`` of the observations the robust loss
            down-weighted beyond :data:`OUTLIER` robust standard deviations.
        sigma, sigma_posterior: the a-priori standard deviation of a reading and the
            a-posteriori one (RMS of the normalised residuals × sigma).
        frame: the measurement-to-machine transform (identified or given), or None.
        iterations, seconds: solver iterations (all robust rounds) and wall time.
        residuals: ``(N, w)`` final residual rows (SI) of the identification set.
        weights: ``(N,)`` final robust weights (ones without ``robust``).
        singular_values: of the identified problem's whitened, tolerance-scaled Jacobian
            (measurement rows; the identifiability spectrum).
        tolerance: ``(p,)`` the tolerances (scales, priors) of the identified parameters.
        chi2, dof: ``Σ (r_i/σ_i)²`` over the identification readings (robust weights
            applied) and its degrees of freedom (readings − identified parameters).
        residuals_before: ``(N, w)`` residual rows (SI) of the nominal machine, set-up fitted.
        covariance: ``(p + s, p + s)`` covariance of the identified parameters (SI; machine
            first, then set-up; ``inf`` on the diagonal of undetermined ones).
        tool_points: ``(N, 3)`` nominal tool point at each measured configuration (m), or None
            (machined parts).
        tool_uncertainty: ``(N,)`` expanded uncertainty (k = 2) of the identified machine's
            tool point at each measured configuration, the joint covariance of the machine
            and set-up parameters propagated (:mod:`pkmkit.calibration.uncertainty`): twice
            the largest standard deviation over directions (m), or None.
        tool_uncertainty_rigid_removed: whether that uncertainty is taken with the free rigid
            motion of the whole machine removed (the set-up absorbs it: identified frame,
            pivots, bed plane).
        propagation: a :class:`~pkmkit.calibration.uncertainty.Propagation` (what maps the
            uncertainty elsewhere: :meth:`workspace_uncertainty`), or None.
        counts: parameter counts: ``candidates``, ``compatible``, ``identified``, ``gauges``,
            ``weak``, ``no_effect``, ``combinations``.
        verdict: the :class:`~pkmkit.calibration.verdict.Verdict` (set by
            :func:`pkmkit.calibration.calibrate`, the judged call; None from this module's).
        condition_with_priors: with ``prior=True``, the condition of the problem with its
            prior rows (what determines the parameters; :attr:`condition` is that of the
            measurement rows alone), else NaN.
        converged: False when the identification did not converge: nothing is identified,
            :attr:`machine` is the nominal machine and :attr:`after` its residuals (set-up
            fitted), :attr:`condition` that of the problem at the nominal machine; such a
            result is never written as a calibrated machine file.
        convergence: why it did not converge (one sentence), else "".
    """

    machine: Any
    nominal: Any
    kind: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    values: np.ndarray
    std: np.ndarray
    setup_names: tuple[str, ...]
    setup_units: tuple[str, ...]
    setup_values: np.ndarray
    setup_std: np.ndarray
    correlation: np.ndarray
    defects: np.ndarray
    defect_names: tuple[str, ...]
    before: ResidualStats
    after: ResidualStats
    validation: Validation | None
    rank: int
    condition: float
    candidates: int
    unidentifiable: dict[str, str]
    outliers: list[tuple[str, float, float]]
    sigma: float
    sigma_posterior: float
    frame: Registration | None
    iterations: int
    seconds: float
    residuals: np.ndarray = field(repr=False, default=None)
    weights: np.ndarray = field(repr=False, default=None)
    singular_values: np.ndarray = field(repr=False, default=None)
    tolerance: np.ndarray = field(repr=False, default=None)
    chi2: float = float("nan")
    dof: int = 0
    residuals_before: np.ndarray = field(repr=False, default=None)
    covariance: np.ndarray = field(repr=False, default=None)
    tool_points: np.ndarray = field(repr=False, default=None)
    tool_uncertainty: np.ndarray = field(repr=False, default=None)
    tool_uncertainty_rigid_removed: bool = False
    propagation: Any = field(repr=False, default=None)
    counts: dict = field(default_factory=dict)
    verdict: Any = None
    condition_with_priors: float = float("nan")
    converged: bool = True
    convergence: str = ""

    def value(self, name: str) -> float:
        """An identified machine or set-up parameter by name (SI)."""
        if name in self.names:
            return float(self.values[self.names.index(name)])
        if name in self.setup_names:
            return float(self.setup_values[self.setup_names.index(name)])
        raise ParameterError(f"{name!r} was not identified", name)

    def workspace_uncertainty(self, n: int | None = None, seed: int = 0
                              ) -> dict[str, Any] | None:
        """The identified machine's tool-point uncertainty (k = 2) over its workspace:
        :func:`pkmkit.calibration.uncertainty.over_workspace` (``n`` configurations, default
        :data:`~pkmkit.calibration.uncertainty.WORKSPACE_SAMPLE`), or None."""
        from pkmkit.calibration.uncertainty import WORKSPACE_SAMPLE, over_workspace

        if self.propagation is None:
            return None
        return over_workspace(self.machine, self.propagation, n=n or WORKSPACE_SAMPLE,
                              seed=seed)

    def to_json(self, units: str = "m") -> dict[str, Any]:
        """JSON-ready summary: lengths in ``units``, ``"rad"`` parameters in degrees,
        direction components dimensionless (≈ rad)."""
        from pkmkit.model.parameters import length_scale

        scale = length_scale(units)

        def conv(v, u):
            return v / scale if u == "m" else (float(np.degrees(v)) if u == "rad" else v)

        def unit_label(u):
            return units if u == "m" else ("deg" if u == "rad" else "1")

        params = {n: conv(float(v), u) for n, v, u in zip(self.names, self.values, self.units,
                                                          strict=True)}
        std = {n: conv(float(v), u) for n, v, u in zip(self.names, self.std, self.units,
                                                       strict=True)}
        setup = {n: conv(float(v), u) for n, v, u in zip(self.setup_names, self.setup_values,
                                                         self.setup_units, strict=True)}
        setup_std = {n: conv(float(v), u) for n, v, u in zip(
            self.setup_names, self.setup_std, self.setup_units, strict=True)}
        out = {
            "machine": self.nominal.id,
            "measure": self.kind,
            "units": units,
            "parameters": params,
            "std": std,
            "parameter_units": {n: unit_label(u) for n, u in zip(self.names, self.units,
                                                                  strict=True)},
            "setup": setup,
            "setup_std": setup_std,
            "rms_before": self.before.rms / scale,
            "rms_after": self.after.rms / scale,
            "mean_before": self.before.mean / scale,
            "mean_after": self.after.mean / scale,
            "max_before": self.before.max / scale,
            "max_after": self.after.max / scale,
            "validation": None if self.validation is None else {
                "poses": int(self.validation.after.per_pose.size),
                "before": self.validation.before.to_dict(scale),
                "after": self.validation.after.to_dict(scale),
                "rms_before": self.validation.before.rms / scale,
                "rms_after": self.validation.after.rms / scale,
                "max_before": self.validation.before.max / scale,
                "max_after": self.validation.after.max / scale},
            "rank": self.rank,
            "condition": self.condition,
            "candidates": self.candidates,
            "unidentifiable": dict(self.unidentifiable),
            "outliers": [{"row": lab, "error": err / scale, "weight": w}
                         for lab, err, w in self.outliers],
            "sigma": self.sigma / scale,
            "sigma_posterior": self.sigma_posterior / scale,
            "poses": int(self.after.per_pose.size),
            "iterations": self.iterations,
            "seconds": self.seconds,
            "correlation_max": _max_correlation(self.correlation, self.names + self.setup_names),
            "correlation": {"names": list(self.names + self.setup_names),
                            "matrix": np.round(self.correlation, 6).tolist()},
            "verdict": None if self.verdict is None else self.verdict.to_dict(),
            "converged": self.converged,
            "counts": dict(self.counts),
            "tool_uncertainty_k2": _tool_uncertainty_json(self, scale),
            "chi2": self.chi2,
            "dof": self.dof,
            "residuals": {"rows": list(self.after.labels),
                          "before": (self.before.per_pose / scale).tolist(),
                          "after": (self.after.per_pose / scale).tolist()},
        }
        if self.frame is not None:
            out["frame"] = {k: v for k, v in self.frame.to_dict(scale).items()
                            if not k.startswith("point") and k not in ("rms", "max")
                            and not k.startswith("direction")}
        return out


def _tool_uncertainty_json(result: CalibrationResult, scale: float) -> dict[str, Any] | None:
    """RMS and max of the tool-point uncertainty (k = 2) over the measured configurations in
    the output unit, and whether the free rigid motion is removed."""
    u = result.tool_uncertainty
    if u is None or not np.size(u):
        return None
    u = np.asarray(u, dtype=float) / scale
    return {"rms": float(np.sqrt(np.mean(u**2))), "max": float(np.max(u)),
            "rigid_motion_removed": bool(result.tool_uncertainty_rigid_removed)}


def _max_correlation(corr: np.ndarray, names: Sequence[str]) -> dict[str, Any] | None:
    if corr.shape[0] < 2:
        return None
    c = np.abs(np.nan_to_num(corr, nan=0.0))
    np.fill_diagonal(c, -1.0)  # a parameter against itself is not a correlation
    i, j = np.unravel_index(int(np.argmax(c)), c.shape)
    return {"pair": [names[i], names[j]], "value": float(corr[i, j])}
