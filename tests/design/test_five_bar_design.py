import numpy as np
import pytest

from pkmkit.analysis.workspace import Criteria, check_region
from pkmkit.design.five_bar import isotropic_orientations, size_five_bar
from pkmkit.errors import InputError


def test_isotropy_of_j_inverse_fixes_the_slide_orientations():
    assert isotropic_orientations() == [(0.0, 90.0)]


def test_sized_designs_hold_the_square():
    iso = size_five_bar(0.2, (1 / 3, 3.0), design="isotropic")
    big = size_five_bar(0.2, (1 / 3, 3.0), design="biglide")
    for res in (iso, big):
        assert res.check.feasible
        # independent re-check with the machine's own joint stops, from scratch
        again = check_region(res.machine, res.square_center, 0.2 * 0.999,
                             Criteria(bounds=(1 / 3, 3.0)), samples=51)
        assert again.feasible, again.worst
        assert res.machine.params["L"] == pytest.approx(res.L)
    np.testing.assert_allclose(np.degrees([iso.machine.params["alpha1"],
                                           iso.machine.params["alpha2"]]), [0, 90])
    # the isotropic design needs much shorter legs and strokes for the same square
    assert big.L / iso.L == pytest.approx(2.575, abs=0.02)
    assert big.stroke / iso.stroke == pytest.approx(1.77, abs=0.03)
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
