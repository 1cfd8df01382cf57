"""Kinematics of joint chains and their closures on a platform, batched, with analytic twists.

**Chains.** :func:`chain_pose` multiplies a chain's element frames and joint motions for k
configurations at once (batch axis last) and, on request, returns the *spatial twist* (v, ω),
linear part first, by which each joint variable and each defect moves the chain's end frame:

- revolute joint at frame L (axis z_L through p_L, world coordinates): ``(p_L × z_L, z_L)``;
- prismatic joint: ``(z_L, 0)``;
- defect of element e with twist ξ in its previous frame T_prev (:func:`pkmkit.model.chains.
  defect_twists`): ``Ad(T_prev) ξ``.

A twist (v, ω) moves the end frame (R, p) by ``δp = v + ω × p``, ``δR = [ω]× R``.

**Closure of a leg on the platform pose X = (p_X, R_X)** (metres; L the characteristic length):

    r = ( p_leg − p_X ,  L · ½ vee(M − Mᵀ) ),     M = R_leg R_Xᵀ

zero iff the leg's end frame is X (the rotation part is L·θ·axis for small differences). With
``S(M) = tr(M) I − M``: a spatial twist on the leg changes it by ``(v + ω × p_leg,
½ L S(M) ω)``; increments (δp_X, δω_X) of X (``p_X += δp_X``, ``R_X ← exp(δω_X) R_X``) by
``(−δp_X, −½ L S(Mᵀ) δω_X)``. A machine's closure stacks one such 6-row block per leg; with more
rows than unknowns (hyperstatic machines: Tripteor 18 rows, 16 unknowns) it is solved in the
least-squares sense by the batched engine — exactly when the geometry is compatible.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.chains import FIXED, PRISMATIC, REVOLUTE, JointChainModel, defect_twists
from pkmkit.solve.least_squares import SolveResult, solve_least_squares
from pkmkit.spatial.rotation import compose_rotvec, rotvec_to_matrix, skew


@dataclass(frozen=True)
class ChainPose:
    """End frames of a chain at k configurations (batch axis last).

    Attributes:
        R: ``(3, 3, k)`` rotations. p: ``(3, k)`` positions (m).
        variable_twists: ``(6, n_var, k)`` spatial twist of each joint variable (zero for
            variables not in the chain), or None.
        defect_twists: ``(6, d, k)`` spatial twist of each defect, or None.
    """

    R: np.ndarray
    p: np.ndarray
    variable_twists: np.ndarray | None = None
    defect_twists: np.ndarray | None = None


def chain_pose(model: JointChainModel, chain: tuple[int, ...], values: np.ndarray, *,
               start: tuple[np.ndarray, np.ndarray] | None = None, twists: bool = False,
               defects: bool = False) -> ChainPose:
    """End frame of ``chain`` for joint values ``values (n_var, k)``.

    Args:
        model: the machine model (its actual frames are used).
        chain: element indices from the chain's start to its end.
        values: every joint variable's value (rad or m), batch last.
        start: ``(R (3, 3, k), p (3, k))`` frame the chain starts from (default: the base).
        twists: also return the joint variables' spatial twists.
        defects: also return the defects' spatial twists.
    """
    k = values.shape[1]
    if start is None:
        rot = np.broadcast_to(np.eye(3)[:, :, None], (3, 3, k)).copy()
        pos = np.zeros((3, k))
    else:
        rot, pos = start[0].copy(), start[1].copy()
    var_tw = np.zeros((6, model.n_variables, k)) if twists else None
    def_tw = None
    if defects:
        def_tw = np.zeros((6, len(model.defect_index), k))
        local = defect_twists(model.frames, model.defect_index, model.nominal_frames,
                              model.defects)
    for e in chain:
        frame = model.frames[e]
        if defects:
            for i in np.flatnonzero(model.defect_index.element == e):
                w = np.einsum("abk,b->ak", rot, local[i, 3:])
                v = np.einsum("abk,b->ak", rot, local[i, :3]) + np.cross(pos, w, axis=0)
                def_tw[:3, i], def_tw[3:, i] = v, w
        pos = pos + np.einsum("abk,b->ak", rot, frame[:3, 3])
        rot = np.einsum("abk,bc->ack", rot, frame[:3, :3])
        kind = model.elements[e].type
        if kind == FIXED:
            continue
        var = model.element_variable[e]
        z = rot[:, 2].copy()
        q = values[var]
        if kind == REVOLUTE:
            if twists:
                var_tw[:3, var] = np.cross(pos, z, axis=0)
                var_tw[3:, var] = z
            c, s = np.cos(q), np.sin(q)
            x, y = rot[:, 0].copy(), rot[:, 1].copy()
            rot[:, 0] = c * x + s * y
            rot[:, 1] = c * y - s * x
        elif kind == PRISMATIC:
            if twists:
                var_tw[:3, var] = z
            pos = pos + q * z
    return ChainPose(R=rot, p=pos, variable_twists=var_tw, defect_twists=def_tw)


def _s_matrix(m: np.ndarray) -> np.ndarray:
    """``tr(M) I − M`` for batch-last ``M (3, 3, k)``."""
    out = -m.copy()
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    for i in range(3):
        out[i, i] += trace
    return out


def _vee_skew(m: np.ndarray) -> np.ndarray:
    """``½ vee(M − Mᵀ)`` ``(3, k)``."""
    return 0.5 * np.stack([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])


def leg_residual(leg: ChainPose, rot_x: np.ndarray, p_x: np.ndarray, length: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Closure residual ``(6, k)`` of one leg on the platform pose and ``M = R_leg R_Xᵀ``."""
    m = np.einsum("abk,cbk->ack", leg.R, rot_x)
    return np.concatenate([leg.p - p_x, length * _vee_skew(m)]), m


def twist_rows(tw: np.ndarray, p_end: np.ndarray, m: np.ndarray, length: float) -> np.ndarray:
    """Residual rows ``(6, c, k)`` of spatial twists ``tw (6, c, k)`` on a leg's end frame."""
    v, w = tw[:3], tw[3:]
    dp = v + np.cross(w, p_end[:, None, :], axis=0)
    dr = 0.5 * length * np.einsum("abk,bck->ack", _s_matrix(m), w)
    return np.concatenate([dp, dr])


def platform_rows(m: np.ndarray, length: float) -> np.ndarray:
    """Residual rows ``(6, 6, k)`` of one leg with respect to the platform increments
    (δp_X, δω_X)."""
    k = m.shape[2]
    out = np.zeros((6, 6, k))
    for i in range(3):
        out[i, i] = -1.0
    out[3:, 3:] = -0.5 * length * _s_matrix(np.swapaxes(m, 0, 1))
    return out


@dataclass(frozen=True)
class ClosureJacobians:
    """Linearised closure of a joint-chain machine at k configurations (batch axis last).

    Attributes:
        residual: ``(6L, k)`` closure residuals (m; rotation rows scaled by L).
        platform: ``(6L, 6, k)`` with respect to the platform increments (δp_X, δω_X).
        variables: ``(6L, n_var, k)`` with respect to every joint variable.
        defects: ``(6L, d, k)`` with respect to every defect, or None.
    """

    residual: np.ndarray
    platform: np.ndarray
    variables: np.ndarray
    defects: np.ndarray | None


def closure(model: JointChainModel, rot_x: np.ndarray, p_x: np.ndarray, values: np.ndarray, *,
            defects: bool = False) -> ClosureJacobians:
    """Residuals and Jacobians of every leg's closure on the platform pose (module docstring).

    Args:
        rot_x: ``(3, 3, k)`` platform rotations; p_x: ``(3, k)`` positions.
        values: ``(n_var, k)`` joint values.
        defects: also differentiate with respect to the defects.
    """
    length = model.characteristic_length
    k = values.shape[1]
    n_legs = len(model.legs)
    res = np.empty((6 * n_legs, k))
    jp = np.empty((6 * n_legs, 6, k))
    jv = np.empty((6 * n_legs, model.n_variables, k))
    jd = np.empty((6 * n_legs, len(model.defect_index), k)) if defects else None
    for i, leg in enumerate(model.legs):
        rows = slice(6 * i, 6 * i + 6)
        end = chain_pose(model, leg, values, twists=True, defects=defects)
        res[rows], m = leg_residual(end, rot_x, p_x, length)
        jp[rows] = platform_rows(m, length)
        jv[rows] = twist_rows(end.variable_twists, end.p, m, length)
        if defects:
            jd[rows] = twist_rows(end.defect_twists, end.p, m, length)
    return ClosureJacobians(residual=res, platform=jp, variables=jv, defects=jd)


def _retract_pose_first(n_pose: int = 6):
    """Retraction of unknowns laid out as (p_X, φ_X, others): rotation increments compose on
    the left, the rest add."""

    def retract(u: np.ndarray, step: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = u + step
        out[3:6] = compose_rotvec(step[3:6].T, u[3:6].T).T
        return out

    return retract


def solve_closure(model: JointChainModel, known: np.ndarray, u0: np.ndarray, *,
                  unknown_variables: np.ndarray, **options) -> SolveResult:
    """Solve the closure for the platform pose and some joint variables, the others known.

    Args:
        model: the machine model.
        known: ``(N, n_var)`` values of every variable (the unknown ones' entries are ignored).
        u0: ``(N, 6 + n_u)`` initial platform position (m), rotation vector (rad), then the
            unknown variables in the order of ``unknown_variables``.
        unknown_variables: indices of the variables solved for (the passive loop variables for
            the direct model).
        **options: forwarded to :func:`pkmkit.solve.least_squares.solve_least_squares`.

    Returns:
        :class:`SolveResult` whose ``u`` holds (p_X, φ_X, unknown variables).
    """
    known_t = np.ascontiguousarray(known.T)
    free = np.asarray(unknown_variables, dtype=int)

    def evaluate(u: np.ndarray, rows: np.ndarray):
        values = known_t[:, rows].copy()
        values[free] = u[6:]
        rot = rotvec_to_matrix(u[3:6].T).transpose(1, 2, 0)
        c = closure(model, rot, u[:3], values)
        jac = np.concatenate([c.platform, c.variables[:, free]], axis=1)
        return c.residual, jac

    return solve_least_squares(evaluate, u0, retract=_retract_pose_first(), **options)


def tool_frame(model: JointChainModel, rot_x: np.ndarray, p_x: np.ndarray, values: np.ndarray,
               *, twists: bool = False, defects: bool = False) -> ChainPose:
    """The tool frame: the head chain from the platform frame (identity head: the platform
    frame itself), with its variables' and defects' spatial twists on request."""
    return chain_pose(model, model.head, values, start=(rot_x, p_x), twists=twists,
                      defects=defects)


def tool_rows(tw: np.ndarray, point: np.ndarray, axis: np.ndarray, length: float) -> np.ndarray:
    """Rows ``(6, c, k)`` of the tool residual (tool point, L × tool axis) for spatial twists
    ``tw (6, c, k)`` of the tool frame."""
    v, w = tw[:3], tw[3:]
    dp = v + np.cross(w, point[:, None, :], axis=0)
    da = length * np.cross(w, axis[:, None, :], axis=0)
    return np.concatenate([dp, da])


def solve_machine_inverse(model: JointChainModel, targets: np.ndarray, u0: np.ndarray, *,
                          tool_length: np.ndarray, **options) -> SolveResult:
    """Inverse model of a complete machine (legs, platform, head): every joint variable and the
    platform pose such that the legs close and the tool point and tool axis reach ``targets``.

    Residual: the closure rows, then ``(p_tool − p_target, L (a_tool − a_target))``; the tool
    point is ``tool_length`` along the tool frame's z axis, the tool axis that z axis.

    Args:
        targets: ``(N, 6)`` tool point (m) and unit tool axis.
        u0: ``(N, 6 + n_var)`` initial platform position, rotation vector, every variable.
        tool_length: ``(N,)`` m.
    """
    length = model.characteristic_length
    targets_t = np.ascontiguousarray(targets.T)
    tool_t = np.ascontiguousarray(np.asarray(tool_length, dtype=float).reshape(-1))

    def evaluate(u: np.ndarray, rows: np.ndarray):
        values = u[6:]
        rot = rotvec_to_matrix(u[3:6].T).transpose(1, 2, 0)
        c = closure(model, rot, u[:3], values)
        tool = tool_frame(model, rot, u[:3], values, twists=True)
        axis = tool.R[:, 2]
        point = tool.p + tool_t[rows] * axis
        res_tool = np.concatenate([point - targets_t[:3, rows],
                                   length * (axis - targets_t[3:, rows])])
        # the platform increments move the tool frame as a rigid body (spatial twist)
        k = u.shape[1]
        plat = np.zeros((6, 6, k))
        for i in range(3):
            plat[i, i] = 1.0
            plat[3 + i, 3 + i] = 1.0
        # (δp_X, δω_X) is the spatial twist (δp_X + [p_X]× δω_X, δω_X)
        plat[:3, 3:] = skew(u[:3].T).transpose(1, 2, 0)
        jt = np.concatenate([tool_rows(plat, point, axis, length),
                             tool_rows(tool.variable_twists, point, axis, length)], axis=1)
        jac = np.concatenate([np.concatenate([c.platform, c.variables], axis=1), jt])
        return np.concatenate([c.residual, res_tool]), jac

    return solve_least_squares(evaluate, u0, retract=_retract_pose_first(), **options)
