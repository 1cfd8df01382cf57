"""The largest square in a disc of radius ρ has side √2 ρ and its centre at the disc's (worked
out by hand: its corners on the circle) for discs down to 10 nm, from several starts (issue 18
§9, plausible bugs: a finite-difference step of 10⁻⁷ in absolute metres instead of relative
to the box passed the tests from 1 µm up, and at 0.1 µm gave a square 11 % too large, outside
the disc)."""

import math

import numpy as np
import pytest

from pkmkit.analysis.inscribed import largest_box


@pytest.mark.parametrize("rho", [1e-7, 1e-8])
@pytest.mark.parametrize("start, half", [((0.3, 0.2), 0.1), ((0.0, 0.0), 0.05),
                                         ((-0.5, 0.1), 0.02)])
def test_largest_square_in_a_sub_micrometre_disc(rho, start, half):
    center, h = largest_box(lambda p: 1 - np.hypot(p[:, 0], p[:, 1]) / rho,
                            lambda c, hh, u: c + hh * u, rho * np.array(start), half * rho,
                            np.full(2, -2.0 * rho), np.full(2, 2.0 * rho), samples=21)
    assert 2 * h == pytest.approx(math.sqrt(2.0) * rho, rel=1e-5)
    np.testing.assert_allclose(center, 0.0, atol=1e-5 * rho)
