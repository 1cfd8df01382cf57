"""One machine protocol (issue 19): every built-in machine and a machine file of each family
answers the same calls with the same conventions and result shapes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.machines.protocol import FAMILIES

EXAMPLES = str(Path(__file__).resolve().parents[2] / "docs" / "examples") + "/"
FILES = {"my-machine.toml": "translational", "hexapod-6-6.toml": "full-pose",
         "planar-3rpr.toml": "chain"}
ATTRIBUTES = ("ik", "fk", "jacobian", "with_params", "mobility", "default_box",
              "reference_poses", "home_pose", "home_q", "pose_names", "actuator_names",
              "actuator_quantities", "angular_actuators", "dims", "n_actuators", "family")


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(lambda name=name: pkmkit.machine(name), id=name)
    for file in FILES:
        yield pytest.param(lambda file=file: pkmkit.load(EXAMPLES + file), id=file)


@pytest.fixture(params=list(_machines()))
def machine(request):
    return request.param()


def test_every_machine_answers_the_protocol(machine):
    missing = [a for a in ATTRIBUTES if not hasattr(machine, a)]
    assert missing == []
    assert machine.family in FAMILIES
    n = machine.n_actuators
    assert len(machine.actuator_names) == n == len(machine.actuator_quantities)
    assert set(machine.actuator_quantities) <= {"length", "angle"}
    np.testing.assert_array_equal(machine.angular_actuators,
                                  [q == "angle" for q in machine.actuator_quantities])
    assert machine.home_q.shape == (n,)


def test_home_round_trip_with_the_same_shapes(machine):
    """ik of one pose gives (n,), of a batch (N, n); fk the reverse; home maps to home."""
    n = machine.n_actuators
    q = machine.ik(machine.home_pose)
    assert q.shape == (n,)
    np.testing.assert_allclose(q, machine.home_q, atol=1e-7)
    batch = machine.ik(np.vstack([machine.home_pose] * 3))
    assert batch.shape == (3, n)
    x = machine.fk(machine.home_q)
    assert x.shape == machine.home_pose.shape
    assert machine.fk(np.vstack([machine.home_q] * 2)).shape == (2, *machine.home_pose.shape)


def test_non_finite_input_is_a_typed_error(machine):
    bad = np.full(machine.home_pose.shape, np.nan)
    with pytest.raises(InputError):
        machine.ik(bad)
    with pytest.raises(InputError):
        machine.fk(np.full(machine.n_actuators, np.inf))


@pytest.mark.parametrize(("file", "family"), FILES.items())
def test_machine_files_of_each_family(file, family):
    assert pkmkit.load(EXAMPLES + file).family == family
