"""The polynomial behind the compiled rod-leg velocity kernels' cos(arccos(h)/3)
(:func:`pkmkit.machines.kernels._cos_third` and its C twin in ``native/rod_velocity.c``), in a
module without Numba so that the C twin reads the very numbers the Numba kernel compiles in."""

from __future__ import annotations

import numpy as np


def cos_third_coefficients(degree: int = 12) -> np.ndarray:
    """Monomial coefficients ``(degree + 1,)`` (increasing powers) of the Chebyshev
    interpolant of s ↦ cos(2 arccos(s) / 3) on [0, 1] (smooth there; error 2e-12 at degree
    12)."""
    from numpy.polynomial import Chebyshev, Polynomial

    def target(s: np.ndarray) -> np.ndarray:
        return np.cos(2.0 * np.arccos(np.clip(s, 0.0, 1.0)) / 3.0)

    fit = Chebyshev.interpolate(target, degree, domain=[0.0, 1.0])
    return fit.convert(kind=Polynomial, domain=[0.0, 1.0], window=[0.0, 1.0]).coef


#: The coefficients the kernels use (13 float64, increasing powers).
COEFFICIENTS = np.ascontiguousarray(cos_third_coefficients(), dtype=np.float64)
COEFFICIENTS.setflags(write=False)
