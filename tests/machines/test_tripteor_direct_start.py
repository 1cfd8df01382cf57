"""The Tripteor X7's near-closed-form start of the direct model
(:func:`pkmkit.machines.tripteor_forms.direct_unknowns`, ``MachineKind.direct_start``) on the
batch path (:func:`pkmkit.machines.chain_starts.default_start`) and the one-pose C call
(``native/chain_one_tripteor.c``), issue 22 §1, session 34: against the joint-chain model's
closure and the inverse (independent oracles), row by row (batch independence), and — with it
turned off — the same answers and statuses as the first-order start's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one_native, chain_starts
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


def test_the_start_is_the_engines_solution_from_home(machine):
    """The first-order start (home moved towards q; the closed start turned off) solved by the
    engine lands where the closed start is: poses and passive joints to 1e-11, the same
    statuses and strokes; from the closed start the solve stops at once."""
    m = machine
    off = pkmkit.machine("tripteor-x7")
    object.__setattr__(off, "_closed_direct_ok", False)
    q = _actuators(m, 1000, 2, spread=1.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        new, old = m.fk(q, full_output=True), off.fk(q, full_output=True)
    assert np.array_equal(new.status, old.status)
    ok = new.status == 0
    assert ok.mean() >= 0.95
    np.testing.assert_allclose(new.pose[ok], old.pose[ok], rtol=0, atol=1e-11)
    np.testing.assert_allclose(new.passive[ok], old.passive[ok], rtol=0, atol=1e-11)
    assert np.array_equal(np.asarray(new.out_of_stroke), np.asarray(old.out_of_stroke))
    closed = chain_starts.closed_direct_starts(m, q)
    np.testing.assert_allclose(closed[ok, 6:], new.passive[ok], rtol=0, atol=1e-11)
    assert new.iterations[ok].mean() < 0.1 * old.iterations[ok].mean()  # counts, not times


def test_declined_rows(machine):
    m = machine
    q = _actuators(m, 4, 3)
    q[1, 0] = 3 * q[1, 2]    # no assembly: Q1 far beyond Q3
    q[2, 1] = 1e-3           # Q2 too short for leg 2
    q[3, 0] = np.nan
    u = forms.direct_unknowns(m.params, q)
    assert list(np.isfinite(u).all(axis=1)) == [True, False, False, False]


def test_a_rows_start_does_not_depend_on_its_batch(machine):
    m = machine
    q = _actuators(m, 60, 4)
    batch = chain_starts.closed_direct_starts(m, q)
    for k in range(len(q)):
        assert np.array_equal(chain_starts.closed_direct_starts(m, q[k:k + 1])[0], batch[k],
                              equal_nan=True)


def test_the_c_call_starts_alike(machine):
    """The C call's direct start against the batch path's: the answers to 1e-12 and the
    closure's iteration counts equal (both start from the near-closed form)."""
    m = machine
    native = chain_one_native.packed(m)
    if native is None:
        pytest.skip("no C extension")
    q = _actuators(m, 300, 5)
    full = m.fk(q, strokes="ignore", full_output=True)
    got = 0
    for k in range(len(q)):
        one = native.fk(native.capsule, q[k], True, True, True)
        if one is None:
            continue
        got += 1
        assert np.abs(np.asarray(one[0]) - full.pose[k]).max() <= 1e-12
        assert one[1] == full.iterations[k]
    assert got >= 0.99 * len(q)
    assert full.iterations.mean() < 0.5
