"""Rod-leg elastostatics against independent oracles."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import InputError, ParameterError
from pkmkit.machines.registry import machine
from pkmkit.stiffness import Material, Section, default_data, stiffness
from pkmkit.stiffness.data import StiffnessData

from .helpers import cubic_hexapod


def _data(m, k, **changes) -> StiffnessData:
    return dataclasses.replace(default_data(m), actuator_stiffness=np.full(m.n_actuators, k),
                               **changes)


def test_cubic_hexapod_about_its_centre():
    a, k = 0.5, 2e7
    m = cubic_hexapod(a)
    result = stiffness(m, np.zeros(6), data=_data(m, k))
    expected = k * np.diag([2, 2, 2, a * a / 2, a * a / 2, 2 * a * a])
    np.testing.assert_allclose(result.stiffness, expected, rtol=1e-12, atol=1e-9 * k)


@pytest.mark.parametrize("scale", [1e-3, 1e3])
def test_cubic_hexapod_of_any_size_is_regular_with_the_scaled_stiffness(scale):
    """The cubic hexapod 1000 times smaller or larger: still regular at home (the singularity
    test scales the moment rows by the characteristic length, so it does not depend on the
    unit or size), forces 2k, moments k a²/2, 2k a² with a the scaled side (rtol 1e-6: the
    diagonal spans 10⁷ at 1e-3, the round-off of the compliance's inverse)."""
    a, k = 0.5 * scale, 2e7
    m = cubic_hexapod(scale=scale)
    result = stiffness(m, m.home_pose, data=_data(m, k))
    assert result.status == 0
    np.testing.assert_allclose(np.diag(result.stiffness),
                               k * np.array([2, 2, 2, a * a / 2, a * a / 2, 2 * a * a]),
                               rtol=1e-6)


def test_singularity_flag_does_not_depend_on_the_size():
    """The singularity test is a condition number of A with its moment columns divided by
    the characteristic length: the cubic hexapod at home is regular at every size, from 10⁻⁶
    to 10⁶ times its own (a size-dependent test flags the small ones)."""
    for scale in (1e-6, 1e-3, 1.0, 1e3, 1e6):
        m = cubic_hexapod(scale=scale)
        assert stiffness(m, m.home_pose[None]).status.tolist() == [0], scale


def test_hexapod_is_k_atransposed_a_with_unit_rows():
    m = machine("gough-stewart")
    k = 3e7
    rng = np.random.default_rng(4)
    poses = m.home_pose + rng.uniform(-1, 1, (20, 6)) * [0.05, 0.05, 0.05, 0.05, 0.05, 0.05]
    result = stiffness(m, poses, data=_data(m, k))
    assert (result.status == 0).all()
    rot = Rotation.from_rotvec(poses[:, 3:]).as_matrix()
    for n in range(len(poses)):
        rows = []
        for j in range(6):
            b = rot[n] @ m.model.rod_platform[j]
            d = poses[n, :3] + b - m.model.rod_base[j]
            u = d / np.linalg.norm(d)
            rows.append(np.concatenate([u, np.cross(b, u)]))
        a = np.array(rows)
        np.testing.assert_allclose(result.stiffness[n], k * a.T @ a, rtol=1e-9,
                                   atol=1e-9 * k)


def test_orthoglide_isotropic_then_k_over_psi_squared():
    m = machine("orthoglide")
    k = 1e8
    home = stiffness(m, m.home_pose, data=_data(m, k))
    np.testing.assert_allclose(home.stiffness, k * np.eye(3), rtol=1e-10, atol=1e-3)
    rng = np.random.default_rng(1)
    poses = m.home_pose + rng.uniform(-0.08, 0.08, (50, 3))
    result = stiffness(m, poses, data=_data(m, k))
    psi = m.jacobian(poses).singular_values
    np.testing.assert_allclose(np.sort(result.eigenvalues, axis=1),
                               np.sort(k / psi**2, axis=1), rtol=1e-9)


def test_different_actuator_stiffness_is_j_inverse_transposed_kq_j_inverse():
    m = machine("delta")
    kq = np.array([1e5, 2e5, 4e5])
    x = m.home_pose + np.array([0.05, -0.03, 0.02])
    result = stiffness(m, x, data=dataclasses.replace(default_data(m), actuator_stiffness=kq))
    j_inv = np.linalg.inv(m.jacobian(x).J)
    np.testing.assert_allclose(result.stiffness, j_inv.T @ np.diag(kq) @ j_inv, rtol=1e-10)


# ------------------------------------------------------------ energy Hessian (kinematics only)
def _rod_energy_stiffness(m, x0, q0, kq, k_rod, full, h=1e-5):
    """K from the Hessian of the elastic energy E(x, q) = ½ Σ k_a (q − q0)² + ½ Σ k_r (|d_j| −
    ℓ_j)², d_j from the rod geometry alone, by central differences, then condensed over the
    actuator displacements (Schur complement). Rows of the equivalent legs (translating
    platforms) or of every rod (full-pose machines)."""
    model = m.model
    x0 = np.array(x0, dtype=float)  # a record's pose is read-only, and scipy needs writeable
    if full:
        base, axis, plat = model.rod_base, model.rod_axis, model.rod_platform
        act, kind = model.rod_actuator, model.rod_kind
        ell0 = None
    else:
        base, axis, plat = model.leg_base, model.leg_axis, model.leg_platform
        act, kind = model.leg_actuator, model.leg_kind

    def rods(u):
        dx, dq = u[: len(x0)], u[len(x0):]
        q = q0 + dq
        if full:
            p = x0[:3] + dx[:3]
            rot = Rotation.from_rotvec(dx[3:]).as_matrix() @ Rotation.from_rotvec(
                x0[3:]).as_matrix()
        else:
            p = np.zeros(3)
            p[: len(x0)] = x0 + dx
            rot = np.eye(3)
        out = []
        for j in range(len(base)):
            qa = q[act[j]]
            a_j = base[j] + (qa * axis[j] if kind[j] == 0 else 0.0)
            length = np.linalg.norm(p + rot @ plat[j] - a_j)
            out.append(length - (qa if kind[j] == 1 else 0.0))
        return np.array(out)

    ell0 = rods(np.zeros(len(x0) + len(q0)))

    def energy(u):
        dq = u[len(x0):]
        return 0.5 * np.sum(kq * dq**2) + 0.5 * np.sum(k_rod * (rods(u) - ell0) ** 2)

    n = len(x0) + len(q0)
    hess = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            ei, ej = np.eye(n)[i] * h, np.eye(n)[j] * h
            hess[i, j] = (energy(ei + ej) - energy(ei - ej) - energy(-ei + ej)
                          + energy(-ei - ej)) / (4 * h * h)
    d = len(x0)
    kxx, kxq, kqq = hess[:d, :d], hess[:d, d:], hess[d:, d:]
    return kxx - kxq @ np.linalg.solve(kqq, kxq.T)


@pytest.mark.parametrize("name", ["linear-delta", "orthoglide", "five-bar", "verne",
                                  "dietmaier-hexapod"])
def test_energy_hessian_by_finite_differences(name):
    m = machine(name)
    full = m.model.full_pose
    section = Section.circle(0.012)
    data = dataclasses.replace(default_data(m), rod_section=section, rod_material=Material())
    x0 = m.home_pose.copy()
    if not full:
        x0 = x0 + 0.02 * np.arange(1, m.dims + 1) / m.dims
    result = stiffness(m, x0 if name != "verne" else x0[:3], data=data)
    q0 = m.ik(x0) if name != "verne" else m.ik(x0[:3])
    if name == "verne":
        x0 = np.asarray(m.ik(x0[:3], full_output=True).pose)
    ea = section.area * 210e9
    if full:
        rows = np.linalg.norm(m.jacobian(x0, q=q0).A[:, :3], axis=1)
        k_rod = ea / rows
    else:
        counts = np.bincount(m.model.rod_leg)
        k_rod = ea * counts / m.model.leg_length
    kq = data.actuator_stiffness
    expected = _rod_energy_stiffness(m, x0, q0, kq, k_rod, full)
    scale = np.abs(expected).max()
    np.testing.assert_allclose(result.stiffness, expected, rtol=1e-5, atol=1e-6 * scale)


def test_rod_compliance_adds_in_series_for_struts():
    """A strut's drive and its rod carry the same force: 1/k = 1/k_a + ℓ/(EA)."""
    a, k = 0.5, 2e7
    m = cubic_hexapod(a)
    section = Section.circle(0.02)
    result = stiffness(m, np.zeros(6), data=_data(m, k, rod_section=section))
    k_leg = 1.0 / (1.0 / k + a / (210e9 * section.area))
    expected = k_leg * np.diag([2, 2, 2, a * a / 2, a * a / 2, 2 * a * a])
    np.testing.assert_allclose(result.stiffness, expected, rtol=1e-12, atol=1e-9 * k)


# ------------------------------------------------------------ invariances
def test_rigid_motion_of_the_whole_machine():
    a, k = 0.4, 1e7
    motion = np.eye(4)
    rot = Rotation.from_rotvec([0.3, -0.5, 0.7]).as_matrix()
    motion[:3, :3], motion[:3, 3] = rot, [0.2, -0.1, 0.9]
    plain, moved = cubic_hexapod(a), cubic_hexapod(a, motion=motion)
    pose = np.array([0.01, -0.02, 0.015, 0.02, 0.01, -0.03])
    moved_pose = np.concatenate([rot @ pose[:3] + motion[:3, 3], (Rotation.from_matrix(rot)
                                 * Rotation.from_rotvec(pose[3:])).as_rotvec()])
    k0 = stiffness(plain, pose, data=_data(plain, k), reference=[0.05, 0.0, 0.1]).stiffness
    k1 = stiffness(moved, moved_pose, data=_data(moved, k), reference=[0.05, 0.0, 0.1]).stiffness
    big = np.zeros((6, 6))
    big[:3, :3] = big[3:, 3:] = rot
    np.testing.assert_allclose(k1, big @ k0 @ big.T, rtol=1e-9, atol=1e-9 * k)


def test_change_of_units():
    """Lengths in mm (and N/mm, N·mm) give K_mm = E K_SI D⁻¹: twists t_mm = D t_SI with
    D = diag(s, s, s, 1, 1, 1), wrenches w_mm = E w_SI with E = diag(1, 1, 1, s, s, s) = s D⁻¹."""
    a, k, s = 0.4, 1e7, 1000.0
    pose = np.array([0.01, -0.02, 0.015, 0.02, 0.01, -0.03])
    si = stiffness(cubic_hexapod(a), pose, data=_data(cubic_hexapod(a), k)).stiffness
    mm_machine = cubic_hexapod(a, scale=s)
    pose_mm = np.concatenate([pose[:3] * s, pose[3:]])
    mm = stiffness(mm_machine, pose_mm, data=_data(mm_machine, k / s)).stiffness
    d_inv = np.diag([1 / s] * 3 + [1.0] * 3)
    np.testing.assert_allclose(mm, s * d_inv @ si @ d_inv, rtol=1e-9, atol=1e-12 * np.abs(mm).max())


# ------------------------------------------------------------ behaviour
def test_deflection_is_compliance_times_wrench_and_batches_match_single():
    m = machine("gough-stewart")
    rng = np.random.default_rng(2)
    poses = m.home_pose + rng.uniform(-0.03, 0.03, (5, 6))
    w = np.array([100.0, -50.0, 300.0, 5.0, -2.0, 1.0])
    batch = stiffness(m, poses, wrench=w)
    for n in range(5):
        one = stiffness(m, poses[n], wrench=w)
        np.testing.assert_allclose(one.stiffness, batch.stiffness[n], rtol=1e-12)
        np.testing.assert_allclose(one.deflection, np.linalg.solve(one.stiffness, w),
                                   rtol=1e-9)


def test_batch_flags_unreachable_rows_and_keeps_the_others():
    m = machine("orthoglide")
    poses = np.array([m.home_pose, m.home_pose + 5.0, [np.nan, 0.0, 0.0]])
    result = stiffness(m, poses)
    assert result.status.tolist()[0] == 0
    assert (result.status[1:] != 0).all()
    assert np.isnan(result.stiffness[1:]).all()
    assert np.isfinite(result.stiffness[0]).all()


def test_verne_with_rigid_rods_is_rigid_in_three_directions():
    m = machine("verne")
    result = stiffness(m, m.home_pose[:3])
    assert result.rigid == 3
    assert np.isnan(result.stiffness).all()
    assert np.isinf(result.eigenvalues[3:]).all()
    assert np.isfinite(result.compliance).all()


@pytest.mark.parametrize("bad", [0.0, -1.0, np.inf, np.nan])
def test_bad_actuator_stiffness_is_refused(bad):
    with pytest.raises(ParameterError, match=r"actuator_stiffness\[1\]"):
        StiffnessData(actuator_stiffness=np.array([1e8, bad, 1e8]))


def test_wrench_of_the_wrong_width_is_refused():
    m = machine("orthoglide")
    with pytest.raises(InputError, match="wrench"):
        stiffness(m, m.home_pose, wrench=[1.0, 2.0])
    with pytest.raises(InputError, match="reference"):
        stiffness(m, m.home_pose, reference=[0.0, 0.0, 0.1])


def test_a_wrench_beyond_1e9_is_refused_with_its_row_and_component():
    """A finite wrench of 1e308 N gave deflections of 4e300 m (exit 0 in a script)."""
    m = machine("linear-delta")
    with pytest.raises(InputError, match=r"wrench component 1 \(dx\) = 1e\+308 is beyond 1e\+09"):
        stiffness(m, [0.0, 0.0, 0.0], wrench=[1e308, 1e308, 0.0])
    with pytest.raises(InputError, match=r"wrench row 1, component 3 \(dz\) = -2e\+09"):
        stiffness(m, [[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]], wrench=[[1.0, 0, 0], [0, 0, -2e9]])


def test_a_deflection_that_overflows_flags_its_row():
    """C w overflowing (a compliance of 1e300 m/N: a mechanism in all but name) gave an inf
    deflection on a row said to be OK; now that row is SINGULAR and NaN, the other kept."""
    from pkmkit.status import Status
    from pkmkit.stiffness.results import summarize

    c = np.array([np.eye(3) * 1e300, np.eye(3) * 1e-8])
    with np.errstate(all="raise"):
        r = summarize(c, np.zeros(2, dtype=int), ("dx", "dy", "dz"), "p",
                      np.array([1e9, 0.0, 0.0]))
    assert r.status.tolist() == [Status.SINGULAR, Status.OK]
    assert np.isnan(r.deflection[0]).all() and np.isnan(r.compliance[0]).all()
    np.testing.assert_allclose(r.deflection[1], [10.0, 0.0, 0.0])


def test_reference_point_moved_in_the_platform_frame():
    """K about a point r (platform frame) is k Σ [u, (R b − R r) × u]ᵀ[u, (R b − R r) × u]."""
    m = machine("gough-stewart")
    k = 3e7
    pose = m.home_pose + np.array([0.02, -0.01, 0.03, 0.05, -0.04, 0.1])
    offset = np.array([0.05, -0.02, -0.2])
    result = stiffness(m, pose, data=_data(m, k), reference=offset)
    rot = Rotation.from_rotvec(pose[3:]).as_matrix()
    rows = []
    for j in range(6):
        b = rot @ m.model.rod_platform[j]
        d = pose[:3] + b - m.model.rod_base[j]
        u = d / np.linalg.norm(d)
        rows.append(np.concatenate([u, np.cross(b - rot @ offset, u)]))
    a = np.array(rows)
    np.testing.assert_allclose(result.stiffness, k * a.T @ a, rtol=1e-9, atol=1e-9 * k)


@pytest.mark.parametrize("bad", [1e308, 1e-300])
def test_absurd_actuator_stiffness_is_a_units_mistake(bad):
    with pytest.raises(ParameterError, match="check the units"):
        StiffnessData(actuator_stiffness=np.array([1e8, 1e8, bad]))


def test_reference_point_of_a_machine_given_positions_turns_with_its_platform():
    """The Verne module is driven by positions, but its platform tilts (orientation from ik):
    the compliance about a point r of the platform is that about the platform origin carried
    to p = R r (a wrench [f, m] at p is [f, m + p × f] at the origin; the point moves by
    v + ω × p), R from the rotation vector ik reports."""
    m = machine("verne")
    x = np.array([0.02, -0.01, 0.01])
    offset = np.array([0.01, 0.02, -0.05])
    c0 = stiffness(m, x).compliance
    moved = stiffness(m, x, reference=offset).compliance
    rotvec = np.atleast_2d(m.ik(x, full_output=True, strokes="ignore").pose)[0, 3:]
    assert np.linalg.norm(rotvec) > 1e-3  # the platform is tilted there
    p = Rotation.from_rotvec(np.array(rotvec)).apply(offset)  # scipy: writeable only
    oracle = np.zeros((6, 6))
    for i, w in enumerate(np.eye(6)):
        t = c0 @ np.concatenate([w[:3], w[3:] + np.cross(p, w[:3])])
        oracle[:, i] = np.concatenate([t[:3] + np.cross(t[3:], p), t[3:]])
    np.testing.assert_allclose(moved, oracle, rtol=1e-9, atol=1e-9 * np.abs(oracle).max())
