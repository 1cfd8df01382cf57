"""Batched rotations and named angle conventions.

Orientations are rotation vectors φ (axis × angle, radians) at the interfaces and rotation
matrices inside computations. Conversions go through :class:`scipy.spatial.transform.Rotation`,
which handles the small-angle and near-π cases carefully, or through its arithmetic redone in
NumPy (:mod:`pkmkit.spatial.euler`) on the command line's start-up paths, where importing SciPy's
``spatial`` (≈ 0.2 s) would cost more than the command.

Perturbations are *left* (world-frame) increments: ``R ← exp([δ]×) R``.

**Angle conventions** are named, never guessed, and used only at I/O (command line, files,
reports). A convention is a scipy-style axis sequence: three letters from ``xyz``, *upper case
for intrinsic* rotations (about the moving axes, e.g. ``"ZYX"`` yaw–pitch–roll) and *lower case
for extrinsic* rotations (about the fixed axes, e.g. ``"xyz"``). The angles are given in the
order of the sequence. A few aliases name common choices (see :data:`CONVENTION_ALIASES`); the
default of the command line, :data:`DEFAULT_CONVENTION`, is ``"xyz"``: A about the fixed x axis,
then B about the fixed y axis, then C about the fixed z axis, i.e. ``R = Rz(C) Ry(B) Rx(A)``
(roll–pitch–yaw, the A/B/C of machine-tool axes named after x/y/z).

>>> import numpy as np
>>> R = rotation_from_angles([90.0, 0.0, 0.0], "xyz", degrees=True)
>>> np.round(R.apply([0.0, 1.0, 0.0]), 12)
array([0., 0., 1.])
>>> np.round(angles_from_rotation(R, "xyz", degrees=True), 9)
array([90.,  0.,  0.])
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.spatial import euler as _euler

if TYPE_CHECKING:
    from scipy.spatial.transform import Rotation


def rotation_class():
    """scipy's Rotation, imported on first use (SciPy's spatial costs ~0.2 s to import, which
    the command line's start-up must not pay)."""
    from scipy.spatial.transform import Rotation

    return Rotation

#: The command line's default angle convention (fixed axes x, then y, then z).
DEFAULT_CONVENTION = "xyz"

#: Common names of angle conventions, mapped to scipy axis sequences.
CONVENTION_ALIASES: dict[str, str] = {
    "rpy": "xyz",  # roll about x, pitch about y, yaw about z, fixed axes
    "roll-pitch-yaw": "xyz",
    "fixed-xyz": "xyz",
    "cardan-xyz": "XYZ",  # Cardan/Bryant angles about the moving axes x, y', z''
    "bryant": "XYZ",
    "ypr": "ZYX",  # yaw-pitch-roll about the moving axes (aerospace)
    "yaw-pitch-roll": "ZYX",
    "euler-zyz": "ZYZ",
    "euler-zxz": "ZXZ",
}

_SEQUENCE = re.compile(r"^(?:[xyz]{3}|[XYZ]{3})$")

#: Tolerance on ‖RᵀR − I‖ and |det R − 1| for a matrix accepted as a rotation.
ROTATION_TOL = 1e-6


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrices ``[v]×`` with ``[v]× w = v × w``.

    Args:
        v: ``(..., 3)``.

    Returns:
        ``(..., 3, 3)``.
    """
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _rows3(value: np.ndarray) -> np.ndarray:
    """``(N, 3)`` float rows scipy's kernels accept (they need writable buffers)."""
    arr = np.asarray(value, dtype=float).reshape(-1, 3)
    return arr if arr.flags.writeable else arr.copy()


def rotvec_to_matrix(phi: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of rotation vectors ``(N, 3)`` (radians), in NumPy alone
    (scipy's ``from_rotvec(...).as_matrix()`` arithmetic, the same bits)."""
    return _euler.matrix_from_quat(_euler.quat_from_rotvec(_rows3(phi)))


def _rotations(arr: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    """Which matrices of ``(N, 3, 3)`` are finite rotations to within ``tol`` (scipy's
    ``from_matrix`` first projects other matrices onto the rotations; only for those do the two
    paths below differ). Row by row, so a row's path never depends on the rows beside it."""
    with np.errstate(invalid="ignore", over="ignore"):
        gram = np.matmul(np.swapaxes(arr, 1, 2), arr) - np.eye(3)
        det = np.einsum("ni,ni->n", arr[:, 0], np.cross(arr[:, 1], arr[:, 2]))
        return np.isfinite(arr).all(axis=(1, 2)) & (np.abs(gram).max(axis=(1, 2)) <= tol) \
            & (det > 0)


def matrix_to_rotvec(matrix: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(N, 3)`` (radians, angle in [0, π]) of rotation matrices ``(N, 3, 3)``;
    NaN rows for matrices with a non-finite entry (failed rows of a batch)."""
    arr = np.asarray(matrix, dtype=float).reshape(-1, 3, 3)
    rotations = _rotations(arr)
    if rotations.all():
        # scipy's arithmetic in NumPy (equal to ~1e-15): building a joint-chain machine (its
        # home) must not import scipy.spatial (≈ 0.2 s of a one-pose command's start-up)
        return _euler.rotvec_from_quat(_euler.quat_from_matrix(arr))
    out = np.full((arr.shape[0], 3), np.nan)
    if rotations.any():
        out[rotations] = _euler.rotvec_from_quat(_euler.quat_from_matrix(arr[rotations]))
    other = np.isfinite(arr).all(axis=(1, 2)) & ~rotations
    if other.any():
        out[other] = rotation_class().from_matrix(arr[other]).as_rotvec()
    return out


def compose_rotvec(delta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rotation vector of ``exp(δ) · exp(φ)`` (left increment δ applied to φ), rows ``(N, 3)``
    (a single row of either broadcast), in NumPy alone (scipy's quaternion arithmetic)."""
    return _euler.compose_rotvecs(_rows3(delta), _rows3(phi))


def left_jacobian(phi: np.ndarray) -> np.ndarray:
    """``J_l(φ)`` of SO(3): ``exp(φ + dφ) ≈ exp(J_l(φ) dφ) exp(φ)`` to first order in dφ.

    Args:
        phi: ``(3,)`` or ``(N, 3)`` rotation vectors (rad).

    Returns:
        ``(3, 3)`` or ``(N, 3, 3)``. Below 1e-3 rad the coefficients' series (to θ², exact to
        1e-15) replace the closed forms, whose ``(1 − cos θ)/θ²`` loses its digits to
        cancellation there.
    """
    phi = np.asarray(phi, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)[..., None, None]
    k = skew(phi)
    small = theta < 1e-3
    safe = np.where(small, 1.0, theta)
    t2 = theta**2
    a = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    b = np.where(small, 1.0 / 6.0 - t2 / 120.0, (safe - np.sin(safe)) / safe**3)
    return np.eye(3) + a * k + b * (k @ k)


def inverse_left_jacobian(phi: np.ndarray) -> np.ndarray:
    """``J_l⁻¹(φ)`` of SO(3) (the inverse of :func:`left_jacobian`).

    Args:
        phi: ``(3,)`` or ``(N, 3)`` rotation vectors (rad), norms below π.

    Returns:
        ``(3, 3)`` or ``(N, 3, 3)``.
    """
    phi = np.asarray(phi, dtype=float)
    theta = np.linalg.norm(phi, axis=-1)[..., None, None]
    k = skew(phi)
    small = theta < 1e-3          # series to θ² (exact to 1e-16): the closed form cancels
    safe = np.where(small, 1.0, theta)
    coef = np.where(small, 1.0 / 12.0 + theta**2 / 720.0,
                    1.0 / safe**2 - (1.0 + np.cos(safe)) / (2.0 * safe * np.sin(safe)))
    return np.eye(3) - 0.5 * k + coef * (k @ k)


def axis_rotation(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices about unit axes by angles (Rodrigues), batched.

    Args:
        axis: ``(..., 3)`` unit vectors.
        angle: ``(...)`` radians (broadcast against ``axis[..., 0]``).

    Returns:
        ``(..., 3, 3)``.
    """
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    k = skew(axis)
    outer = axis[..., :, None] * axis[..., None, :]
    eye = np.eye(3)
    return (c[..., None, None] * eye + s[..., None, None] * k
            + (1.0 - c)[..., None, None] * outer)


def resolve_convention(name: Any) -> str:
    """The scipy axis sequence of a named angle convention.

    Accepts a sequence (``"xyz"`` extrinsic, ``"ZYX"`` intrinsic, ...) or an alias of
    :data:`CONVENTION_ALIASES` (case-insensitive for aliases).

    Raises:
        InputError: an unknown name (the message lists the valid forms).
    """
    if isinstance(name, str):
        text = name.strip()
        alias = CONVENTION_ALIASES.get(text.lower())
        if alias is not None:
            return alias
        if _SEQUENCE.match(text) and len(set(text.lower())) >= 2 and text[0].lower() != text[
                1].lower() and text[1].lower() != text[2].lower():
            return text
    raise InputError(
        f"unknown angle convention {name!r}: give three axes from x, y, z with no axis twice in a "
        "row, lower case for rotations about the fixed axes (e.g. 'xyz') or upper case about the "
        f"moving axes (e.g. 'ZYX', 'ZYZ'), or one of {', '.join(sorted(CONVENTION_ALIASES))}"
    )


def describe_convention(name: Any) -> str:
    """One-line description of a convention, e.g. ``"xyz: extrinsic (fixed axes) x, y, z"``."""
    seq = resolve_convention(name)
    kind = "intrinsic (moving axes)" if seq.isupper() else "extrinsic (fixed axes)"
    return f"{seq}: {kind} {', '.join(seq.lower())}"


def _checked_angles(angles: Any) -> np.ndarray:
    arr = np.asarray(angles, dtype=float)
    if arr.shape[-1:] != (3,) or arr.ndim > 2:
        raise InputError(f"angles must have shape (3,) or (N, 3), got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputError(f"angles must be finite, got {arr.tolist()}")
    return arr


def rotation_from_angles(angles: Any, convention: str = DEFAULT_CONVENTION, *,
                         degrees: bool = False) -> Rotation:
    """A (batched) :class:`~scipy.spatial.transform.Rotation` from angles in a named convention.

    Args:
        angles: ``(3,)`` or ``(N, 3)`` angles in the order of the convention's axes.
        convention: see :func:`resolve_convention`.
        degrees: angles in degrees (the command line) instead of radians.

    Raises:
        InputError: unknown convention, mis-shaped or non-finite angles.
    """
    seq = resolve_convention(convention)
    arr = _checked_angles(angles)
    return rotation_class().from_euler(seq, arr, degrees=degrees)


def rotvec_from_angles(angles: Any, convention: str = DEFAULT_CONVENTION, *,
                       degrees: bool = False) -> np.ndarray:
    """Rotation vectors ``(3,)`` or ``(N, 3)`` (rad, angle in [0, π]) of angles in a named
    convention, in NumPy alone (no SciPy import: the command line's start-up path); the same
    numbers as ``rotation_from_angles(...).as_rotvec()`` to a few ulps.

    Args:
        angles: ``(3,)`` or ``(N, 3)`` angles in the order of the convention's axes.
        convention: see :func:`resolve_convention`.
        degrees: angles in degrees instead of radians.

    Raises:
        InputError: unknown convention, mis-shaped or non-finite angles.
    """
    seq = resolve_convention(convention)
    return _euler.rotvec_from_angles(_checked_angles(angles), seq, degrees=degrees)


def angles_from_rotvec(rotvec: Any, convention: str = DEFAULT_CONVENTION, *,
                       degrees: bool = False) -> np.ndarray:
    """Angles ``(3,)`` or ``(N, 3)`` in a named convention of rotation vectors ``(3,)`` or
    ``(N, 3)`` (rad), in NumPy alone; the numbers of scipy's ``as_euler`` (ranges and gimbal
    lock as :func:`angles_from_rotation`) to a few ulps.

    Raises:
        InputError: unknown convention, mis-shaped rotation vectors.
    """
    seq = resolve_convention(convention)
    arr = np.asarray(rotvec, dtype=float)
    if arr.shape[-1:] != (3,) or arr.ndim > 2:
        raise InputError(f"rotation vectors must have shape (3,) or (N, 3), got {arr.shape}")
    return _euler.angles_from_rotvec(arr, seq, degrees=degrees)


def angles_from_rotation(rotation: Rotation, convention: str = DEFAULT_CONVENTION, *,
                         degrees: bool = False) -> np.ndarray:
    """Angles ``(3,)`` or ``(N, 3)`` of a rotation in a named convention.

    The first and third angles lie in [−π, π], the middle one in [−π/2, π/2] for Cardan
    sequences (three different axes) and in [0, π] for proper Euler ones (``"ZYZ"``...). At a
    gimbal lock (the middle angle at ±90° for Cardan sequences, 0/180° for Euler ones) the
    first and third angles are not unique; scipy then sets the third to zero.
    """
    seq = resolve_convention(convention)
    import warnings

    with warnings.catch_warnings():  # the gimbal-lock warning: documented above
        warnings.simplefilter("ignore", UserWarning)
        return rotation.as_euler(seq, degrees=degrees)


def as_rotation_matrices(value: Any, name: str = "rotation") -> np.ndarray:
    """Validate rotation matrices ``(3, 3)`` or ``(N, 3, 3)``: finite, orthonormal, det +1.

    Returns:
        ``(N, 3, 3)`` float array.

    Raises:
        InputError: wrong shape, non-finite entries, or a matrix that is not a rotation (the
            message names the first bad matrix and by how much it fails).
    """
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be an array of real numbers") from None
    if arr.shape[-2:] != (3, 3) or arr.ndim not in (2, 3):
        raise InputError(f"{name} must have shape (3, 3) or (N, 3, 3), got {arr.shape}")
    arr = arr.reshape(-1, 3, 3)
    if not np.isfinite(arr).all():
        k = int(np.flatnonzero(~np.isfinite(arr).all(axis=(1, 2)))[0])
        raise InputError(f"{name} {k} has non-finite entries")
    gram = np.einsum("kji,kjl->kil", arr, arr) - np.eye(3)
    ortho = np.abs(gram).max(axis=(1, 2))
    det = np.linalg.det(arr)
    bad = (ortho > ROTATION_TOL) | (np.abs(det - 1.0) > ROTATION_TOL)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputError(
            f"{name} {k} is not a rotation matrix: |RᵀR − I| = {ortho[k]:.3g}, det = {det[k]:.6g} "
            f"(a rotation needs orthonormal columns and det = +1)")
    return arr
