"""A batch and a single call accept and refuse the same values, and one bad row of a batch
flags that row only (issue 18 §5): hostile coordinates (non-finite, beyond
``MAX_COORDINATE``, huge but finite) put in any column of a pose or an actuator vector of a
machine of every family, alone and between two good rows."""

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import pkmkit
from pkmkit.exceptions import PkmError
from pkmkit.machines.common import MAX_COORDINATE
from pkmkit.status import Status

#: One machine of each family and closure kind (rod legs, six-rod platforms, a module with
#: fewer actuators than degrees of freedom, joint chains).
MACHINES = ("linear-delta", "five-bar", "delta", "gough-stewart", "verne", "tripteor-x7")
HOSTILE = st.sampled_from([np.inf, -np.inf, np.nan, 1e300, -1e300, 2 * MAX_COORDINATE,
                           -1e12, 0.999 * MAX_COORDINATE, 1e5, -3.0])


@pytest.fixture(scope="module")
def machines():
    return {name: pkmkit.machine(name) for name in MACHINES}


def _goods(m, call):
    """The good rows a call takes: the home pose (and a Verne module's home position), or
    the home actuator values."""
    if call == "fk":
        return [np.asarray(m.home_q, dtype=float)]
    pose = np.asarray(m.home_pose, dtype=float)
    if m.family == "full-pose" and m.position_controlled:
        return [pose, pose[:3]]
    return [pose]


def _single_accepts(f, row) -> bool:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            f(row, strokes="ignore")
    except PkmError:
        return False
    return True


def _batch(m, call, rows):
    """Per-row acceptance ``(N,)`` and the results ``(N, k)`` of a batch call."""
    f = getattr(m, call)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if m.family == "chain" and call == "ik":  # joint chains: NaN rows where refused
            out = np.atleast_2d(f(rows, strokes="ignore"))
            return np.isfinite(out).all(axis=1), out
        res = f(rows, strokes="ignore", full_output=True)
    out = np.atleast_2d(res.q if call == "ik" else res.pose)
    return np.asarray(res.status) == Status.OK, out


@pytest.mark.parametrize("name", MACHINES)
@pytest.mark.parametrize("call", ["ik", "fk"])
@given(data=st.data())
def test_a_bad_row_alone_and_in_a_batch(machines, name, call, data):
    m = machines[name]
    good = data.draw(st.sampled_from(_goods(m, call)), label="good row")
    bad = good.copy()
    column = data.draw(st.integers(0, len(good) - 1), label="column")
    bad[column] = data.draw(HOSTILE, label="value")
    accepted, out = _batch(m, call, np.stack([good, bad, good]))
    assert accepted[1] == _single_accepts(getattr(m, call), bad), (bad, accepted)
    assert accepted[0] and accepted[2], "a good row was flagged with the bad one"
    _, alone = _batch(m, call, np.stack([good, good]))
    np.testing.assert_array_equal(out[[0, 2]], alone)
