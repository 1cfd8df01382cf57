"""The Tripteor X7's near-closed-form inverse
(:func:`pkmkit.machines.tripteor_forms.inverse_unknowns`), issue 22 §1, session 34: its own
geometry — the actuators back from the engine's direct model (an independent oracle: the
joint-chain model's closure, not the forms' geometry), the head's other branch, the declined
rows, the near singularity where its answer is the exact one, a C constant planted off. The
properties every kind's start shares (the engine's oracles, batch independence, the start turned
off, the C call, the compiled twin) are tested once for every kind in test_closed_starts.py."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one_native
from pkmkit.machines import tripteor_forms as forms
from pkmkit.solve import chain_rows

Q4, Q5 = 6 + forms.VARIABLES.index("Q4"), 6 + forms.VARIABLES.index("Q5")
ACTUATORS = [6 + forms.VARIABLES.index(k) for k in ("Q1", "Q2", "Q3", "Q4", "Q5")]


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("tripteor-x7")


def _actuators(m, n: int, seed: int, spread: float = 0.9) -> np.ndarray:
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((n, len(act))))


def _poses(m, n: int, seed: int, spread: float = 0.9, q5_min: float | None = None):
    """Actuators and the engine's direct model's tool poses (``m.fk``, the oracle), Q5 ≥
    ``q5_min`` (rad) if given."""
    q = _actuators(m, n, seed, spread)
    if q5_min is not None:
        q[:, 4] = np.maximum(q[:, 4], q5_min)
    x = m.fk(q, strokes="ignore")
    keep = np.isfinite(x).all(axis=1)
    return q[keep], x[keep]


def _with_tool(m, x: np.ndarray, tools: np.ndarray) -> np.ndarray:
    """The targets of tool lengths ``tools`` at the same flange: the point moved along the axis."""
    out = x.copy()
    out[:, :3] += (tools - m.tool_length)[:, None] * x[:, 3:]
    return out


def test_the_closed_inverse_inverts_the_engines_direct_model(machine):
    """Tool poses of the engine's direct model (its own solve of the closure) at known
    actuators, under random tool lengths: the closed inverse gives those actuators back, and
    the engine's inverse solve started from it stops at once (0 iterations, residual within
    its tolerance, the same unknowns)."""
    m = machine
    q, x = _poses(m, 400, 1, q5_min=np.radians(3.0))
    tools = np.random.default_rng(2).uniform(0.0, 0.3, len(x))
    target = _with_tool(m, x, tools)
    u = forms.inverse_unknowns(m.params, target, tools, 1.0)
    assert np.isfinite(u).all()
    np.testing.assert_allclose(u[:, ACTUATORS], q, rtol=0, atol=1e-11)
    assert (np.linalg.norm(u[:, 3:6], axis=1) <= np.pi + 1e-12).all()
    got, status, residual, iterations = chain_rows.solve_inverse(m.model, target, u, tools)[:4]
    assert (status == 0).all() and residual.max() <= 1e-12
    assert (iterations == 0).all()
    assert np.abs(got - u).max() <= 1e-12


def test_the_other_branch_is_the_heads_mirror(machine):
    """Branch −1: (Q4 ± π, −Q5), the Q5 axis's foot on the other side of the flange (another
    platform pose): the engine's direct model of those actuators lands on the same tool
    pose."""
    m = machine
    _, x = _poses(m, 200, 3, q5_min=np.radians(3.0))
    tools = np.full(len(x), m.tool_length)
    u = forms.inverse_unknowns(m.params, x, tools, 1.0)
    w = forms.inverse_unknowns(m.params, x, tools, -1.0)
    assert np.isfinite(w).all()
    assert (w[:, Q5] < 0).all() and (u[:, Q5] > 0).all()
    assert (np.abs(np.angle(np.exp(1j * (w[:, Q4] - u[:, Q4])))) > np.pi / 2).all()
    back = m.fk(w[:, ACTUATORS], strokes="ignore")
    np.testing.assert_allclose(back, x, rtol=0, atol=1e-11)


def test_declined_rows(machine):
    """At and near the wrist singularity (Q5 = 0, where Q4 is undetermined), a NaN target and
    a flange point no platform reaches: NaN rows (the first-order start there)."""
    m = machine
    q = np.tile(m.home_q, (4, 1))
    q[:, 4] = [0.0, 1e-4, 5e-4, 0.2]
    x = m.fk(q, strokes="ignore")
    reach = m.params["spindle"] + m.tool_length
    far = np.array([0.01, -0.3, 0.01, 0.0, 0.0, 1.0])
    far[:3] += reach * far[3:]
    x = np.vstack([x, [np.nan, 0, 1, 0, 0, 1], far])
    u = forms.start_unknowns(m.params, x, np.full(len(x), m.tool_length))
    assert list(np.isfinite(u).all(axis=1)) == [False, False, False, True, False, False]
    np.testing.assert_allclose(u[3, ACTUATORS], q[3], rtol=0, atol=1e-11)
    # the batch path answers them all the same (from the first-order start there)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        r = m.ik(x[:4], full_output=True)
    assert (r.status == 0).all()
    np.testing.assert_allclose(r.q, q, rtol=0, atol=1e-9)


def test_near_the_singularity_the_closed_answer_is_the_exact_one(machine):
    """Where the two starts' answers differ beyond 1e-12 (|Q5| within ~2° of the wrist
    singularity), the engine's direct model of each answer's actuators against the target:
    the closed start's lands closer."""
    m = machine
    off = pkmkit.machine("tripteor-x7")
    object.__setattr__(off, "_closed_start_ok", False)
    _, x = _poses(m, 2100, 7, spread=1.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        new, old = m.ik(x, full_output=True), off.ik(x, full_output=True)
        rows = np.flatnonzero(np.abs(new.q - old.q).max(axis=1) > 1e-12)
        assert 0 < len(rows) <= 10
        miss_new = np.abs(m.fk(new.q[rows], strokes="ignore") - x[rows]).max(axis=1)
        miss_old = np.abs(m.fk(old.q[rows], strokes="ignore") - x[rows]).max(axis=1)
    assert (miss_new <= miss_old).all()


def test_a_wrong_constant_in_c_is_caught(machine):
    """The C twin's constants planted off (c1 by 1 µm; the assembly's sign): its start no
    longer the solution — the iteration counts differ from the batch path's."""
    m = machine
    native = chain_one_native.packed(m)
    if native is None:
        pytest.skip("no C extension")
    _, x = _poses(m, 40, 9, q5_min=np.radians(3.0))
    ref = m.ik(x, strokes="ignore", full_output=True)
    assert (ref.iterations == 0).all()
    args = chain_one_native.pack_arguments(m)
    for index, change in ((1, 1e-6), (24, -2.0)):  # c1; s_σ: −1 → +1
        closed = args[-1].copy()
        closed[index] += change
        capsule = native.ik.__self__.chain_one_pack(*args[:-1], closed)
        counts = [r[2] for r in (native.ik(capsule, v, True, True) for v in x) if r is not None]
        assert np.mean(counts) > 0.5
