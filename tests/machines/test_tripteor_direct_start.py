"""The Tripteor X7's near-closed-form start of the direct model
(:func:`pkmkit.machines.tripteor_forms.direct_unknowns`, ``MachineKind.direct_start``) on the
batch path (:func:`pkmkit.machines.chain_starts.default_start`) and the one-pose C call
(``native/chain_one_tripteor.c``), issue 22 §1, session 34: against the joint-chain model's
closure and the inverse (independent oracles), row by row (batch independence), and — with it
turned off — the same answers and statuses as the first-order start's. The properties every
kind's start shares (the engine's oracles, batch independence, the start turned off, the C call,
the compiled twin) are tested once for every kind in test_closed_starts.py."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import tripteor_forms as forms
from pkmkit.solve.chains import closure_residuals, rotvec_matrices


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("tripteor-x7")


def _actuators(m, n: int, seed: int, spread: float = 0.9) -> np.ndarray:
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((n, len(act))))


def test_the_start_closes_the_legs_and_inverts_back(machine):
    """The joint-chain model's closure residual at the start (platform, passive joints, the
    given actuators) is zero to rounding; the given actuators stand in the start; the closed
    inverse of the start's tool pose gives them back."""
    m = machine
    q = _actuators(m, 300, 1, spread=1.1)
    u = forms.direct_unknowns(m.params, q)
    assert np.isfinite(u).all()
    v = u[:, 6:]
    for j, name in enumerate(("Q1", "Q2", "Q3", "Q4", "Q5")):
        np.testing.assert_allclose(v[:, forms.VARIABLES.index(name)], q[:, j], rtol=0,
                                   atol=1e-12)
    res = closure_residuals(m.model, rotvec_matrices(u[:, 3:6].T), u[:, :3].T,
                            np.ascontiguousarray(v.T))
    assert np.abs(res).max() <= 1e-12
    away = q[:, 4] > np.radians(3.0)
    x = m.fk(q[away], strokes="ignore")
    back = forms.inverse_unknowns(m.params, x, np.full(len(x), m.tool_length), 1.0)
    np.testing.assert_allclose(back, u[away], rtol=0, atol=1e-11)


def test_declined_rows(machine):
    m = machine
    q = _actuators(m, 4, 3)
    q[1, 0] = 3 * q[1, 2]    # no assembly: Q1 far beyond Q3
    q[2, 1] = 1e-3           # Q2 too short for leg 2
    q[3, 0] = np.nan
    u = forms.direct_unknowns(m.params, q)
    assert list(np.isfinite(u).all(axis=1)) == [True, False, False, False]
