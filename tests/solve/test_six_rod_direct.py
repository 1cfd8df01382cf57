"""Every real solution of the six-rod direct kinematics: truth, residuals, counts, completeness.

The oracles here are written independently of the solver: rod lengths from poses with
``scipy.spatial.transform.Rotation``; known counts (40 for a general 6-6, 40 real for
Dietmaier's 1998 platform, 16 for the octahedral 3-3); mirror symmetry of planar platforms;
and a many-start ``scipy.optimize.least_squares`` search that must never find a real solution
the solver missed.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import InputError
from pkmkit.solve.six_rod_direct import MAX_SOLUTIONS, six_rod_direct_all
from pkmkit.solve.six_rod_paths import EndKind
from pkmkit.status import Status

# Dietmaier, P. (1998) "The Stewart-Gough platform of general geometry can have 40 real
# postures", Advances in Robot Kinematics: Analysis and Control, 7-16. Numbers as published in
# the test script of github.com/martyushev/fkSGP (matlab|python/test1_fkSGP.py): base points,
# platform points, rod lengths (the script passes their squares).
DIETMAIER_BASE = np.array([
    [0, 0, 0], [1.107915, 0, 0], [0.549094, 0.756063, 0], [0.735077, -0.223935, 0.525991],
    [0.514188, -0.526063, -0.368418], [0.590473, 0.094733, -0.205018]])
DIETMAIER_PLATFORM = np.array([
    [0, 0, 0], [0.542805, 0, 0], [0.956919, -0.528915, 0], [0.665885, -0.353482, 1.402538],
    [0.478359, 1.158742, 0.107672], [-0.137087, -0.235121, 0.353913]])
DIETMAIER_LENGTHS = np.array([1, 0.645275, 1.086284, 1.503439, 1.281933, 0.771071])


# ----------------------------------------------------------------------------- oracles


def rod_lengths(base, platform, poses):
    """``|p + R b_j − a_j|`` for poses ``(..., 6)`` (position, rotation vector)."""
    poses = np.asarray(poses)
    rot = Rotation.from_rotvec(poses[..., 3:].reshape(-1, 3)).as_matrix()
    rot = rot.reshape(*poses.shape[:-1], 3, 3)
    rb = np.einsum("...ij,...kj->...ki", rot, platform)
    return np.linalg.norm(poses[..., None, :3] + rb - base, axis=-1)


def pose_gap(u, v):
    """Largest of the position difference and the relative rotation angle."""
    u, v = np.array(u, ndmin=2), np.array(v, ndmin=2)  # copies: Rotation wants writeable
    ru, rv = Rotation.from_rotvec(u[:, 3:]), Rotation.from_rotvec(v[:, 3:])
    return np.maximum(np.abs(u[:, :3] - v[:, :3]).max(axis=1), (ru.inv() * rv).magnitude())


def contains(solutions, pose, tol):
    return solutions.shape[0] > 0 and pose_gap(solutions, np.broadcast_to(
        pose, solutions.shape)).min() <= tol


def random_configurations(n, seed):
    """General 6-6 geometries (metres) and poses; lengths from the poses."""
    rng = np.random.default_rng(seed)
    base = rng.uniform(-0.8, 0.8, (n, 6, 3)) * [1, 1, 0.3]
    platform = rng.uniform(-0.3, 0.3, (n, 6, 3))
    rotvec = Rotation.random(n, random_state=seed).as_rotvec() * rng.uniform(0.1, 0.6, (n, 1))
    position = rng.normal(0, 0.1, (n, 3)) + np.array([0, 0, 0.9])
    poses = np.hstack([position, rotvec])
    return base, platform, rod_lengths(base, platform, poses), poses


def many_start_search(base, platform, lengths, n_starts, seed):
    """Real solutions found by scipy's least_squares from random starts (independent)."""
    rng = np.random.default_rng(seed)
    reach = np.linalg.norm(base, axis=1).max() + np.linalg.norm(platform, axis=1).max() + max(
        lengths)
    found = []
    for rotvec0 in Rotation.random(n_starts, random_state=rng.integers(1 << 31)).as_rotvec():
        p0 = rng.uniform(-reach, reach, 3)

        def residual(u):
            rb = Rotation.from_rotvec(u[3:]).apply(platform)
            return np.linalg.norm(u[:3] + rb - base, axis=1) - lengths

        sol = least_squares(residual, np.r_[p0, rotvec0], method="lm", xtol=1e-14, ftol=1e-14)
        if np.abs(sol.fun).max() < 1e-10:
            found.append(sol.x)
    return np.array(found).reshape(-1, 6)


def mirror(poses):
    """Reflection through the plane z = 0 of a pose whose base and platform points lie in
    their z = 0 planes: p → M p, R → M R M (M = diag(1, 1, −1))."""
    m = np.diag([1.0, 1.0, -1.0])
    rot = Rotation.from_rotvec(poses[:, 3:]).as_matrix()
    return np.hstack([poses[:, :3] @ m, Rotation.from_matrix(m @ rot @ m).as_rotvec()])


def assert_verified(sols, base, platform, lengths, tol=1e-9):
    """Every returned solution closes every rod (own computation), and they are distinct."""
    poses = sols.poses[: sols.count]
    assert (np.abs(rod_lengths(base, platform, poses) - lengths).max(axis=-1) <= tol).all()
    assert (sols.residual[: sols.count] <= tol).all()
    assert np.isnan(sols.poses[sols.count :]).all()
    for i in range(len(poses)):
        for j in range(i):
            assert pose_gap(poses[i], poses[j])[0] > 1e-6


# ----------------------------------------------------------------------------- general


@pytest.fixture(scope="module")
def general():
    base, platform, lengths, poses = random_configurations(24, seed=4)
    return base, platform, lengths, poses, six_rod_direct_all(base, platform, lengths)


@pytest.mark.ci
def test_general_geometries_find_the_true_pose_among_40(general):
    base, platform, lengths, poses, sols = general
    assert sols.poses.shape == (24, MAX_SOLUTIONS, 6)
    assert (sols.status == Status.OK).all()
    assert (sols.n_finite == 40).all()
    assert (sols.n_failed == 0).all() and (sols.n_singular == 0).all()
    assert (sols.path_ends == EndKind.REGULAR).all()
    assert (sols.count >= 1).all() and (sols.count % 2 == 0).all()  # complex pairs: 40 − even
    for k in range(24):
        assert contains(sols.poses[k, : sols.count[k]], poses[k], 1e-9)
        assert_verified(
            type(sols)(**{f: getattr(sols, f)[k] for f in sols.__dataclass_fields__}),
            base[k], platform[k], lengths[k])
    assert (sols.multiplicity[sols.valid] == 1).all()
    assert np.isfinite(sols.condition[sols.valid]).all()
    # sorted by decreasing height
    for k in range(24):
        assert (np.diff(sols.poses[k, : sols.count[k], 2]) <= 0).all()


def test_single_call_matches_the_batch_and_drops_the_batch_axis(general):
    base, platform, lengths, _, batch = general
    one = six_rod_direct_all(base[3], platform[3], lengths[3])
    assert one.poses.shape == (MAX_SOLUTIONS, 6) and one.count.shape == ()
    assert int(one.count) == batch.count[3]
    np.testing.assert_allclose(one.poses[: one.count], batch.poses[3, : one.count], atol=1e-12)


@pytest.mark.ci
def test_invariance_to_units_and_frames():
    """Millimetres give the same poses ×1000; moving the base frame moves every solution."""
    base, platform, lengths, _ = random_configurations(1, seed=9)
    ref = six_rod_direct_all(base[0], platform[0], lengths[0])
    mm = six_rod_direct_all(1000 * base[0], 1000 * platform[0], 1000 * lengths[0])
    assert mm.count == ref.count
    np.testing.assert_allclose(mm.poses[: mm.count, :3], 1000 * ref.poses[: ref.count, :3],
                               atol=1e-9)
    np.testing.assert_allclose(mm.poses[: mm.count, 3:], ref.poses[: ref.count, 3:], atol=1e-11)
    assert mm.residual[: mm.count].max() <= 1e-9
    # base frame rotated and shifted: solutions are the transformed ones
    g = Rotation.from_rotvec([0.3, -0.2, 1.0])
    shift = np.array([5.0, -2.0, 1.0])
    moved = six_rod_direct_all(g.apply(base[0]) + shift, platform[0], lengths[0])
    expected = np.hstack([g.apply(ref.poses[: ref.count, :3]) + shift,
                          (g * Rotation.from_rotvec(ref.poses[: ref.count, 3:])).as_rotvec()])
    assert moved.count == ref.count
    for pose in expected:
        assert contains(moved.poses[: moved.count], pose, 1e-9)


# ----------------------------------------------------------------------------- known counts


def test_dietmaier_platform_has_40_real_solutions():
    sols = six_rod_direct_all(DIETMAIER_BASE, DIETMAIER_PLATFORM, DIETMAIER_LENGTHS)
    assert sols.status == Status.OK
    assert sols.n_finite == 40
    assert sols.count == 40
    assert_verified(sols, DIETMAIER_BASE, DIETMAIER_PLATFORM, DIETMAIER_LENGTHS)


def _triangle(radius, phase):
    ang = np.radians([0, 120, 240]) + phase
    return np.c_[radius * np.cos(ang), radius * np.sin(ang), np.zeros(3)]


def test_octahedral_3_3_platform_has_16_solutions_in_mirror_pairs():
    base = _triangle(1.0, 0.0)[[0, 0, 1, 1, 2, 2]]
    platform = _triangle(0.5, np.pi / 3)[[0, 1, 1, 2, 2, 0]]
    truth = np.array([0.05, -0.02, 0.8, 0.1, -0.05, 0.2])
    lengths = rod_lengths(base, platform, truth)
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.OK
    assert sols.n_finite == 16
    assert sols.n_finite + sols.n_infinite + sols.n_exceptional == 40
    assert contains(sols.poses[: sols.count], truth, 1e-9)
    assert_verified(sols, base, platform, lengths)
    poses = sols.poses[: sols.count]
    assert sols.count % 2 == 0 and (poses[:, 2] > 0).sum() == sols.count // 2
    for pose in mirror(poses):
        assert contains(poses, pose, 1e-9)


def test_6_3_platform_has_16_solutions():
    ang = np.radians([0, 50, 120, 170, 240, 290])
    base = np.c_[np.cos(ang), np.sin(ang), np.zeros(6)]
    platform = _triangle(0.5, np.pi / 3)[[0, 0, 1, 1, 2, 2]]
    truth = np.array([0.05, -0.02, 0.8, 0.1, -0.05, 0.2])
    lengths = rod_lengths(base, platform, truth)
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.OK
    assert sols.n_finite == 16
    assert contains(sols.poses[: sols.count], truth, 1e-9)
    assert_verified(sols, base, platform, lengths)


def test_planar_base_and_platform_give_mirror_pairs():
    rng = np.random.default_rng(21)
    base = np.c_[rng.uniform(-1, 1, (6, 2)), np.zeros(6)]
    platform = np.c_[rng.uniform(-0.4, 0.4, (6, 2)), np.zeros(6)]
    truth = np.array([0.1, 0.05, 0.7, 0.2, 0.1, -0.3])
    lengths = rod_lengths(base, platform, truth)
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.OK and sols.n_finite == 40
    poses = sols.poses[: sols.count]
    assert contains(poses, truth, 1e-9) and contains(poses, mirror(truth[None])[0], 1e-9)
    assert (poses[:, 2] > 0).sum() == sols.count // 2
    for pose in mirror(poses):
        assert contains(poses, pose, 1e-9)


@pytest.mark.parametrize("spread", [0.08, 0.0])
def test_slide_module_with_two_rods_per_carriage(spread):
    """Verne-type: base points in pairs on three carriages of parallel vertical slides (two
    joints per carriage, or one joint shared by both rods: a 3-6 platform)."""
    ang = np.radians([90, 210, 330])
    carriage = np.c_[np.cos(ang), np.sin(ang), [0.3, 0.5, 0.4]]
    offset = np.c_[-np.sin(ang), np.cos(ang), np.zeros(3)] * spread
    sign = np.array([1.0, -1.0] * 3)[:, None]
    base = np.repeat(carriage, 2, axis=0) + np.repeat(offset, 2, axis=0) * sign
    pang = np.radians([80, 100, 200, 220, 320, 340])
    platform = np.c_[0.2 * np.cos(pang), 0.2 * np.sin(pang), np.zeros(6)]
    truth = np.array([0.02, 0.01, -0.5, 0.02, 0.03, 0.01])
    lengths = rod_lengths(base, platform, truth)
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.OK
    assert sols.n_finite == (40 if spread else 16)
    assert contains(sols.poses[: sols.count], truth, 1e-9)
    assert_verified(sols, base, platform, lengths)


def test_singular_configuration_is_reported_not_hidden():
    """Fichter's singularity: a semi-regular hexapod turned 90° about the vertical."""
    base = np.c_[np.cos(np.radians([-10, 10, 110, 130, 230, 250])),
                 np.sin(np.radians([-10, 10, 110, 130, 230, 250])), np.zeros(6)]
    pang = np.radians([-50, 50, 70, 170, 190, 290])
    platform = 0.5 * np.c_[np.cos(pang), np.sin(pang), np.zeros(6)]
    truth = np.array([0.0, 0.0, 0.8, 0.0, 0.0, np.pi / 2])
    lengths = rod_lengths(base, platform, truth)
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.SINGULAR
    assert sols.n_singular >= 2
    assert (sols.path_ends == EndKind.SINGULAR).sum() == sols.n_singular
    poses = sols.poses[: sols.count]
    assert contains(poses, truth, 1e-5)
    k = np.argmin(pose_gap(poses, np.broadcast_to(truth, poses.shape)))
    assert sols.multiplicity[k] >= 2
    assert sols.condition[k] > 1e5
    assert sols.residual[: sols.count].max() <= 1e-9


def test_worked_example_of_the_docs():
    """docs/full-pose.md §8.5: eight real assembly modes, the first the pose the (rounded) rod
    lengths came from."""
    base = np.array([[0.70, 0.05, 0.00], [0.30, 0.62, 0.08], [-0.33, 0.60, -0.05],
                     [-0.68, 0.02, 0.04], [-0.30, -0.64, 0.00], [0.35, -0.58, -0.06]])
    platform = np.array([[0.25, 0.10, 0.02], [-0.05, 0.27, 0.00], [-0.22, 0.15, -0.03],
                         [-0.20, -0.16, 0.01], [0.02, -0.27, 0.03], [0.24, -0.08, -0.02]])
    lengths = np.array([0.989367, 0.934041, 1.001207, 0.979918, 1.008889, 1.035137])
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.status == Status.OK and sols.count == 8 and sols.n_finite == 40
    # lengths rounded to 1 µm, Jacobian condition ≈ 50: the pose to about 10⁻⁵
    assert pose_gap(sols.poses[0], [0.02, -0.01, 0.85, 0.05, -0.03, 0.10])[0] < 5e-5
    assert (sols.poses[: sols.count, 2] < 0).sum() == 2
    assert_verified(sols, base, platform, lengths)


def test_no_assembly_is_certified_empty():
    base, platform, lengths, _ = random_configurations(1, seed=2)
    sols = six_rod_direct_all(base[0], platform[0], 0.05 * lengths[0])
    assert sols.status == Status.NO_ASSEMBLY and sols.complete
    assert sols.count == 0 and np.isnan(sols.poses).all()


# ----------------------------------------------------------------------------- completeness


@pytest.mark.parametrize("case", ["random", "planar", "dietmaier"])
@pytest.mark.ci
def test_many_start_search_never_finds_a_missed_solution(case):
    if case == "dietmaier":
        base, platform, lengths = DIETMAIER_BASE, DIETMAIER_PLATFORM, DIETMAIER_LENGTHS
    elif case == "planar":
        rng = np.random.default_rng(8)
        base = np.c_[rng.uniform(-1, 1, (6, 2)), np.zeros(6)]
        platform = np.c_[rng.uniform(-0.6, 0.6, (6, 2)), np.zeros(6)]
        lengths = rod_lengths(base, platform, [0.1, 0.0, 0.6, 0.3, -0.2, 0.5])
    else:
        b, p, ell, _ = random_configurations(1, seed=17)
        base, platform, lengths = b[0], p[0], ell[0]
    sols = six_rod_direct_all(base, platform, lengths)
    assert sols.complete
    found = many_start_search(base, platform, lengths, n_starts=120, seed=1)
    assert len(found) > 0
    for pose in found:
        assert contains(sols.poses[: sols.count], pose, 1e-7)


# ----------------------------------------------------------------------------- bad input


def test_bad_rows_are_flagged_and_the_others_kept(general):
    base, platform, lengths, _, ref = general
    base, platform, lengths = base[:5].copy(), platform[:5].copy(), lengths[:5].copy()
    base[1, 2, 0] = np.nan
    lengths[2, 4] = 0.0
    lengths[3, 0] = -1.0
    platform[4, 5, 2] = np.inf
    sols = six_rod_direct_all(base, platform, lengths)
    assert list(sols.status[1:]) == [Status.INVALID_INPUT] * 4
    assert (sols.path_ends[1:] == -1).all()
    assert (sols.count[1:] == 0).all() and np.isnan(sols.poses[1:]).all()
    assert sols.status[0] == Status.OK and sols.count[0] == ref.count[0]
    np.testing.assert_allclose(sols.poses[0], ref.poses[0], atol=1e-12)


def test_broadcasting_a_shared_platform():
    base, platform, lengths, poses = random_configurations(3, seed=5)
    shared = platform[0]
    lengths = rod_lengths(base, shared, poses)
    sols = six_rod_direct_all(base, shared, lengths)
    assert sols.count.shape == (3,)
    for k in range(3):
        assert contains(sols.poses[k, : sols.count[k]], poses[k], 1e-9)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ((np.zeros((5, 3)), np.zeros((6, 3)), np.ones(6)), r"base must have shape \(6, 3\)"),
        ((np.zeros((6, 3)), np.zeros((6, 2)), np.ones(6)), r"platform must have shape"),
        ((np.zeros((6, 3)), np.zeros((6, 3)), np.ones(5)), r"lengths must have shape \(6,\)"),
        ((np.zeros((2, 6, 3)), np.zeros((3, 6, 3)), np.ones(6)), "batch sizes"),
        ((np.zeros((0, 6, 3)), np.zeros((6, 3)), np.ones(6)), "empty batch"),
        ((np.zeros((6, 3)), np.zeros((6, 3)), "abc"), "lengths must be an array of real"),
    ],
)
def test_misshaped_arguments_raise(args, message):
    with pytest.raises(InputError, match=message):
        six_rod_direct_all(*args)


@pytest.mark.parametrize(
    ("option", "message"),
    [({"tol": 0.0}, "tol must be"), ({"tol": np.nan}, "tol must be"),
     ({"predictor_tol": 2.0}, "predictor_tol"), ({"retries": -1}, "retries"),
     ({"retries": 0.5}, "retries")],
)
def test_options_out_of_range_raise(option, message):
    with pytest.raises(InputError, match=message):
        six_rod_direct_all(np.eye(6, 3), np.eye(6, 3), np.ones(6), **option)
