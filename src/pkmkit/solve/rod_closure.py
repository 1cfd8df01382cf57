"""Closure equations of rod-leg machines and their analytic Jacobians, for the generic engine.

Residual of rod j (metres)::

    r_j = | p + R b_j − a_j(q) | − ℓ_j(q)
    a_j(q) = a0_j + κs_j q_k u_j          (slide, or fixed for a strut)
    a_j(q) = P_k + Rot(w_k, q_k)(a0_j − P_k)   (crank turning about the axis (P_k, w_k))
    ℓ_j(q) = ℓ0_j + κt_j q_k

(κs = 1 for slide rods, κt = 1 for strut rods, k the rod's actuator.) With d_j the rod vector and
d̂_j = d_j / |d_j|:

    ∂r_j/∂p = d̂_jᵀ,   ∂r_j/∂δ = (R b_j × d̂_j)ᵀ  (left rotation increment R ← exp(δ)R),
    ∂r_j/∂q_k = −(d̂_j·∂a_j/∂q_k + κt_j),   ∂a_j/∂q_k = u_k (slide), w_k × (a_j − P_k) (crank).

Direct kinematics solves for the platform pose with q known; inverse kinematics for q with the
pose known; both through :func:`pkmkit.solve.least_squares.solve_least_squares`. The platform
unknowns are either its translation (``"translation"``: the closure of a parallelogram machine
is then over-constrained, two rods per leg for one translational constraint) or its full pose
(``"full"``: 6 unknowns in space, x, y, θz in the plane — the rods then also fix the rotation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.rods import CRANK, SLIDE, STRUT, RodModel
from pkmkit.solve.least_squares import SolveResult, solve_least_squares
from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix

PLATFORM_DOF = ("translation", "full")


@dataclass(frozen=True)
class RodVectors:
    """Rod geometry at a batch of k configurations, batch axis last (m rods).

    Attributes:
        d: ``(3, m, k)`` rod vectors from carriage/base joint to platform joint, m.
        dist: ``(m, k)`` their lengths |d|, m.
        length: ``(m, k)`` required rod lengths ℓ(q), m.
        rb: ``(3, m, k)`` or ``(3, m, 1)``: platform joint offsets R b in the fixed frame, m.
    """

    d: np.ndarray
    dist: np.ndarray
    length: np.ndarray
    rb: np.ndarray


def rod_vectors(
    model: RodModel, p: np.ndarray, q: np.ndarray, rot: np.ndarray | None = None
) -> RodVectors:
    """Rod vectors, batch axis last: platform positions ``p (3, k)``, rotations
    ``rot (3, 3, k)`` (None: identity), actuator coordinates ``q (n_act, k)``."""
    qr = q[model.rod_actuator]  # (m, k)
    kind = model.rod_kind[:, None]
    carriage = rod_base_points(model, q)
    if rot is None:
        rb = model.rod_platform.T[:, :, None]
    else:
        rb = np.einsum("ijk,mj->imk", rot, model.rod_platform)
    d = p[:, None, :] + rb - carriage
    dist = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    length = model.rod_length[:, None] + np.where(kind == STRUT, qr, 0.0)
    return RodVectors(d=d, dist=dist, length=length, rb=rb)


def rod_base_points(model: RodModel, q: np.ndarray) -> np.ndarray:
    """Base-side joint centres ``a_j(q)`` ``(3, m, k)`` of every rod for actuator coordinates
    ``q (n_act, k)`` (batch last): carriage joints moved along their slide, crank-arm joints
    turned about their axis, fixed strut joints."""
    qr = q[model.rod_actuator]
    carriage = model.rod_base.T[:, :, None] + model.rod_axis.T[:, :, None] * np.where(
        (model.rod_kind == SLIDE)[:, None], qr, 0.0)
    if (model.rod_kind == CRANK).any():
        carriage = carriage + _crank_displacement(model, qr)
    return carriage


def _crank_displacement(model: RodModel, qr: np.ndarray) -> np.ndarray:
    """``a_j(q) − a0_j`` ``(3, m, k)`` of crank rods (Rodrigues), zero for the others."""
    crank = (model.rod_kind == CRANK)[None, :, None]
    w = model.rod_axis.T[:, :, None]  # (3, m, 1)
    rel = (model.rod_base - model.rod_pivot).T[:, :, None]
    c, s = np.cos(qr)[None], np.sin(qr)[None]
    along = (w * rel).sum(axis=0, keepdims=True)
    rotated = rel * c + np.cross(w, rel, axis=0) * s + w * along * (1.0 - c)
    return np.where(crank, rotated - rel, 0.0)


def actuator_rates(model: RodModel, q: np.ndarray) -> np.ndarray:
    """``∂a_j/∂q`` ``(3, m, k)`` of every rod's base-side joint for actuator coordinates
    ``q (n_act, k)``: the slide axis, ``w × (a_j − P)`` for a crank, zero for a strut."""
    qr = q[model.rod_actuator]
    kind = model.rod_kind[:, None]
    out = model.rod_axis.T[:, :, None] * np.where(kind == SLIDE, 1.0, 0.0)
    out = np.broadcast_to(out, (3, model.n_rods, q.shape[1]))
    if (model.rod_kind == CRANK).any():
        arm = (model.rod_base - model.rod_pivot).T[:, :, None] + _crank_displacement(model, qr)
        spin = np.cross(model.rod_axis.T[:, :, None], arm, axis=0)
        out = np.where((kind == CRANK)[None], spin, out)
    return out


def _unit_rods(v: RodVectors) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v.d / v.dist


def _q_columns(model: RodModel, unit: np.ndarray, q: np.ndarray) -> np.ndarray:
    """∂r/∂q ``(m, n_act, k)`` for actuator coordinates ``q (n_act, k)``."""
    kind = model.rod_kind[:, None]
    along = np.einsum("imk,imk->mk", unit, actuator_rates(model, q))
    dr_dq = -np.where(kind == STRUT, 1.0, along)
    out = np.zeros((model.n_rods, model.n_actuators, unit.shape[2]))
    out[np.arange(model.n_rods), model.rod_actuator] = dr_dq
    return out


def _pose_columns(model: RodModel, v: RodVectors, unit: np.ndarray, dof: str) -> np.ndarray:
    """∂r/∂(platform unknowns) ``(m, n_pose, k)`` in the unknown layout of ``dof``."""
    dims = model.dims
    if dof == "translation":
        return unit[:min(dims, 3)].transpose(1, 0, 2)
    rb = np.broadcast_to(v.rb, unit.shape)
    moment = np.cross(rb, unit, axis=0)
    if dims != 2:
        cols = np.concatenate([unit, moment], axis=0)
    else:
        cols = np.concatenate([unit[:2], moment[2:3]], axis=0)
    return cols.transpose(1, 0, 2)


def pose_unknown_count(model: RodModel, dof: str) -> int:
    """Number of platform unknowns for ``dof`` (``"translation"`` or ``"full"``)."""
    if dof not in PLATFORM_DOF:
        raise ValueError(f"platform dof must be one of {PLATFORM_DOF}, got {dof!r}")
    if dof == "translation":
        return min(model.dims, 3)
    return 3 if model.dims == 2 else 6


def split_pose(model: RodModel, u: np.ndarray, dof: str) -> tuple[np.ndarray, np.ndarray | None]:
    """Platform position ``(3, k)`` and rotation ``(3, 3, k)`` (None: identity) from the
    unknowns ``u (n_pose, k)``."""
    p = np.zeros((3, u.shape[1]))
    n_position = min(model.dims, 3)
    p[:n_position] = u[:n_position]
    if dof == "translation":
        return p, None
    phi = np.zeros((u.shape[1], 3))
    if model.dims != 2:
        phi[:] = u[3:6].T
    else:
        phi[:, 2] = u[2]
    return p, rotvec_to_matrix(phi).transpose(1, 2, 0)


def _retract(model: RodModel, dof: str):
    if dof == "full" and model.dims != 2:

        def retract(u: np.ndarray, step: np.ndarray, rows: np.ndarray) -> np.ndarray:
            out = u + step
            out[3:6] = compose_rotvec(step[3:6].T, u[3:6].T).T
            return out

        return retract
    return None  # additive: translations, and planar rotation angles


def solve_direct(
    model: RodModel,
    q: np.ndarray,
    u0: np.ndarray,
    *,
    dof: str = "translation",
    **options,
) -> SolveResult:
    """Direct kinematics by least squares over every rod.

    Args:
        model: the machine's rod model.
        q: ``(N, n_act)`` actuator coordinates (m).
        u0: ``(N, n_pose)`` initial platform unknowns (see :func:`pose_unknown_count`):
            position (m), then rotation vector (rad) for ``dof="full"`` (θz for planar).
        dof: ``"translation"`` or ``"full"``.
        **options: forwarded to :func:`solve_least_squares`.

    Returns:
        :class:`SolveResult` whose ``u`` holds the platform unknowns.
    """
    pose_unknown_count(model, dof)

    q_t = np.ascontiguousarray(q.T)

    def evaluate(u: np.ndarray, rows: np.ndarray):
        p, rot = split_pose(model, u, dof)
        v = rod_vectors(model, p, q_t[:, rows], rot)
        unit = _unit_rods(v)
        return v.dist - v.length, _pose_columns(model, v, unit, dof)

    return solve_least_squares(evaluate, u0, retract=_retract(model, dof), **options)


def solve_inverse(
    model: RodModel,
    pose: np.ndarray,
    q0: np.ndarray,
    *,
    rotation: np.ndarray | None = None,
    **options,
) -> SolveResult:
    """Inverse kinematics by least squares over every rod.

    Args:
        model: the machine's rod model.
        pose: ``(N, dims)`` platform positions (m).
        q0: ``(N, n_act)`` initial actuator coordinates (warm start), m.
        rotation: ``(N, 3, 3)`` platform rotations (None: identity).
        **options: forwarded to :func:`solve_least_squares`.
    """
    p_t = np.ascontiguousarray(model.pad(pose).T)
    rot_t = None if rotation is None else rotation.transpose(1, 2, 0)

    def evaluate(q: np.ndarray, rows: np.ndarray):
        rot = None if rot_t is None else rot_t[:, :, rows]
        v = rod_vectors(model, p_t[:, rows], q, rot)
        unit = _unit_rods(v)
        return v.dist - v.length, _q_columns(model, unit, q)

    return solve_least_squares(evaluate, q0, **options)


def closure_jacobians(
    model: RodModel, pose: np.ndarray, q: np.ndarray, dof: str = "full"
) -> tuple[np.ndarray, np.ndarray]:
    """Closure Jacobians ``(∂r/∂pose (k, m, n_pose), ∂r/∂q (k, m, n_act))`` at poses
    ``(k, dims)`` and actuator coordinates ``(k, n_act)``. Translational machines' platforms are
    taken unrotated; a full pose's rotation vector is applied. The pose columns are with respect
    to the platform twist (v, ω) (left rotation increments) for ``dof="full"``."""
    rot = None
    if model.full_pose:
        rot = rotvec_to_matrix(pose[:, 3:6]).transpose(1, 2, 0)
    v = rod_vectors(model, model.pad(pose).T, q.T, rot)
    unit = _unit_rods(v)
    jp = _pose_columns(model, v, unit, dof).transpose(2, 0, 1)
    return jp, _q_columns(model, unit, q.T).transpose(2, 0, 1)


def solve_position_inverse(
    model: RodModel,
    position: np.ndarray,
    u0: np.ndarray,
    **options,
) -> SolveResult:
    """Inverse kinematics of a full-pose machine with fewer than six actuators from the platform
    *position* alone: the unknowns are the actuator coordinates and the platform rotation, which
    the rods fix (the Verne-type module's coupled orientation).

    Args:
        model: a full-pose rod model (``dims = 6``).
        position: ``(N, 3)`` platform positions (m).
        u0: ``(N, n_act + 3)`` initial actuator coordinates then rotation vector (rad).
        **options: forwarded to :func:`solve_least_squares`.

    Returns:
        :class:`SolveResult` whose ``u`` holds ``(q, rotation vector)``.
    """
    p_t = np.ascontiguousarray(position.T)
    n_act = model.n_actuators

    def evaluate(u: np.ndarray, rows: np.ndarray):
        q = u[:n_act]
        rot = rotvec_to_matrix(u[n_act:].T).transpose(1, 2, 0)
        v = rod_vectors(model, p_t[:, rows], q, rot)
        unit = _unit_rods(v)
        moment = np.cross(np.broadcast_to(v.rb, unit.shape), unit, axis=0).transpose(1, 0, 2)
        return v.dist - v.length, np.concatenate([_q_columns(model, unit, q), moment], axis=1)

    def retract(u: np.ndarray, step: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = u + step
        out[n_act:] = compose_rotvec(step[n_act:].T, u[n_act:].T).T
        return out

    return solve_least_squares(evaluate, u0, retract=retract, **options)


@dataclass(frozen=True)
class InstantaneousMobility:
    """Rank-based mobility of the rod closure at one configuration.

    Attributes:
        unknowns: platform unknowns (6 spatial, 3 planar) plus actuator coordinates.
        constraints: number of rod equations.
        rank: rank of the closure Jacobian with respect to all unknowns.
        mobility: ``unknowns − rank`` (degrees of freedom of the mechanism).
        platform_freedom_locked: platform degrees of freedom left with the actuators locked
            (0 for a well-constrained machine).
        redundant_constraints: ``constraints − rank`` (over-constraint degree).
    """

    unknowns: int
    constraints: int
    rank: int
    mobility: int
    platform_freedom_locked: int
    redundant_constraints: int


def instantaneous_mobility(
    model: RodModel, pose: np.ndarray, q: np.ndarray, rcond: float = 1e-9
) -> InstantaneousMobility:
    """Rank-based mobility at a (non-singular) configuration ``pose (dims,)``, ``q (n_act,)``."""
    jp, jq = closure_jacobians(model, pose[None], q[None], dof="full")
    full = np.concatenate([jp[0], jq[0]], axis=1)

    def rank(m: np.ndarray) -> int:
        sv = np.linalg.svd(m, compute_uv=False)
        return int((sv > rcond * sv[0]).sum())

    r_full = rank(full)
    n_pose = jp.shape[2]
    return InstantaneousMobility(
        unknowns=full.shape[1],
        constraints=full.shape[0],
        rank=r_full,
        mobility=full.shape[1] - r_full,
        platform_freedom_locked=n_pose - rank(jp[0]),
        redundant_constraints=full.shape[0] - r_full,
    )


def defect_columns(model: RodModel, index, position: np.ndarray, rotation: np.ndarray | None,
                   q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closure residuals and their derivatives with respect to the rod defects.

    The residual of rod j of the defect level (:func:`pkmkit.model.rod_defects.rod_set`) is
    ``r_j = |p + R b_j − a_j(q)| − ℓ_j(q)``. The derivatives are those of the defect rule
    (:func:`pkmkit.model.rod_defects.apply_rod_defects` on the *nominal* geometry), also for a
    model that carries defects: the rods are taken before their actuator offsets dq
    (:func:`~pkmkit.model.rod_defects.before_offsets`: ``a0`` = nominal base + base defect),
    driven by ``q̃ = q + dq``, and a direction keeps the nominal's parametrisation (the
    component that follows from the unit norm is the nominal's largest,
    :func:`~pkmkit.model.rod_defects.axis_majors`). With d̂ the unit rod vector, Rot the crank
    rotation by q̃, c = a0 − P:

    - base ``∂r/∂a0 = −d̂`` (slide, strut), ``−Rotᵀ d̂`` (crank); platform ``Rᵀ d̂``; length −1;
    - slide direction ``−q̃ d̂·∂u``; crank axis ``−d̂·((∂w × c) sin q̃ + (∂w (w·c) + w (∂w·c))
      (1 − cos q̃))``; crank pivot ``−d̂·(I − Rot)``; offset ``∂r/∂q``.

    (Linearising on the current rods instead — ``q`` for ``q̃``, the current largest
    component — drops the terms in dq and switches the direction parametrisation once a tilt
    passes 45°: an identification far from the nominal geometry then steps along a wrong
    Jacobian and crawls.)

    Args:
        model: the rod model (nominal, or carrying the defects ``model.defects`` in ``index``
            order).
        index: the :class:`~pkmkit.model.rod_defects.RodDefectIndex` of its nominal model.
        position: ``(N, 3)`` platform positions; rotation: ``(N, 3, 3)`` (None: identity).
        q: ``(N, n_act)`` actuator coordinates.

    Returns:
        ``(residual (N, m), columns (N, m, d))``.
    """
    from pkmkit.model.rod_defects import axis_majors, before_offsets, direction_increment

    rods, offset = before_offsets(model, index)
    majors = axis_majors(index, model.n_actuators)
    n, m = position.shape[0], len(rods.length)
    qr = q[:, rods.actuator] + offset[None]  # (N, m) q̃
    rel = rods.base - rods.pivot  # (m, 3)
    w = rods.axis
    c, s = np.cos(qr)[:, :, None], np.sin(qr)[:, :, None]
    crank = (rods.kind == CRANK)[None, :, None]
    slide = (rods.kind == SLIDE)[None, :, None]
    turned = rel * c + np.cross(w, rel) * s + w * np.einsum("md,md->m", w, rel)[:, None] * (
        1.0 - c)
    base_now = np.where(crank, rods.pivot + turned, rods.base + np.where(slide, qr[:, :, None]
                                                                         * w, 0.0))
    rb = rods.platform[None] if rotation is None else np.einsum("kab,mb->kma", rotation,
                                                                rods.platform)
    d = position[:, None, :] + rb - base_now
    dist = np.linalg.norm(d, axis=2)
    unit = d / dist[:, :, None]
    strut = rods.kind == STRUT
    length = rods.length[None] + np.where(strut[None], qr, 0.0)
    residual = dist - length
    rates = np.where(slide, w[None], np.where(crank, np.cross(w[None], turned), 0.0))
    dr_dq = -np.einsum("kmd,kmd->km", unit, rates) - strut[None]
    cols = np.zeros((n, m, len(index)))
    for i, (kind, t, comp) in enumerate(zip(index.kind, index.target, index.component,
                                            strict=True)):
        if kind == "base":
            e = np.zeros(3)
            e[comp] = 1.0
            if rods.kind[t] == CRANK:
                moved = e * c[:, t] + np.cross(w[t], e) * s[:, t] + w[t] * w[t, comp] * (
                    1.0 - c[:, t])
                cols[:, t, i] = -np.einsum("kd,kd->k", unit[:, t], moved)
            else:
                cols[:, t, i] = -unit[:, t, comp]
        elif kind == "platform":
            e = np.zeros(3)
            e[comp] = 1.0
            rv = e[None] if rotation is None else rotation[:, :, comp]
            cols[:, t, i] = np.einsum("kd,kd->k", unit[:, t], rv)
        elif kind == "length":
            cols[:, t, i] = -1.0
        else:
            mine = np.flatnonzero(rods.actuator == t)
            for j in mine:
                if kind == "offset":
                    cols[:, j, i] = dr_dq[:, j]
                elif kind == "pivot":
                    e = np.zeros(3)
                    e[comp] = 1.0
                    moved = e * c[:, j] + np.cross(w[j], e) * s[:, j] + w[j] * w[j, comp] * (
                        1.0 - c[:, j])
                    cols[:, j, i] = -np.einsum("kd,kd->k", unit[:, j], e[None] - moved)
                elif rods.kind[j] == SLIDE:  # slide direction
                    du = direction_increment(w[j], int(comp), int(majors[t]))
                    cols[:, j, i] = -qr[:, j] * (unit[:, j] @ du)
                else:  # crank axis
                    dw = direction_increment(w[j], int(comp), int(majors[t]))
                    cr = rel[j]
                    moved = (np.cross(dw, cr)[None] * s[:, j]
                             + (dw * (w[j] @ cr) + w[j] * (dw @ cr))[None] * (1.0 - c[:, j]))
                    cols[:, j, i] = -np.einsum("kd,kd->k", unit[:, j], moved)
    return residual, cols
