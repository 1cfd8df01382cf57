"""The five-bar's home configuration (``five_bar.home_configuration``) at any size: both
carriages on their slide lines, each a rod length L from the tool point, for crossing slides
(the five-bar, its isotropic variant) and parallel ones (the Biglide), at L = 0.5 m and 5 mm
(a plausible bug, ``L · u2`` → ``u2 / L``, passed every test: the home pose is right, only
the second carriage is placed wrong)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.five_bar import home_configuration

LENGTHS = ("A", "B", "L", "parallelogram_width", "q_min", "q_max")


def _scaled(name: str, scale: float):
    m = pkmkit.machine(name)
    return m.with_params(**{k: np.multiply(m.params[k], scale).tolist()
                            if isinstance(m.params[k], tuple) else m.params[k] * scale
                            for k in LENGTHS})


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


@pytest.mark.parametrize("name", ["five-bar", "five-bar-isotropic", "five-bar-biglide"])
@pytest.mark.parametrize("scale", [1.0, 0.01])
def test_home_carriages_are_a_rod_length_from_the_tool_point(name, scale):
    params = _scaled(name, scale).params
    p, c, d = home_configuration(params)
    length = params["L"]
    assert np.linalg.norm(p - c) == pytest.approx(length, rel=1e-12)
    assert np.linalg.norm(p - d) == pytest.approx(length, rel=1e-12)
    for point, origin, angle in ((c, params["A"], params["alpha1"]),
                                 (d, params["B"], params["alpha2"])):
        along = np.array([np.cos(angle), np.sin(angle)])
        assert abs(_cross(np.subtract(point, origin), along)) <= 1e-12 * scale
