"""VJM of joint-chain (hyperstatic) machines against independent formulations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pkmkit.machines.registry import machine
from pkmkit.model.chains import FIXED
from pkmkit.solve.chains import chain_pose, twist_rows
from pkmkit.stiffness import Section, default_data, stiffness
from pkmkit.stiffness.beam import beam_compliance
from pkmkit.stiffness.joint_chains import assemble, null_space_compliance
from pkmkit.stiffness.links import link_geometry, spring_twists


def _data(m, section=None):
    return dataclasses.replace(default_data(m), link_section=section)


SECTIONS = {"tripteor-x7": Section.tube(0.08, 0.06), "trimule-600": Section.tube(0.08, 0.06),
            "crank-slider": Section.circle(0.02)}


def _configurations(m, count=3, seed=0):
    rng = np.random.default_rng(seed)
    home = m.home_q
    q = np.tile(home, (count, 1))
    q[1:] += rng.uniform(-0.008, 0.008, (count - 1, m.n_actuators))
    return q


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600", "crank-slider"])
def test_rigid_links_give_j_cq_jt(name):
    """Actuator springs only: the tool compliance is J C_q Jᵀ with J the machine's own velocity
    model (tool point, base axes) — hyperstatic closures add no compliance when rigid."""
    m = machine(name)
    q = _configurations(m)
    result = stiffness(m, q=q)
    j = m.jacobian(q).J
    c_q = 1.0 / default_data(m).actuator_stiffness
    expected = np.einsum("nia,a,nja->nij", j, c_q, j)
    np.testing.assert_allclose(result.compliance, expected, rtol=1e-7,
                               atol=1e-9 * np.abs(expected).max())


def _kkt_compliance(system):
    """Lagrange multipliers through the closure: [[H, Gᵀ], [G, 0]] [z; λ] = [Tᵀ w; 0] for the
    six unit wrenches (least squares: the hyperstatic rows are redundant, λ not unique)."""
    out = []
    for g, h, t in zip(system.G, system.H, system.T, strict=True):
        r, nz = g.shape
        scale = np.abs(h).max()  # multipliers in the units of H: a balanced matrix
        kkt = np.zeros((nz + r, nz + r))
        kkt[:nz, :nz], kkt[:nz, nz:], kkt[nz:, :nz] = h, scale * g.T, scale * g
        rhs = np.zeros((nz + r, 6))
        rhs[:nz] = t.T
        z = np.linalg.lstsq(kkt, rhs, rcond=1e-14)[0][:nz]
        out.append(t @ z)
    return np.array(out)


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600", "crank-slider"])
def test_null_space_against_lagrange_multipliers(name):
    m = machine(name)
    data = _data(m, SECTIONS[name])
    system = assemble(m, _configurations(m), data)
    c, status = null_space_compliance(system.G, system.H, system.T, system.status)
    assert (status == 0).all()
    kkt = _kkt_compliance(system)
    np.testing.assert_allclose(c, kkt, rtol=1e-9, atol=1e-9 * np.abs(kkt).max())


def _leg_jacobians(m, system_q, data, leg_index):
    """Pashkevich's leg model from the chain alone: J_θ (actuator and link springs) and J_q
    (passive joints) as small displacements of the platform origin, and C_θ."""
    model = m.model
    res = m.fk(system_q, full_output=True, strokes="ignore", check_singular=False)
    values = model.home.copy()
    act = np.flatnonzero(model.actuated)
    values[act] = system_q
    passive = [model.variables.index(n) for n in m.passive_names]
    values[passive] = res.passive
    values = values[:, None]
    leg = model.legs[leg_index]
    end = chain_pose(model, leg, values, twists=True)
    origin = res.platform[:3]

    def at_origin(tw):
        return np.concatenate([tw[:3] + np.cross(tw[3:].T, origin).T, tw[3:]])

    mine = [model.element_variable[e] for e in leg if model.elements[e].type != FIXED]
    springs = [v for v in mine if model.actuated[v]]
    free = [v for v in mine if not model.actuated[v]]
    cols, compliances = [], []
    for v in springs:
        cols.append(at_origin(end.variable_twists[:, v, 0]))
        k = data.actuator_stiffness[list(act).index(v)]
        compliances.append(np.array([[1.0 / k]]))
    from pkmkit.solve.chains import rotvec_matrices
    from pkmkit.stiffness.joint_chains import _compliant_links

    rot = rotvec_matrices(res.platform[3:, None])
    for link in _compliant_links(m, data):
        if link.chain == "leg" and link.index == leg_index:
            point, axes, length = link_geometry(model, link, values, rot, res.platform[:3, None])
            tw = spring_twists(point, axes)[:, :, 0]
            cols += [at_origin(tw[:, j]) for j in range(6)]
            compliances.append(beam_compliance(length[0], data.link_section, data.link_material))
    j_theta = np.array(cols).T
    c_theta = np.zeros((j_theta.shape[1],) * 2)
    start = 0
    for block in compliances:
        n = block.shape[0]
        c_theta[start:start + n, start:start + n] = block
        start += n
    j_q = np.array([at_origin(end.variable_twists[:, v, 0]) for v in free]).T
    return j_theta, c_theta, j_q


def test_per_leg_aggregation_matches_the_global_model():
    """Pashkevich's VJM: K_leg = top-left block of [[J_θ C_θ J_θᵀ, J_q], [J_qᵀ, 0]]⁻¹, legs in
    parallel K = Σ K_leg, against the global null-space model at the platform origin."""
    m = machine("tripteor-x7")
    data = _data(m, SECTIONS["tripteor-x7"])
    q = _configurations(m, 2, seed=3)
    system = assemble(m, q, data)
    c_platform, status = null_space_compliance(system.G, system.H, system.P, system.status)
    assert (status == 0).all()
    for n in range(len(q)):
        total = np.zeros((6, 6))
        for i in range(len(m.model.legs)):
            j_theta, c_theta, j_q = _leg_jacobians(m, q[n], data, i)
            s = j_theta @ c_theta @ j_theta.T
            f = j_q.shape[1]
            bordered = np.zeros((6 + f, 6 + f))
            bordered[:6, :6], bordered[:6, 6:], bordered[6:, :6] = s, j_q, j_q.T
            total += np.linalg.inv(bordered)[:6, :6]
        k_global = np.linalg.inv(c_platform[n])
        np.testing.assert_allclose(total, k_global, rtol=1e-9, atol=1e-9 * np.abs(total).max())


def test_releasing_a_constraint_lowers_the_stiffness():
    """The Tripteor is hyperstatic of degree 2 (legs 1 and 3 constrain three freedoms each,
    leg 2 two). A free rotation added at the end of leg 1 releases one redundant constraint:
    K' ≤ K with a strictly positive difference."""
    m = machine("tripteor-x7")
    data = _data(m, SECTIONS["tripteor-x7"])
    system = assemble(m, m.home_q[None], data)
    c, _ = null_space_compliance(system.G, system.H, system.T, system.status)
    g = system.G[0]
    rows = system.leg_rows[0]
    end = system.platform_point[0]
    axis = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    twist = np.concatenate([np.cross(end, axis), axis])[:, None, None]
    extra = np.zeros((g.shape[0], 1))
    m_id = np.eye(3)[:, :, None]
    extra[rows] = twist_rows(twist, end[:, None], m_id, m.model.characteristic_length)[:, :, 0]
    g2 = np.concatenate([g, extra], axis=1)[None]
    nz = g2.shape[2]
    h2 = np.zeros((1, nz, nz))
    h2[0, :-1, :-1] = system.H[0]
    t2 = np.concatenate([system.T, np.zeros((1, 6, 1))], axis=2)
    c2, status = null_space_compliance(g2, h2, t2, system.status)
    assert status[0] == 0
    k, k2 = np.linalg.inv(c[0]), np.linalg.inv(c2[0])
    diff = np.linalg.eigvalsh(k - k2)
    assert diff.min() > -1e-9 * np.abs(k).max()
    assert diff.max() > 1e-3 * np.abs(k).max()


def test_links_soften_the_machine():
    m = machine("tripteor-x7")
    rigid = stiffness(m, q=m.home_q)
    soft = stiffness(m, q=m.home_q, data=_data(m, SECTIONS["tripteor-x7"]))
    assert rigid.rigid == 1 and soft.rigid == 0
    diff = np.linalg.eigvalsh(soft.compliance - rigid.compliance)
    assert diff.min() > -1e-12 * np.abs(soft.compliance).max()


def test_batch_matches_single_and_pose_input():
    m = machine("tripteor-x7")
    data = _data(m, SECTIONS["tripteor-x7"])
    q = _configurations(m, 3)
    batch = stiffness(m, q=q, data=data)
    one = stiffness(m, q=q[1], data=data)
    np.testing.assert_allclose(one.stiffness, batch.stiffness[1], rtol=1e-9)
    pose = m.fk(q[1])
    by_pose = stiffness(m, pose, data=data)
    np.testing.assert_allclose(by_pose.stiffness, one.stiffness, rtol=1e-6)


def test_internal_zero_energy_motion_is_not_a_mechanism():
    """A free rotation coaxial with leg 2's last passive joint adds an internal motion (the two
    turn against each other) that moves nothing: the compliance is unchanged."""
    m = machine("tripteor-x7")
    data = _data(m, SECTIONS["tripteor-x7"])
    system = assemble(m, m.home_q[None], data)
    c, _ = null_space_compliance(system.G, system.H, system.T, system.status)
    phi2 = m.model.variables.index("phi2")
    col = system.columns["passive"].start + m.passive_names.index("phi2")
    g2 = np.concatenate([system.G, system.G[:, :, col:col + 1]], axis=2)
    nz = g2.shape[2]
    h2 = np.zeros((1, nz, nz))
    h2[0, :-1, :-1] = system.H[0]
    t2 = np.concatenate([system.T, np.zeros((1, 6, 1))], axis=2)
    c2, status = null_space_compliance(g2, h2, t2, system.status)
    assert phi2 >= 0 and status[0] == 0
    np.testing.assert_allclose(c2, c, rtol=1e-8, atol=1e-10 * np.abs(c).max())


def test_rigid_block_directions_are_infinite_not_rounding_noise():
    """The crank–slider's piston is held rigidly in rotation by its slider: the rotational
    stiffness is inf, not the inverse of a rounding-level compliance."""
    m = machine("crank-slider")
    r = stiffness(m, q=m.home_q)
    assert np.isinf(r.rotational).all()
    assert np.isfinite(r.translational[0]) and np.isinf(r.translational[1:]).all()


def test_spring_rotations_and_twists_at_a_point_leave_their_pivot_still():
    """A rotation about an axis through a point P moves P by nothing: the spring twists'
    rotation columns (v, ω) satisfy v + ω × P = 0, and a twist about the origin seen as the
    small displacement of P (``_at_point``: v + ω × P) has no translation there — in the
    (6, k) and the (6, c, k) layouts."""
    from pkmkit.stiffness.joint_chains import _at_point

    rng = np.random.default_rng(3)
    point = rng.normal(size=(3, 4))
    axes = np.stack([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(4)], axis=2)
    tw = spring_twists(point, axes)
    for k in range(4):
        for c in range(3, 6):
            v, w = tw[:3, c, k], tw[3:, c, k]
            np.testing.assert_allclose(v + np.cross(w, point[:, k]), 0.0, atol=1e-14)
            np.testing.assert_allclose(w, axes[:, c - 3, k])
    moved = _at_point(tw, point)
    np.testing.assert_allclose(moved[:3, 3:], 0.0, atol=1e-14)
    np.testing.assert_allclose(_at_point(tw[:, 4], point)[:3], 0.0, atol=1e-14)
