"""The seed studies reproduced by docs/analysis.md and the demo."""

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.workspace import Criteria, feasible_interval, useful_workspace


def test_orthoglide_reference_points_on_the_diagonal():
    """Q1, Q2: where the factors reach 0.5 or 2 along the diagonal (seed 001 §3.4)."""
    m = pkmkit.machine("orthoglide")
    t1, t2 = feasible_interval(m, np.zeros(3), np.ones(3),
                               Criteria(bounds=(0.5, 2.0), strokes=False))
    np.testing.assert_allclose(m.jacobian([t1] * 3).singular_values, [2.0, 2.0, 0.5],
                               atol=1e-9)
    assert m.jacobian([t2] * 3).singular_values[0] == pytest.approx(2.0, abs=1e-9)
    assert (t1, t2) == pytest.approx((-0.12656, 0.07307), abs=1e-5)


def test_five_bar_designs_compared_as_in_seed_004():
    """Isotropic vs biglide with the same AB and L and 1/3 < λ < 3: the square inscribed in the
    useful workspace is about 7 times larger (by area) for the isotropic design."""
    crit = Criteria(bounds=(1 / 3, 3.0))
    iso = useful_workspace(pkmkit.machine("five-bar-isotropic"), crit, resolution=201)
    big = useful_workspace(pkmkit.machine("five-bar-biglide"), crit, resolution=201)
    length = 0.5
    # joint squares centred at the home configurations, refined by bisection
    assert iso.joint_square.side / length == pytest.approx(0.7735, abs=2e-3)
    assert big.joint_square.side / length == pytest.approx(0.5324, abs=2e-3)
    ratio = iso.inscribed.side / big.inscribed.side
    assert 6.0 < ratio**2 < 7.5
    lo, hi = iso.factor_range
    assert 0.55 < lo < 0.65 and 2.7 < hi < 3.0
    lo, hi = iso.inscribed_factor_range
    assert 0.68 < lo < 0.73 and 1.65 < hi < 1.75


def test_five_bar_results_do_not_depend_on_ab():
    """Moving B along its slide line only offsets ρ2: the useful square is unchanged."""
    crit = Criteria(bounds=(1 / 3, 3.0))
    a = useful_workspace(pkmkit.machine("five-bar-isotropic"), crit, resolution=121)
    b = useful_workspace(pkmkit.machine("five-bar-isotropic", B=(1.5, -1.5)), crit,
                         resolution=121)
    assert a.joint_square.side == pytest.approx(b.joint_square.side, rel=1e-6)
