"""Full (6-DOF) poses: the API convention and conversions at I/O.

**The 6-DOF pose convention of the API**: a pose is a row of six numbers
``(x, y, z, rx, ry, rz)`` = the position of the platform (or tool) reference point in metres,
then the **rotation vector** (axis × angle, radians) of its frame, both in the fixed frame;
batches are ``(N, 6)``. Internally a pose is a position and a rotation matrix; angles in a named
convention (:mod:`pkmkit.spatial.rotation`) appear only at the boundaries.

A batch of poses as one value is scipy's :class:`~scipy.spatial.transform.RigidTransform`
(compose with ``*``, ``inv()``, ``apply(points)``); :func:`to_transform` and
:func:`from_transform` convert between it and pose rows.

>>> import numpy as np
>>> x = pose_from_angles([0.1, 0.0, 0.5], [0.0, 0.0, 90.0], "xyz", degrees=True)
>>> np.round(x, 6)
array([0.1     , 0.      , 0.5     , 0.      , 0.      , 1.570796])
>>> np.round(pose_to_angles(x, "xyz", degrees=True)[1], 9)
array([ 0.,  0., 90.])
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.spatial import euler
from pkmkit.spatial.rotation import (
    DEFAULT_CONVENTION,
    angles_from_rotvec,
    as_rotation_matrices,
    rotation_class,
    rotvec_from_angles,
)

if TYPE_CHECKING:
    from scipy.spatial.transform import RigidTransform, Rotation


def _rigid_class():
    from scipy.spatial.transform import RigidTransform  # lazy: start-up time

    return RigidTransform


#: Names of the six pose coordinates.
POSE_NAMES = ("x", "y", "z", "rx", "ry", "rz")


def _pose_rows(pose: Any) -> tuple[np.ndarray, bool]:
    arr = np.asarray(pose, dtype=float)
    if arr.shape[-1:] != (6,) or arr.ndim not in (1, 2):
        raise InputError(f"a 6-DOF pose must have shape (6,) or (N, 6), got {arr.shape}")
    return arr.reshape(-1, 6), arr.ndim == 1


def pose_from_parts(position: Any, rotation: Rotation | Any) -> np.ndarray:
    """Pose rows ``(N, 6)`` (or ``(6,)``) from positions ``(3,)``/``(N, 3)`` (m) and a
    :class:`Rotation` or rotation matrices ``(3, 3)``/``(N, 3, 3)``.

    Raises:
        InputError: mis-shaped or non-finite positions, matrices that are not rotations.
    """
    rotation_type = rotation_class()
    if isinstance(rotation, rotation_type):
        return _pose_rows_of(position, rotation.as_rotvec().reshape(-1, 3), rotation.single)
    # scipy's from_matrix: a matrix within the tolerance but not orthonormal to 1e-12 is
    # orthonormalised by SVD first
    rotvec = rotation_type.from_matrix(as_rotation_matrices(rotation)).as_rotvec()
    return _pose_rows_of(position, rotvec, np.asarray(rotation).ndim == 2)


def _pose_rows_of(position: Any, rotvec: np.ndarray, rot_single: bool) -> np.ndarray:
    """Pose rows of positions ``(3,)``/``(N, 3)`` and rotation vectors ``(M, 3)``, one of
    ``N``, ``M`` broadcast when it is 1; a single row when both inputs are single."""
    pos = np.asarray(position, dtype=float)
    if pos.shape[-1:] != (3,) or pos.ndim not in (1, 2) or not np.isfinite(pos).all():
        raise InputError(f"position must be finite with shape (3,) or (N, 3), got {pos.shape}")
    p = pos.reshape(-1, 3)
    if rotvec.shape[0] != p.shape[0] and 1 not in (rotvec.shape[0], p.shape[0]):
        raise InputError(f"{p.shape[0]} positions but {rotvec.shape[0]} rotations")
    n = max(p.shape[0], rotvec.shape[0])
    out = np.concatenate([np.broadcast_to(p, (n, 3)), np.broadcast_to(rotvec, (n, 3))], axis=1)
    return out[0] if pos.ndim == 1 and rot_single else out


def pose_from_angles(position: Any, angles: Any, convention: str = DEFAULT_CONVENTION, *,
                     degrees: bool = False) -> np.ndarray:
    """Pose rows from positions (m) and angles in a named convention (see
    :mod:`pkmkit.spatial.rotation`), in NumPy alone (:func:`rotvec_from_angles`).

    Raises:
        InputError: unknown convention, mis-shaped or non-finite positions or angles.
    """
    rotvec = rotvec_from_angles(angles, convention, degrees=degrees)
    return _pose_rows_of(position, rotvec.reshape(-1, 3), rotvec.ndim == 1)


def pose_parts(pose: Any) -> tuple[np.ndarray, Rotation]:
    """``(positions (N, 3) or (3,), Rotation)`` of pose rows ``(N, 6)`` or ``(6,)``."""
    rows, single = _pose_rows(pose)
    rot = rotation_class().from_rotvec(np.array(rows[:, 3:]))  # scipy: writeable buffers only
    if single:
        return rows[0, :3].copy(), rot[0]
    return rows[:, :3].copy(), rot


def pose_to_angles(pose: Any, convention: str = DEFAULT_CONVENTION, *,
                   degrees: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(positions, angles)`` of pose rows in a named convention, in NumPy alone
    (:func:`pkmkit.spatial.rotation.angles_from_rotvec`: ranges and gimbal lock as scipy's)."""
    rows, single = _pose_rows(pose)
    angles = angles_from_rotvec(rows[:, 3:], convention, degrees=degrees)
    if single:
        return rows[0, :3].copy(), angles[0]
    return rows[:, :3].copy(), angles


def to_transform(pose: Any) -> RigidTransform:
    """The pose rows as one (batched) :class:`RigidTransform`."""
    rows, single = _pose_rows(pose)
    out = _rigid_class().from_components(  # scipy's from_rotvec: writeable buffers only
        rows[:, :3], rotation_class().from_rotvec(np.array(rows[:, 3:])))
    return out[0] if single else out


def from_transform(transform: RigidTransform) -> np.ndarray:
    """Pose rows ``(N, 6)`` (``(6,)`` for a single transform) of a :class:`RigidTransform`."""
    translation, rotation = transform.as_components()
    rows = np.concatenate([np.reshape(translation, (-1, 3)),
                           np.reshape(rotation.as_rotvec(), (-1, 3))], axis=1)
    return rows[0] if transform.single else rows


def pose_matrices(pose: Any) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``(N, 3)`` and rotation matrices ``(N, 3, 3)`` of pose rows (kernel form)."""
    rows, _ = _pose_rows(pose)
    return rows[:, :3], euler.matrix_from_quat(euler.quat_from_rotvec(rows[:, 3:]))


def compose_poses(a: Any, b: Any) -> np.ndarray:
    """Pose rows of ``a ∘ b`` (b expressed in the frame of a), batched with broadcasting of a
    single pose."""
    return from_transform(to_transform(a) * to_transform(b))


def invert_poses(pose: Any) -> np.ndarray:
    """Pose rows of the inverse transforms."""
    return from_transform(to_transform(pose).inv())


def pose_difference(a: Any, b: Any) -> np.ndarray:
    """Small-displacement torsor-like difference ``(Δp, Δφ) (N, 6)`` from b to a, in the fixed
    frame: ``Δp = p_a − p_b`` and ``Δφ`` the rotation vector of ``R_a R_bᵀ``."""
    pa, ra = pose_parts(a)
    pb, rb = pose_parts(b)
    out = np.concatenate([np.reshape(pa - pb, (-1, 3)),
                          np.reshape((ra * rb.inv()).as_rotvec(), (-1, 3))], axis=1)
    return out
