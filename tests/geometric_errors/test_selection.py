"""Defect selection and configuration sampling shared by every error analysis."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, ParameterError
from pkmkit.geometric_errors.configurations import check_region, halton, sample_configurations
from pkmkit.geometric_errors.model import defect_set
from pkmkit.geometric_errors.selection import select_defects


def test_selection_by_name_pattern_owner_kind_and_scope():
    t = pkmkit.machine("tripteor-x7")
    names = defect_set(t).names
    pick = lambda *a, **k: [names[i] for i in select_defects(t, *a, **k)]  # noqa: E731
    assert pick("dK21,dJ41") == ["dK21", "dJ41"]
    assert pick("psi2") == ["dJ12", "dK12", "db12", "dc12"]  # an owner: all its defects
    assert pick("d?13") == ["dI13", "dK13", "da13", "dc13"]
    assert all(n[1] in "IJK" for n in pick(kinds="orientation"))
    loops = pick(scope="loops")
    assert "dIMPS" not in loops and "dJ21" in loops and len(loops) == 58
    assert pick(scope="head")[0] == "dIMPS"
    assert not {"dI11", "dK11", "da11", "dc11"} & set(pick(reference_nominal=True))
    assert "dS62" not in pick(exclude="dS*")
    with pytest.raises(ParameterError, match="unknown scope"):
        select_defects(t, scope="legs")
    with pytest.raises(ParameterError, match="empty"):
        select_defects(t, "dK21", exclude="dK21")


def test_configurations_are_reachable_and_in_the_region():
    m = pkmkit.machine("linear-delta")
    lo, hi = np.array([-0.1, -0.1, 0.0]), np.array([0.1, 0.1, 0.2])
    conf = sample_configurations(m, 25, region=(lo, hi), method="halton")
    assert conf.q.shape == (25, 3) and np.isfinite(conf.q).all()
    assert np.all((conf.points >= lo) & (conf.points <= hi))
    np.testing.assert_allclose(m.fk(conf.q), conf.points, atol=1e-9)
    # Halton points: the first radical inverses in bases 2 and 3
    np.testing.assert_allclose(halton(np.arange(3), 2), [[0.5, 1 / 3], [0.25, 2 / 3],
                                                          [0.75, 1 / 9]])
    with pytest.raises(InputError, match=r"MIN = 0\.2 not below MAX = 0\.1"):
        check_region(m, [0, 1, 0, 1, 0.2, 0.1])
    with pytest.raises(InputError, match="3 pairs"):
        check_region(m, [0, 1])
    with pytest.raises(InputError, match="reachable"):
        sample_configurations(m, 3, region=([5, 5, 5], [6, 6, 6]))
    hexapod = pkmkit.machine("gough-stewart")
    assert check_region(hexapod, None)[0].size == 6  # orientation varies by default
