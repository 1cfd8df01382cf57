"""Angle conventions, rotation vectors and matrices in NumPy alone (no SciPy import).

The command line's full-pose commands convert angles to rotation vectors and back on every call;
importing :mod:`scipy.spatial.transform` for that costs ≈ 0.2 s, more than the rest of a one-pose
``pkmkit ik``. These functions reproduce the arithmetic of scipy's ``Rotation`` (its NumPy
backend) step by step, through unit quaternions ``(x, y, z, w)``:

* angles → quaternion: the product of the three elementary quaternions (intrinsic sequences
  multiply on the right, extrinsic ones on the left), as ``Rotation.from_euler``;
* quaternion → angles: the method of Bernardes & Viollet (2022, "Quaternion to Euler angles
  conversion: a direct, general and computationally efficient method", PLoS ONE 17(11)), as
  ``Rotation.as_euler``: the first and third angles in [−π, π], the middle one in [−π/2, π/2]
  for Cardan sequences (three different axes) and in [0, π] for proper Euler ones; at a gimbal
  lock (middle angle within 1e-7 rad of its end values) the third angle is set to zero;
* rotation vectors and matrices: ``from_rotvec``/``as_rotvec`` (series below 1e-3 rad) and
  ``from_matrix`` (the largest of the diagonal and trace picks the formula)/``as_matrix``.

Conventions are scipy axis sequences as :func:`pkmkit.spatial.rotation.resolve_convention`
returns them (``"xyz"`` extrinsic, ``"ZYX"`` intrinsic, ...). Shapes: a single ``(3,)`` angle
or rotation-vector row gives a single result; ``(N, 3)`` rows give ``N`` results.
"""

from __future__ import annotations

import numpy as np

_AXIS = {"x": 0, "y": 1, "z": 2}

#: A middle angle within this of 0 or π (proper Euler), of ±π/2 (Cardan), is a gimbal lock.
GIMBAL_EPS = 1e-7


def _norm3(v: np.ndarray) -> np.ndarray:
    return np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1] + v[..., 2] * v[..., 2])


def quat_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton products ``p q`` of quaternions ``(..., 4)`` stored ``(x, y, z, w)``."""
    cross = np.cross(p[..., :3], q[..., :3])
    xyz = (p[..., 3, None] * q[..., :3] + q[..., 3, None] * p[..., :3] + cross)
    w = (p[..., 3] * q[..., 3] - p[..., 0] * q[..., 0] - p[..., 1] * q[..., 1]
         - p[..., 2] * q[..., 2])
    return np.concatenate([xyz, w[..., None]], axis=-1)


def _elementary(axis: int, angle: np.ndarray) -> np.ndarray:
    quat = np.zeros((*angle.shape, 4))
    quat[..., 3] = np.cos(angle / 2.0)
    quat[..., axis] = np.sin(angle / 2.0)
    return quat


def quat_from_angles(angles: np.ndarray, seq: str) -> np.ndarray:
    """Quaternions ``(N, 4)`` of angles ``(N, 3)`` (rad) about the axes of ``seq``."""
    angles = np.asarray(angles, dtype=float).reshape(-1, 3)
    axes = [_AXIS[c] for c in seq.lower()]
    e0, e1, e2 = (_elementary(axes[k], angles[:, k]) for k in range(3))
    if seq.isupper():  # intrinsic: about the moving axes, products on the right
        return quat_multiply(quat_multiply(e0, e1), e2)
    return quat_multiply(e2, quat_multiply(e1, e0))


def _wrap(angles: np.ndarray) -> np.ndarray:
    """One turn added below −π, removed above π (scipy's reduction: π stays π)."""
    return np.where(angles < -np.pi, angles + 2.0 * np.pi,
                    np.where(angles > np.pi, angles - 2.0 * np.pi, angles))


def angles_from_quat(quat: np.ndarray, seq: str) -> np.ndarray:
    """Angles ``(N, 3)`` (rad) of quaternions ``(N, 4)`` in the sequence ``seq`` (see the module
    docstring for the ranges and the gimbal-lock rule)."""
    quat = np.asarray(quat, dtype=float).reshape(-1, 4)
    extrinsic = seq.islower()
    i, j, k = (_AXIS[c] for c in (seq.lower() if extrinsic else seq.lower()[::-1]))
    symmetric = i == k
    if symmetric:
        k = 3 - i - j
    sign = (i - j) * (j - k) * (k - i) // 2
    if symmetric:
        a, b, c, d = quat[:, 3], quat[:, i], quat[:, j], quat[:, k] * sign
    else:
        a = quat[:, 3] - quat[:, j]
        b = quat[:, i] + quat[:, k] * sign
        c = quat[:, j] + quat[:, 3]
        d = quat[:, k] * sign - quat[:, i]
    middle = 2.0 * np.arctan2(np.hypot(c, d), np.hypot(a, b))
    half_sum, half_diff = np.arctan2(b, a), np.arctan2(d, c)
    at_zero = np.abs(middle) <= GIMBAL_EPS
    at_pi = np.abs(middle - np.pi) <= GIMBAL_EPS
    regular = ~(at_zero | at_pi)
    first, third = (0, 2) if extrinsic else (2, 0)
    out = np.zeros((quat.shape[0], 3))
    out[:, 1] = middle
    locked = np.where(at_zero, 2.0 * half_sum, 2.0 * half_diff * (-1.0 if extrinsic else 1.0))
    out[:, 0] = np.where(regular, 0.0, locked)  # at a lock: angle 0 carries it, angle 2 is zero
    out[:, first] = np.where(regular, half_sum - half_diff, out[:, first])
    out[:, third] = np.where(regular, half_sum + half_diff, out[:, third])
    if not symmetric:
        out[:, third] *= sign
        out[:, 1] -= np.pi / 2.0
    return _wrap(out)


def quat_from_rotvec(rotvec: np.ndarray) -> np.ndarray:
    """Quaternions ``(N, 4)`` of rotation vectors ``(N, 3)`` (rad)."""
    rotvec = np.asarray(rotvec, dtype=float).reshape(-1, 3)
    with np.errstate(invalid="ignore", over="ignore"):  # non-finite rows give NaN, silently
        angle = _norm3(rotvec)
        small = angle <= 1e-3
        angle2 = angle * angle
        safe = np.where(small, 1.0, angle)
        scale = np.where(small, 0.5 - angle2 / 48.0 + angle2 * angle2 / 3840.0,
                         np.sin(safe / 2.0) / safe)
        return np.concatenate([rotvec * scale[:, None], np.cos(angle / 2.0)[:, None]], axis=1)


def rotvec_from_quat(quat: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(N, 3)`` (rad, angle in [0, π]) of quaternions ``(N, 4)``."""
    quat = np.asarray(quat, dtype=float).reshape(-1, 4)
    x, y, z, w = quat.T  # canonical: w > 0, else the first non-zero of x, y, z positive
    flip = (w < 0) | ((w == 0) & ((x < 0) | ((x == 0) & ((y < 0) | ((y == 0) & (z < 0))))))
    quat = np.where(flip[:, None], -quat, quat)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
        angle = 2.0 * np.arctan2(_norm3(quat[:, :3]), quat[:, 3])
        small = angle <= 1e-3
        angle2 = angle * angle
        half_sin = np.where(small, 1.0, np.sin(angle / 2.0))
        scale = np.where(small, 2.0 + angle2 / 12.0 + 7.0 * angle2 * angle2 / 2880.0,
                         angle / half_sin)
        return scale[:, None] * quat[:, :3]


def compose_rotvecs(delta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(N, 3)`` of ``exp(δ) exp(φ)`` (rows ``(N, 3)`` or ``(1, 3)``
    broadcast), as ``(Rotation.from_rotvec(δ) * Rotation.from_rotvec(φ)).as_rotvec()``."""
    return rotvec_from_quat(quat_multiply(quat_from_rotvec(delta), quat_from_rotvec(phi)))


def matrix_from_quat(quat: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of unit quaternions ``(N, 4)``."""
    quat = np.asarray(quat, dtype=float).reshape(-1, 4)
    x, y, z, w = quat.T
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    return np.stack([x2 - y2 - z2 + w2, 2 * (xy - zw), 2 * (xz + yw),
                     2 * (xy + zw), -x2 + y2 - z2 + w2, 2 * (yz - xw),
                     2 * (xz - yw), 2 * (yz + xw), -x2 - y2 + z2 + w2],
                    axis=-1).reshape(-1, 3, 3)


def quat_from_matrix(matrix: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(N, 4)`` of rotation matrices ``(N, 3, 3)`` (assumed orthonormal with
    det +1: validate them with :func:`pkmkit.spatial.rotation.as_rotation_matrices`)."""
    m = np.asarray(matrix, dtype=float).reshape(-1, 3, 3)
    trace = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    choice = np.argmax(np.stack([m[:, 0, 0], m[:, 1, 1], m[:, 2, 2], trace], axis=1), axis=1)
    cases = np.stack([
        np.stack([1 - trace + 2 * m[:, 0, 0], m[:, 1, 0] + m[:, 0, 1],
                  m[:, 2, 0] + m[:, 0, 2], m[:, 2, 1] - m[:, 1, 2]], axis=1),
        np.stack([m[:, 1, 0] + m[:, 0, 1], 1 - trace + 2 * m[:, 1, 1],
                  m[:, 2, 1] + m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0]], axis=1),
        np.stack([m[:, 2, 0] + m[:, 0, 2], m[:, 2, 1] + m[:, 1, 2],
                  1 - trace + 2 * m[:, 2, 2], m[:, 1, 0] - m[:, 0, 1]], axis=1),
        np.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0],
                  m[:, 1, 0] - m[:, 0, 1], 1 + trace], axis=1)], axis=0)
    quat = cases[choice, np.arange(m.shape[0])]
    norm = np.sqrt(quat[:, 0] * quat[:, 0] + quat[:, 1] * quat[:, 1]
                   + quat[:, 2] * quat[:, 2] + quat[:, 3] * quat[:, 3])
    return quat / norm[:, None]


def _angles_rad(angles: np.ndarray, degrees: bool) -> np.ndarray:
    return np.deg2rad(angles) if degrees else angles


def _angles_out(angles: np.ndarray, degrees: bool, single: bool) -> np.ndarray:
    out = np.rad2deg(angles) if degrees else angles
    return out[0] if single else out


def rotvec_from_angles(angles: np.ndarray, seq: str, *, degrees: bool = False) -> np.ndarray:
    """Rotation vectors ``(3,)``/``(N, 3)`` (rad) of angles ``(3,)``/``(N, 3)`` in ``seq``."""
    arr = np.asarray(angles, dtype=float)
    out = rotvec_from_quat(quat_from_angles(_angles_rad(arr, degrees), seq))
    return out[0] if arr.ndim == 1 else out


def matrix_from_angles(angles: np.ndarray, seq: str, *, degrees: bool = False) -> np.ndarray:
    """Rotation matrices ``(3, 3)``/``(N, 3, 3)`` of angles ``(3,)``/``(N, 3)`` in ``seq``."""
    arr = np.asarray(angles, dtype=float)
    out = matrix_from_quat(quat_from_angles(_angles_rad(arr, degrees), seq))
    return out[0] if arr.ndim == 1 else out


def angles_from_rotvec(rotvec: np.ndarray, seq: str, *, degrees: bool = False) -> np.ndarray:
    """Angles ``(3,)``/``(N, 3)`` in ``seq`` of rotation vectors ``(3,)``/``(N, 3)`` (rad)."""
    arr = np.asarray(rotvec, dtype=float)
    return _angles_out(angles_from_quat(quat_from_rotvec(arr), seq), degrees, arr.ndim == 1)


def angles_from_matrix(matrix: np.ndarray, seq: str, *, degrees: bool = False) -> np.ndarray:
    """Angles ``(3,)``/``(N, 3)`` in ``seq`` of rotation matrices ``(3, 3)``/``(N, 3, 3)``."""
    arr = np.asarray(matrix, dtype=float)
    return _angles_out(angles_from_quat(quat_from_matrix(arr), seq), degrees, arr.ndim == 2)
