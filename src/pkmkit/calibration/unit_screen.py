"""A magnitude check of measurements before the identification (issue 18 §5): readings in
another length unit than the file says are named before any expensive solve.

The nominal machine's residual at the set-up's initial values is computed for the readings as
read and rescaled by each factor of :data:`~pkmkit.calibration.diagnosis.UNIT_FACTORS`
(25.4, 1/25.4, 10³, 10⁻³, 10⁶, 10⁻⁶: inches, millimetres, micrometres read as another unit).
The readings are **implausible as read** when the nominal machine does not assemble at most
rows, or its RMS error exceeds :data:`~pkmkit.calibration.verdict.SIZE_FRACTION` of the
machine's size (no built machine errs by that much). A factor **names the unit** when, with it,
every row assembles, the RMS error is within that bound, at least
:data:`~pkmkit.calibration.verdict.EXPLAINS` times smaller than as read, and that many times
smaller than with the readings set to zero (shrunk readings are "fitted" by any bed plane or
pivot). Only the reading columns are rescaled (a whole file in another unit moves the actuator
values out of their strokes, which :func:`~pkmkit.calibration.identify.check_measurements`
already refuses with the rows).

Cost: one residual evaluation per factor (no set-up fit, no identification), a fraction of a
second where the identification of a 60-row machined part in inches read as mm took 20–100 s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pkmkit.calibration.divergence import machine_size
from pkmkit.calibration.results import residual_stats
from pkmkit.calibration.verdict import EXPLAINS, SIZE_FRACTION
from pkmkit.exceptions import PkmError
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.model.parameters import LENGTH_UNITS, length_scale

#: Unit factors tried (true SI value = read SI value × factor).
UNIT_FACTORS = (1e-3, 1e3, 1e-6, 1e6, 0.0254 / 1e-3, 1e-3 / 0.0254)
#: Units named in the messages (metres per unit).
NAMED_UNITS = {**LENGTH_UNITS, "µm": 1e-6, "km": 1e3}


@dataclass(frozen=True)
class UnitSuspicion:
    """Readings that look like they are in another unit.

    Attributes:
        factor: the factor that makes them plausible (true = read × factor).
        rms_read: RMS error of the nominal machine on the readings as read (m; inf when it
            does not assemble at most rows).
        rms_scaled: the same with the readings rescaled (m).
        assembled_read: share of rows where the nominal machine assembles as read.
        file_unit: the unit the file was read in.
    """

    factor: float
    rms_read: float
    rms_scaled: float
    assembled_read: float
    file_unit: str

    def hint(self) -> str:
        """One sentence naming the likely unit error and how to fix it."""
        unit = self.file_unit
        s = length_scale(unit)
        read = (f"the nominal machine assembles at only {self.assembled_read:.0%} of the rows"
                if not np.isfinite(self.rms_read) else
                f"the nominal machine misses them by RMS {self.rms_read / s:.4g} {unit}")
        return (f"wrong unit: {unit_guess(self.factor, unit)}: {read}; rescaled "
                f"×{self.factor:g} it fits them to RMS {self.rms_scaled / s:.4g} {unit}. "
                "Fix the file's '# units:' line or give --units (or convert the reading "
                "columns)")


def unit_guess(factor: float, unit: str) -> str:
    """What readings needing ``factor`` (true = read × factor) in a file of ``unit`` look
    like: ``"the readings look like they are in in, not mm (25.4× too small)"``."""
    size = f"{1 / factor:.4g}× too large" if factor < 1 else f"{factor:.4g}× too small"
    true = unit_named(length_scale(unit) * factor)
    if true:
        return f"the readings look like they are in {true}, not {unit} ({size})"
    mixed = np.isclose(max(factor, 1 / factor), 25.4)
    return (f"the readings look {size} ("
            + ("inches and millimetres mixed up?" if mixed else "another unit?") + ")")


def unit_named(scale: float) -> str | None:
    """The name of the length unit of ``scale`` metres (``"in"``, ``"mm"``…), or None."""
    for name, value in NAMED_UNITS.items():
        if np.isclose(value, scale, rtol=1e-9):
            return name
    return None


def scaled_readings(data: MeasurementSet, factor: float) -> MeasurementSet:
    """``data`` with its reading columns multiplied by ``factor`` (positions of point, pose
    and part readings; a ball-bar length; a probed height)."""
    values = data.values.copy()
    values[:, :3 if data.kind in ("point", "pose", "part") else 1] *= factor
    return replace(data, values=values)


def screen_units(machine, data: MeasurementSet, sigma_rows: np.ndarray, *,
                 file_unit: str | None = None) -> UnitSuspicion | None:
    """The module's check on ``data`` (readings in the machine frame, nominal ``machine``):
    a :class:`UnitSuspicion` when the readings are implausible as read and one factor makes
    them plausible, else None.

    Args:
        sigma_rows: the per-row reading noise of the residual model
            (:func:`pkmkit.calibration.identify.sigma_rows`).
        file_unit: the unit the file was read in (messages), default ``"m"``.
    """
    from pkmkit.calibration.models import make_model

    bound = SIZE_FRACTION * machine_size(machine)

    def evaluate(factor: float | None) -> tuple[float, float]:
        """(RMS over the assembled rows, share of rows assembled) at the initial set-up."""
        d = data if factor is None else scaled_readings(data, factor)
        try:
            model = make_model(machine, d, sigma_rows, registration=None,
                               identify_frame=False)
            with np.errstate(all="ignore"):
                r, _, _ = model.residuals(machine, model.setup.initial, jacobian=False)
        except (PkmError, np.linalg.LinAlgError, ValueError):
            return np.inf, 0.0
        ok = np.isfinite(r).all(axis=1)
        if not ok.any():
            return np.inf, 0.0
        with np.errstate(all="ignore"):
            errors = residual_stats(model, r).per_pose[ok]
        return float(np.sqrt(np.mean(errors**2))), float(ok.mean())

    rms_read, share = evaluate(None)
    if share >= 0.5 and rms_read <= bound:
        return None  # plausible as read: the identification and its verdict judge it
    best = None
    for factor in UNIT_FACTORS:
        rms, ok = evaluate(factor)
        if ok == 1.0 and rms <= bound and (best is None or rms < best[0]):
            best = (rms, factor)
    if best is None:
        return None
    rms_best, factor = best
    if share >= 0.5 and not rms_best * EXPLAINS <= rms_read:
        return None
    rms_zero, _ = evaluate(0.0)
    if not rms_best * EXPLAINS <= rms_zero:
        return None
    return UnitSuspicion(factor=factor, rms_read=rms_read if share >= 0.5 else np.inf,
                         rms_scaled=rms_best, assembled_read=share,
                         file_unit=file_unit or "m")
