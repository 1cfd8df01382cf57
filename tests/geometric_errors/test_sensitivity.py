"""Sensitivity analysis: first order against the exact model, scaling with the defect size,
and the Tripteor's absorbed defects."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.sensitivity import sensitivity_analysis


@pytest.mark.parametrize("name", ["linear-delta", "gough-stewart", "five-bar"])
def test_first_order_matches_the_exact_model(name):
    m = pkmkit.machine(name)
    # around home (the five-bar's default box reaches near-singular poses, where a 10 µm
    # defect already acts nonlinearly)
    home = np.asarray(m.home_pose, dtype=float)[:min(m.dims, 3)]
    region = (home - 0.1, home + 0.1)
    tab = sensitivity_analysis(m, n_points=40, exact=True, region=region)
    big = tab.max_displacement > 1e-9
    np.testing.assert_allclose(tab.exact_max[big], tab.max_displacement[big], rtol=1e-3)
    assert np.all(tab.max_components <= tab.max_displacement[:, None] * (1 + 1e-12))
    # linear in the size
    twice = sensitivity_analysis(m, n_points=40, length_size=2e-5, region=region)
    lengths = np.array([u == "m" for u in tab.units])
    np.testing.assert_allclose(twice.max_displacement[lengths],
                               2 * tab.max_displacement[lengths], rtol=1e-12)


def test_tripteor_table_orders_and_absorbs():
    m = pkmkit.machine("tripteor-x7")
    tab = sensitivity_analysis(m, n_points=15, scope="loops")
    rows = {r["name"]: r for r in tab.rows()}
    for name in ("dJ21", "dJ41", "dJ23", "dJ43", "dJ12", "dK22"):
        assert rows[name]["max_displacement"] < 1e-15, name
    assert tab.rows()[0]["max_displacement"] > 1e-5
    with pytest.raises(InputError, match="length_size"):
        sensitivity_analysis(m, length_size=-1.0)


def test_default_angle_size_moves_a_point_at_the_characteristic_length_by_the_length_size():
    """Documented default: angle-like defects get the size length_size / L (L the
    characteristic length, 0.5 m for the Tripteor), i.e. the same metres at L as a length
    defect; an explicit size is used as given."""
    from pkmkit.geometric_errors.sensitivity import sensitivity_analysis

    m = pkmkit.machine("tripteor-x7")
    r = sensitivity_analysis(m, q=np.atleast_2d(m.home_q), length_size=2e-5)
    angle = np.array([u in ("1", "rad") for u in r.units])
    assert angle.any() and (~angle).any()
    np.testing.assert_allclose(r.size[angle], 2e-5 / 0.5, rtol=1e-15)
    np.testing.assert_allclose(r.size[~angle], 2e-5, rtol=1e-15)
    given = sensitivity_analysis(m, q=np.atleast_2d(m.home_q), length_size=2e-5,
                                 angle_size=1e-4)
    np.testing.assert_allclose(given.size[angle], 1e-4, rtol=1e-15)
