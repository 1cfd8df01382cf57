"""Property tests (Hypothesis) of the spatial layer against formulas written out here, never
against the code itself: composition order, inverses, exp/log, adjoint identities and rigid
registration with non-commuting rotations and known transforms.

The oracle for rotations is Rodrigues' formula with an explicit cross-product matrix (below);
for transforms, 4×4 homogeneous products."""

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st
from scipy.linalg import expm

from pkmkit.spatial import (
    adjoint,
    adjoint_inverse,
    compose_poses,
    compose_rotvec,
    hat,
    invert_poses,
    move_reduction_point,
    point_displacement,
    pose_difference,
    rotvec_to_matrix,
    se3_exp,
    se3_log,
)
from pkmkit.spatial.registration import rigid_registration

coord = st.floats(-1.0, 1.0, allow_nan=False)
vec3 = st.tuples(coord, coord, coord).map(np.array)
#: rotation vectors of angle in [0.2, 2.8] rad (well away from 0 and π, so that two of them
#: do not commute)
rotvec = st.tuples(vec3, st.floats(0.2, 2.8)).filter(lambda t: np.linalg.norm(t[0]) > 0.1).map(
    lambda t: t[0] / np.linalg.norm(t[0]) * t[1])
pose = st.tuples(vec3, rotvec).map(np.concatenate)


def cross_matrix(v):
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def rodrigues(phi):
    """R = I + sin θ K + (1 − cos θ) K², K the cross matrix of the unit axis."""
    theta = np.linalg.norm(phi)
    if theta == 0.0:
        return np.eye(3)
    k = cross_matrix(phi / theta)
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def homogeneous(p):
    t = np.eye(4)
    t[:3, :3], t[:3, 3] = rodrigues(p[3:]), p[:3]
    return t


def rows_of(t):
    """Position and rotation matrix of a 4×4 transform (the pose as the oracle sees it)."""
    return t[:3, 3], t[:3, :3]


def assert_same_pose(row, t):
    np.testing.assert_allclose(row[:3], t[:3, 3], atol=1e-12)
    np.testing.assert_allclose(rodrigues(row[3:]), t[:3, :3], atol=1e-12)


@given(pose, pose)
def test_compose_is_the_product_of_transforms_in_order(a, b):
    """``compose_poses(a, b)`` = T_a T_b (b in the frame of a): the order matters for
    non-commuting rotations, and the test checks it is not T_b T_a."""
    assert_same_pose(compose_poses(a, b), homogeneous(a) @ homogeneous(b))
    assert_same_pose(invert_poses(a), np.linalg.inv(homogeneous(a)))
    # the point of a's frame at b's origin is p_a + R_a p_b
    np.testing.assert_allclose(compose_poses(a, b)[:3], a[:3] + rodrigues(a[3:]) @ b[:3],
                               atol=1e-12)


@given(rotvec, rotvec)
def test_compose_rotvec_applies_the_increment_on_the_left(delta, phi):
    np.testing.assert_allclose(rodrigues(compose_rotvec(delta, phi)[0]),
                               rodrigues(delta) @ rodrigues(phi), atol=1e-12)
    np.testing.assert_allclose(rotvec_to_matrix(phi)[0], rodrigues(phi), atol=1e-12)


@given(pose, pose)
def test_pose_difference_is_the_left_increment_from_b_to_a(a, b):
    d = pose_difference(a, b)[0]
    np.testing.assert_allclose(d[:3], a[:3] - b[:3], atol=1e-12)
    np.testing.assert_allclose(rodrigues(d[3:]) @ rodrigues(b[3:]), rodrigues(a[3:]),
                               atol=1e-11)


@given(vec3, rotvec)
def test_exp_and_log_of_twists(v, w):
    """Linear part first: exp of (v, ω) is the matrix exponential of [[ω]×, v; 0, 0]."""
    xi = np.concatenate([v, 0.8 * w / max(1.0, np.linalg.norm(w) / 2.5)])
    twist_matrix = np.zeros((4, 4))
    twist_matrix[:3, :3], twist_matrix[:3, 3] = cross_matrix(xi[3:]), xi[:3]
    np.testing.assert_allclose(hat(xi), twist_matrix, atol=0)
    np.testing.assert_allclose(se3_exp(xi), expm(twist_matrix), atol=1e-12)
    np.testing.assert_allclose(se3_log(expm(twist_matrix)), xi, atol=1e-10)


@given(pose, vec3, vec3)
def test_adjoint_maps_body_twists_to_spatial_ones(p, v, w):
    """T exp(ξ̂) T⁻¹ = exp((Ad_T ξ)^), with Ad_T⁻¹ its inverse; the torsor moved to a point
    gives that point's displacement v + ω × x."""
    t = homogeneous(p)
    xi = np.concatenate([v, w])
    big = np.zeros((4, 4))
    big[:3, :3], big[:3, 3] = cross_matrix(w), v
    ad = adjoint(t[:3, :3], t[:3, 3])
    spatial = t @ big @ np.linalg.inv(t)
    np.testing.assert_allclose(ad @ xi, np.concatenate([spatial[:3, 3], [
        spatial[2, 1], spatial[0, 2], spatial[1, 0]]]), atol=1e-12)
    np.testing.assert_allclose(adjoint_inverse(t[:3, :3], t[:3, 3]),
                               np.linalg.inv(ad), atol=1e-11)
    x = p[:3]
    explicit = v + cross_matrix(w) @ x
    np.testing.assert_allclose(point_displacement(xi, x), explicit, atol=1e-14)
    np.testing.assert_allclose(move_reduction_point(xi, x), np.concatenate([explicit, w]),
                               atol=1e-14)


@given(pose, st.integers(4, 8), st.integers(0, 2**32 - 1))
def test_registration_recovers_a_known_transform(p, n, seed):
    """Points (and tool directions) mapped by a known transform with a large rotation: the
    registration returns that transform, its inverse maps back, and composing two
    registrations is the product in order (A then B is T_B T_A, not T_A T_B)."""
    rng = np.random.default_rng(seed)
    source = rng.uniform(-0.5, 0.5, (n, 3))
    t = homogeneous(p)
    target = source @ t[:3, :3].T + t[:3, 3]
    reg = rigid_registration(source, target)
    np.testing.assert_allclose(reg.rotation, t[:3, :3], atol=1e-9)
    np.testing.assert_allclose(reg.translation, t[:3, 3], atol=1e-9)
    np.testing.assert_allclose(reg.matrix, t, atol=1e-9)
    np.testing.assert_allclose(reg.apply(source), target, atol=1e-9)
    np.testing.assert_allclose(reg.inverse().apply(target), source, atol=1e-9)
    dirs = rng.normal(size=(2, 3))
    with_dirs = rigid_registration(source[:2], target[:2], source_directions=dirs,
                                   target_directions=dirs @ t[:3, :3].T)
    np.testing.assert_allclose(with_dirs.rotation, t[:3, :3], atol=1e-9)
    np.testing.assert_allclose(with_dirs.apply_directions(dirs), dirs @ t[:3, :3].T,
                               atol=1e-9)
    # a second, non-commuting transform after the first
    q = np.concatenate([p[3:] * 0.5 + 0.1, np.roll(p[3:], 1)])
    if np.linalg.norm(q[3:]) < 0.2:
        q[3:] += 0.3
    u = homogeneous(q)
    final = target @ u[:3, :3].T + u[:3, 3]
    both = rigid_registration(source, final)
    np.testing.assert_allclose(both.matrix, u @ t, atol=1e-9)


@given(pose, vec3.filter(lambda v: np.linalg.norm(v) > 0.1), st.integers(3, 6))
def test_collinear_points_leave_the_roll_free(p, direction, n):
    """Points on a line in a general direction (so the second singular value of H is round-off,
    not an exact zero) do not fix the rotation about that line: the registration is flagged
    ill-posed whatever the transform, and a direction off the line fixes it."""
    line = np.linspace(-0.5, 0.7, n)[:, None] * direction + [0.1, -0.2, 0.3]
    across = np.cross(direction, [0.3, -0.7, 0.2])
    assume(np.linalg.norm(across) > 0.05)
    t = homogeneous(p)
    target = line @ t[:3, :3].T + t[:3, 3]
    batch = rigid_registration(np.stack([line, line]), np.stack([target, target]),
                               source_directions=np.stack([[across], [direction]]),
                               target_directions=np.stack([t[:3, :3] @ across,
                                                           t[:3, :3] @ direction])[:, None])
    assert batch.well_posed.tolist() == [True, False]
    np.testing.assert_allclose(batch.rotation[0], t[:3, :3], atol=1e-8)
