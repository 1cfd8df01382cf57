"""Uncertainty of the identified machine's tool point: the parameters' covariance propagated to
the tool points, with the free rigid motion removed when the measurements cannot see it.

What is propagated. The identification's unknowns are the machine parameters θ and the set-up
parameters s (instrument frame, pivots, bed plane), with the joint covariance ``C`` of
``(θ, s)``. The set-up moves nothing of the machine: in the machine frame the tool points
``p(θ)`` have the Jacobian ``[J_θ, 0]`` with respect to ``(θ, s)``, so the joint propagation is
``J_θ C_θθ J_θᵀ`` (``C_θθ`` the machine block of the *joint* covariance). When the set-up
absorbs a rigid motion of the whole machine (an identified frame, identified pivots, a bed
plane: :attr:`~pkmkit.calibration.models.ResidualModel.rigid_motion_free`), machine parameter
combinations that move the tool points nearly rigidly are traded against the set-up: their
marginal variances are large, and so would be the tool point's, although the measurements
determine the machine's *shape* well. The tool points are then only defined up to that free
rigid motion (a gauge, as the workpiece set-up on the machine): the uncertainty is that of the
tool points with the best rigid motion of the whole set of points removed,
``P J_θ C_θθ J_θᵀ Pᵀ``, with ``P`` the orthogonal projector of the ``3N`` point coordinates
onto the complement of the 6 rigid motions of those points (the linearisation of a least-squares
rigid alignment, which is what a Monte-Carlo check with an aligning fit measures).

Directions the data do not determine (a null space of the identification's Jacobian) have no
finite variance: a tool point they move (after the removal of the free rigid motion) has an
infinite uncertainty.

All lengths in m; ``k = 2`` expanded uncertainty: twice the largest standard deviation over
directions (the largest eigenvalue of the point's 3 × 3 covariance).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import PkmError

#: Configurations drawn over the workspace for the uncertainty map (:func:`over_workspace`).
WORKSPACE_SAMPLE = 120

#: A null-space direction touches a tool point when it moves it (after the rigid removal) by
#: more than this fraction of its largest effect on any point before the removal.
NULL_EFFECT = 1e-6


def rigid_motion_basis(points: np.ndarray) -> np.ndarray:
    """``(3N, 6)`` displacements of ``points (N, 3)`` (m) under the six small rigid motions:
    unit translations along x, y, z, then unit rotations (rad) about x, y, z through the
    points' centroid (``δp = t + ω × (p − c)``), flattened point by point."""
    points = np.asarray(points, dtype=float)
    n = len(points)
    d = points - points.mean(axis=0)
    out = np.zeros((n, 3, 6))
    out[:, :, :3] = np.eye(3)
    # ω × d = −[d]× ω
    out[:, 0, 4], out[:, 0, 5] = d[:, 2], -d[:, 1]
    out[:, 1, 3], out[:, 1, 5] = -d[:, 2], d[:, 0]
    out[:, 2, 3], out[:, 2, 4] = d[:, 1], -d[:, 0]
    return out.reshape(3 * n, 6)


def without_rigid_motion(points: np.ndarray, jac: np.ndarray,
                         motions: Any = True) -> np.ndarray:
    """``jac (N, 3, p)`` (displacements of ``points (N, 3)`` per unit of p parameters) with
    its component along the rigid motions of the whole point set removed (orthogonal
    projection of the ``3N`` coordinates, least squares). ``motions``: True (all six) or a
    ``(6,)`` mask of the free ones in :func:`rigid_motion_basis`'s order."""
    jac = np.asarray(jac, dtype=float)
    n, _, p = jac.shape
    flat = jac.reshape(3 * n, p)
    basis = rigid_motion_basis(points)[:, _mask(motions)]
    coef = np.linalg.lstsq(basis, flat, rcond=None)[0]
    return (flat - basis @ coef).reshape(n, 3, p)


def _mask(motions: Any) -> np.ndarray:
    """``(6,)`` bool mask of free rigid motions from True/False or a mask."""
    if isinstance(motions, bool | np.bool_):
        return np.full(6, bool(motions))
    out = np.asarray(motions, dtype=bool)
    if out.shape != (6,):
        raise ValueError(f"a mask of the six rigid motions is (6,), got {out.shape}")
    return out


def tool_point_uncertainty(points: np.ndarray, jac: np.ndarray, cov: np.ndarray, *,
                           rigid_motion_free: Any, null: np.ndarray | None = None
                           ) -> np.ndarray:
    """Expanded uncertainty (k = 2) of each tool point.

    Args:
        points: ``(N, 3)`` tool points (m).
        jac: ``(N, 3, p)`` their derivatives with respect to the identified machine
            parameters (SI).
        cov: ``(p, p)`` covariance of those parameters (the machine block of the joint
            covariance with the set-up parameters; finite: the data's null space dropped).
        rigid_motion_free: remove the rigid motion of the whole point set (see the module
            docstring): True, False, or a ``(6,)`` mask of the free motions (translations
            x, y, z, rotations about x, y, z).
        null: ``(k, p)`` parameter directions the data do not determine (SI), or None.

    Returns:
        ``(N,)`` twice the largest standard deviation of each point (m); ``inf`` where a
        null direction moves the point.
    """
    jac = np.asarray(jac, dtype=float)
    if jac.shape[2] == 0:
        return np.zeros(len(jac))
    free = _mask(rigid_motion_free)
    moved = without_rigid_motion(points, jac, free) if free.any() else jac
    c = np.where(np.isfinite(cov), cov, 0.0)
    tool = np.einsum("nip,pq,njq->nij", moved, c, moved)
    u = 2.0 * np.sqrt(np.clip(np.linalg.eigvalsh(tool)[:, -1], 0.0, None))
    if null is not None and len(null):
        before = np.linalg.norm(jac @ np.asarray(null).T, axis=1)      # (N, k)
        after = np.linalg.norm(moved @ np.asarray(null).T, axis=1)
        touched = (after > NULL_EFFECT * before.max(axis=0)[None, :]).any(axis=1)
        u = np.where(touched, np.inf, u)
    return u


@dataclass(frozen=True)
class Propagation:
    """What :func:`tool_point_uncertainty` needs to map the uncertainty of a calibrated
    machine anywhere (kept by :class:`~pkmkit.calibration.results.CalibrationResult`).

    Attributes:
        basis: ``(d, p)`` identified parameters → defect vector.
        cov: ``(p, p)`` machine block of the joint covariance (finite, SI).
        null: ``(k, p)`` undetermined parameter directions (SI).
        rigid_motion_free: the free rigid motions removed (bool or ``(6,)`` mask).
        tool_length: tool length of the map (m; joint-chain machines), or None.
    """

    basis: np.ndarray
    cov: np.ndarray
    null: np.ndarray
    rigid_motion_free: Any
    tool_length: float | None


def over_workspace(machine, propagation: Propagation, *, n: int = WORKSPACE_SAMPLE,
                   seed: int = 0, q: np.ndarray | None = None) -> dict[str, Any] | None:
    """The k = 2 tool-point uncertainty of ``machine`` (the identified one) at ``n``
    configurations drawn over its default region
    (:func:`~pkmkit.calibration.simulate.default_configurations`, ``seed``) or at the
    configurations ``q (N, a)``, the free rigid motion (if any) removed over those points:
    ``{"q": (n, a), "points": (n, 3) m, "uncertainty": (n,) m}`` (rows whose tool point
    cannot be computed left out), or None when the region cannot be sampled."""
    from pkmkit.calibration.simulate import default_configurations
    from pkmkit.geometric_errors.model import tool_sensitivity

    try:
        if q is None:
            q = default_configurations(machine, n, np.random.default_rng(seed))
        sens = tool_sensitivity(machine, q, tool_length=propagation.tool_length)
    except (PkmError, np.linalg.LinAlgError):
        return None
    points = np.asarray(sens.pose)[:, :3]
    ok = np.isfinite(points).all(axis=1) & np.isfinite(sens.point).all(axis=(1, 2))
    if ok.sum() < 3:
        return None
    jac = np.asarray(sens.point)[ok] @ propagation.basis
    u = tool_point_uncertainty(points[ok], jac, propagation.cov,
                               rigid_motion_free=propagation.rigid_motion_free,
                               null=propagation.null)
    return {"q": q[ok], "points": points[ok], "uncertainty": u}
