"""The refinement of the largest box is invariant under a similarity: the largest square in a
disc of radius ρ has side √2 ρ (worked out by hand: its corners on the circle), found from the
same relative start whatever ρ — a disc of 1 mm as of 1 km."""

import math

import numpy as np
import pytest

from pkmkit.analysis.inscribed import largest_box


@pytest.mark.parametrize("rho", [1e-6, 1e-3, 1.0, 1e3])
def test_largest_square_in_a_disc_of_any_size(rho):
    center, half = largest_box(lambda p: 1 - np.hypot(p[:, 0], p[:, 1]) / rho,
                               lambda c, h, u: c + h * u, rho * np.array([0.3, 0.2]),
                               0.1 * rho, np.full(2, -2.0 * rho), np.full(2, 2.0 * rho),
                               samples=21)
    assert 2 * half == pytest.approx(math.sqrt(2.0) * rho, rel=1e-5)
    np.testing.assert_allclose(center, 0.0, atol=1e-5 * rho)
