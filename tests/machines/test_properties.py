"""Properties over random machines of every kind (tests/strategies.py): inverse ∘ direct round
trips in every assembly mode, analytic Jacobians against finite differences, mode names against
the geometry, invariance under a rigid motion of the whole machine and under a change of units.
"""

import math
import warnings

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import pkmkit
from pkmkit.exceptions import PkmError
from tests.strategies import (
    FAMILIES,
    five_bars,
    linear_deltas,
    load_text,
    near_home,
    orthoglides,
    rod_leg_specs,
    rod_legs_toml,
    well_posed,
)


@st.composite
def machine_and_pose(draw, family):
    m = draw(FAMILIES[family])
    x = near_home(draw, m)
    assume(well_posed(m, x))
    return m, x


every_family = pytest.mark.parametrize("family", sorted(FAMILIES))


@every_family
@given(data=st.data())
def test_inverse_direct_round_trip_in_every_mode(family, data):
    m, x = data.draw(machine_and_pose(family))
    q = m.ik(x)
    scale = float(m.model.leg_length.max())
    np.testing.assert_allclose(m.fk(q), x, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(m.fk(q, method="numeric"), x, rtol=0, atol=1e-9 * scale)
    modes = m.fk_all(q)
    assert modes.valid[0]
    np.testing.assert_allclose(modes.poses[0], x, atol=1e-11 * scale)
    for col in np.flatnonzero(modes.valid):
        back = m.ik(modes.poses[col], branches=modes.branches[col])
        # another mode's pose may sit near a leg's reach boundary (well_posed judges x only):
        # a rounding-level error δ of the pose moves q by the inverse model's gain, and within
        # the step of a boundary (gain None: the square root's) by up to sqrt(2 L δ)
        gain = mode_gain(m, modes.poses[col], modes.branches[col], 1e-6 * scale)
        tol = 1e-10 * scale * gain if gain is not None else math.sqrt(2e-11) * scale
        np.testing.assert_allclose(back, q, rtol=0, atol=tol)
    # the numeric inverse stops at its tolerance in pose space, which q sees through the gain
    gain = mode_gain(m, x, None, 1e-6 * scale) or 1.0
    np.testing.assert_allclose(m.ik(x, method="numeric"), q, rtol=0, atol=1e-10 * scale * gain)


def mode_gain(m, x, branches, h):
    """max(1, largest |∂q_i/∂x_j|) of the inverse model in one assembly mode at ``x``
    (central differences of step ``h``), or None where a shifted pose is out of reach (``x``
    within ``h`` of a leg's reach boundary, where the gain grows without bound)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = central(lambda v: np.asarray(m.ik(v, strokes="ignore", **(
                {} if branches is None else {"branches": branches})), float),
                np.asarray(x, float), h)
    except PkmError:
        return None
    return max(1.0, float(np.abs(d).max())) if np.isfinite(d).all() else None


def central(f, v, h):
    """Central differences of f at v, columns ∂f/∂v_i, step h."""
    cols = []
    for i in range(v.size):
        e = np.zeros_like(v)
        e[i] = h
        cols.append((f(v + e) - f(v - e)) / (2 * h))
    return np.stack(cols, axis=-1)


@every_family
@given(data=st.data(), direction=st.lists(st.floats(-1, 1), min_size=3, max_size=3))
def test_jacobians_against_finite_differences(family, data, direction):
    """J = ∂x/∂q (direct model), J⁻¹ = ∂q/∂x (inverse model), A ẋ = B q̇, and J̇ = dJ/dt along
    ẋ — each against central differences of an independent route."""
    m, x = data.draw(machine_and_pose(family))
    scale = float(m.model.leg_length.max())
    h = 1e-6 * scale
    jac = m.jacobian(x)
    q = m.ik(x)
    tol = 1e-6 * max(jac.condition, 1.0)
    j_fd = central(lambda v: m.fk(v), q, h)
    np.testing.assert_allclose(jac.J, j_fd, rtol=0, atol=tol * np.abs(j_fd).max())
    j_inv_fd = central(lambda v: m.ik(v), x, h)
    np.testing.assert_allclose(jac.J_inv, j_inv_fd, rtol=0, atol=tol * np.abs(j_inv_fd).max())
    np.testing.assert_allclose(jac.A @ jac.J, jac.B, atol=1e-12 * np.abs(jac.B).max())
    xd = np.asarray(direction[: m.dims])
    assume(np.linalg.norm(xd) > 0.1)
    rates = m.jacobian_dot(x, xd)
    np.testing.assert_allclose(rates.qd, jac.J_inv @ xd, rtol=1e-12, atol=1e-14)
    t = 1e-5 * scale
    j_dot_fd = (m.jacobian(x + t * xd).J - m.jacobian(x - t * xd).J) / (2 * t)
    np.testing.assert_allclose(rates.J_dot, j_dot_fd, rtol=0,
                               atol=tol * max(np.abs(j_dot_fd).max(), 1e-3 / scale))


def _side(m, pose, q):
    """The assembly mode's name that the geometry says ``pose`` is in (None: unknown kind)."""
    kind = m.kind.kind if m.kind is not None else "rod-legs"
    p = m.params
    if kind == "five-bar":
        u1 = np.array([math.cos(p["alpha1"]), math.sin(p["alpha1"])])
        u2 = np.array([math.cos(p["alpha2"]), math.sin(p["alpha2"])])
        c, d = np.asarray(p["A"]) + q[0] * u1, np.asarray(p["B"]) + q[1] * u2
        cross = (d - c)[0] * (pose - c)[1] - (d - c)[1] * (pose - c)[0]
        return "left-of-CD" if cross > 0 else "right-of-CD"
    if kind == "linear-delta":
        theta = np.asarray(p["angles"])
        d = p["R"] - p["r"]
        centres = np.column_stack([d * np.cos(theta), d * np.sin(theta), q])
        normal = np.cross(centres[1] - centres[0], centres[2] - centres[0])
        normal *= np.sign(normal[2])  # upward
        return "nacelle-below" if (pose - centres[0]) @ normal < 0 else "nacelle-above"
    if kind == "orthoglide":
        carriages = np.diag(q)
        normal = np.cross(carriages[1] - carriages[0], carriages[2] - carriages[0])
        origin_side = np.sign(-carriages[0] @ normal)
        return "origin-side" if np.sign((pose - carriages[0]) @ normal) == origin_side \
            else "far-side"
    # rod-legs: the sign of det of the rod vectors, one rod per leg (first rod of a pair)
    model = m.model
    rows = []
    for k in range(model.n_legs):
        j = np.flatnonzero(model.rod_leg == k)[0]
        centre = model.rod_base[j] + q[k] * model.rod_axis[j] - model.rod_platform[j]
        rows.append((model.pad(pose[None])[0] - centre)[: m.dims])
    return model.mode_names[0] if np.linalg.det(np.array(rows)) < 0 else model.mode_names[1]


@every_family
@given(data=st.data())
def test_mode_names_follow_the_geometry(family, data):
    """Each real assembly mode's name is the side of the carriage points' line or plane the
    tool point is on (built-in kinds) or the sign of det of the rod vectors (rod-legs)."""
    m, x = data.draw(machine_and_pose(family))
    q = m.ik(x)
    modes = m.fk_all(q)
    for col in np.flatnonzero(modes.valid):
        pose = modes.poses[col]
        jac = m.jacobian(pose, q=q)
        assume(jac.parallel_measure > 1e-3)
        assert modes.labels[col] == _side(m, pose, q)
        assert np.sign(jac.det_A) == modes.mode_signs[col]
    assert modes.labels[0] == m.mode_labels[0]


def _rotation(draw, dims):
    if dims == 2:
        a = draw(st.floats(-math.pi, math.pi))
        return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0],
                         [0, 0, 1.0]])
    v = np.array([draw(st.floats(-3, 3)) for _ in range(3)])
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    angle = np.linalg.norm(v)
    if angle < 1e-9:
        return np.eye(3)
    k /= angle
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


@given(st.data())
def test_rigid_motion_of_the_whole_machine(data):
    """Rotating and translating every base point, axis and platform offset (and the poses)
    changes no actuator value, no transmission factor and no mode name, and turns J with the
    machine: J' = R J."""
    spec = data.draw(rod_leg_specs())
    dims = spec.dims
    rot = _rotation(data.draw, dims)
    shift = np.array([data.draw(st.floats(-2, 2)) for _ in range(dims)] + [0.0] * (3 - dims))
    try:
        m = load_text(rod_legs_toml(spec))
        moved = load_text(rod_legs_toml(spec, rotation=rot, translation=shift))
    except pkmkit.PkmError:
        assume(False)
        raise
    x = near_home(data.draw, m)
    assume(well_posed(m, x))
    x_moved = (rot @ np.append(x, [0.0] * (3 - dims)) + shift)[:dims]
    scale = float(m.model.leg_length.max())
    q = m.ik(x)
    np.testing.assert_allclose(moved.ik(x_moved), q, rtol=0, atol=1e-11 * scale)
    jac, jac_moved = m.jacobian(x), moved.jacobian(x_moved)
    np.testing.assert_allclose(jac_moved.singular_values, jac.singular_values, rtol=1e-9)
    np.testing.assert_allclose(jac_moved.J, rot[:dims, :dims] @ jac.J, atol=1e-9 * np.abs(
        jac.J).max())
    np.testing.assert_allclose(moved.fk(q), x_moved, atol=1e-11 * scale)
    a, b = m.fk_all(q), moved.fk_all(q)
    assert a.valid.tolist() == b.valid.tolist() and a.labels == b.labels


@given(st.data())
def test_change_of_units(data):
    """The same machine file in mm or in m is the same machine; and a machine scaled by s has
    actuator values × s, the same J and J̇ / s (a dimensional formula with a wrong power of a
    length fails here, whatever the machine)."""
    spec = data.draw(rod_leg_specs())
    try:
        m = load_text(rod_legs_toml(spec))
        mm = load_text(rod_legs_toml(spec, units="mm"))
    except pkmkit.PkmError:
        assume(False)
        raise
    x = near_home(data.draw, m)
    assume(well_posed(m, x))
    scale = float(m.model.leg_length.max())
    np.testing.assert_allclose(mm.ik(x), m.ik(x), rtol=1e-12, atol=1e-13 * scale)
    np.testing.assert_allclose(mm.jacobian(x).J, m.jacobian(x).J, rtol=1e-9, atol=1e-12)
    s = data.draw(st.floats(0.01, 100.0))
    spec_scaled = type(spec)(dims=spec.dims, home=spec.home * s, mode_names=spec.mode_names,
                             legs=[type(leg)(leg.kind, leg.base * s, leg.axis,
                                             leg.platform * s, leg.length * s, leg.branch,
                                             leg.width * s, leg.direction)
                                   for leg in spec.legs])
    scaled = load_text(rod_legs_toml(spec_scaled))
    xd = np.ones(m.dims)
    np.testing.assert_allclose(scaled.ik(s * x), s * m.ik(x), rtol=1e-10, atol=1e-12 * s * scale)
    np.testing.assert_allclose(scaled.jacobian(s * x).J, m.jacobian(x).J, rtol=1e-9,
                               atol=1e-12)
    np.testing.assert_allclose(scaled.jacobian_dot(s * x, xd).J_dot,
                               m.jacobian_dot(x, xd).J_dot / s, rtol=1e-8,
                               atol=1e-10 * np.abs(m.jacobian_dot(x, xd).J_dot).max() / s)


@given(st.data())
def test_built_in_kinds_scale_with_their_dimensions(data):
    """Every length parameter × s: actuator values × s (slides measured from a point that
    scales too), J unchanged — for each built-in kind."""
    m = data.draw(st.one_of(linear_deltas(), orthoglides(), five_bars()))
    x = near_home(data.draw, m)
    assume(well_posed(m, x))
    s = data.draw(st.floats(0.01, 100.0))
    lengths = {spec.name for spec in m.kind.parameters if spec.quantity == "length"}
    scaled = m.with_params(**{k: (np.asarray(v) * s if np.ndim(v) else v * s)
                              for k, v in m.params.items() if k in lengths})
    np.testing.assert_allclose(scaled.ik(s * x), s * m.ik(x), rtol=1e-10,
                               atol=1e-12 * s * float(m.model.leg_length.max()))
    np.testing.assert_allclose(scaled.jacobian(s * x).J, m.jacobian(x).J, rtol=1e-9,
                               atol=1e-12)
