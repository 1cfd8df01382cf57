"""Rigid registration: the rotation and translation that best map measured points (and,
optionally, measured directions) of one frame onto the same points and directions in another —
the frame transfer of every calibration set-up (laser tracker → machine frame, CMM → part frame,
model frame → tracker frame).

Problem (weighted least squares, solved exactly; Kabsch/Umeyama with directions)::

    min over R ∈ SO(3), t   Σ_i w_i ‖R a_i + t − b_i‖²  +  Σ_j v_j ‖R d_j − e_j‖²

with points ``a_i → b_i`` and unit directions ``d_j → e_j`` (directions are normalised here:
a tool vector measured as the difference of two tool tips carries only its direction). The
translation is fixed by the weighted centroids, ``t = b̄ − R ā``; the rotation maximises
``tr(Rᵀ H)`` with ``H = Σ w_i (b_i − b̄)(a_i − ā)ᵀ + Σ v_j e_j d_jᵀ``, from the SVD of H
with the determinant correction that forbids reflections.

A direction weight ``v_j`` is a squared length: an angular error δ of a direction costs as much
as a point error of ``sqrt(v_j)·δ`` (a direction measured with a tool of length ℓ naturally
weighs ``ℓ²``).

The problem is well posed when H has rank ≥ 2 (three non-collinear points, or two distinct
points and one direction not along them, or two non-parallel directions); otherwise the rotation
about one axis is undetermined and the row is flagged (single problems raise
:class:`~pkmkit.exceptions.InputError`).

Batched: every argument may carry leading batch dimensions ``(..., n, 3)`` (one registration
per batch entry, all with the same numbers of points and directions).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError

#: A registration is ill-posed when the second singular value of H is below this fraction of
#: the first.
RANK_RCOND = 1e-10


@dataclass(frozen=True)
class RigidRegistration:
    """Result of :func:`rigid_registration` (batch dimensions ``...`` first).

    Attributes:
        rotation: ``(..., 3, 3)`` R, source frame → target frame.
        translation: ``(..., 3)`` t (units of the points).
        residuals: ``(..., n, 3)`` ``b_i − (R a_i + t)``.
        point_errors: ``(..., n)`` norms of the residuals.
        rms: ``(...,)`` root mean square of ``point_errors`` (unweighted).
        direction_angles: ``(..., m)`` angles between ``R d_j`` and ``e_j`` (rad); ``(..., 0)``
            without directions.
        well_posed: ``(...,)`` bool; ill-posed rows hold NaN.
    """

    rotation: np.ndarray
    translation: np.ndarray
    residuals: np.ndarray
    point_errors: np.ndarray
    rms: np.ndarray
    direction_angles: np.ndarray
    well_posed: np.ndarray

    @property
    def matrix(self) -> np.ndarray:
        """``(..., 4, 4)`` homogeneous transform ``[R t; 0 1]``."""
        out = np.zeros((*self.rotation.shape[:-2], 4, 4))
        out[..., :3, :3] = self.rotation
        out[..., :3, 3] = self.translation
        out[..., 3, 3] = 1.0
        return out

    def apply(self, points: Any) -> np.ndarray:
        """Map points ``(..., k, 3)`` of the source frame into the target frame."""
        p = np.asarray(points, dtype=float)
        return np.einsum("...ij,...kj->...ki", self.rotation, p) + self.translation[..., None, :]

    def apply_directions(self, directions: Any) -> np.ndarray:
        """Rotate directions ``(..., k, 3)`` of the source frame into the target frame."""
        d = np.asarray(directions, dtype=float)
        return np.einsum("...ij,...kj->...ki", self.rotation, d)

    def inverse(self) -> RigidRegistration:
        """The transform target → source (residuals expressed in the source frame)."""
        rot = np.swapaxes(self.rotation, -1, -2)
        trans = -np.einsum("...ij,...j->...i", rot, self.translation)
        res = -np.einsum("...ij,...kj->...ki", rot, self.residuals)
        return RigidRegistration(rotation=rot, translation=trans, residuals=res,
                                 point_errors=self.point_errors, rms=self.rms,
                                 direction_angles=self.direction_angles,
                                 well_posed=self.well_posed)


def _vectors(value: Any, name: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim < 2 or arr.shape[-1] != 3:
        raise InputError(f"{name} must have shape (..., n, 3), got {arr.shape}")
    bad = ~np.isfinite(arr).all(axis=-1)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"{name} has a non-finite entry at index {where}")
    return arr


def _weights(value: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    if value is None:
        return np.ones(shape)
    arr = np.asarray(value, dtype=float)
    try:
        arr = np.broadcast_to(arr, shape)
    except ValueError:
        raise InputError(f"{name} must broadcast to {shape}, got shape {arr.shape}") from None
    if not (np.isfinite(arr).all() and (arr >= 0).all()):
        raise InputError(f"{name} must be finite and ≥ 0")
    return arr


def _direction_terms(source_directions: Any, target_directions: Any, direction_weights: Any,
                     batch: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Unit directions ``d, e (..., m, 3)`` in both frames and their term
    ``Σ v_j e_j d_jᵀ (..., 3, 3)`` of the cross-covariance (None without directions)."""
    if (source_directions is None) != (target_directions is None):
        raise InputError("give both source_directions and target_directions, or neither")
    if source_directions is None:
        d = e = np.zeros((*batch, 0, 3))
        return d, e, None
    d = _vectors(source_directions, "source_directions")
    e = _vectors(target_directions, "target_directions")
    if d.shape != e.shape or d.shape[:-2] != batch:
        raise InputError(f"directions must have shape {(*batch, 'm', 3)} in both frames, got "
                         f"{d.shape} and {e.shape}")
    norms_d = np.linalg.norm(d, axis=-1)
    norms_e = np.linalg.norm(e, axis=-1)
    if not ((norms_d > 0).all() and (norms_e > 0).all()):
        raise InputError("directions must not have zero length")
    d = d / norms_d[..., None]
    e = e / norms_e[..., None]
    v = _weights(direction_weights, d.shape[:-1], "direction_weights")
    return d, e, np.einsum("...m,...mi,...mj->...ij", v, e, d)


def rigid_registration(
    source: Any,
    target: Any,
    *,
    weights: Any = None,
    source_directions: Any = None,
    target_directions: Any = None,
    direction_weights: Any = 1.0,
) -> RigidRegistration:
    """Best rigid transform mapping source points (and directions) onto target ones.

    Args:
        source: ``(..., n, 3)`` points a_i in the source frame.
        target: ``(..., n, 3)`` the same points b_i measured in the target frame.
        weights: ``(..., n)`` point weights w_i ≥ 0 (default 1).
        source_directions: ``(..., m, 3)`` directions d_j in the source frame (normalised here).
        target_directions: ``(..., m, 3)`` the same directions e_j in the target frame.
        direction_weights: ``(..., m)`` or a scalar, v_j ≥ 0, a squared length (module
            docstring); default 1 (one unit of length squared).

    Returns:
        :class:`RigidRegistration`.

    Raises:
        InputError: mis-shaped or non-finite input, zero-length directions, no positive point
            weight, or (for a single problem) an ill-posed registration.

    >>> import numpy as np
    >>> a = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> b = a @ np.array([[0., -1, 0], [1, 0, 0], [0, 0, 1]]).T + [1, 2, 3]
    >>> reg = rigid_registration(a, b)
    >>> np.round(reg.translation, 12).tolist(), float(np.round(reg.rms, 12))
    ([1.0, 2.0, 3.0], 0.0)
    """
    a = _vectors(source, "source")
    b = _vectors(target, "target")
    if a.shape != b.shape:
        raise InputError(f"source and target must have the same shape, got {a.shape} and "
                         f"{b.shape}")
    batch, n = a.shape[:-2], a.shape[-2]
    if n < 1:
        raise InputError("at least one point is needed")
    w = _weights(weights, (*batch, n), "weights")
    total = w.sum(axis=-1)
    if not (total > 0).all():
        raise InputError("the point weights must not all be zero")
    centre_a = np.einsum("...n,...ni->...i", w, a) / total[..., None]
    centre_b = np.einsum("...n,...ni->...i", w, b) / total[..., None]
    da, db = a - centre_a[..., None, :], b - centre_b[..., None, :]
    h = np.einsum("...n,...ni,...nj->...ij", w, db, da)
    d, e, h_directions = _direction_terms(source_directions, target_directions,
                                         direction_weights, batch)
    if h_directions is not None:
        h = h + h_directions
    u, s, vt = np.linalg.svd(h)
    well_posed = s[..., 1] > RANK_RCOND * s[..., 0]
    if not batch and not well_posed:
        raise InputError("the registration is ill-posed: the points (and directions) do not "
                         "fix the rotation (fewer than three non-collinear points, or collinear "
                         "points with no direction off their line)")
    fix = np.ones((*batch, 3))
    fix[..., 2] = np.where(np.linalg.det(u @ vt) < 0, -1.0, 1.0)
    rot = np.einsum("...ij,...j,...jk->...ik", u, fix, vt)
    rot = np.where(well_posed[..., None, None], rot, np.nan)
    trans = centre_b - np.einsum("...ij,...j->...i", rot, centre_a)
    res = b - (np.einsum("...ij,...nj->...ni", rot, a) + trans[..., None, :])
    errors = np.linalg.norm(res, axis=-1)
    rms = np.sqrt(np.mean(errors**2, axis=-1))
    turned = np.einsum("...ij,...mj->...mi", rot, d)
    angles = np.arctan2(np.linalg.norm(np.cross(turned, e), axis=-1),
                        np.einsum("...mi,...mi->...m", turned, e))
    return RigidRegistration(rotation=rot, translation=trans, residuals=res,
                             point_errors=errors, rms=rms, direction_angles=angles,
                             well_posed=well_posed)
