"""Rigid registration of a measurement frame (laser tracker, CMM) to the machine frame.

:func:`register_points` finds the rotation R and translation t that map points measured in the
instrument's frame onto the same points known in the machine frame (``nominal ≈ R measured +
t``) in the least-squares sense — Kabsch/Umeyama, by one SVD of the cross-covariance — from three
or more points, optionally with direction vectors measured in both frames (seed 002's Table 5.4:
four points and the spindle directions given by two tool lengths). Directions constrain only the
rotation; each counts like a pair of points ``direction_weight`` apart (default: the RMS spread of
the points about their centroid), so both kinds of data weigh comparably.

The result carries the residuals per point (m) and per direction (angle, rad), their RMS and
maximum, and maps further points and directions. Registration by itself treats the machine
frame's points as exact; when they come from the machine's own (uncalibrated) controller, their
errors end up in the residuals — 0.085 mm rms on seed 002's Table 5.4 points (pkmkit's fit; the
thesis prints no residual) — and the frame can instead be identified
jointly with the machine (:mod:`pkmkit.calibration.identify`, ``frame="identify"``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.spatial.euler import angles_from_quat, quat_from_matrix, rotvec_from_quat
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix


@dataclass(frozen=True)
class Registration:
    """A rigid transform from a measurement frame to the machine frame, with its residuals.

    Attributes:
        rotation: ``(3, 3)`` R. translation: ``(3,)`` t (m): ``x_machine = R x_measured + t``.
        point_residuals: ``(N, 3)`` ``R m_i + t − n_i`` (m), or an empty array.
        direction_residuals: ``(K,)`` angle between ``R d_i`` and the nominal direction (rad).
    """

    rotation: np.ndarray
    translation: np.ndarray
    point_residuals: np.ndarray
    direction_residuals: np.ndarray

    @classmethod
    def identity(cls) -> Registration:
        """The identity transform (measurements already in the machine frame)."""
        return cls(np.eye(3), np.zeros(3), np.zeros((0, 3)), np.zeros(0))

    @property
    def rms(self) -> float:
        """RMS of the point residual norms (m)."""
        r = np.linalg.norm(self.point_residuals, axis=1)
        return float(np.sqrt(np.mean(r**2))) if r.size else 0.0

    @property
    def max(self) -> float:
        """Largest point residual norm (m)."""
        r = np.linalg.norm(self.point_residuals, axis=1)
        return float(r.max()) if r.size else 0.0

    def apply(self, points: Any) -> np.ndarray:
        """Map points ``(N, 3)`` (or ``(3,)``) from the measurement frame to the machine frame."""
        p = np.asarray(points, dtype=float)
        return p @ self.rotation.T + self.translation

    def apply_directions(self, directions: Any) -> np.ndarray:
        """Rotate directions ``(N, 3)`` into the machine frame."""
        return np.asarray(directions, dtype=float) @ self.rotation.T

    def apply_rotations(self, rotvecs: Any) -> np.ndarray:
        """Map orientations (rotation vectors ``(N, 3)``) into the machine frame."""
        r = rotvec_to_matrix(np.atleast_2d(np.asarray(rotvecs, dtype=float)))
        return matrix_to_rotvec(self.rotation[None] @ r)

    def inverse(self) -> Registration:
        """The transform from the machine frame to the measurement frame (no residuals)."""
        rt = self.rotation.T
        return Registration(rt, -rt @ self.translation, np.zeros((0, 3)), np.zeros(0))

    def compose(self, first: Registration) -> Registration:
        """``self ∘ first``: apply ``first`` then ``self`` (no residuals)."""
        return Registration(self.rotation @ first.rotation,
                            self.rotation @ first.translation + self.translation,
                            np.zeros((0, 3)), np.zeros(0))

    def to_dict(self, scale: float = 1.0) -> dict[str, Any]:
        """JSON-ready fields; lengths divided by ``scale`` (metres per output unit)."""
        # scipy's Rotation arithmetic in NumPy (pkmkit.spatial.euler): `pkmkit register` need
        # not import scipy.spatial (≈ 0.2 s)
        quat = quat_from_matrix(self.rotation)
        res = np.linalg.norm(self.point_residuals, axis=1) / scale
        return {
            "rotation": self.rotation.tolist(),
            "rotation_vector_deg": np.degrees(rotvec_from_quat(quat)[0]).tolist(),
            "euler_xyz_deg": np.degrees(angles_from_quat(quat, "xyz")[0]).tolist(),
            "translation": (self.translation / scale).tolist(),
            "point_residuals": (self.point_residuals / scale).tolist(),
            "point_residual_norms": res.tolist(),
            "rms": self.rms / scale,
            "max": self.max / scale,
            "direction_residuals_deg": np.degrees(self.direction_residuals).tolist(),
        }


#: Largest lever arm of a direction, m (1000 km: beyond, a unit mistake).
MAX_LEVER = 1e6


def register_points(measured: Any, nominal: Any, *, measured_directions: Any = None,
                    nominal_directions: Any = None, direction_weight: float | None = None,
                    weights: Any = None) -> Registration:
    """Least-squares rigid transform taking ``measured`` points onto ``nominal`` ones.

    Args:
        measured: ``(N, 3)`` points in the measurement frame (m).
        nominal: ``(N, 3)`` the same points in the machine frame (m).
        measured_directions, nominal_directions: optional ``(K, 3)`` directions in each frame
            (any length; normalised here).
        direction_weight: lever arm (m) at which a direction counts like a point pair; default
            the RMS distance of the points to their centroid.
        weights: optional ``(N,)`` positive weights of the points.

    Raises:
        InputError: mis-shaped or non-finite input, fewer than 3 points without directions, or
            data that do not fix the rotation (collinear points and no independent direction).
    """
    m = _points(measured, "measured points")
    n = _points(nominal, "nominal points")
    if m.shape != n.shape:
        raise InputError(f"measured and nominal points differ in number: {len(m)} vs {len(n)}")
    w = np.ones(len(m)) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
    if w.shape != (len(m),) or not (np.isfinite(w).all() and (w > 0).all()):
        raise InputError("weights must be one positive number per point")
    dm = dn = None
    if (measured_directions is None) != (nominal_directions is None):
        raise InputError("give directions in both frames or in neither")
    if measured_directions is not None:
        dm = _unit(_points(measured_directions, "measured directions"), "measured directions")
        dn = _unit(_points(nominal_directions, "nominal directions"), "nominal directions")
        if dm.shape != dn.shape:
            raise InputError(f"measured and nominal directions differ in number: {len(dm)} vs "
                             f"{len(dn)}")
    if len(m) < 3 and dm is None:
        raise InputError(f"a rigid registration needs at least 3 points (or directions), got "
                         f"{len(m)}")
    if len(m) < 1:
        raise InputError("a registration needs at least one point to fix the translation")
    cm = (w[:, None] * m).sum(axis=0) / w.sum()
    cn = (w[:, None] * n).sum(axis=0) / w.sum()
    h = ((w[:, None] * (m - cm)).T @ (n - cn))
    if dm is not None:
        spread = float(np.sqrt((w * ((m - cm) ** 2).sum(axis=1)).sum() / w.sum()))
        lever = direction_weight if direction_weight is not None else max(spread, 1e-3)
        if not (np.isfinite(lever) and lever > 0):
            raise InputError("direction_weight must be a positive length")
        if lever > MAX_LEVER:  # its square would overflow long before: a unit mistake
            raise InputError(f"direction_weight = {lever:g} m is beyond {MAX_LEVER:g} m: check "
                             "the units")
        h = h + w.mean() * lever**2 * (dm.T @ dn)
    u, s, vt = np.linalg.svd(h)
    if s[1] <= 1e-12 * max(s[0], 1e-300):
        raise InputError("the points and directions do not fix the rotation (collinear points "
                         "and no direction across them); add a point off the line or a "
                         "direction")
    d = np.sign(np.linalg.det(vt.T @ u.T))
    rot = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    t = cn - rot @ cm
    residuals = m @ rot.T + t - n
    angles = np.zeros(0)
    if dm is not None:
        cosines = np.clip(np.einsum("ij,ij->i", dm @ rot.T, dn), -1.0, 1.0)
        angles = np.arccos(cosines)
    return Registration(rot, t, residuals, angles)


def _points(value: Any, what: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.size == 3:
        arr = arr[None]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InputError(f"{what} must be an (N, 3) array, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        row = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
        raise InputError(f"{what}: row {row} is not finite")
    return arr


def _unit(arr: np.ndarray, what: str) -> np.ndarray:
    norm = np.linalg.norm(arr, axis=1)
    if not (norm > 0).all():
        raise InputError(f"{what}: row {int(np.flatnonzero(~(norm > 0))[0])} has zero length")
    return arr / norm[:, None]


def save_registration(path: str | Path, reg: Registration, *, units: str = "m") -> None:
    """Write a registration as JSON (lengths in ``units``), atomically."""
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text
    from pkmkit.model.parameters import length_scale

    payload = {"units": units, **reg.to_dict(length_scale(units))}
    atomic_write_text(path, json.dumps(payload, indent=2) + "\n")


def load_registration(path: str | Path) -> Registration:
    """Read a registration written by :func:`save_registration` (or ``pkmkit register
    --out``).

    Raises:
        InputError: unreadable file, missing or malformed fields.
    """
    from pkmkit.model.parameters import length_scale

    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read file: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a UTF-8 text file (byte {exc.start}): not a registration "
                         "JSON") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}:{exc.lineno}: not JSON: {exc.msg}") from None
    except RecursionError:
        raise InputError(f"{path}: not a registration JSON (nested too deeply)") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        raise InputError(f"{path}: not a registration JSON: {exc}") from None
    try:
        scale = length_scale(data.get("units", "m"))
        rot = np.asarray(data["rotation"], dtype=float)
        t = np.asarray(data["translation"], dtype=float) * scale
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: a registration needs 'rotation' (3×3) and 'translation' "
                         f"(3) [{exc}]") from None
    except Exception as exc:  # an unknown unit
        raise InputError(f"{path}: {exc}") from None
    if rot.shape != (3, 3) or t.shape != (3,) or not (np.isfinite(rot).all()
                                                      and np.isfinite(t).all()):
        raise InputError(f"{path}: rotation must be 3×3 and translation 3 finite numbers")
    if (np.abs(rot).max() > 1.0 + 1e-6  # entries of a rotation lie in [-1, 1] (and R^T R
            or not np.allclose(rot.T @ rot, np.eye(3), atol=1e-6)  # overflows beyond)
            or np.linalg.det(rot) < 0):
        raise InputError(f"{path}: 'rotation' is not a rotation matrix")
    return Registration(rot, t, np.zeros((0, 3)), np.zeros(0))
