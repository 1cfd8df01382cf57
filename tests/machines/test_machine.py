"""Generic behaviour of :class:`pkmkit.Machine` on every preset and on random machines."""

import warnings

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import pkmkit
from pkmkit.exceptions import (
    InputError,
    NoAssemblyError,
    SingularConfigurationError,
    UnreachablePoseError,
)
from pkmkit.numerics.linalg import batched_det
from pkmkit.status import Status
from tests.conftest import random_poses


def test_round_trip_and_every_mode_closes(preset):
    x = random_poses(preset, 300, seed=1)
    q = preset.ik(x)
    modes = preset.fk_all(q)
    assert modes.valid.all()
    np.testing.assert_allclose(modes.poses[:, 0], x, atol=1e-12)
    # both modes satisfy every leg closure, and the mode is the sign of det A
    for col in range(2):
        p = modes.poses[:, col]
        jac = preset.jacobian(p, q=q)
        lengths = np.linalg.norm(jac.A, axis=2)
        np.testing.assert_allclose(lengths, preset.model.leg_length[None].repeat(300, 0),
                                   atol=1e-12)
        assert (np.sign(jac.det_A) == modes.mode_signs[col]).all()
    assert modes.labels == preset.mode_labels


def test_jacobian_matches_finite_differences_of_the_models(preset):
    x = random_poses(preset, 20, seed=2)
    jac = preset.jacobian(x)
    h = 1e-6
    for j in range(preset.dims):
        dx = np.zeros(preset.dims)
        dx[j] = h
        dq = (preset.ik(x + dx) - preset.ik(x - dx)) / (2 * h)  # column j of J^-1
        np.testing.assert_allclose(jac.J_inv[:, :, j], dq, atol=1e-7)
    q = jac.q
    for i in range(preset.n_actuators):
        dq = np.zeros(preset.n_actuators)
        dq[i] = h
        dp = (preset.fk(q + dq) - preset.fk(q - dq)) / (2 * h)  # column i of J
        np.testing.assert_allclose(jac.J[:, :, i], dp, atol=1e-7)
    np.testing.assert_allclose(np.einsum("kij,kjl->kil", jac.J, jac.J_inv),
                               np.broadcast_to(np.eye(preset.dims), jac.J.shape), atol=1e-10)
    sv = np.linalg.svd(jac.J, compute_uv=False)
    np.testing.assert_allclose(jac.singular_values, sv, rtol=1e-12)
    np.testing.assert_allclose(jac.condition, sv[:, 0] / sv[:, -1], rtol=1e-12)
    np.testing.assert_allclose(jac.det_A, np.linalg.det(jac.A), rtol=1e-10)


def test_jacobian_rate_matches_finite_differences(preset):
    rng = np.random.default_rng(3)
    x = random_poses(preset, 10, seed=3)
    xd = rng.normal(size=x.shape)
    rates = preset.jacobian_dot(x, xd)
    h = 1e-6
    fd = (preset.jacobian(x + h * xd).J - preset.jacobian(x - h * xd).J) / (2 * h)
    np.testing.assert_allclose(rates.J_dot, fd, rtol=1e-7, atol=1e-8)
    fd_a = (preset.jacobian(x + h * xd).A - preset.jacobian(x - h * xd).A) / (2 * h)
    np.testing.assert_allclose(rates.A_dot, fd_a, rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose(rates.qd, (preset.ik(x + h * xd) - preset.ik(x - h * xd)) / (2 * h),
                               atol=1e-7)


def test_power_balance_of_the_velocity_model(preset):
    """Actuator forces f = Jᵀ F balance the platform force: f·q̇ = F·ẋ."""
    rng = np.random.default_rng(4)
    x = random_poses(preset, 50, seed=4)
    jac = preset.jacobian(x)
    qd = rng.normal(size=(50, preset.n_actuators))
    force = rng.normal(size=(50, preset.dims))
    xd = np.einsum("kij,kj->ki", jac.J, qd)
    f = np.einsum("kji,kj->ki", jac.J, force)
    np.testing.assert_allclose((f * qd).sum(1), (force * xd).sum(1), rtol=1e-10, atol=1e-12)


def test_single_and_batch_shapes(preset):
    x = preset.home_pose
    assert preset.ik(x).shape == (preset.n_actuators,)
    assert preset.ik(x[None]).shape == (1, preset.n_actuators)
    jac = preset.jacobian(x)
    assert jac.A.shape == (preset.n_actuators, preset.dims) and np.ndim(jac.condition) == 0
    assert isinstance(jac.status, str)
    batch = preset.jacobian(np.stack([x, x]))
    assert batch.J.shape == (2, preset.dims, preset.n_actuators) and len(batch.status) == 2
    res = preset.fk(preset.home_q, full_output=True)
    assert res.pose.shape == (preset.dims,) and int(res.status) == Status.OK
    assert res.mode_label == preset.mode_labels[0]


def test_mode_selection(preset):
    q = preset.home_q
    modes = preset.fk_all(q)
    other = preset.fk(q, mode="other")
    np.testing.assert_allclose(other, modes.poses[1], atol=1e-12)
    np.testing.assert_allclose(preset.fk(q, mode=preset.mode_labels[1]), other, atol=1e-12)
    np.testing.assert_allclose(preset.fk(q, mode=-preset.working_mode), other, atol=1e-12)
    with pytest.raises(InputError, match="unknown assembly mode"):
        preset.fk(q, mode="sideways")


def test_unreachable_single_pose_names_leg_and_shortfall():
    m = pkmkit.machine("linear-delta")
    x = np.array([2.0, 0.0, 0.0])  # leg 1 reaches at most R - r + L = 1.85 m along x
    with pytest.raises(UnreachablePoseError) as info:
        m.ik(x)
    err = info.value
    # legs 2 and 3 sit at -0.275 m: the horizontal distance is hypot(2.275, 0.476) > L
    expected = np.hypot(2.0 + 0.275, 0.55 * np.sqrt(3) / 2) - 1.3
    assert err.leg in (1, 2) and err.shortfall == pytest.approx(expected)
    assert "too short by" in str(err) and m.model.leg_names[err.leg] in str(err)


def test_batch_flags_bad_rows_and_keeps_good_ones():
    m = pkmkit.machine("linear-delta")
    x = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [np.nan, 0.0, 0.0], [0.0, 0.0, np.inf],
                  [0.25, 0.25, 0.0]])
    res = m.ik(x, full_output=True)
    assert res.status.tolist() == [Status.OK, Status.UNREACHABLE, Status.INVALID_INPUT,
                                   Status.INVALID_INPUT, Status.OK]
    assert np.isnan(res.q[1:4]).all() and np.isfinite(res.q[[0, 4]]).all()
    assert res.shortfall[1].max() > 0 and (res.shortfall[[0, 4]] < 0).all()
    q = m.ik(x)
    fk = m.fk(q, full_output=True)
    assert fk.status.tolist() == [Status.OK] + [Status.INVALID_INPUT] * 3 + [Status.OK]
    jac = m.jacobian(x)
    assert jac.status == ["regular", "unreachable", "unreachable", "unreachable", "regular"]


def test_non_finite_and_misshaped_inputs():
    m = pkmkit.machine("orthoglide")
    with pytest.raises(InputError, match="not finite"):
        m.ik([0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="not finite"):
        m.fk([0.3, 0.3, np.inf])
    with pytest.raises(InputError, match="3 components"):
        m.ik([0.0, 0.0])
    with pytest.raises(InputError, match="shape"):
        m.jacobian(np.zeros((2, 4)))
    with pytest.raises(InputError, match="branches"):
        m.ik([0, 0, 0], branches=[1, 0, 1])
    with pytest.raises(InputError, match="method"):
        m.ik([0, 0, 0], method="magic")


def test_no_assembly_single_call():
    m = pkmkit.machine("five-bar")
    with pytest.raises(NoAssemblyError, match="no real assembly"):
        m.fk([5.0, -5.0])
    modes = m.fk_all([5.0, -5.0])
    assert modes.count == 0 and modes.status == Status.NO_ASSEMBLY


def test_aligned_centres_are_singular():
    m = pkmkit.machine("five-bar-biglide")
    # both carriages at the same point: the circles coincide
    q = np.array([0.5, 0.5 - m.model.leg_base[1, 0]])
    with pytest.raises(SingularConfigurationError):
        m.fk(q)


def test_branch_choice_changes_the_inverse_model():
    m = pkmkit.machine("linear-delta")
    x = np.array([0.1, 0.0, 0.0])
    up = m.ik(x)
    down = m.ik(x, branches=[1, -1, 1])
    assert down[1] < x[2] < up[1] and down[0] == up[0]
    res = m.fk(down, full_output=True)
    assert res.branches.tolist() == [1, -1, 1]


def test_with_params_rebuilds():
    m = pkmkit.machine("linear-delta").with_params(L=1.04)
    assert m.params["L"] == 1.04
    assert m.ik([0, 0, 0]) == pytest.approx([0.882666] * 3, abs=1e-6)


@given(
    big_r=st.floats(0.3, 1.0),
    small_r=st.floats(0.05, 0.25),
    extra=st.floats(0.3, 1.0),
    angle=st.floats(60.0, 170.0),
    offset=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
)
def test_random_linear_deltas_round_trip(big_r, small_r, extra, angle, offset):
    length = big_r - small_r + extra
    m = pkmkit.machine("linear-delta", R=big_r, r=small_r, L=length,
                       angles=tuple(np.radians([0.0, angle, 2 * angle])))
    # within 0.2·extra·√2 < extra of the axis horizontally: every leg reaches (0.2·L did not)
    x = 0.2 * extra * np.asarray(offset)
    q = m.ik(x)
    np.testing.assert_allclose(m.fk(q), x, atol=1e-10)
    np.testing.assert_allclose(m.fk(q, method="numeric"), x, atol=1e-9)


@given(
    alpha1=st.floats(-60, 60),
    alpha2=st.floats(30, 150),
    length=st.floats(0.3, 1.0),
    bx=st.floats(0.5, 1.5),
    by=st.floats(-1.5, -0.5),
    offset=st.tuples(st.floats(-1, 1), st.floats(-1, 1)),
)
def test_random_five_bars_round_trip(alpha1, alpha2, length, bx, by, offset):
    # (nearly) parallel slides: the automatic home needs collinear slides
    assume(abs(alpha2 - alpha1) >= 20 and abs(abs(alpha2 - alpha1) - 180) >= 20)
    m = pkmkit.machine("five-bar", alpha1=np.radians(alpha1), alpha2=np.radians(alpha2),
                       L=length, B=(bx, by))
    x = m.home_pose + 0.1 * length * np.asarray(offset)
    q = m.ik(x)
    np.testing.assert_allclose(m.fk(q), x, atol=1e-10)
    modes = m.fk_all(q)
    assert np.sign(batched_det(m.jacobian(modes.poses, q=np.stack([q, q])).A)).tolist() == \
        modes.mode_signs.tolist()


def _decimal_singular_values(rows):
    """Singular values of a small float matrix in 50-digit decimal arithmetic (cyclic Jacobi
    on MᵀM), largest first."""
    from decimal import Decimal, getcontext

    getcontext().prec = 50
    a = [[Decimal(float(v)) for v in row] for row in rows]
    n = len(a)
    m = [[sum(a[k][i] * a[k][j] for k in range(n)) for j in range(n)] for i in range(n)]
    for _ in range(60):
        off = sum(abs(m[i][j]) for i in range(n) for j in range(n) if i != j)
        if off < Decimal(10) ** -45:
            break
        for p in range(n):
            for q in range(p + 1, n):
                if m[p][q] == 0:
                    continue
                theta = (m[q][q] - m[p][p]) / (2 * m[p][q])
                t = (1 if theta >= 0 else -1) / (abs(theta) + (theta * theta + 1).sqrt())
                c = 1 / (t * t + 1).sqrt()
                s_ = t * c
                for k in range(n):  # M ← Gᵀ M G
                    mkp, mkq = m[k][p], m[k][q]
                    m[k][p], m[k][q] = c * mkp - s_ * mkq, s_ * mkp + c * mkq
                for k in range(n):
                    mpk, mqk = m[p][k], m[q][k]
                    m[p][k], m[q][k] = c * mpk - s_ * mqk, s_ * mpk + c * mqk
    return sorted((m[i][i].sqrt() for i in range(n)), reverse=True)


@pytest.mark.parametrize("ident, start, end", [
    ("five-bar", [1.0, 0.0], [0.7, -0.5]),
    ("orthoglide", [0.0, 0.0, 0.0], [0.2, 0.2, 0.2]),
])
def test_transmission_factors_stay_accurate_near_a_parallel_singularity(ident, start, end):
    """Poses approaching a parallel singularity (κ up to ~1e5–1e6): the singular values of J
    equal the reversed reciprocals of those of J⁻¹ = B⁻¹A computed here from the same A and B
    in 50-digit decimal arithmetic — to ~eps·κ, not the eps·κ² of forming A⁻¹."""
    m = pkmkit.machine(ident)
    start, end = np.array(start), np.array(end)
    sign0 = np.sign(m.jacobian(start).det_A)
    lo, hi = 0.0, 1.0
    for _ in range(200):  # bisect det A along the segment
        mid = 0.5 * (lo + hi)
        res = m.jacobian(start + mid * (end - start))
        lo, hi = (mid, hi) if np.isfinite(res.det_A) and np.sign(res.det_A) == sign0 else (lo,
                                                                                            mid)
    for gap in (1e-3, 1e-4, 1e-5, 2e-6):  # closer, the pose is classified parallel (NaN)
        jac = m.jacobian(start + (lo - gap) * (end - start))
        if jac.status != "regular":
            continue
        inverse_rows = jac.A / np.diag(jac.B)[:, None]
        sigma = _decimal_singular_values(inverse_rows)
        expected = np.array([float(1 / v) for v in sigma[::-1]])
        kappa = expected[0] / expected[-1]
        np.testing.assert_allclose(jac.singular_values, expected, rtol=50 * 2.2e-16 * kappa)


def test_jacobian_dot_batch_flags_rows_with_absurd_velocities():
    """A batch row with an infinite or 1e308 velocity gives NaN rates (no overflow warning);
    the other rows are those of the same call on them alone."""
    m = pkmkit.machine("linear-delta-ch3")
    x = np.array([[0.0, 0.0, 0.0], [-0.05, 0.02, 0.01], [0.03, 0.0, -0.02]])
    xd = np.array([[1.3e308, 0.0, 0.0], [0.1, -0.2, 0.05], [np.inf, 0.0, 0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rates = m.jacobian_dot(x, xd)
    assert np.isnan(rates.J_dot[[0, 2]]).all() and np.isnan(rates.qd[[0, 2]]).all()
    alone = m.jacobian_dot(x[1], xd[1])
    np.testing.assert_allclose(rates.J_dot[1], alone.J_dot, rtol=1e-12)
    np.testing.assert_allclose(rates.qd[1], alone.qd, rtol=1e-12)
