"""Shared synthetic calibration cases (session-scoped: identification runs are reused)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import calibrate, default_configurations, random_defects, simulate
from pkmkit.model.defects_table import apply_defect_vector


@dataclass
class Case:
    machine: object
    true: object
    delta: np.ndarray
    data: object
    validation: object
    result: object = None


@pytest.fixture(scope="session")
def tripteor_case() -> Case:
    """Seed 002's protocol, small: 60 + 20 poses, two tools, tracker noise, compatible random
    defects, identified once."""
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(11)
    delta = random_defects(m, rng)
    true = apply_defect_vector(m, delta)
    q = default_configurations(m, 80, rng)
    data = simulate(true, m, "point", 80, rng, q=q, noise="tracker")
    ident, valid = data.subset(np.arange(60)), data.subset(np.arange(60, 80))
    case = Case(m, true, delta, ident, valid)
    case.result = calibrate(m, ident, validation=valid)
    return case


@pytest.fixture(scope="session")
def delta_case() -> Case:
    """Linear Delta, tool points (fast: the test bed of the solver's properties)."""
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(5)
    delta = random_defects(m, rng)
    true = apply_defect_vector(m, delta)
    data = simulate(true, m, "point", 60, rng, noise=1e-5)
    valid = simulate(true, m, "point", 30, rng, noise=1e-5)
    case = Case(m, true, delta, data, valid)
    case.result = calibrate(m, data, validation=valid)
    return case
