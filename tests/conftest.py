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

settings.register_profile("dev", max_examples=25, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow,
                                                 HealthCheck.filter_too_much])
settings.register_profile("ci", settings.get_profile("dev"), max_examples=100)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE")
                      or ("ci" if os.environ.get("CI") else "dev"))


PRESETS = [m for m in pkmkit.machines() if m not in ALIASES]


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
    """Every built-in preset machine."""
    return pkmkit.machine(request.param)
