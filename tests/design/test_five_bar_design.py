import numpy as np
import pytest

from pkmkit.analysis.workspace import Criteria, check_region
from pkmkit.design.five_bar import isotropic_orientations, size_five_bar
from pkmkit.exceptions import InputError


def test_isotropy_of_j_inverse_fixes_the_slide_orientations():
    assert isotropic_orientations() == [(0.0, 90.0)]


@pytest.mark.ci
def test_sized_designs_hold_the_square():
    iso = size_five_bar(0.2, (1 / 3, 3.0), design="isotropic")
    big = size_five_bar(0.2, (1 / 3, 3.0), design="biglide")
    for res in (iso, big):
        assert res.check.feasible
        # independent re-check with the machine's own joint stops, from scratch
        again = check_region(res.machine, res.square_center, 0.2 * 0.999,
                             Criteria(bounds=(1 / 3, 3.0)), samples=51)
        assert again.feasible, again.worst
        # ... and tight: a square 0.5 % larger at the same centre no longer holds
        larger = check_region(res.machine, res.square_center, 0.2 * 1.005,
                              Criteria(bounds=(1 / 3, 3.0)), samples=51)
        assert not larger.feasible
        assert res.machine.params["L"] == res.L
    np.testing.assert_allclose(np.degrees([iso.machine.params["alpha1"],
                                           iso.machine.params["alpha2"]]), [0, 90])
    # the isotropic design needs much shorter legs and strokes for the same square
    # (both grid-limited: the useful workspace is sampled with 301 points a side)
    assert big.L / iso.L == pytest.approx(2.5660, abs=2e-3)
    assert big.stroke / iso.stroke == pytest.approx(1.7663, abs=2e-3)
    # the isotropic configuration stays J⁻¹ = I after sizing
    np.testing.assert_allclose(iso.machine.jacobian(iso.machine.home_pose).J_inv, np.eye(2),
                               atol=1e-12)


def test_bad_five_bar_specifications():
    with pytest.raises(InputError, match="exclude the home configuration"):
        size_five_bar(0.2, (1.5, 3.0))
    with pytest.raises(InputError, match="unknown design"):
        size_five_bar(0.2, (1 / 3, 3.0), design="triglide")
    with pytest.raises(InputError, match="must be > 0"):
        size_five_bar(-1.0, (1 / 3, 3.0))


@pytest.mark.ci
def test_narrow_bounds_around_the_isotropic_configuration():
    """[0.99, 1.01] holds near home (λ = 1 there) but only in a tiny useful zone: the sizing
    must find it (it said "criteria fail there" on a coarse joint grid) and call the
    specification degenerate (legs ~50 times the square)."""
    res = size_five_bar(0.2, (0.99, 1.01), design="isotropic", resolution=101)
    assert res.check.feasible
    lo, hi = res.check.factor_range
    assert 0.99 * (1 - 1e-6) <= lo and hi <= 1.01 * (1 + 1e-6)
    again = check_region(res.machine, res.square_center, 0.2 * 0.999,
                         Criteria(bounds=(0.99, 1.01)), samples=41)
    assert again.feasible, again.worst
    assert res.L / 0.2 > 20 and any("degenerate" in n for n in res.notes)


def test_sizing_does_not_depend_on_ab():
    """The sizing uses one unit study because moving B along its slide only offsets ρ2. Check
    that claim on the sized design: B moved by 0.3 m along slide 2 with the stops of actuator 2
    moved by −0.3 m gives the same verification — feasibility, factor range and q ranges
    (offset) — over the same square."""
    res = size_five_bar(0.2, (1 / 3, 3.0), design="isotropic", resolution=101)
    axis = np.array([np.cos(res.machine.params["alpha2"]), np.sin(res.machine.params["alpha2"])])
    shift = 0.3
    moved = res.machine.with_params(B=tuple(res.B + shift * axis),
                                    q_min=tuple(res.q_min - [0.0, shift]),
                                    q_max=tuple(res.q_max - [0.0, shift]))
    crit = Criteria(bounds=(1 / 3, 3.0))
    a = check_region(res.machine, res.square_center, 0.2, crit, samples=31)
    b = check_region(moved, res.square_center, 0.2, crit, samples=31)
    assert a.feasible and b.feasible and a.failures == b.failures == {}
    np.testing.assert_allclose(a.factor_range, b.factor_range, rtol=1e-12)
    np.testing.assert_allclose(b.q_range[0] - a.q_range[0], [0.0, -shift], atol=1e-9)
    np.testing.assert_allclose(b.q_range[1] - a.q_range[1], [0.0, -shift], atol=1e-9)
    pts = np.array([[0.5, 0.05], [0.62, -0.08]])
    np.testing.assert_allclose(moved.jacobian(pts).J, res.machine.jacobian(pts).J, atol=1e-12)


def test_out_of_range_square():
    with pytest.raises(InputError, match="between 1e-06 m"):
        size_five_bar(1e-300, (1 / 3, 3.0))
