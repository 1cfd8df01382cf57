"""The TriMule's closed-form inverse (:func:`pkmkit.machines.trimule_forms.inverse_unknowns`),
issue 22 §1, session 33: its own geometry — against the forward closed forms (an independent
oracle), the declined rows, a caller's start leaving the legs' home modes. The properties every
kind's start shares (the engine's oracles, batch independence, the start turned off, the C call,
the compiled twin) are tested once for every kind in test_closed_starts.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one_native
from pkmkit.machines import trimule_forms as forms
from pkmkit.spatial.rotation import rotvec_to_matrix


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("trimule-600")


def _configurations(n: int, seed: int) -> tuple[np.ndarray, ...]:
    """The measured leg and the head over their working ranges, |Q5| ≥ 8° (off the wrist
    singularity)."""
    rng = np.random.default_rng(seed)
    length = rng.uniform(0.85, 1.15, n)
    psi, theta = np.radians(rng.uniform(-15, 15, (2, n)))
    q4 = rng.uniform(-np.pi, np.pi, n)
    q5 = np.radians(rng.uniform(8, 45, n)) * rng.choice([-1.0, 1.0], n)
    return length, psi, theta, q4, q5


def test_the_closed_inverse_inverts_the_forward_closed_forms(machine):
    p = machine.params
    length, psi, theta, q4, q5 = _configurations(400, 1)
    tools = np.random.default_rng(2).uniform(0.0, 0.3, len(q4))
    rot, point = forms.platform_pose(length, psi, theta)
    x = forms.tool_pose(p, rot, point, q4, q5, tools)
    u = forms.inverse_unknowns(p, x, tools, np.sign(q5))
    assert np.isfinite(u).all()
    v = u[:, 6:]
    names = forms.VARIABLES
    for name, want in (("L4", length), ("psi1", psi), ("theta4", theta), ("Q5", q5)):
        np.testing.assert_allclose(v[:, names.index(name)], want, rtol=0, atol=1e-12)
    turn = v[:, names.index("Q4")] - q4
    assert np.abs(np.angle(np.exp(1j * turn))).max() <= 1e-12
    # the platform: its point and its frame (the rotation vector read back)
    np.testing.assert_allclose(u[:, :3], point, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rotvec_to_matrix(u[:, 3:6]), rot,
                               rtol=0, atol=1e-12)
    assert (np.linalg.norm(u[:, 3:6], axis=1) <= np.pi + 1e-12).all()
    # the parallel part's joints: the matrix forms of passive_joints and actuators
    for name, want in forms.passive_joints(p, length, psi, theta).items():
        np.testing.assert_allclose(v[:, names.index(name)], want, rtol=0, atol=1e-12)
    act = forms.actuators(p, length, psi, theta)
    np.testing.assert_allclose(v[:, [names.index(k) for k in ("Q1", "Q2", "Q3")]], act,
                               rtol=0, atol=1e-12)
    # the other branch: (Q4 + π, −Q5), the same tool pose
    w = forms.inverse_unknowns(p, x, tools, -np.sign(q5))
    assert np.array_equal(np.sign(w[:, 6 + names.index("Q5")]), -np.sign(q5))
    back = forms.tool_pose(p, rotvec_to_matrix(w[:, 3:6]), w[:, :3],
                           w[:, 6 + names.index("Q4")], w[:, 6 + names.index("Q5")], tools)
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-12)


def test_declined_rows(machine):
    p = machine.params
    length, psi, theta, q4, q5 = _configurations(3, 4)
    q5 = np.array([0.0, 0.002, 0.3])  # at and near the wrist singularity, then away
    rot, point = forms.platform_pose(length, psi, theta)
    x = forms.tool_pose(p, rot, point, q4, q5, 0.1)
    x = np.vstack([x, [np.nan, 0, 1, 0, 0, 1], [0, 0, 0, 0, 0, 1]])  # NaN; W at the origin
    u = forms.inverse_unknowns(p, x, 0.1, 1.0)
    answered = np.isfinite(u).all(axis=1)
    assert list(answered[2:]) == [True, False, False]
    # near the singularity the sweeps mostly diverge (declined); a row they answer is exact
    v = u[answered, 6:]
    back = forms.tool_pose(p, rotvec_to_matrix(u[answered, 3:6]), u[answered, :3],
                           v[:, forms.VARIABLES.index("Q4")], v[:, forms.VARIABLES.index("Q5")],
                           0.1)
    np.testing.assert_allclose(back, x[answered], rtol=0, atol=1e-12)


def _actuators(m, n: int, seed: int, spread: float = 0.9) -> np.ndarray:
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((n, len(act))))


def test_a_start_leaving_the_modes_ends_on_the_default_starts_answer(machine):
    """A caller's start (home's unknowns, ``start=``) that converges outside the legs' home
    modes is solved again from the closed-form start, not from home (whose answer leaves them
    too): the default start's answer — batch rows, the one-pose path and the C call alike."""
    m = machine
    home = np.concatenate([m.home_platform, m.home_values])
    x = m.fk(_actuators(m, 1500, 9, spread=1.1), strokes="ignore")
    x = x[np.isfinite(x).all(axis=1)]
    off = pkmkit.machine("trimule-600")
    object.__setattr__(off, "_closed_start_ok", False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        before = off.ik(x, start=home, full_output=True)  # the retry from home: out of modes
        rows = np.flatnonzero((before.status == 0) & ~m.in_home_modes(before.solution))
        x = x[rows]
        default = m.ik(x, full_output=True)
        warm = m.ik(x, start=home, full_output=True)
        # the premise: the default start's answer within them on some (8 of 13 measured; on
        # the others it leaves them too, and is solved again from home: the same answer)
        assert m.in_home_modes(default.solution).sum() >= 3
        np.testing.assert_allclose(warm.q, default.q, rtol=0, atol=1e-12)
        native = chain_one_native.packed(m)
        for k in range(len(x)):
            one = m.ik(x[k], start=home, full_output=True)
            np.testing.assert_allclose(one.q, default.q[k], rtol=0, atol=1e-12)
            if native is not None:
                c = native.ik(native.capsule, x[k], True, True, home)
                assert c is None or np.abs(c[0] - default.q[k]).max() <= 1e-12
