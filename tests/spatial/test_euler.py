"""NumPy angle conventions (:mod:`pkmkit.spatial.euler`) against their oracle, scipy's
``Rotation``: every axis sequence :func:`resolve_convention` accepts, random angles over the
whole ranges (±180°, ±90°), at and near gimbal lock, exact quarter turns, round trips."""

import itertools
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import InputError
from pkmkit.spatial import euler
from pkmkit.spatial.poses import pose_from_angles, pose_matrices, pose_to_angles
from pkmkit.spatial.rotation import (
    CONVENTION_ALIASES,
    angles_from_rotvec,
    resolve_convention,
    rotvec_from_angles,
)

SEQUENCES = [a + b + c for a, b, c in itertools.product("xyz", repeat=3) if a != b != c]
SEQUENCES += [s.upper() for s in SEQUENCES]
TOL = 1e-14


def _symmetric(seq: str) -> bool:
    return seq[0].lower() == seq[2].lower()


def _angle_gap(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a − b| modulo a turn (−π and π are one angle; which comes out rests on an ulp)."""
    return np.abs((a - b + np.pi) % (2.0 * np.pi) - np.pi)


def _scipy_angles(rotation: Rotation, seq: str) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the gimbal-lock warning
        return rotation.as_euler(seq)


def _samples(seq: str, seed: int) -> np.ndarray:
    """Angles (rad): uniform over the ranges, the middle angle at and within 1e-9..1e-5 of a
    lock, and all combinations of multiples of 90°."""
    rng = np.random.default_rng(seed)
    uniform = rng.uniform(-np.pi, np.pi, (600, 3))
    locks = [0.0, np.pi] if _symmetric(seq) else [np.pi / 2, -np.pi / 2]
    near = rng.uniform(-np.pi, np.pi, (300, 3))
    near[:, 1] = rng.choice(locks, 300) + rng.choice([0.0, 1e-9, -1e-9, 1e-5, -1e-5], 300)
    quarters = np.array(list(itertools.product(np.arange(-2, 3) * np.pi / 2, repeat=3)))
    return np.concatenate([uniform, near, quarters])


def test_the_sequences_are_those_the_conventions_accept():
    assert {resolve_convention(s) for s in SEQUENCES} == set(SEQUENCES)
    assert {resolve_convention(a) for a in CONVENTION_ALIASES} <= set(SEQUENCES)


@pytest.mark.parametrize("seq", SEQUENCES)
def test_angles_to_rotation_vectors_and_matrices_match_scipy(seq):
    angles = _samples(seq, SEQUENCES.index(seq))
    oracle = Rotation.from_euler(seq, angles)
    np.testing.assert_allclose(euler.quat_from_angles(angles, seq), oracle.as_quat(), rtol=0,
                               atol=TOL)
    np.testing.assert_allclose(rotvec_from_angles(angles, seq), oracle.as_rotvec(), rtol=0,
                               atol=4 * TOL)
    np.testing.assert_allclose(euler.matrix_from_angles(angles, seq), oracle.as_matrix(),
                               rtol=0, atol=TOL)
    deg = np.degrees(angles[:50])
    np.testing.assert_allclose(rotvec_from_angles(deg, seq, degrees=True),
                               Rotation.from_euler(seq, deg, degrees=True).as_rotvec(), rtol=0,
                               atol=4 * TOL)


@pytest.mark.parametrize("seq", SEQUENCES)
def test_rotation_vectors_and_matrices_to_angles_match_scipy(seq):
    """The same angles as scipy's ``as_euler`` (Bernardes–Viollet), in its ranges, with the
    third angle zero at a gimbal lock."""
    oracle = Rotation.from_euler(seq, _samples(seq, 100 + SEQUENCES.index(seq)))
    expected = _scipy_angles(oracle, seq)
    got = angles_from_rotvec(oracle.as_rotvec(), seq)
    assert _angle_gap(got, _scipy_angles(Rotation.from_rotvec(oracle.as_rotvec()), seq)).max() \
        <= 4 * TOL
    assert _angle_gap(euler.angles_from_quat(oracle.as_quat(), seq), expected).max() <= 4 * TOL
    matrices = oracle.as_matrix()
    from_matrix = _scipy_angles(Rotation.from_matrix(matrices), seq)
    locked = np.isclose(np.abs(np.cos(from_matrix[:, 1] if _symmetric(seq)
                                      else from_matrix[:, 1] + np.pi / 2)), 1.0, atol=1e-12)
    gap = _angle_gap(euler.angles_from_matrix(matrices, seq), from_matrix)
    assert gap[~locked].max() <= 1e-12  # the quaternions of a matrix differ by an ulp
    middle = got[:, 1]
    if _symmetric(seq):
        assert ((middle >= 0) & (middle <= np.pi)).all()
    else:
        assert ((middle >= -np.pi / 2) & (middle <= np.pi / 2)).all()
    assert (np.abs(got) <= np.pi).all()
    at_lock = np.minimum(np.abs(middle - (0 if _symmetric(seq) else np.pi / 2)),
                         np.abs(middle - (np.pi if _symmetric(seq) else -np.pi / 2))) <= 1e-7
    assert at_lock.sum() >= 100 and (got[at_lock, 2] == 0.0).all()
    assert (expected[at_lock, 2] == 0.0).all()


@pytest.mark.parametrize("seq", SEQUENCES)
def test_round_trips(seq):
    """angles → rotation vector → angles gives the angles back inside the ranges away from a
    lock; at a lock another triple of the same rotation, its third angle zero."""
    rng = np.random.default_rng(7)
    angles = rng.uniform(-np.pi, np.pi, (500, 3))
    angles[:, 1] = (rng.uniform(0.01, np.pi - 0.01, 500) if _symmetric(seq)
                    else rng.uniform(-np.pi / 2 + 0.01, np.pi / 2 - 0.01, 500))
    back = angles_from_rotvec(rotvec_from_angles(angles, seq), seq)
    assert _angle_gap(back, angles).max() <= 1e-12
    locked = angles.copy()
    locked[:, 1] = 0.0 if _symmetric(seq) else np.pi / 2
    again = angles_from_rotvec(rotvec_from_angles(locked, seq), seq)
    assert (again[:, 2] == 0.0).all()
    np.testing.assert_allclose(euler.matrix_from_angles(again, seq),
                               euler.matrix_from_angles(locked, seq), rtol=0, atol=1e-12)
    mats = euler.matrix_from_angles(angles, seq)
    assert _angle_gap(euler.angles_from_matrix(mats, seq), angles).max() <= 1e-12


def test_intrinsic_is_the_reverse_extrinsic_and_the_axes_are_right_handed():
    """Independent of scipy: ``R = Rz(c) Ry(b) Rx(a)`` for extrinsic xyz and for intrinsic ZYX
    with the angles reversed; a quarter turn about z takes x to y."""
    a, b, c = 0.3, -0.7, 1.9
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    np.testing.assert_allclose(euler.matrix_from_angles([a, b, c], "xyz"), rz @ ry @ rx,
                               atol=1e-15)
    np.testing.assert_allclose(euler.matrix_from_angles([c, b, a], "ZYX"), rz @ ry @ rx,
                               atol=1e-15)
    np.testing.assert_allclose(euler.matrix_from_angles([0, 0, 90], "xyz", degrees=True)
                               @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_rotation_vector_near_zero_and_near_half_turn():
    for phi in ([1e-9, -2e-9, 0.5e-9], [0.0, 0.0, 0.0], [np.pi, 0, 0], [0, -np.pi, 0],
                [1e-4, 2e-4, -3e-4], [2.0, -1.5, 1.0]):
        q = euler.quat_from_rotvec(np.asarray(phi))
        np.testing.assert_allclose(q[0], Rotation.from_rotvec(phi).as_quat(), rtol=0, atol=TOL)
        np.testing.assert_allclose(euler.rotvec_from_quat(q)[0],
                                   Rotation.from_rotvec(phi).as_rotvec(), rtol=0, atol=TOL)
    small = np.array([[5e-4, -6e-4, 4e-4], [9e-4, 1e-5, 0.0]])  # the series' branch, relative
    np.testing.assert_allclose(euler.rotvec_from_quat(euler.quat_from_rotvec(small)), small,
                               rtol=1e-15, atol=0)
    np.testing.assert_allclose(euler.quat_from_rotvec(small),
                               Rotation.from_rotvec(small).as_quat(), rtol=1e-15, atol=0)


def test_poses_convert_without_scipy_as_before():
    rng = np.random.default_rng(3)
    pos = rng.normal(size=(40, 3))
    ang = rng.uniform(-180, 180, (40, 3))
    for conv in ("xyz", "ZYX", "euler-zyz", "XZX"):
        seq = resolve_convention(conv)
        x = pose_from_angles(pos, ang, conv, degrees=True)
        oracle = Rotation.from_euler(seq, ang, degrees=True)
        np.testing.assert_allclose(x[:, 3:], oracle.as_rotvec(), rtol=0, atol=1e-14)
        p, back = pose_to_angles(x, conv, degrees=True)
        assert _angle_gap(np.radians(back), _scipy_angles(Rotation.from_rotvec(x[:, 3:]),
                                                          seq)).max() <= 1e-13
        np.testing.assert_array_equal(p, pos)
        np.testing.assert_allclose(pose_matrices(x)[1], oracle.as_matrix(), rtol=0, atol=TOL)
    single = pose_from_angles([0.1, 0.2, 0.3], [10.0, 20.0, 30.0], degrees=True)
    assert single.shape == (6,)
    assert pose_to_angles(single, degrees=True)[1].shape == (3,)
    position, angles = pose_to_angles(single, degrees=True)  # one pose: its own parts
    np.testing.assert_array_equal(position, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(angles, [10.0, 20.0, 30.0], rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="angles must be finite"):
        pose_from_angles([0, 0, 0], [np.nan, 0, 0])
    with pytest.raises(InputError, match="unknown angle convention"):
        pose_from_angles([0, 0, 0], [0, 0, 0], "xxy")
    with pytest.raises(InputError, match="rotation vectors must have shape"):
        angles_from_rotvec(np.zeros(4))


def test_non_finite_rows_give_nan_rows_silently():
    """A batch's failed rows (NaN, ±inf) come out NaN without a warning (warnings are errors
    under pytest; scipy's kernels are silent too), the good rows unchanged."""
    from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix

    phi = np.array([[0.1, 0.2, 0.3], [np.nan, 0, 0], [np.inf, 0, 0], [0, -np.inf, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mats = rotvec_to_matrix(phi)
        composed = compose_rotvec(phi, phi)
        angles = angles_from_rotvec(phi)
    assert np.isnan(mats[1:]).all() and np.isnan(composed[1:]).all()
    assert np.isnan(angles[1:]).any(axis=1).all()
    np.testing.assert_allclose(mats[0], Rotation.from_rotvec(phi[0]).as_matrix(), atol=TOL)
