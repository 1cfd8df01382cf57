"""Calibration of a machine's geometry from measurements (seed 002, seed 003; docs/calibration.md).

- :mod:`~pkmkit.model.measurement_set` — a set of measurements of one type, SI;
- :mod:`~pkmkit.calibration.registration` — rigid registration of an instrument frame;
- :mod:`~pkmkit.calibration.simulate` — realistic defects, configurations and noisy readings;
- :mod:`~pkmkit.calibration.models` — residual models of each measurement type with their
  analytic Jacobians (and the set-up parameters: frame, part placement, pivots, bed);
- :mod:`~pkmkit.calibration.identifiability` — compatible subspace of a hyperstatic machine and
  the identifiable parameters (a small interface meant to delegate to ``pkmkit.geometric_errors``'
  identifiability analysis once it exists);
- :mod:`~pkmkit.calibration.identify` — identification, uncertainties, validation;
- :mod:`~pkmkit.calibration.verdict`, :mod:`~pkmkit.calibration.diagnosis` — the verdict on a
  calibration and its likely causes; :func:`calibrate` is the identification with its verdict;
- :mod:`~pkmkit.calibration.controller`, :mod:`~pkmkit.calibration.compensation` — commands of a
  nominal controller and their compensation;
- :mod:`~pkmkit.calibration.studies` — the seed reproductions and the demo's study.

>>> import numpy as np, pkmkit
>>> from pkmkit.calibration import calibrate, random_defects, simulate
>>> m = pkmkit.machine("linear-delta")
>>> rng = np.random.default_rng(0)
>>> true = m.with_defects(random_defects(m, rng))
>>> result = calibrate(m, simulate(true, m, "point", 60, rng))
>>> bool(result.after.rms < 3e-5 < result.before.rms), result.verdict.passed
(True, True)
"""

from pkmkit.calibration.diagnosis import calibrate
from pkmkit.calibration.identify import (
    CalibrationResult,
    check_measurements,
    identification_problem,
)
from pkmkit.calibration.registration import Registration, register_points
from pkmkit.calibration.simulate import default_configurations, random_defects, simulate
from pkmkit.model.measurement_set import KINDS, MeasurementSet

__all__ = [
    "KINDS",
    "CalibrationResult",
    "MeasurementSet",
    "Registration",
    "calibrate",
    "check_measurements",
    "default_configurations",
    "identification_problem",
    "random_defects",
    "register_points",
    "simulate",
]
