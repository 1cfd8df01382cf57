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

    r = ( p_leg − p_X ,  L · v / c ),    M = R_leg R_Xᵀ,  v = ½ vee(M − Mᵀ),  c = (1 + tr M) / 4

i.e. the translation error and L times the Gibbs vector 2 tan(θ/2)·n of the rotation error
(angle θ about n): L·θ·n to first order, zero **only** at M = I and growing without bound
towards θ = π. (A residual ``L·v`` = L sin θ·n alone also vanishes at θ = π: a least-squares
solver can stop there on a leg turned upside down and call it closed.) With
``S(M) = tr(M) I − M``: a spatial twist (v, ω) on the leg changes r by ``(v + ω × p_leg,
L (½ S(M) / c + v vᵀ / (2c²)) ω)``; increments (δp_X, δω_X) of X (``p_X += δp_X``,
``R_X ← exp(δω_X) R_X``) by ``(−δp_X, −L (½ S(Mᵀ) / c + v vᵀ / (2c²)) δω_X)``. A machine's
closure stacks one such 6-row block per leg; with more rows than unknowns (hyperstatic
machines: Tripteor 18 rows, 16 unknowns) it is solved in the least-squares sense by the batched
engine — exactly when the geometry is compatible.

**Structure.** Each leg's rows involve only the platform pose and that leg's joints, so the
normal equations are bordered block-diagonal (:class:`pkmkit.solve.least_squares.BlockPattern`):
the solvers pass that pattern to the engine, which then eliminates each leg's joints before
solving for the platform pose. Joints shared by several legs (the TriMule's ψ1) join the shared
block.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.chains import (
    FIXED,
    PRISMATIC,
    REVOLUTE,
    JointChainModel,
    cached_defect_twists,
)
from pkmkit.numerics.rowwise import einsum
from pkmkit.solve.least_squares import BlockPattern, SolveResult, solve_least_squares
from pkmkit.spatial.rotation import skew

#: Initial Levenberg–Marquardt factor of the closures (the engine's default is 1e-4).
CLOSURE_DAMPING = 1e-8


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
               defects: bool = False, twist_variables: np.ndarray | None = None) -> ChainPose:
    """End frame of ``chain`` for joint values ``values (n_var, k)``.

    Args:
        model: the machine model (its actual frames are used).
        chain: element indices from the chain's start to its end.
        values: every joint variable's value (rad or m), batch last.
        start: ``(R (3, 3, k), p (3, k))`` frame the chain starts from (default: the base).
        twists: also return the joint variables' spatial twists.
        defects: also return the defects' spatial twists.
        twist_variables: with ``twists``, only these variables' twists, as
            ``variable_twists (6, len(twist_variables), k)`` in this order (the others are not
            computed).
    """
    k = values.shape[1]
    if start is None:
        rot = np.empty((3, 3, k))
        rot[:] = np.eye(3)[:, :, None]
        pos = np.zeros((3, k))
    else:
        rot, pos = start[0].copy(), start[1].copy()
    column = None
    if twists and twist_variables is not None:
        column = {int(v): i for i, v in enumerate(twist_variables)}
        var_tw = np.zeros((6, len(column), k))
    else:
        var_tw = np.zeros((6, model.n_variables, k)) if twists else None
    def_tw = None
    if defects:
        def_tw = np.zeros((6, len(model.defect_index), k))
        local = cached_defect_twists(model)
    for e in chain:
        frame = model.frames[e]
        if defects:
            mine = np.flatnonzero(model.defect_index.element == e)
            if mine.size:
                w = einsum("abk,ib->aik", rot, local[mine, 3:])
                v = einsum("abk,ib->aik", rot, local[mine, :3]) + _cross(pos[:, None], w)
                def_tw[:3, mine], def_tw[3:, mine] = v, w
        pos = pos + _rotate(rot, frame[:3, 3])
        rot = _times_constant(rot, frame[:3, :3])
        kind = model.elements[e].type
        if kind == FIXED:
            continue
        var = model.element_variable[e]
        col = var if column is None else column.get(int(var))
        z = rot[:, 2]
        q = values[var]
        if kind == REVOLUTE:
            if twists and col is not None:
                var_tw[:3, col] = _cross(pos, z)
                var_tw[3:, col] = z
            c, s = np.cos(q), np.sin(q)
            x, y = rot[:, 0].copy(), rot[:, 1].copy()
            rot[:, 0] = c * x + s * y
            rot[:, 1] = c * y - s * x
        elif kind == PRISMATIC:
            if twists and col is not None:
                var_tw[:3, col] = z
            pos = pos + q * z
    return ChainPose(R=rot, p=pos, variable_twists=var_tw, defect_twists=def_tw)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of batch-last vectors ``(3, ...)``."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def with_column_twists(model: JointChainModel, elements: np.ndarray, twists: np.ndarray
                       ) -> JointChainModel:
    """``model`` (same frames) whose "defect" columns are the given element twists: row i moves
    element ``elements[i]`` by the twist ``twists[i]`` ``(6,)`` (linear part first, previous
    frame, as :func:`pkmkit.model.chains.defect_twists`) — so that :func:`closure` and
    :func:`tool_frame` with ``defects=True`` differentiate with respect to other parameters
    (a nominal parameter moving an element's frame)."""
    from dataclasses import replace

    from pkmkit.model.chains import DefectIndex

    elements = np.asarray(elements, dtype=int)
    count = len(elements)
    index = DefectIndex(names=tuple(f"column {i}" for i in range(count)), units=("1",) * count,
                        element=elements, kind=("twist",) * count,
                        component=np.full(count, -1))
    out = replace(model, defect_index=index, defects=np.zeros(count))
    object.__setattr__(out, "_local_defect_twists", np.asarray(twists, dtype=float))
    return out


def _rotate(rot: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``R v`` for batch-last ``R (3, 3, k)`` and a constant ``v (3,)``."""
    out = rot[:, 0] * vector[0]
    for j in (1, 2):
        if vector[j]:
            out = out + rot[:, j] * vector[j]
    return out


def _times_constant(rot: np.ndarray, const: np.ndarray) -> np.ndarray:
    """``R C`` for batch-last ``R (3, 3, k)`` and a constant ``C (3, 3)``; columns of C that
    are signed unit vectors (most junction and invariant frames) cost a copy."""
    out = np.empty_like(rot)
    for j in range(3):
        col = const[:, j]
        nz = np.flatnonzero(col)
        if nz.size == 1 and abs(col[nz[0]]) == 1.0:
            out[:, j] = rot[:, nz[0]] if col[nz[0]] > 0 else -rot[:, nz[0]]
        else:
            out[:, j] = _rotate(rot, col)
    return out


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


def _gibbs_factor(m: np.ndarray) -> np.ndarray:
    """``c = (1 + tr M) / 4 = cos²(θ/2)`` ``(k,)``."""
    return 0.25 * (1.0 + m[0, 0] + m[1, 1] + m[2, 2])


def rotation_rows(m: np.ndarray, length: float) -> np.ndarray:
    """``(3, 3, k)`` derivative of the rotation residual ``L v / c`` with respect to a left
    (world) rotation increment ω of the leg's end frame: ``L (½ S(M) / c + v vᵀ / (2c²))``."""
    v = _vee_skew(m)
    c = _gibbs_factor(m)
    with np.errstate(divide="ignore", invalid="ignore"):  # c = 0: a half turn, no derivative
        out = _s_matrix(m) * (0.5 * length / c)
        out += v[:, None] * v[None, :] * (0.5 * length / (c * c))
    return out


def leg_residual(leg: ChainPose, rot_x: np.ndarray, p_x: np.ndarray, length: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Closure residual ``(6, k)`` of one leg on the platform pose and ``M = R_leg R_Xᵀ``."""
    m = einsum("abk,cbk->ack", leg.R, rot_x)
    with np.errstate(divide="ignore", invalid="ignore"):
        rot_res = length * _vee_skew(m) / _gibbs_factor(m)
    return np.concatenate([leg.p - p_x, rot_res]), m


def twist_rows(tw: np.ndarray, p_end: np.ndarray, m: np.ndarray, length: float,
               rot_rows: np.ndarray | None = None) -> np.ndarray:
    """Residual rows ``(6, c, k)`` of spatial twists ``tw (6, c, k)`` on a leg's end frame
    (``rot_rows``: :func:`rotation_rows` of M, if already computed)."""
    v, w = tw[:3], tw[3:]
    dp = v + _cross(w, p_end[:, None, :])
    rows = rotation_rows(m, length) if rot_rows is None else rot_rows
    dr = einsum("abk,bck->ack", rows, w)
    return np.concatenate([dp, dr])


def platform_rows(m: np.ndarray, length: float) -> np.ndarray:
    """Residual rows ``(6, 6, k)`` of one leg with respect to the platform increments
    (δp_X, δω_X)."""
    k = m.shape[2]
    out = np.zeros((6, 6, k))
    for i in range(3):
        out[i, i] = -1.0
    # Mᵀ = R_X R_legᵀ takes the left increment δω_X and r(M) = −r(Mᵀ)
    out[3:, 3:] = -rotation_rows(np.swapaxes(m, 0, 1), length)
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
        rot_rows = rotation_rows(m, length)
        jp[rows] = platform_rows(m, length)
        jv[rows] = twist_rows(end.variable_twists, end.p, m, length, rot_rows)
        if defects:
            jd[rows] = twist_rows(end.defect_twists, end.p, m, length, rot_rows)
    return ClosureJacobians(residual=res, platform=jp, variables=jv, defects=jd)


def closure_residuals(model: JointChainModel, rot_x: np.ndarray, p_x: np.ndarray,
                      values: np.ndarray) -> np.ndarray:
    """Closure residuals ``(6L, k)`` alone (no Jacobian): for choosing among starts."""
    length = model.characteristic_length
    return np.concatenate([leg_residual(chain_pose(model, leg, values), rot_x, p_x, length)[0]
                           for leg in model.legs])


def rotvec_matrices(phi: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(3, 3, k)`` of batch-last rotation vectors ``φ (3, k)`` (Rodrigues,
    with series below 1e-4 rad)."""
    sq = einsum("ak,ak->k", phi, phi)
    theta = np.sqrt(sq)
    small = theta < 1e-4
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(small, 1.0 - sq / 6.0 + sq * sq / 120.0, np.sin(theta) / theta)
        b = np.where(small, 0.5 - sq / 24.0 + sq * sq / 720.0, (1.0 - np.cos(theta)) / sq)
    x, y, z = phi
    out = np.empty((3, 3, phi.shape[1]))
    out[0, 0] = 1.0 - b * (y * y + z * z)
    out[1, 1] = 1.0 - b * (x * x + z * z)
    out[2, 2] = 1.0 - b * (x * x + y * y)
    bxy, bxz, byz = b * x * y, b * x * z, b * y * z
    out[0, 1], out[1, 0] = bxy - a * z, bxy + a * z
    out[0, 2], out[2, 0] = bxz + a * y, bxz - a * y
    out[1, 2], out[2, 1] = byz - a * x, byz + a * x
    return out


def _quaternions(phi: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(w, x, y, z)`` ``(4, k)`` of batch-last rotation vectors ``(3, k)``."""
    sq = einsum("ak,ak->k", phi, phi)
    half = 0.5 * np.sqrt(sq)
    small = half < 1e-4
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(small, 0.5 - sq / 48.0 + sq * sq / 3840.0, np.sin(half) / (2 * half))
    return np.concatenate([np.cos(half)[None], scale * phi])


def compose_rotvecs(delta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Rotation vectors ``(3, k)`` of ``exp(δ) exp(φ)`` for batch-last ``δ, φ (3, k)``, angle in
    [0, π] (through unit quaternions; the angle from atan2, accurate at every size)."""
    a, b = _quaternions(delta), _quaternions(phi)
    w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
    vec = np.stack([a[0] * b[1] + b[0] * a[1] + a[2] * b[3] - a[3] * b[2],
                    a[0] * b[2] + b[0] * a[2] + a[3] * b[1] - a[1] * b[3],
                    a[0] * b[3] + b[0] * a[3] + a[1] * b[2] - a[2] * b[1]])
    vec = np.where(w < 0, -vec, vec)  # the same rotation with w ≥ 0: angle ≤ π
    w = np.abs(w)
    norm = np.sqrt(einsum("ak,ak->k", vec, vec))
    angle = 2.0 * np.arctan2(norm, w)
    small = norm < 1e-8
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(small, 2.0 / w * (1.0 + norm * norm / (3.0 * w * w)), angle / norm)
    return scale * vec


def _retract_pose_first(n_pose: int = 6):
    """Retraction of unknowns laid out as (p_X, φ_X, others): rotation increments compose on
    the left, the rest add."""

    def retract(u: np.ndarray, step: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = u + step
        out[3:6] = compose_rotvecs(step[3:6], u[3:6])
        return out

    return retract


def leg_variables(model: JointChainModel) -> list[np.ndarray]:
    """The joint variables of each leg (indices into ``model.variables``)."""
    out = []
    for leg in model.legs:
        out.append(np.array([model.element_variable[e] for e in leg
                             if model.element_variable[e] >= 0], dtype=int))
    return out


def _as_index(ids: list[int]) -> slice | np.ndarray:
    """A slice for contiguous increasing indices (writes through a view), else an array."""
    if ids and ids == list(range(ids[0], ids[0] + len(ids))):
        return slice(ids[0], ids[0] + len(ids))
    return np.array(ids, dtype=int)


def closure_pattern(model: JointChainModel, unknown_variables: np.ndarray,
                    extra_groups: tuple[np.ndarray, ...] = ()
                    ) -> tuple[BlockPattern, list[np.ndarray], list[np.ndarray]]:
    """Block pattern of a closure whose unknowns are ``(p_X, φ_X, unknown_variables)``.

    The residual rows are 6 per leg, then 6 per extra group (e.g. the tool rows of the inverse
    model, whose variables are ``extra_groups[0]``). An unknown variable seen by one row group
    only is private to it; one seen by several (a joint shared by legs) is shared with the
    platform pose.

    Returns:
        the pattern, and for every row group the positions in u of its variables (a slice when
        contiguous) and those variables (the order of their twist columns).
    """
    unknown = np.asarray(unknown_variables, dtype=int)
    position = {int(v): 6 + i for i, v in enumerate(unknown)}
    seen = [*leg_variables(model), *extra_groups]
    owners: dict[int, set[int]] = {}
    for g, variables in enumerate(seen):
        for v in variables:
            if int(v) in position:
                owners.setdefault(int(v), set()).add(g)
    shared = list(range(6)) + [position[v] for v, g in owners.items() if len(g) > 1]
    groups, positions, members = [], [], []
    for g, variables in enumerate(seen):
        mine = [int(v) for v in variables if int(v) in position]
        private = [position[v] for v in mine if len(owners[v]) == 1]
        if private:
            groups.append((tuple(range(6 * g, 6 * g + 6)), tuple(private)))
        positions.append(_as_index([position[v] for v in mine]))
        members.append(np.array(mine, dtype=int))
    unused = sorted(set(position.values()) - set(shared)
                    - {c for _, cols in groups for c in cols})
    if unused:  # unknowns no row sees: their own (empty) group keeps the pattern a partition
        shared += unused
    return BlockPattern(shared=tuple(sorted(shared)), groups=tuple(groups)), positions, members


def _columns(a: np.ndarray, rows: slice | np.ndarray) -> np.ndarray:
    """Batch entries of a batch-last 2-D array as a contiguous copy (the engine passes a slice
    or an index array)."""
    return a[:, rows].copy() if isinstance(rows, slice) else np.take(a, rows, axis=1)


class _Buffers:
    """Residual and Jacobian arrays reused from one evaluation to the next (the engine copies
    what it keeps): the Jacobian's structural zeros are written once, and a fresh 20 MB array
    per evaluation would cost its page faults every time."""

    def __init__(self):
        self._arrays: dict[tuple[int, int, int], tuple[np.ndarray, np.ndarray]] = {}

    def get(self, m: int, n: int, k: int) -> tuple[np.ndarray, np.ndarray]:
        key = (m, n, k)
        if key not in self._arrays:
            self._arrays.clear()  # the former size's arrays freed before the new ones exist
            self._arrays[key] = (np.empty((m, k)), np.zeros((m, n, k)))
        return self._arrays[key]


def _closure_into(model: JointChainModel, rot: np.ndarray, p_x: np.ndarray, values: np.ndarray,
                  res: np.ndarray, jac: np.ndarray, positions: list,
                  members: list[np.ndarray]) -> None:
    """Write every leg's closure residual and its non-zero Jacobian blocks (platform columns
    0–5, the leg's unknown variables at ``positions``) into ``res``/``jac`` (zeros elsewhere)."""
    length = model.characteristic_length
    for i, leg in enumerate(model.legs):
        rows = slice(6 * i, 6 * i + 6)
        end = chain_pose(model, leg, values, twists=True, twist_variables=members[i])
        res[rows], m = leg_residual(end, rot, p_x, length)
        jac[rows, :6] = platform_rows(m, length)
        if len(members[i]):
            jac[rows, positions[i]] = twist_rows(end.variable_twists, end.p, m, length)


#: Engine options the compiled closure (:mod:`pkmkit.solve.chain_kernel`) implements.
COMPILED_OPTIONS = frozenset({"max_iter", "xtol", "atol", "gtol", "stall", "residual_tol",
                              "damping", "compute_rank"})


def solve_closure(model: JointChainModel, known: np.ndarray, u0: np.ndarray, *,
                  unknown_variables: np.ndarray, compiled: bool = False,
                  **options) -> SolveResult:
    """Solve the closure for the platform pose and some joint variables, the others known.

    Args:
        model: the machine model.
        known: ``(N, n_var)`` values of every variable (the unknown ones' entries are ignored).
        u0: ``(N, 6 + n_u)`` initial platform position (m), rotation vector (rad), then the
            unknown variables in the order of ``unknown_variables``.
        unknown_variables: indices of the variables solved for (the passive loop variables for
            the direct model).
        compiled: solve every row in the compiled kernel of :mod:`pkmkit.solve.chain_kernel`
            (the same algorithm, to rounding) when Numba is available and the options are
            among :data:`COMPILED_OPTIONS` with ``compute_rank=False`` (the kernel reports no rank:
            ``rank`` is −1); else the NumPy engine.
        **options: forwarded to :func:`pkmkit.solve.least_squares.solve_least_squares`.

    Returns:
        :class:`SolveResult` whose ``u`` holds (p_X, φ_X, unknown variables).
    """
    if compiled and _compiled_closure_applies(len(u0), options):
        from pkmkit.solve import chain_rows as chain_kernel  # C twin or Numba

        options.pop("compute_rank", None)
        options.setdefault("damping", CLOSURE_DAMPING)
        u, status, residual, iterations = chain_kernel.solve(
            model, known, u0, np.asarray(unknown_variables, dtype=int), **options)
        return SolveResult(u=u, status=status, residual=residual, iterations=iterations,
                           rank=np.full(len(u), -1))
    known_t = np.ascontiguousarray(known.T)
    free = np.asarray(unknown_variables, dtype=int)
    pattern, positions, members = closure_pattern(model, free)
    n_rows = 6 * len(model.legs)

    buffers = _Buffers()

    def evaluate(u: np.ndarray, rows: np.ndarray):
        values = _columns(known_t, rows)
        values[free] = u[6:]
        res, jac = buffers.get(n_rows, u.shape[0], u.shape[1])
        _closure_into(model, rotvec_matrices(u[3:6]), u[:3], values, res, jac, positions,
                      members)
        return res, jac

    options.setdefault("pattern", pattern)
    # from a good start a closure is nearly linear: Gauss–Newton steps (the damping grows
    # tenfold on every rejected step where it is not)
    options.setdefault("damping", CLOSURE_DAMPING)
    return solve_least_squares(evaluate, u0, retract=_retract_pose_first(), **options)


def compiled_closure_available() -> bool:
    """Whether the compiled closure kernels (:mod:`pkmkit.solve.chain_kernel`) can run: Numba
    installed and not disabled (``PKMKIT_COMPILED=0``)."""
    from pkmkit.numerics import jit

    return jit.mode() != "0" and jit.numba_available()


def _compiled_closure_applies(rows: int, options: dict) -> bool:
    """Whether ``solve_closure(..., compiled=True)`` runs the compiled kernel."""
    from pkmkit.numerics import jit  # the C twin of the closure needs no Numba

    native = jit.native_kernel("pkmkit.solve.chain_kernel", "_solve_rows") is not None
    return (set(options) <= COMPILED_OPTIONS and not options.get("compute_rank", True)
            and rows > 0 and (native or compiled_closure_available()))


def tool_frame(model: JointChainModel, rot_x: np.ndarray, p_x: np.ndarray, values: np.ndarray,
               *, twists: bool = False, defects: bool = False,
               twist_variables: np.ndarray | None = None) -> ChainPose:
    """The tool frame: the head chain from the platform frame (identity head: the platform
    frame itself), with its variables' and defects' spatial twists on request."""
    return chain_pose(model, model.head, values, start=(rot_x, p_x), twists=twists,
                      defects=defects, twist_variables=twist_variables)


def tool_rows(tw: np.ndarray, point: np.ndarray, axis: np.ndarray, length: float) -> np.ndarray:
    """Rows ``(6, c, k)`` of the tool residual (tool point, L × tool axis) for spatial twists
    ``tw (6, c, k)`` of the tool frame."""
    v, w = tw[:3], tw[3:]
    dp = v + _cross(w, point[:, None, :])
    da = length * _cross(w, axis[:, None, :])
    return np.concatenate([dp, da])


def solve_machine_inverse(model: JointChainModel, targets: np.ndarray, u0: np.ndarray, *,
                          tool_length: np.ndarray, compiled: bool = False,
                          **options) -> SolveResult:
    """Inverse model of a complete machine (legs, platform, head): every joint variable and the
    platform pose such that the legs close and the tool point and tool axis reach ``targets``.

    Residual: the closure rows, then ``(p_tool − p_target, L (a_tool − a_target))``; the tool
    point is ``tool_length`` along the tool frame's z axis, the tool axis that z axis.

    Args:
        targets: ``(N, 6)`` tool point (m) and unit tool axis.
        u0: ``(N, 6 + n_var)`` initial platform position, rotation vector, every variable.
        tool_length: ``(N,)`` m.
        compiled: solve every row in the compiled kernel
            (:func:`pkmkit.solve.chain_kernel.solve_inverse`, the same algorithm to rounding)
            under the conditions of :func:`solve_closure`'s ``compiled``; else the NumPy engine.
    """
    if compiled and _compiled_closure_applies(len(u0), options):
        from pkmkit.solve import chain_rows as chain_kernel  # C twin or Numba

        options.pop("compute_rank", None)
        u, status, residual, iterations = chain_kernel.solve_inverse(
            model, targets, u0, np.asarray(tool_length, dtype=float).reshape(-1), **options)
        return SolveResult(u=u, status=status, residual=residual, iterations=iterations,
                           rank=np.full(len(u), -1))
    length = model.characteristic_length
    targets_t = np.ascontiguousarray(targets.T)
    tool_t = np.ascontiguousarray(np.asarray(tool_length, dtype=float).reshape(-1))
    every = np.arange(model.n_variables)
    head = np.array([model.element_variable[e] for e in model.head
                     if model.element_variable[e] >= 0], dtype=int)
    pattern, positions, members = closure_pattern(model, every, (head,))
    n_legs = len(model.legs)
    buffers = _Buffers()
    tool = slice(6 * n_legs, 6 * n_legs + 6)

    def evaluate(u: np.ndarray, rows: np.ndarray):
        values = u[6:]
        k = u.shape[1]
        rot = rotvec_matrices(u[3:6])
        res, jac = buffers.get(6 * n_legs + 6, u.shape[0], k)
        _closure_into(model, rot, u[:3], values, res, jac, positions, members)
        frame = tool_frame(model, rot, u[:3], values, twists=True, twist_variables=head)
        axis = frame.R[:, 2]
        point = frame.p + tool_t[rows] * axis
        target = _columns(targets_t, rows)
        res[tool] = np.concatenate([point - target[:3], length * (axis - target[3:])])
        # the platform increments move the tool frame as a rigid body: (δp_X, δω_X) is the
        # spatial twist (δp_X + [p_X]× δω_X, δω_X)
        plat = np.zeros((6, 6, k))
        for i in range(3):
            plat[i, i] = 1.0
            plat[3 + i, 3 + i] = 1.0
        plat[:3, 3:] = skew(u[:3].T).transpose(1, 2, 0)
        jac[tool, :6] = tool_rows(plat, point, axis, length)
        if len(head):
            jac[tool, positions[n_legs]] = tool_rows(frame.variable_twists, point, axis,
                                                      length)
        return res, jac

    options.setdefault("pattern", pattern)
    return solve_least_squares(evaluate, u0, retract=_retract_pose_first(), **options)
