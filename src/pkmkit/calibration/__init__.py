"""Calibration of parallel kinematic machines: identifiability (from :mod:`pkmkit.errors`),
and — on its own branch — identification from measurements, registration, validation and
compensation."""
