"""``boundary.kinematics``: one inverse call and result type for every family, and the options a
machine's ``ik`` takes (issue 19: one ``ik`` code path on the command line)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.boundary.kinematics import InverseRows, inverse, inverse_options
from pkmkit.exceptions import InputError
from pkmkit.status import Status

MACHINES = ("linear-delta", "five-bar", "gough-stewart", "verne", "tripteor-x7")


@pytest.mark.parametrize("name", MACHINES)
def test_rows_of_every_family_agree_with_the_machine(name):
    m = pkmkit.machine(name)
    poses = np.array([m.home_pose, np.full(len(m.home_pose), np.nan)])
    rows = inverse(m, poses)
    assert isinstance(rows, InverseRows)
    assert rows.q.shape == (2, m.n_actuators) and rows.status.shape == (2,)
    assert rows.status[0] == Status.OK and rows.status[1] != Status.OK
    # the oracle: the machine's own plain inverse of the home pose, and its home actuators
    assert np.allclose(rows.q[0], m.ik(m.home_pose, strokes="ignore"), atol=1e-9)
    assert np.allclose(rows.q[0], m.home_q, atol=1e-7)
    assert np.isnan(rows.q[1]).all()
    if m.family == "chain":
        assert rows.passive.shape == (2, len(m.passive_names)) and rows.mode is None
    else:
        assert rows.passive is None and rows.mode.shape == (2,)


def test_one_pose_gives_one_row():
    m = pkmkit.machine("tripteor-x7")
    rows = inverse(m, m.home_pose)
    assert rows.q.shape == (1, m.n_actuators) and rows.passive.shape[0] == 1


def test_a_position_of_a_position_controlled_machine_gives_its_full_pose():
    m = pkmkit.machine("verne")
    rows = inverse(m, m.home_pose[:3][None])
    assert rows.pose.shape == (1, 6)
    assert np.allclose(rows.pose[0], m.home_pose, atol=1e-7)


def test_options_the_machine_does_not_take_are_refused_not_ignored():
    assert inverse_options(pkmkit.machine("orthoglide"), method="numeric", branches=[1, 1, 1],
                           q0=None, tool_length=None) == {"method": "numeric",
                                                          "branches": [1, 1, 1]}
    with pytest.raises(InputError, match="takes no method"):
        inverse_options(pkmkit.machine("gough-stewart"), method="numeric")
    with pytest.raises(InputError, match="takes no branches"):
        inverse_options(pkmkit.machine("tripteor-x7"), branches=[1, 1, 1])
    with pytest.raises(InputError, match="takes no tool length"):
        inverse_options(pkmkit.machine("orthoglide"), tool_length=0.1)
    assert inverse_options(pkmkit.machine("tripteor-x7"), tool_length=0.1) == {
        "tool_length": 0.1}


def test_a_joint_chains_rows_are_read_without_its_deprecated_tuple_form():
    """The machine reads its own result (``inverse_rows``): ``pkmkit ik`` on a joint chain no
    longer unpacks the deprecated ``(q, direct)`` tuple, which warned on every call."""
    import warnings

    m = pkmkit.machine("tripteor-x7")
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        rows = inverse(m, m.home_pose)
    np.testing.assert_allclose(rows.passive[0], m.home_passive, atol=1e-7)
