"""Cutting-force time series."""

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics import WrenchSeries, inverse_dynamics, load_wrench_series, mass_properties
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.exceptions import InputError
from pkmkit.motion import line


def test_interpolation_and_hold():
    series = WrenchSeries([0.0, 1.0, 3.0], [[0, 0, 0], [10, 0, -100], [10, 20, -100]])
    np.testing.assert_allclose(series.at([-1.0, 0.5, 2.0, 5.0]),
                               [[0, 0, 0], [5, 0, -50], [10, 10, -100], [10, 20, -100]])


@pytest.mark.ci
def test_time_series_drives_the_forces(tmp_path):
    """Massless machine: the actuator forces are Jᵀ of the sampled cutting force, sample by
    sample."""
    m = pkmkit.machine("linear-delta-table-iv1")
    path = tmp_path / "cut.csv"
    path.write_text("# force ramps up as the tool enters the material\nt,fx,fy,fz,note\n"
                    "0,0,0,0,\n1,50,0,-200,engaged\n2,50,0,-200,\n")
    series = load_wrench_series(path)
    massless = mass_properties(m, gravity=(0, 0, 0))
    res = simulate_path(m, line([0, 0, 0.2], [0.1, 0, 0.2]), feed=0.05, accel=0.5, jerk=5.0,
                        period=0.01, masses=massless, wrench=series)
    motion = res.motion
    forces = series.at(motion.t)
    zeros = np.zeros_like(motion.q)
    expected = inverse_dynamics(m, massless, motion.x, motion.xd, motion.xdd, motion.q, zeros,
                                zeros, wrench=forces).force
    np.testing.assert_allclose(res.forces.force, expected, atol=1e-9)
    jac = m.jacobian(motion.x)
    np.testing.assert_allclose(res.forces.force, -np.einsum("nij,ni->nj", jac.J, forces),
                               atol=1e-9)
    assert np.abs(res.forces.force[0]).max() < 1e-12 and np.abs(res.forces.force[-1]).max() > 50


@pytest.mark.parametrize("text, message", [
    ("t,fx,fy\n0,1,2\n", "missing column"),
    ("t,fx,fy,fz\n0,1,2,3\n0,1,2,3\n", "row 2 has t = 0 after 0"),
    ("t,fx,fy,fz\n0,1,2,3\n1,x,2,3\n", r"w.csv:3"),
    ("t,fx,fy,fz\n0,1,nan,3\n", "non-finite"),
    ("t,fx,fy,fz\n0,1,2,3\n1,1,-1e300,3\n", r"row 2 has a force of 1e\+300 N, beyond 1e\+09"),
])
def test_bad_wrench_files(tmp_path, text, message):
    path = tmp_path / "w.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        load_wrench_series(path)
