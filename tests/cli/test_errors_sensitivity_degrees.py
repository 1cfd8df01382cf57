"""``pkmkit errors --sensitivity`` speaks degrees for angles: ``--angle-size`` is read in
degrees and ``max_rotation_deg`` written in degrees, the same physical values as the library
call in radians (the hexapod, whose defects move the platform's orientation)."""

import math

import numpy as np

import pkmkit
from pkmkit.geometric_errors.sensitivity import sensitivity_analysis


def test_sensitivity_angles_in_degrees_are_the_library_values_in_radians(run, as_json):
    out = as_json(run("errors", "gough-stewart", "--sensitivity", "--angle-size", "0.02",
                      "--points", "6", "--seed", "3", "--json"))["sensitivity"]
    table = sensitivity_analysis(pkmkit.machine("gough-stewart"), n_points=6, seed=3,
                                 angle_size=math.radians(0.02))
    expected = {r["name"]: r["max_rotation"] for r in table.rows()}
    got = {r["name"]: r["max_rotation_deg"] for r in out["rows"]}
    assert set(got) == set(expected)
    names = sorted(expected)
    np.testing.assert_allclose([got[n] for n in names],
                               [math.degrees(expected[n]) for n in names], rtol=1e-9,
                               atol=1e-15)
    assert max(got.values()) > 1e-4  # degrees: some defects do turn the platform
