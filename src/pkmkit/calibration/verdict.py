"""The verdict on a calibration: is the identified machine fit to be written and used?

A pure function of numbers (no machine, no files): :func:`judge` takes the whitened residual
sum of squares and its degrees of freedom, the assumed reading noise, the condition of the
identified problem, the identified values with their tolerances and the machine's size, and the
alternative hypotheses a diagnosis has tried (:class:`Alternative`), and returns a
:class:`Verdict` that the text output, the JSON (key ``verdict``) and ``report.html`` all
render.

Checks (each a :class:`Check` with its value, limit and reason):

- **noise** — the a-posteriori noise against the assumed one. With ``χ² = Σ (r_i/σ_i)²`` over
  the readings and ``ν = readings − identified parameters`` degrees of freedom, the
  a-posteriori noise is ``σ̂ = σ √(χ²/ν)`` (tails of the χ² distribution from
  :func:`scipy.special.chdtrc`, the function behind ``scipy.stats.chi2.sf``). The check
  fails when **both** the χ² test rejects the assumed noise (upper tail
  ``P(χ²_ν ≥ χ²) <`` :data:`ALPHA`) **and** ``σ̂/σ >`` :data:`RATIO_MAX`. The χ² test
  alone is too strict for a real machine: with hundreds of readings it rejects a model error
  of 20 % of the noise, which is harmless; the ratio alone is too lax with few readings,
  where a ratio of 2 happens by chance. A σ̂ far *below* the
  assumed σ (lower tail below ALPHA and ratio below 1/RATIO_MAX) is a warning, not a failure:
  the machine is fine, but its uncertainties are overstated and parameters may have been
  dropped as "weakly identifiable" for nothing.
- **condition** — the condition number of the identified problem (whitened, tolerance-scaled
  Jacobian at the solution) must not exceed :data:`CONDITION_MAX` (the reciprocal of the
  selection's rank tolerance): beyond it the parameters are not determined by the data.
- **magnitude** — every identified length defect within :data:`SIZE_FRACTION` of the machine's
  size, every direction component or angle within :data:`ANGLE_MAX` rad. Values beyond
  :data:`TOLERANCE_FACTOR` times their tolerance but within those bounds give a warning.
- **convergence** (only when the identification did not converge,
  :mod:`pkmkit.calibration.divergence`) — always fails: nothing was identified, the other
  checks judge the nominal machine's fit.

When a check fails, the alternatives that *explain* the misfit are the likely causes: an
alternative explains when its own a-posteriori noise passes the noise check, or when it
reduces the RMS residual at least :data:`EXPLAINS` times to an error a machine can have
(below :data:`SIZE_FRACTION` of its size); of those, the ones within :data:`EXPLAINS` times
the best are listed, best first. Without one, the likely cause is a noise level stated too
small or an error source the model lacks (noise check), undetermined parameters (condition
check), implausible readings (magnitude check) or readings no plausible machine fits
(convergence check).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

#: Significance level of the χ² test (one-sided, each tail).
ALPHA = 1e-3
#: Largest tolerated ratio of a-posteriori to assumed noise (model error up to ~1.7 σ).
RATIO_MAX = 2.0
#: Largest tolerated condition number of the identified problem (1 / the selection's rcond).
CONDITION_MAX = 1e7
#: Largest plausible length defect, as a fraction of the machine's size.
SIZE_FRACTION = 0.05
#: Largest plausible direction component or angle defect (rad, ≈ 5.7°).
ANGLE_MAX = 0.1
#: Identified values beyond this many tolerances are flagged (a warning).
TOLERANCE_FACTOR = 20.0
#: An alternative that reduces the RMS residual this many times explains the misfit.
EXPLAINS = 10.0


@dataclass(frozen=True)
class Check:
    """One test of the verdict.

    Attributes:
        name: ``"noise"``, ``"condition"``, ``"magnitude"`` or ``"convergence"``.
        passed: False when the check fails the verdict.
        value, limit: what was measured and its bound (the check's own units: a ratio, a
            condition number, a fraction of the bound).
        reason: one sentence saying what was found.
        warning: a passed check that still deserves attention (e.g. noise overstated).
    """

    name: str
    passed: bool
    value: float
    limit: float
    reason: str
    warning: bool = False

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "passed": self.passed, "warning": self.warning,
                "value": self.value, "limit": self.limit, "reason": self.reason}


@dataclass(frozen=True)
class Alternative:
    """A hypothesis a diagnosis tried, with what it gives.

    Attributes:
        cause: short name (``"frame"``, ``"unit"``, ``"weak-parameters"``).
        description: what the hypothesis is and how the user acts on it (one or two
            sentences, with the option to use).
        rms: RMS error of the observations under the hypothesis (m, SI like ``rms_after``).
        sigma_posterior: its a-posteriori noise (m) when the hypothesis was identified as a
            calibration, else None.
    """

    cause: str
    description: str
    rms: float
    sigma_posterior: float | None = None


@dataclass(frozen=True)
class Cause:
    """A likely cause of a failed verdict (an alternative that explains the misfit, or the
    fallback ``"noise-or-model"``)."""

    cause: str
    message: str

    def to_dict(self) -> dict[str, Any]:
        return {"cause": self.cause, "message": self.message}


@dataclass(frozen=True)
class Verdict:
    """The verdict: checks and, when it fails, the likely causes.

    Attributes:
        checks: every check, in the order noise, condition, magnitude (and convergence when
            the identification did not converge).
        causes: likely causes (empty when the verdict passes).
        chi2, dof, p_value: the χ² statistic, its degrees of freedom and the upper-tail
            probability ``P(χ²_ν ≥ χ²)``.
        sigma, sigma_posterior: assumed and a-posteriori noise (m).
    """

    checks: tuple[Check, ...]
    causes: tuple[Cause, ...] = ()
    chi2: float = float("nan")
    dof: int = 0
    p_value: float = float("nan")
    sigma: float = float("nan")
    sigma_posterior: float = float("nan")
    alternatives: tuple[Alternative, ...] = field(default=(), repr=False)

    @property
    def passed(self) -> bool:
        """True when every check passed."""
        return all(c.passed for c in self.checks)

    @property
    def failed(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)

    @property
    def warnings(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if c.passed and c.warning)

    def headline(self) -> str:
        """One line: ``PASSED`` or ``FAILED`` with the failed checks."""
        if self.passed:
            return "verdict: PASSED" + (" (with warnings)" if self.warnings else "")
        return "verdict: FAILED (" + ", ".join(c.name for c in self.failed) + ")"

    def lines(self) -> list[str]:
        """The verdict as text lines (headline, failed checks and warnings, likely causes)."""
        out = [self.headline()]
        for c in self.checks:
            if not c.passed:
                out.append(f"  ✗ {c.name}: {c.reason}")
            elif c.warning:
                out.append(f"  ! {c.name}: {c.reason}")
        for c in self.causes:
            out.append(f"  likely cause ({c.cause}): {c.message}")
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"passed": self.passed, "checks": [c.to_dict() for c in self.checks],
                "causes": [c.to_dict() for c in self.causes], "chi2": self.chi2,
                "dof": self.dof, "p_value": self.p_value,
                "sigma_ratio": (self.sigma_posterior / self.sigma if self.sigma > 0
                                else float("nan"))}


def noise_check(chi2: float, dof: int, *, alpha: float = ALPHA,
                ratio_max: float = RATIO_MAX, model: str = "identified") -> tuple[Check, float]:
    """The noise check and the upper-tail probability of ``chi2`` with ``dof`` degrees of
    freedom (module docstring); ``model`` names the machine judged (``"identified"``, or
    ``"nominal"`` when nothing was identified)."""
    dof = max(int(dof), 1)
    if not np.isfinite(chi2):
        return Check("noise", False, float("inf"), ratio_max,
                     "the residual is not finite"), 0.0
    ratio = float(np.sqrt(max(chi2, 0.0) / dof))
    from scipy.special import chdtr, chdtrc  # at first use (≈ 0.1 s of imports)

    upper = float(chdtrc(dof, chi2))  # scipy.stats.chi2.sf / .cdf, without its slow import
    lower = float(chdtr(dof, chi2))
    if upper < alpha and ratio > ratio_max:
        return Check("noise", False, ratio, ratio_max,
                     f"a-posteriori noise {ratio:.3g}× the assumed one (χ² = {chi2:.4g} for "
                     f"{dof} degrees of freedom, P = {upper:.2g} < {alpha:g}): the {model} "
                     "model does not explain the readings"), upper
    if lower < alpha and ratio < 1.0 / ratio_max:
        return Check("noise", True, ratio, ratio_max,
                     f"a-posteriori noise {ratio:.3g}× the assumed one: the readings are more "
                     "precise than stated (--sigma); uncertainties are overstated and "
                     "parameters may have been dropped as weakly identifiable for nothing",
                     warning=True), upper
    return Check("noise", True, ratio, ratio_max,
                 f"a-posteriori noise {ratio:.3g}× the assumed one (χ² = {chi2:.4g} for {dof} "
                 f"degrees of freedom)"), upper


def condition_check(condition: float, *, limit: float = CONDITION_MAX) -> Check:
    """The condition check (module docstring)."""
    ok = bool(np.isfinite(condition) and condition <= limit)
    reason = (f"condition {condition:.3g} of the identified problem" +
              ("" if ok else f" beyond {limit:.0e}: the data do not determine the identified "
                             "parameters"))
    return Check("condition", ok, float(condition), limit, reason)


def magnitude_check(names: Sequence[str], values: np.ndarray, units: Sequence[str],
                    tolerances: np.ndarray, machine_size: float, *,
                    fraction: float = SIZE_FRACTION, angle_max: float = ANGLE_MAX,
                    factor: float = TOLERANCE_FACTOR, length_unit: str = "mm") -> Check:
    """Identified values against plausible bounds and their tolerances.

    Args:
        names, units: ``(p,)`` identified parameters and their units (``"m"``, ``"rad"``,
            ``"1"``).
        values, tolerances: ``(p,)`` SI.
        machine_size: the machine's size (m): lengths beyond ``fraction`` of it fail.
        length_unit: unit of the lengths in the reason.
    """
    values = np.asarray(values, dtype=float)
    tolerances = np.asarray(tolerances, dtype=float)
    bound = np.array([fraction * machine_size if u == "m" else angle_max for u in units])
    if values.size == 0:
        return Check("magnitude", True, 0.0, 1.0, "no machine parameter identified")
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = np.abs(values) / bound
    rel = np.where(np.isfinite(rel), rel, np.inf)
    worst = int(np.argmax(rel))
    if rel[worst] > 1.0:
        bad = [names[i] for i in np.flatnonzero(rel > 1.0)]
        return Check("magnitude", False, float(rel[worst]), 1.0,
                     f"{len(bad)} identified value(s) beyond a plausible defect "
                     f"({_show(values[worst], units[worst], length_unit)} for {names[worst]}; "
                     f"bound {_show(bound[worst], units[worst], length_unit)}"
                     + (f" for a machine of {_show(machine_size, 'm', length_unit)}"
                        if units[worst] == "m" else "")
                     + "): " + ", ".join(bad[:8]) + (" …" if len(bad) > 8 else ""))
    with np.errstate(invalid="ignore", divide="ignore"):
        over = np.abs(values) / tolerances
    big = [names[i] for i in np.flatnonzero(over > factor)]
    if big:
        return Check("magnitude", True, float(rel[worst]), 1.0,
                     f"{len(big)} identified value(s) beyond {factor:g}× their tolerance ("
                     + ", ".join(big[:8]) + (" …" if len(big) > 8 else "")
                     + "): check the tolerances (--tolerance) or the machine's nominal "
                     "dimensions", warning=True)
    return Check("magnitude", True, float(rel[worst]), 1.0,
                 "identified values within plausible bounds")


def _show(value: float, unit: str, length_unit: str = "mm") -> str:
    """A value in SI shown in ``length_unit`` (lengths) or degrees (``"rad"``)."""
    from pkmkit.model.parameters import length_scale

    if unit == "m":
        return f"{value / length_scale(length_unit):.4g} {length_unit}"
    if unit == "rad":
        return f"{np.degrees(value):.4g}°"
    return f"{value:.4g}"


def judge(*, chi2: float, dof: int, sigma: float, condition: float, names: Sequence[str],
          values: np.ndarray, units: Sequence[str], tolerances: np.ndarray,
          machine_size: float, rms: float,
          alternatives: Sequence[Alternative] = (), length_unit: str = "mm",
          convergence: str | None = None) -> Verdict:
    """The verdict on a calibration (module docstring).

    Args:
        chi2: ``Σ (r_i/σ_i)²`` over the identification readings (whitened residual).
        dof: readings − identified parameters.
        sigma: the assumed standard deviation of one reading (m).
        condition: of the identified problem.
        names, values, units, tolerances: identified machine parameters (SI).
        machine_size: the machine's size (m).
        rms: RMS error of the observations after identification (m).
        alternatives: hypotheses tried by a diagnosis; those that explain the misfit become
            the likely causes of a failed verdict.
        length_unit: unit of the lengths in the messages.
        convergence: why the identification did not converge (the other arguments then
            describe the nominal machine's fit), or None when it converged.
    """
    noise, p = noise_check(chi2, dof,
                           model="identified" if convergence is None else "nominal")
    checks = (noise, condition_check(condition),
              magnitude_check(names, values, units, tolerances, machine_size,
                              length_unit=length_unit))
    if convergence is not None:
        checks += (Check("convergence", False, float("nan"), float("nan"),
                         f"{convergence}; nothing identified, the other checks judge the "
                         "nominal machine"),)
    sigma_post = sigma * float(np.sqrt(max(chi2, 0.0) / max(int(dof), 1)))
    causes: list[Cause] = []
    if not all(c.passed for c in checks):
        good = [a for a in alternatives if explains(a, rms=rms, sigma=sigma, dof=dof)
                and a.rms <= SIZE_FRACTION * machine_size]
        best = min((a.rms for a in good), default=np.inf)
        for alt in sorted(good, key=lambda a: a.rms):
            if alt.rms <= EXPLAINS * best:  # much worse than the best one: not the cause
                causes.append(Cause(alt.cause, alt.description))
        if not causes and convergence is not None:
            causes.append(Cause(
                "diverged", "no plausible defects fit these readings: check that they come "
                "from this machine, in its frame (--frame) and in the file's unit (--units)"))
        if not causes and not noise.passed:
            causes.append(Cause(
                "noise-or-model",
                f"no simple alternative explains the residual: either the reading noise is "
                f"larger than stated (the residual corresponds to σ ≈ "
                f"{_show(sigma_post, 'm', length_unit)}"
                f", give it with --sigma if that is the instrument's) or the machine has "
                "errors its model lacks (thermal drift, backlash, compliance, outliers: "
                "try --robust)"))
        if not causes and not checks[1].passed:
            causes.append(Cause(
                "undetermined", "these measurements do not determine the identified "
                "parameters: add poses spread over the workspace, or restrict the candidates "
                "(--parameters)"))
        if not causes and not checks[2].passed:
            causes.append(Cause(
                "implausible", "defects this large are not the geometric errors of a built "
                "machine: the readings may come from another machine, frame or unit, or the "
                "nominal dimensions are wrong"))
    return Verdict(checks=checks, causes=tuple(causes), chi2=float(chi2), dof=int(dof),
                   p_value=p, sigma=float(sigma), sigma_posterior=sigma_post,
                   alternatives=tuple(alternatives))


def explains(alt: Alternative, *, rms: float, sigma: float, dof: int) -> bool:
    """Whether an alternative explains a misfit: its own a-posteriori noise passes the noise
    check, or it reduces the RMS residual at least :data:`EXPLAINS` times."""
    if alt.sigma_posterior is not None and np.isfinite(alt.sigma_posterior):
        ratio = alt.sigma_posterior / sigma
        if ratio <= RATIO_MAX:
            return True
    return bool(np.isfinite(alt.rms) and alt.rms * EXPLAINS <= rms)
