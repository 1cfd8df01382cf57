"""The linear Delta's search of the slide offset d (``linear_delta._Search.best_d``, the inner
step of ``size_linear_delta``'s "size" objective) is the same at every scale: the kinematics
of a linear Delta scaled by s are those of the original scaled by s (its transmission factors
are ratios of lengths), so for the cube, nacelle and arms scaled by s the best d is s times
the original's, as far as the bounded search's tolerance, relative to the arm length, allows.
The sizing itself (a full verification) is checked at two scales by the ``ci`` test
``tests/design/test_sizing_scale.py``; this is its cheap core (about 30 margins on a 3³ grid
per search)."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from pkmkit.design.linear_delta import _Search
from pkmkit.design.metrics import Region
from pkmkit.machines.registry import machine as builtin_machine

BOUNDS = (0.4, 2.5)


@cache
def _best_d(scale: float) -> tuple[float, float]:
    side, length = 0.5 * scale, 1.1 * scale
    search = _Search(builtin_machine("linear-delta"), Region(side, (0.0, 0.0, 0.5 * side)),
                     0.15 * scale, BOUNDS, 3)
    return search.best_d(length)


@pytest.mark.parametrize("scale", [1e-4, 1e3])
def test_best_offset_scales_with_the_machine(scale):
    d_one, margin_one = _best_d(1.0)
    d, margin = _best_d(scale)
    assert 0.0 < d_one < 1.1  # within the search's bracket (1e-3 L, L)
    np.testing.assert_allclose(d / scale, d_one, rtol=1e-5)
    np.testing.assert_allclose(margin, margin_one, rtol=1e-6, atol=1e-9)
