"""Pose rows (position + rotation vector), named angle conventions and rotation validation."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import InputError
from pkmkit.spatial import (
    DEFAULT_CONVENTION,
    angles_from_rotation,
    as_rotation_matrices,
    compose_poses,
    describe_convention,
    from_transform,
    invert_poses,
    pose_difference,
    pose_from_angles,
    pose_from_parts,
    pose_matrices,
    pose_to_angles,
    resolve_convention,
    rotation_from_angles,
    to_transform,
)

RNG = np.random.default_rng(7)


def _rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


@pytest.mark.parametrize(
    ("convention", "compose"),
    [
        ("xyz", lambda a, b, c: _rz(c) @ _ry(b) @ _rx(a)),  # fixed axes: last applied on the left
        ("XYZ", lambda a, b, c: _rx(a) @ _ry(b) @ _rz(c)),  # moving axes
        ("ZYX", lambda a, b, c: _rz(a) @ _ry(b) @ _rx(c)),
        ("ZYZ", lambda a, b, c: _rz(a) @ _ry(b) @ _rz(c)),
        ("rpy", lambda a, b, c: _rz(c) @ _ry(b) @ _rx(a)),
    ],
)
def test_conventions_against_explicit_products(convention, compose):
    # symmetric Euler sequences (ZYZ) report the middle angle in [0, π]
    a, b, c = 0.3, (0.7 if convention[0] == convention[2] else -0.7), 1.1
    mat = rotation_from_angles([a, b, c], convention).as_matrix()
    np.testing.assert_allclose(mat, compose(a, b, c), atol=1e-14)
    back = angles_from_rotation(Rotation.from_matrix(mat), convention)
    np.testing.assert_allclose(back, [a, b, c], atol=1e-12)


def test_default_convention_is_fixed_xyz():
    assert DEFAULT_CONVENTION == "xyz"
    assert describe_convention("xyz").startswith("xyz: extrinsic")
    assert describe_convention("ZYX").startswith("ZYX: intrinsic")


@pytest.mark.parametrize("bad", ["xxy", "XyZ", "abc", "", "xy", 3, None, "zyxz", "YY Z"])
def test_unknown_conventions_are_refused(bad):
    with pytest.raises(InputError, match="angle convention"):
        resolve_convention(bad)


def test_angles_must_be_finite_and_shaped():
    with pytest.raises(InputError, match="finite"):
        rotation_from_angles([0.0, np.nan, 0.0])
    with pytest.raises(InputError, match="shape"):
        rotation_from_angles([0.0, 1.0])


def test_rotation_validation_names_the_bad_matrix():
    good = Rotation.random(3, random_state=1).as_matrix()
    assert as_rotation_matrices(good).shape == (3, 3, 3)
    bad = good.copy()
    bad[1] *= 1.01
    with pytest.raises(InputError, match="rotation 1 is not a rotation"):
        as_rotation_matrices(bad)
    with pytest.raises(InputError, match="det = -1"):
        as_rotation_matrices(-np.eye(3))
    with pytest.raises(InputError, match="non-finite"):
        as_rotation_matrices(np.full((3, 3), np.nan))


def test_pose_rows_round_trip_through_angles_transforms_and_matrices():
    pos = RNG.normal(size=(10, 3))
    angles = RNG.uniform(-80, 80, size=(10, 3))
    poses = pose_from_angles(pos, angles, "ZYX", degrees=True)
    assert poses.shape == (10, 6)
    p, back = pose_to_angles(poses, "ZYX", degrees=True)
    np.testing.assert_allclose(p, pos)
    np.testing.assert_allclose(back, angles, atol=1e-10)
    np.testing.assert_allclose(from_transform(to_transform(poses)), poses, atol=1e-14)
    p2, mats = pose_matrices(poses)
    np.testing.assert_allclose(pose_from_parts(p2, mats), poses, atol=1e-14)
    single = pose_from_parts([1.0, 2.0, 3.0], np.eye(3))
    assert single.shape == (6,)
    np.testing.assert_array_equal(single, [1, 2, 3, 0, 0, 0])


def test_compose_invert_and_difference():
    a = pose_from_angles(RNG.normal(size=(5, 3)), RNG.normal(size=(5, 3)))
    b = pose_from_angles(RNG.normal(size=(5, 3)), RNG.normal(size=(5, 3)))
    ab = compose_poses(a, b)
    # composing with the inverse gives the identity
    np.testing.assert_allclose(compose_poses(invert_poses(a), ab), b, atol=1e-12)
    # the point b's origin lands where a maps it
    pa, ra = to_transform(a).as_components()
    np.testing.assert_allclose(ab[:, :3], pa + ra.apply(b[:, :3]), atol=1e-12)
    np.testing.assert_allclose(pose_difference(a, a), 0.0, atol=1e-15)
    d = pose_difference(ab, a)
    np.testing.assert_allclose(d[:, :3], ab[:, :3] - a[:, :3])


def test_pose_shape_errors():
    with pytest.raises(InputError, match="6-DOF pose"):
        pose_matrices(np.zeros(5))
    with pytest.raises(InputError, match="position"):
        pose_from_parts([0.0, np.inf, 0.0], np.eye(3))
