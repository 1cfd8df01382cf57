"""Seed 002's Fig. 2.4 (Chanal et al. 2012, L543–570): the exact reason its sensitivities are not
reproduced (docs/errors.md §4). Besides a parametrisation the thesis never defines (λ, u2, w2,
d1…d3, e, f), the table does not state the variation behind each row, and its own rows show that
no single variation, absolute or relative to the initial value, produced them all."""

import itertools

import numpy as np

#: The O_BCS O_ICS rows: initial value (mm) and the maximal offsets X_OMPS, Y_OMPS, Z_OMPS.
ICS_ROWS = {"X_ICS": (1295.0, (1.000, 9e-16, 2e-15)),
            "Y_ICS": (1696.179, (0.125, 9.956, 4.202)),
            "Z_ICS": (1313.664, (0.076, 25.111, 10.783))}


def variation_bounds(maxima) -> tuple[float, float]:
    """A variation δ of the ICS origin translates every platform point by a vector of norm |δ|
    at every pose. Whatever (fixed or moving) frame the offsets are written in, the vector m of
    per-component maxima over poses satisfies |δ| ≤ |m| (one pose already has norm |δ|) and
    |m| ≤ √3 |δ| (each component is at most |δ|): |δ| lies in [|m|/√3, |m|]."""
    norm = float(np.linalg.norm(maxima))
    return norm / np.sqrt(3.0), norm


def test_fig_2_4_origin_rows_need_different_variations():
    bounds = {k: variation_bounds(m) for k, (_, m) in ICS_ROWS.items()}
    # absolute: X_ICS was varied by at most 1.000 mm, Y_ICS and Z_ICS by at least 6.2 and 15.8
    assert bounds["X_ICS"][1] < bounds["Y_ICS"][0] < bounds["Z_ICS"][0]
    assert bounds["X_ICS"][1] < 1.0001 and bounds["Y_ICS"][0] > 6.2 and bounds["Z_ICS"][0] > 15.7
    # relative to the initial values: disjoint intervals as well
    relative = {k: (lo / ICS_ROWS[k][0], hi / ICS_ROWS[k][0]) for k, (lo, hi) in bounds.items()}
    order = sorted(relative.values())
    assert all(a[1] < b[0] for a, b in itertools.pairwise(order))
    # the X_ICS row alone is what a 1 mm translation along x gives
    np.testing.assert_allclose(ICS_ROWS["X_ICS"][1], [1.0, 0.0, 0.0], atol=1e-12)
