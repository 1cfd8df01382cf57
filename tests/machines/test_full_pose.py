"""Full-pose rod machines (hexapod, Verne-type module, six-DOF files): closed-form IK against
leg lengths written here with scipy's Rotation and against the generic engine, IK∘FK round
trips on 1000 poses, twist Jacobians against finite differences, the Verne module's coupled
tilt against its symmetry, and bad input."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.exceptions import InputError, ParameterError, UnreachablePoseError
from pkmkit.machines.full_pose import FullPoseMachine
from pkmkit.machines.full_pose_forms import FullPoseForms
from pkmkit.solve.rod_closure import solve_inverse
from pkmkit.spatial import pose_difference, pose_from_angles
from pkmkit.status import Status

RNG = np.random.default_rng(8)


@pytest.fixture(scope="module")
def hexapod():
    return pkmkit.machine("gough-stewart")


@pytest.fixture(scope="module")
def verne():
    return pkmkit.machine("verne")


def _hexapod_poses(m, n, seed=0):
    rng = np.random.default_rng(seed)
    lo, hi = m.default_box()
    return pose_from_angles(rng.uniform(lo, hi, (n, 3)), rng.uniform(-12, 12, (n, 3)),
                            "xyz", degrees=True)


def test_hexapod_leg_lengths_are_the_joint_distances(hexapod):
    x = _hexapod_poses(hexapod, 200)
    q = hexapod.ik(x)
    model = hexapod.model
    rot = Rotation.from_rotvec(x[:, 3:])
    for j in range(6):
        joint = x[:, :3] + rot.apply(model.rod_platform[j].copy())
        np.testing.assert_allclose(q[:, j], np.linalg.norm(joint - model.rod_base[j], axis=1),
                                   atol=1e-14)


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_round_trips_on_a_thousand_poses(name):
    m = pkmkit.machine(name)
    if m.position_controlled:
        lo, hi = m.default_box()
        inv = m.ik(RNG.uniform(lo, hi, (1000, 3)), full_output=True)
        assert (inv.status == Status.OK).all()
        poses, q = inv.pose, inv.q
        # the full pose the rods impose is consistent: the closed form gives the same q
        np.testing.assert_allclose(m.ik(poses), q, atol=1e-9)
    else:
        poses = _hexapod_poses(m, 1000, seed=3)
        q = m.ik(poses)
    back = m.fk(q)
    assert np.abs(pose_difference(back, poses)).max() < 1e-9


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_closed_form_agrees_with_the_engine(name):
    m = pkmkit.machine(name)
    if m.position_controlled:
        lo, hi = m.default_box()
        poses = m.ik(RNG.uniform(lo, hi, (50, 3)), full_output=True).pose
    else:
        poses = _hexapod_poses(m, 50, seed=5)
    q = m.ik(poses)
    rot = Rotation.from_rotvec(np.array(poses[:, 3:])).as_matrix()  # records: read-only
    res = solve_inverse(m.model, poses[:, :3], np.tile(m.home_q, (50, 1)), rotation=rot)
    assert (res.status == Status.OK).all()
    np.testing.assert_allclose(res.u, q, atol=1e-9)


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_twist_jacobian_against_finite_differences(name):
    m = pkmkit.machine(name)
    if m.position_controlled:
        poses = m.ik(np.array([[0.1, -0.05, 0.08], [-0.12, 0.1, -0.1]]), full_output=True).pose
    else:
        poses = _hexapod_poses(m, 2, seed=9)
    jac = m.jacobian(poses)
    h = 1e-6
    for k in range(len(poses)):
        for col in range(m.n_actuators):
            dq = np.zeros(m.n_actuators)
            dq[col] = h
            fd = pose_difference(m.fk(jac.q[k] + dq), m.fk(jac.q[k] - dq))[0] / (2 * h)
            np.testing.assert_allclose(jac.J[k][:, col], fd, atol=2e-8)
        # homogenisation and the factors, against numpy's SVD
        scale = np.array([1, 1, 1, *[m.characteristic_length] * 3])
        np.testing.assert_allclose(jac.J_homogeneous[k], scale[:, None] * jac.J[k])
        np.testing.assert_allclose(jac.singular_values[k],
                                   np.linalg.svd(jac.J_homogeneous[k], compute_uv=False))
        np.testing.assert_allclose(jac.translation_singular_values[k],
                                   np.linalg.svd(jac.J[k][:3], compute_uv=False))
        np.testing.assert_allclose(jac.rotation_singular_values[k],
                                   np.linalg.svd(jac.J[k][3:], compute_uv=False))
        # A t = B q̇ for every rod
        np.testing.assert_allclose(jac.A[k] @ jac.J[k], jac.B[k], atol=1e-12)


def test_verne_tilt_is_zero_exactly_on_the_symmetry_plane(verne):
    lo, hi = verne.default_box()
    positions = RNG.uniform(lo, hi, (300, 3))
    on_plane = positions.copy()
    on_plane[:, 0] = 0.0
    tilt_on = np.linalg.norm(verne.ik(on_plane, full_output=True).pose[:, 3:], axis=1)
    assert tilt_on.max() < 1e-12
    off = positions[np.abs(positions[:, 0]) > 1e-3]
    tilt_off = np.linalg.norm(verne.ik(off, full_output=True).pose[:, 3:], axis=1)
    assert tilt_off.min() > 1e-6
    # mirror symmetry about x = 0: the mirrored position has the mirrored rotation
    mirrored = off * np.array([-1.0, 1.0, 1.0])
    rv = verne.ik(off, full_output=True).pose[:, 3:]
    rv_m = verne.ik(mirrored, full_output=True).pose[:, 3:]
    # a reflection S = diag(-1, 1, 1) maps a rotation vector φ to −Sφ
    np.testing.assert_allclose(rv_m, -rv * np.array([-1.0, 1.0, 1.0]), atol=1e-12)


def test_verne_refuses_orientations_its_rods_do_not_impose(verne):
    pose = verne.ik([0.1, 0.05, 0.0], full_output=True).pose
    tilted = pose.copy()
    tilted[3] += 0.01
    with pytest.raises(UnreachablePoseError, match="reaches only the orientations"):
        verne.ik(tilted)
    res = verne.ik(np.stack([pose, tilted]), full_output=True)
    assert res.status.tolist() == [Status.OK, Status.UNREACHABLE]
    assert np.isfinite(res.q[0]).all() and np.isnan(res.q[1]).all()


def test_mobility_counts(hexapod, verne):
    assert hexapod.mobility()["grubler"].mobility == 6
    assert hexapod.mobility()["instantaneous"].mobility == 6
    assert verne.mobility()["grubler"].mobility == 3
    inst = verne.mobility()["instantaneous"]
    assert (inst.mobility, inst.platform_freedom_locked) == (3, 0)


def test_out_of_reach_and_bad_input(hexapod):
    far = hexapod.home_pose.copy()
    far[2] += 5.0
    q = hexapod.ik(far)  # struts: any pose has lengths; the stroke is a separate check
    assert (q > hexapod.model.q_max).all()
    with pytest.raises(InputError):
        hexapod.ik([0.0, 0.0, np.nan, 0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="6 components"):
        hexapod.ik(np.zeros(5))
    batch = np.stack([hexapod.home_pose, np.full(6, np.nan)])
    res = hexapod.ik(batch, full_output=True)
    assert res.status.tolist() == [Status.OK, Status.INVALID_INPUT]


def test_six_dof_file_machine_with_shared_actuators(tmp_path, verne):
    """The Verne module described rod by rod in a file (two legs per actuator) is the same
    machine; inconsistent sharing and a home pose that does not assemble are refused."""
    model = verne.model
    lines = ['[machine]', 'kind = "rod-legs"', 'dims = 6', 'units = "m"',
             'home = [0, 0, 0, 0, 0, 0]']
    for j in range(model.n_rods):
        a = int(model.rod_actuator[j])
        lines += ['[[legs]]', f'actuator = "q{a + 1}"', 'type = "slide"', 'axis = [0, 0, 1]',
                  f'base = {model.rod_base[j].tolist()}',
                  f'platform = {model.rod_platform[j].tolist()}',
                  f'length = {model.rod_length[j]}']
    path = tmp_path / "verne.toml"
    path.write_text("\n".join(lines))
    m = pkmkit.load(path)
    assert isinstance(m, FullPoseMachine) and m.n_actuators == 3
    positions = RNG.uniform(-0.1, 0.1, (20, 3))
    np.testing.assert_allclose(m.ik(positions), verne.ik(positions), atol=1e-10)

    bad = path.read_text().replace('axis = [0, 0, 1]', 'axis = [0, 0.1, 1]', 1)
    (tmp_path / "bad.toml").write_text(bad)
    with pytest.raises(pkmkit.MachineFileError,
                       match="share actuator 'q1' but have different axes"):
        pkmkit.load(tmp_path / "bad.toml")
    far = path.read_text().replace('home = [0, 0, 0, 0, 0, 0]', 'home = [3, 0, 0, 0, 0, 0]')
    (tmp_path / "far.toml").write_text(far)
    with pytest.raises(pkmkit.MachineFileError, match="does not assemble"):
        pkmkit.load(tmp_path / "far.toml")


def test_full_pose_kinds_validate_their_parameters():
    with pytest.raises(ParameterError, match="third parallelogram"):
        pkmkit.machine("verne", platform_width_1=0.3)
    with pytest.raises(ParameterError, match="between 0 and 60"):
        pkmkit.machine("gough-stewart", base_half_angle=0.0)


def test_verne_carriages_hang_the_rods_down_at_home(verne):
    """The working branch is the one with every carriage above its platform joints: at home,
    q_k = joint_height + sqrt(L² − horizontal distance²), computed here from the parameters."""
    p = verne.params
    theta = np.asarray(p["angles"])
    for k in range(3):
        half = 0.5 * (p["carriage_width_1"] if k == 0 else p["width"])
        half_p = 0.5 * (p["platform_width_1"] if k == 0 else p["width"])
        radial = np.array([np.cos(theta[k]), np.sin(theta[k])])
        tangent = np.array([-np.sin(theta[k]), np.cos(theta[k])])
        carriage = p["R"] * radial + half * tangent
        joint = p["r"] * radial + half_p * tangent
        horizontal = np.linalg.norm(carriage - joint)
        expected = p["joint_height"] + np.sqrt(p["L"] ** 2 - horizontal**2)
        assert verne.home_q[k] == pytest.approx(expected, abs=1e-12)


def test_every_assembly_mode_of_a_general_hexapod():
    """Dietmaier's 1998 geometry (the dietmaier-hexapod preset): all 40 modes real, each closes
    every rod and gives back the same strut lengths; the working one is where the engine goes
    from home."""
    m = pkmkit.machine("dietmaier-hexapod")
    modes = m.fk_all(m.home_q)
    assert (modes.count, modes.n_finite, modes.status) == (40, 40, Status.OK)
    poses = modes.poses[:40]
    np.testing.assert_allclose(m.ik(poses), np.tile(m.home_q, (40, 1)), atol=1e-9)
    assert np.abs(pose_difference(poses[modes.working], m.home_pose)).max() < 1e-9
    assert modes.labels[modes.working] == "working" and len(set(modes.labels)) == 40
    # distinct, and both det A signs occur
    gaps = np.linalg.norm(poses[:, None, :3] - poses[None, :, :3], axis=2) + np.eye(40)
    assert gaps.min() > 1e-6
    assert set(modes.mode_sign[:40]) == {-1, 1}


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
@pytest.mark.ci
def test_fk_all_batches_and_contains_the_engine_solution(name):
    m = pkmkit.machine(name)
    if m.position_controlled:
        q = m.ik(RNG.uniform(-0.1, 0.1, (3, 3)))
    else:
        q = m.ik(_hexapod_poses(m, 3, seed=11))
    q = np.vstack([q, np.full(m.n_actuators, np.nan)])
    modes = m.fk_all(q)
    assert modes.status[-1] == Status.INVALID_INPUT and modes.count[-1] == 0
    engine = m.fk(q[:3])
    for k in range(3):
        assert modes.status[k] in (Status.OK, Status.SINGULAR)
        assert modes.working[k] >= 0
        np.testing.assert_allclose(modes.poses[k, modes.working[k]], engine[k], atol=1e-9)
        # every mode closes every rod at q (other modes may use other inverse branches)
        found = modes.poses[k, :modes.count[k]]
        rods = FullPoseForms(m.model).rod_vectors(found, np.tile(q[k], (len(found), 1)))
        np.testing.assert_allclose(np.linalg.norm(rods, axis=2),
                                   np.broadcast_to(m.model.rod_length, rods.shape[:2]) if
                                   not m.model.rod_kind.any() else np.tile(q[k], (len(found), 1)),
                                   atol=1e-9)


def _full_pose_delta():
    """The Delta robot's six forearm rods on a full-pose platform (crank actuators)."""
    from pkmkit.model.rods import build_rod_model, leg_specs

    delta = pkmkit.machine("delta")
    model = build_rod_model(leg_specs(delta.model), dims=6, actuator_names=("q1", "q2", "q3"),
                            home_pose=(*delta.home_pose, 0.0, 0.0, 0.0))
    return FullPoseMachine(id="delta6", name="delta6", kind=None, params={}, model=model)


@pytest.mark.parametrize("name", ["gough-stewart", "verne", "delta6"])
def test_compiled_inverse_kernel_matches_the_numpy_reference(name, monkeypatch):
    m = _full_pose_delta() if name == "delta6" else pkmkit.machine(name)
    forms = FullPoseForms(m.model)
    rng = np.random.default_rng(4)
    poses = np.tile(m.home_pose, (3000, 1))
    poses[:, :3] += rng.uniform(-0.3, 0.3, (3000, 3))  # some out of reach
    poses[:, 3:] += rng.uniform(-0.1, 0.1, (3000, 3))
    poses[7] = np.nan
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    compiled = forms.rod_coordinates(poses)
    reference = forms.rod_coordinates_numpy(poses, forms.rod_branch)
    np.testing.assert_array_equal(np.isnan(compiled), np.isnan(reference))
    assert np.isnan(reference).any() and np.isfinite(reference).any()
    np.testing.assert_allclose(compiled, reference, atol=1e-12, equal_nan=True)


def test_a_crank_machine_on_a_full_pose_platform_keeps_its_translational_answers():
    """The Delta robot's rods on a free platform: the parallelograms hold its orientation, so
    the full-pose model reproduces the translational closed forms."""
    delta = pkmkit.machine("delta")
    full = _full_pose_delta()
    positions = delta.home_pose + RNG.uniform(-0.1, 0.1, (20, 3))
    q = delta.ik(positions)
    poses = np.concatenate([positions, np.zeros((20, 3))], axis=1)
    np.testing.assert_allclose(full.ik(poses), q, atol=1e-12)
    np.testing.assert_allclose(full.fk(q)[:, :3], positions, atol=1e-10)
    np.testing.assert_allclose(full.fk(q)[:, 3:], 0.0, atol=1e-10)


def test_positions_no_orientation_can_serve_are_refused_soundly():
    """The Verne module's pre-test (dist(p, slide line) − |b| > L for some slide rod) flags only
    positions that no rotation makes reachable: 3000 random rotations each leave a rod short,
    and the positions it does not flag that the solver reaches are never flagged."""
    from scipy.spatial.transform import Rotation

    m = pkmkit.machine("verne")
    rng = np.random.default_rng(7)
    points = rng.uniform(-1.2, 1.2, (400, 3))
    flagged = m._surely_unreachable(points)
    assert 0 < flagged.sum() < len(points)
    rot = Rotation.random(3000, random_state=1).as_matrix()
    model = m.model
    for p in points[flagged][:25]:
        tips = p[None, None] + np.einsum("rij,kj->rki", rot, model.rod_platform)
        w = tips - model.rod_base[None]
        along = np.einsum("rki,ki->rk", w, model.rod_axis)
        perp = np.sqrt(np.maximum((w * w).sum(axis=2) - along ** 2, 0.0))
        assert ((perp - model.rod_length[None]) > 0).any(axis=1).all()
    q = m.ik(points)
    assert not np.isfinite(q[flagged]).any()
    assert np.isfinite(q[~flagged]).all(axis=1).any()


def _moved(x, twist, s):
    """The pose reached from ``x`` after time ``s`` at constant twist (v, ω)."""
    from pkmkit.spatial.rotation import compose_rotvec

    return np.concatenate([x[:3] + twist[:3] * s,
                           compose_rotvec(twist[3:][None] * s, x[3:][None])[0]])


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod"])
def test_jacobian_dot_of_a_hexapod_matches_central_differences_along_its_twist(name):
    m = pkmkit.machine(name)
    x = m.reference_poses().get("tilted", m.home_pose)
    twist = np.array([0.1, -0.05, 0.02, 0.3, -0.2, 0.1])
    rates = m.jacobian_dot(x, twist)
    h = 1e-6
    fd_j = (m.jacobian(_moved(x, twist, h)).J - m.jacobian(_moved(x, twist, -h)).J) / (2 * h)
    np.testing.assert_allclose(rates.J_dot, fd_j, atol=2e-8 * np.abs(fd_j).max())
    fd_q = (m.ik(_moved(x, twist, h)) - m.ik(_moved(x, twist, -h))) / (2 * h)
    np.testing.assert_allclose(rates.qd, fd_q, atol=1e-8)
    # Ȧ and Ḃ are the rates of A and B themselves
    jp, jm = m.jacobian(_moved(x, twist, h)), m.jacobian(_moved(x, twist, -h))
    np.testing.assert_allclose(rates.A_dot, (jp.A - jm.A) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(rates.B_dot, (jp.B - jm.B) / (2 * h), atol=1e-7)
    # batched rows equal single rows
    batch = m.jacobian_dot(np.stack([x, m.home_pose]), np.stack([twist, -twist]))
    np.testing.assert_allclose(batch.J_dot[0], rates.J_dot, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("name", ["verne", "delta6"])
def test_jacobian_dot_of_a_position_controlled_module(name):
    """Positions and their velocities in: the twist follows from the rods (the Verne module
    tilts, the Delta's parallelograms hold the platform), J̇ against central differences of
    J along the position's motion."""
    m = _full_pose_delta() if name == "delta6" else pkmkit.machine(name)
    p = m.home_pose[:3] + np.array([0.04, 0.03, -0.05])
    pd = np.array([0.2, -0.1, 0.05])
    rates = m.jacobian_dot(p, pd)
    h = 1e-6
    fd = (m.jacobian(p + pd * h).J - m.jacobian(p - pd * h).J) / (2 * h)
    np.testing.assert_allclose(rates.J_dot, fd, atol=2e-8 * max(np.abs(fd).max(), 1.0))
    np.testing.assert_allclose(m.jacobian(p).J[:3] @ rates.qd, pd, atol=1e-12)
    if name == "verne":
        with pytest.raises(InputError, match="not one the rods"):
            m.jacobian_dot(p, np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0]))


def test_jacobian_dot_refuses_mismatched_rates(hexapod):
    with pytest.raises(InputError, match="xd must have shape"):
        hexapod.jacobian_dot(hexapod.home_pose, np.zeros(3))
    with pytest.raises(InputError, match="finite"):
        hexapod.jacobian_dot(hexapod.home_pose, np.full(6, np.nan))


def test_characteristic_length_from_a_file_and_in_python(tmp_path, hexapod):
    """L scales the angular rows of the homogenised Jacobian (and nothing else); it is read in
    the file's units, kept by with_params, and refused where it means nothing."""
    from pkmkit.machines.registry import preset_path

    text = Path(preset_path("gough-stewart")).read_text()
    path = tmp_path / "hexapod.toml"
    assert 'units = "mm"' in text
    path.write_text(text.replace("[machine]\n", "[machine]\ncharacteristic_length = 500\n", 1))
    m = pkmkit.load(path)
    assert m.characteristic_length == pytest.approx(0.5) and m.length_given
    x = hexapod.reference_poses()["tilted"]
    plain, scaled = hexapod.jacobian(x), m.jacobian(x)
    np.testing.assert_allclose(scaled.J, plain.J, rtol=1e-14)
    np.testing.assert_allclose(scaled.J_homogeneous[3:], 0.5 * plain.J[3:], rtol=1e-14)
    np.testing.assert_allclose(scaled.J_homogeneous[:3], plain.J[:3], rtol=1e-14)
    assert scaled.condition != pytest.approx(plain.condition)
    assert m.with_params(height=0.85).characteristic_length == pytest.approx(0.5)
    assert hexapod.with_params(platform_radius=0.35).characteristic_length == pytest.approx(
        0.35)  # the default follows the platform
    assert hexapod.with_characteristic_length(0.2).characteristic_length == 0.2
    with pytest.raises(ParameterError, match="finite length > 0"):
        hexapod.with_characteristic_length(-1.0)
    bad = path.read_text().replace("characteristic_length = 500", "characteristic_length = 0")
    path.write_text(bad)
    with pytest.raises(pkmkit.MachineFileError, match="characteristic length") as info:
        pkmkit.load(path)
    line = bad.splitlines().index("characteristic_length = 0") + 1
    assert f"hexapod.toml:{line}:" in str(info.value)
    ortho = Path(preset_path("orthoglide")).read_text().replace(
        "[machine]\n", "[machine]\ncharacteristic_length = 1\n", 1)
    (tmp_path / "o.toml").write_text(ortho)
    with pytest.raises(pkmkit.MachineFileError, match="applies to full-pose machines"):
        pkmkit.load(tmp_path / "o.toml")


def test_jacobian_dot_refuses_bad_twists_with_typed_errors():
    m = pkmkit.machine("gough-stewart")
    x = m.home_pose
    for bad in (["a"] * 6, [np.inf] + [0.0] * 5, [1e300] + [0.0] * 5, np.zeros(5)):
        with pytest.raises(pkmkit.exceptions.InputError, match="xd"):
            m.jacobian_dot(x, bad)


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_fk_batch_flags_a_row_of_1e308_and_keeps_the_others(name):
    """A finite but absurd row (1e308) made the first-order guess a NaN rotation and SciPy
    raised 'zero norm quaternions' for the whole batch (issue 18 §7 fuzz)."""
    m = pkmkit.machine(name)
    q_home = m.ik(m.home_pose)
    bad = np.zeros_like(q_home)
    bad[0] = 1e308
    res = m.fk(np.stack([q_home, bad]), full_output=True)
    assert res.status.tolist() == [Status.OK, Status.INVALID_INPUT]
    np.testing.assert_allclose(res.pose[0], m.home_pose, atol=1e-9)


def test_pseudo_inverse_of_rod_b_matches_lapack_with_its_cutoff():
    """B⁺ of a rod machine's B (one entry per row, in its actuator's column) in closed form is
    np.linalg.pinv's, a column of zeros (an actuator whose rods are all at a serial
    singularity) included; and the velocity model's J⁻¹ = B⁺A with it."""
    from pkmkit.machines.full_pose_rates import rod_b_pinv

    rng = np.random.default_rng(11)
    for name, rods, actuators in (("gough-stewart", 6, 6), ("verne", 6, 3)):
        m = pkmkit.machine(name)
        b = np.zeros((40, rods, actuators))
        b[:, np.arange(rods), m.model.rod_actuator] = rng.normal(size=(40, rods))
        b[3, :, 0] = 0.0
        b[5, m.model.rod_actuator == 1, 1] = 1e-17  # below the cutoff: treated as zero
        np.testing.assert_allclose(rod_b_pinv(b), np.linalg.pinv(b), rtol=1e-13, atol=1e-15)
        assert not rod_b_pinv(b)[3, 0].any() and not rod_b_pinv(b)[5, 1].any()
        x = m.home_pose if name == "gough-stewart" else m.home_pose[:3]
        jac = m.jacobian(np.array([x, x]))
        np.testing.assert_allclose(jac.J_inv, np.linalg.pinv(jac.B) @ jac.A, rtol=1e-13,
                                   atol=1e-15)
