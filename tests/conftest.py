"""Shared fixtures: built-in machines and random poses inside their workspaces."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.registry import ALIASES

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
