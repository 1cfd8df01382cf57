"""Shared fixtures: built-in machines and random poses inside their workspaces; Hypothesis
settings profiles (``dev`` locally, ``ci`` — four times the examples — when ``CI`` is set, as in
``.ci/run``; ``HYPOTHESIS_PROFILE=NAME`` chooses one explicitly)."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

import pkmkit
from pkmkit.machines.registry import ALIASES
from pkmkit.model.rods import CRANK

settings.register_profile("dev", max_examples=25, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.filter_too_much])
settings.register_profile("ci", settings.get_profile("dev"), max_examples=100)
settings.register_profile("explore", settings.get_profile("ci"), derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE")
                      or ("ci" if os.environ.get("CI") else "dev"))



ALL_PRESETS = [m for m in pkmkit.machines() if m not in ALIASES]
#: Presets whose platform only translates (dims 2 or 3).
PRESETS = [m for m in ALL_PRESETS if pkmkit.machine(m).dims in (2, 3)]
#: Rod-leg presets whose platform has a full pose (dims 6).
FULL_POSE_PRESETS = [m for m in ALL_PRESETS
                     if type(pkmkit.machine(m)).__name__ == "FullPoseMachine"]
#: Joint-chain presets.
CHAIN_PRESETS = [m for m in ALL_PRESETS
                 if type(pkmkit.machine(m)).__name__ == "JointChainMachine"]
#: Translational presets whose actuators are all linear (slides, struts): what the dynamics
#: layer models.
LINEAR_PRESETS = [m for m in PRESETS if not (pkmkit.machine(m).model.leg_kind == CRANK).any()]


def workspace_half_width(machine: pkmkit.Machine) -> float:
    """Half side of a box around home that is reachable and far from singularities."""
    return 0.25 * float(machine.model.leg_length.min())


def random_poses(machine: pkmkit.Machine, n: int, seed: int = 0) -> np.ndarray:
    """``n`` poses drawn uniformly in a box around the home pose, ``(n, dims)``."""
    rng = np.random.default_rng(seed)
    h = workspace_half_width(machine)
    return machine.home_pose + rng.uniform(-h, h, (n, machine.dims))


@pytest.fixture(params=PRESETS)
def preset(request) -> pkmkit.Machine:
    """Every built-in preset machine with a translational platform."""
    return pkmkit.machine(request.param)


@pytest.fixture(params=FULL_POSE_PRESETS)
def full_pose_preset(request):
    """Every built-in full-pose (6-DOF platform) machine."""
    return pkmkit.machine(request.param)


@pytest.fixture(params=LINEAR_PRESETS)
def linear_preset(request) -> pkmkit.Machine:
    """Every built-in preset machine with linear actuators only (slides, struts)."""
    return pkmkit.machine(request.param)
