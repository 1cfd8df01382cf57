"""The TriMule's closed-form start of the direct model
(:func:`pkmkit.machines.trimule_forms.direct_unknowns`, ``MachineKind.direct_start``) on the
batch path (:func:`pkmkit.machines.chain_starts.default_start`) and the one-pose C call
(``native/chain_one.c`` ``closed_direct``), issue 22 §1, session 33 wave 2: against the inverse
closed forms and the joint-chain model's closure (independent oracles), row by row (batch
independence), and — with it turned off — the same answers and statuses as the first-order
start's. The properties every kind's start shares (the engine's oracles, batch independence, the
start turned off, the C call, the compiled twin) are tested once for every kind in
test_closed_starts.py."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import trimule_forms as forms
from pkmkit.solve.chains import closure_residuals, rotvec_matrices


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("trimule-600")


def _actuators(m, n: int, seed: int, spread: float = 0.9) -> np.ndarray:
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((n, len(act))))


def test_the_start_gives_back_the_actuators_and_closes_the_legs(machine):
    """The inverse closed forms (:func:`~pkmkit.machines.trimule_forms.actuators`) of the
    start's measured leg give back Q1..Q3, and the joint-chain model's closure residual at the
    start (platform, passive joints, the given actuators) is zero to rounding."""
    m = machine
    q = _actuators(m, 300, 1)
    u = forms.direct_unknowns(m.params, q)
    assert np.isfinite(u).all()
    v = u[:, 6:]
    names = forms.VARIABLES
    leg = [v[:, names.index(k)] for k in ("L4", "psi1", "theta4")]
    np.testing.assert_allclose(forms.actuators(m.params, *leg), q[:, :3], rtol=0, atol=1e-12)
    for j, name in enumerate(("Q1", "Q2", "Q3", "Q4", "Q5")):
        np.testing.assert_allclose(v[:, names.index(name)], q[:, j], rtol=0, atol=1e-12)
    res = closure_residuals(m.model, rotvec_matrices(u[:, 3:6].T), u[:, :3].T,
                            np.ascontiguousarray(v.T))
    assert np.abs(res).max() <= 1e-12


def test_declined_rows(machine):
    m = machine
    q = _actuators(m, 4, 3)
    q[1, 0] = 3 * q[1, 2]    # no assembly: Q1 far beyond Q3
    q[2, 1] = 1e-3           # Q2 too short for leg 2
    q[3, 0] = np.nan
    u = forms.direct_unknowns(m.params, q)
    assert list(np.isfinite(u).all(axis=1)) == [True, False, False, False]
