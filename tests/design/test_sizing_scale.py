"""Dimensional synthesis is invariant under a similarity: transmission factors are
dimensionless, so the linear Delta sized for a cube s times smaller is the same machine s times
smaller (arms, slide offset, strokes). Checked from the seed's 0.5 m cube down to a 0.5 mm cube
(a micro-positioning stage), where a search range written in metres instead of in arm lengths
would no longer contain the answer."""

import numpy as np
import pytest

from pkmkit.design.linear_delta import size_linear_delta


@pytest.mark.ci
def test_linear_delta_sized_for_a_cube_a_thousand_times_smaller_is_a_thousand_times_smaller():
    big = size_linear_delta(0.5, (0.4, 1.2), samples=9, search_samples=5)
    small = size_linear_delta(0.5e-3, (0.4, 1.2), samples=9, search_samples=5)
    for name in ("L", "d", "R", "r", "stroke"):
        np.testing.assert_allclose(getattr(small, name), 1e-3 * getattr(big, name), rtol=1e-9,
                                   err_msg=name)
    np.testing.assert_allclose(small.q_min, 1e-3 * big.q_min, rtol=1e-9)
    np.testing.assert_allclose(small.q_max, 1e-3 * big.q_max, rtol=1e-9)
    np.testing.assert_allclose(small.index_range, big.index_range, rtol=1e-9)
    np.testing.assert_allclose(small.compactness, big.compactness, rtol=1e-9)


@pytest.mark.ci
def test_most_compact_linear_delta_for_a_cube_1000_times_smaller_is_1000_times_smaller():
    kw = {"objective": "compactness", "samples": 9, "search_samples": 5}
    big = size_linear_delta(0.5, (0.4, 1.2), max_leg=1.5, **kw)
    small = size_linear_delta(0.5e-3, (0.4, 1.2), max_leg=1.5e-3, **kw)
    for name in ("L", "d", "stroke"):
        np.testing.assert_allclose(getattr(small, name), 1e-3 * getattr(big, name), rtol=1e-9,
                                   err_msg=name)
    np.testing.assert_allclose(small.compactness, big.compactness, rtol=1e-9)
