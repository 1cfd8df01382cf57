"""Joint-chain closure kernels: the Gibbs-vector rotation residual and its analytic rows
against finite differences (also away from closure), the block pattern handed to the engine,
the batch-last rotation helpers against SciPy, and the selective twists."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.model.chains import ElementSpec, build_chain_model
from pkmkit.solve.chains import (
    chain_pose,
    closure,
    closure_pattern,
    closure_residuals,
    compose_rotvecs,
    leg_residual,
    rotvec_matrices,
    solve_closure,
    solve_machine_inverse,
)
from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix
from pkmkit.status import Status


@pytest.fixture(scope="module")
def tripteor():
    return pkmkit.machine("tripteor-x7")


def random_state(machine, rng, k, spread=0.05):
    """Joint values, platform rotations and positions near home, not closed."""
    values = machine._home["values"][:, None] + rng.normal(0.0, spread, (machine.model.n_variables,
                                                                        k))
    phi = machine._home["platform"][3:, None] + rng.normal(0.0, 0.3, (3, k))
    p = machine._home["platform"][:3, None] + rng.normal(0.0, 0.02, (3, k))
    return values, rotvec_matrices(phi), p


def test_closure_rows_match_finite_differences_away_from_closure(tripteor):
    """Exact Jacobians of the residual (translation, L × Gibbs vector) with respect to every
    joint variable, the platform position and the platform's left rotation increment, at
    states far from closure (leg rotations off by up to ~60°), where the Gibbs terms matter."""
    rng = np.random.default_rng(3)
    model = tripteor.model
    values, rot, p = random_state(tripteor, rng, 6)
    c = closure(model, rot, p, values)
    assert np.abs(c.residual[3:6]).max() > 0.05  # genuinely not closed
    h = 1e-6
    for j in range(model.n_variables):
        step = np.zeros_like(values)
        step[j] = h
        fd = (closure(model, rot, p, values + step).residual
              - closure(model, rot, p, values - step).residual) / (2 * h)
        assert np.abs(c.variables[:, j] - fd).max() < 1e-6
    for i in range(3):
        e = np.zeros((3, 1))
        e[i] = h
        fd = (closure(model, rot, p + e, values).residual
              - closure(model, rot, p - e, values).residual) / (2 * h)
        assert np.abs(c.platform[:, i] - fd).max() < 1e-6
        turn = rotvec_matrices(np.tile(e, (1, 6)))
        back = rotvec_matrices(np.tile(-e, (1, 6)))
        fd = (closure(model, np.einsum("abk,bck->ack", turn, rot), p, values).residual
              - closure(model, np.einsum("abk,bck->ack", back, rot), p, values).residual) / (2 * h)
        assert np.abs(c.platform[:, 3 + i] - fd).max() < 1e-6


def test_defect_rows_match_finite_differences(tripteor):
    rng = np.random.default_rng(4)
    values, rot, p = random_state(tripteor, rng, 3, spread=0.01)
    model = tripteor.model
    c = closure(model, rot, p, values, defects=True)
    h = 1e-7
    names = model.defect_index.names
    for i in rng.choice(len(names), 25, replace=False):
        plus = model.with_defects({names[i]: h})
        minus = model.with_defects({names[i]: -h})
        fd = (closure(plus, rot, p, values).residual
              - closure(minus, rot, p, values).residual) / (2 * h)
        assert np.abs(c.defects[:, i] - fd).max() < 1e-5, names[i]


def test_rotation_residual_vanishes_only_at_identity(tripteor):
    """L × 2 tan(θ/2) n: L θ n for small θ, unbounded towards θ = π — never zero there (the
    former L sin θ n was, and made half-turned legs look closed)."""
    length = tripteor.model.characteristic_length
    rng = np.random.default_rng(5)
    axis = rng.normal(size=(3, 5))
    axis /= np.linalg.norm(axis, axis=0)
    rot_x = rotvec_matrices(rng.normal(size=(3, 5)))
    for theta, expected in ((1e-7, 1e-7), (0.3, 2 * np.tan(0.15)), (np.pi - 1e-6, None)):
        turn = rotvec_matrices(theta * axis)
        leg = type("Leg", (), {"R": np.einsum("abk,bck->ack", turn, rot_x),
                               "p": np.zeros((3, 5))})
        res, _ = leg_residual(leg, rot_x, np.zeros((3, 5)), length)
        size = np.linalg.norm(res[3:], axis=0) / length
        if expected is None:
            assert (size > 1e5).all()
        else:
            np.testing.assert_allclose(size, expected, rtol=1e-9)
            np.testing.assert_allclose(res[3:] / (length * size), axis, atol=1e-9)


def test_rotation_helpers_match_scipy():
    rng = np.random.default_rng(6)
    for scale in (1e-12, 1e-5, 1e-2, 1.0):
        delta, phi = rng.normal(size=(2, 3, 200)) * scale
        np.testing.assert_allclose(rotvec_matrices(phi),
                                   rotvec_to_matrix(phi.T).transpose(1, 2, 0), atol=1e-15)
        np.testing.assert_allclose(compose_rotvecs(delta, phi), compose_rotvec(delta.T, phi.T).T,
                                   rtol=1e-12, atol=1e-20)
    # across π the composed vector flips to the short way round: same rotation
    phi = rng.normal(size=(3, 200))
    phi *= (np.pi - 1e-7) / np.linalg.norm(phi, axis=0)
    delta = rng.normal(size=(3, 200)) * 1e-5
    out = compose_rotvecs(delta, phi)
    assert np.linalg.norm(out, axis=0).max() <= np.pi + 1e-12
    np.testing.assert_allclose(Rotation.from_rotvec(out.T).as_matrix(),
                               (Rotation.from_rotvec(delta.T) * Rotation.from_rotvec(phi.T))
                               .as_matrix(), atol=1e-12)


def test_selected_twists_are_columns_of_the_full_ones(tripteor):
    rng = np.random.default_rng(7)
    values, _, _ = random_state(tripteor, rng, 4)
    model = tripteor.model
    leg = model.legs[1]
    full = chain_pose(model, leg, values, twists=True)
    some = np.array([model.variables.index(n) for n in ("eta2", "psi2", "Q2")])
    part = chain_pose(model, leg, values, twists=True, twist_variables=some)
    np.testing.assert_array_equal(part.variable_twists, full.variable_twists[:, some])
    np.testing.assert_array_equal(part.R, full.R)


def test_tripteor_pattern_is_one_block_per_leg(tripteor):
    passive = tripteor._passive
    pattern, _, members = closure_pattern(tripteor.model, passive)
    assert pattern.shared == tuple(range(6))
    assert [len(cols) for _, cols in pattern.groups] == [3, 4, 3]
    assert [rows for rows, _ in pattern.groups] == [tuple(range(6 * g, 6 * g + 6))
                                                    for g in range(3)]
    names = [tuple(tripteor.model.variables[v] for v in m) for m in members]
    assert names == [("psi1", "theta1", "phi1"), ("psi2", "theta2", "eta2", "phi2"),
                     ("psi3", "theta3", "phi3")]


def shared_joint_model():
    """Two planar two-link legs sharing their base revolute (as the TriMule's legs share ψ1),
    closed on a platform frame: the shared joint must join the shared block."""
    e = [ElementSpec("s", "R", axis=(0, 0, 1), home=0.3),
         ElementSpec("a1", "R", axis=(0, 0, 1), point=(1, 0, 0), actuated=True, home=0.5),
         ElementSpec("b1", "R", axis=(0, 0, 1), point=(1, 0, 0), home=-0.5),
         ElementSpec("f1", "F", axis=(0, 0, 1), point=(0.5, 0, 0)),
         ElementSpec("a2", "R", axis=(0, 0, 1), point=(1, 0.2, 0), actuated=True, home=0.5),
         ElementSpec("b2", "P", axis=(1, 0, 0), home=1.0),
         ElementSpec("c2", "R", axis=(0, 0, 1), home=-0.5)]
    return build_chain_model(e, legs=[["s", "a1", "b1", "f1"], ["s", "a2", "b2", "c2"]])


def test_shared_joint_joins_the_shared_block():
    model = shared_joint_model()
    unknown = np.array([model.variables.index(n) for n in ("s", "b1", "b2", "c2")])
    pattern, _, _ = closure_pattern(model, unknown)
    assert pattern.shared == (0, 1, 2, 3, 4, 5, 6)  # the platform and s
    assert [cols for _, cols in pattern.groups] == [(7,), (8, 9)]
    # the block-structured solve agrees with the dense one on the same closure
    rng = np.random.default_rng(8)
    known = np.tile(model.home, (20, 1))
    known[:, [1, 4]] += rng.normal(0.0, 0.05, (20, 2))
    start = chain_pose(model, model.legs[0], model.home[:, None])
    u0 = np.concatenate([start.p[:, 0], Rotation.from_matrix(start.R[:, :, 0]).as_rotvec(),
                         model.home[unknown]])
    u0 = np.tile(u0, (20, 1))
    block = solve_closure(model, known, u0, unknown_variables=unknown)
    dense = solve_closure(model, known, u0, unknown_variables=unknown, pattern=None)
    np.testing.assert_allclose(block.u, dense.u, atol=1e-12)
    assert np.array_equal(block.status, dense.status)
    assert np.array_equal(block.iterations, dense.iterations)


def test_block_and_dense_direct_models_agree(tripteor):
    """The engine's Schur path on the Tripteor's closure gives the dense path's answers."""
    rng = np.random.default_rng(9)
    q = tripteor.home_q + rng.normal(0.0, [0.01, 0.01, 0.01, 0.2, 0.2], (50, 5))
    block = tripteor.fk(q, full_output=True)
    dense = tripteor.fk(q, full_output=True, pattern=None)
    assert (block.status == Status.OK).all()
    np.testing.assert_allclose(block.passive, dense.passive, atol=1e-13)
    np.testing.assert_allclose(block.pose, dense.pose, atol=1e-13)
    res = closure_residuals(tripteor.model, rotvec_matrices(block.platform[:, 3:].T),
                            block.platform[:, :3].T,
                            _values(tripteor, q, block.passive))
    assert np.abs(res).max() < 1e-13


def _values(machine, q, passive):
    values = machine.full_values(q)
    values[:, machine._passive] = passive
    return values.T


@pytest.mark.parametrize("tool_length", [0.0, 0.3])
def test_machine_inverse_recovers_the_actuators_of_a_forward_pose(tripteor, tool_length):
    """The engine's inverse model of the whole machine, from the home start, on tool points and
    axes made by the direct model at known actuator values: it converges on those values (the
    tool axis residual is L (a − a_target), its Jacobian rows L [ω]× a)."""
    rng = np.random.default_rng(8)
    q = tripteor.home_q + rng.uniform(-0.03, 0.03, (3, tripteor.n_actuators))
    targets = np.asarray(tripteor.fk(q, tool_length=tool_length, strokes="ignore"))
    start = np.concatenate([tripteor._home["platform"], tripteor._home["values"]])
    res = solve_machine_inverse(tripteor.model, targets, np.tile(start, (3, 1)),
                                tool_length=np.full(3, tool_length))
    assert (res.status == Status.OK).all()
    np.testing.assert_allclose(res.u[:, 6:][:, tripteor._actuated], q, atol=1e-9)
