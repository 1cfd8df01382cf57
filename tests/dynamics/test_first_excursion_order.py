"""The first limit excursion reported for a path is the earliest one of any actuator, even when
the actuators exceed their limit several times each in another order.

Linear Delta of seed 000 (Table IV.1), a path out and back: +x, then the direction at 120°,
back, then −x. At 0.1 m/s along x the first slide moves at 0.062 m/s and the others at 0.031;
along 120° the second slide does. With a 0.05 m/s limit the first slide exceeds it on the
first and last legs, the second on the two middle ones: the first excursion is the first
slide's, although its second excursion comes after the second slide's. Oracle: the output
samples (10 ms apart), independently of the continuous-time search."""

import itertools

import numpy as np
import pytest

import pkmkit
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.motion.joints import Limits
from pkmkit.motion.paths import Path, line


@pytest.mark.ci
def test_first_excursion_is_the_earliest_of_all_actuators():
    m = pkmkit.machine("linear-delta-table-iv1")
    p0 = np.array([0.0, 0.0, 0.2])
    d1 = np.array([1.0, 0.0, 0.0])
    d2 = np.array([np.cos(2 * np.pi / 3), np.sin(2 * np.pi / 3), 0.0])
    p1, p2 = p0 + 0.05 * d1, p0 + 0.05 * (d1 + d2)
    corners = [p0, p1, p2, p1, p0]
    path = Path(tuple(line(a, b).segments[0] for a, b in itertools.pairwise(corners)))
    limit = 0.05
    r = simulate_path(m, path, feed=0.1, accel=1.0, jerk=10.0, period=0.01,
                      limits=Limits(speed=limit))
    over = np.abs(r.motion.qd) > limit
    # the pattern the test is built on: slide 1, slide 2, slide 2, slide 1, one at a time
    assert (over.sum(axis=1) <= 1).all()
    who = np.flatnonzero(over.any(axis=1))
    runs = [int(np.flatnonzero(over[k])[0]) for k in who[np.r_[True, np.diff(who) > 1]]]
    assert runs == [0, 1, 1, 0]
    first = r.limits["speed"]["first"]
    k = who[0]
    assert first["actuator"] == m.actuator_names[0]
    assert r.motion.t[k - 1] <= first["t"] <= r.motion.t[k]
