"""The stiffness part of the machine protocol (:mod:`pkmkit.machines.stiffness_model`): what
the elastostatic models ask instead of testing the family."""

from __future__ import annotations

import pytest

import pkmkit
from pkmkit.machines.registry import machines
from pkmkit.model.chains import JointChainModel


@pytest.mark.parametrize("name", sorted(machines()))
def test_members_configuration_and_twist_of_every_built_in(name):
    m = pkmkit.machine(name)
    chains = isinstance(m.model, JointChainModel)  # the independent answer: the model's type
    assert m.elastic_members == ("links" if chains else "rods")
    assert m.stiffness_from_actuators is chains
    width = 6 if chains or m.model.full_pose else m.dims
    assert m.twist_names == ("dx", "dy", "dz", "rx", "ry", "rz")[:width]
