"""One configuration per call through the compiled joint-chain closure (issue 22 §1): the
single-row entry points of :mod:`pkmkit.machines.chain_one`.

Each is one Numba call on arrays built once per machine, running the loop of
:mod:`pkmkit.solve.chain_kernel` (``_solve_rows``, the same function the batches call) on one
row:

- :func:`inverse_one`: the machine's inverse model from the start given (the batch path's
  ``solve_inverse`` on one row: the same bits from the same start); :func:`inverse_first_one`
  the same from the default first-order start (:func:`inverse_start`, the bits of
  :func:`pkmkit.machines.chain_starts.inverse_starts`);
- :func:`direct_one`: the direct model's closure from the first-order start of
  :meth:`~pkmkit.machines.joint_chain.JointChainMachine._default_start` (here in scalars: the
  start agrees with the batch path's NumPy one to rounding, not bit for bit), a lower bound of
  σ_min/σ_max of the closure Jacobian at the solution (``σ_min² ≥ 1/‖L⁻¹‖²_F`` with
  ``LLᵀ = CᵀC``, ``σ_max² ≤ ‖C‖²_F``: where it clears the singularity threshold the closure is
  certainly regular; elsewhere the caller takes the batch path, which computes the SVD), and
  the tool point and axis;
- :func:`velocity_one`: :func:`direct_one`, then the velocity model at the solution — the
  closure rates ``dU = −(C_UᵀC_U)⁻¹ C_Uᵀ C_q`` by Cholesky with one step of refinement (the
  batch path: LAPACK's pseudo-inverse; equal to rounding × the closure's condition) and the
  tool point's twist per actuator (``J (6, n)``) and the passive rates.

The C extension may hold twins of these (:data:`pkmkit.numerics.jit.NATIVE_TWINS`): the
callers go through :func:`pkmkit.numerics.jit.kernel`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.solve.chain_kernel import (
    _OPTIONS,
    _cholesky_apply,
    _evaluate,
    _head_walk,
    _retract,
    _scratch,
    _solve_rows,
)
from pkmkit.solve.chain_rows import _NO_HEAD, _NO_TARGETS

#: ``info`` slots: status, largest residual, iterations, lower bound of σ_min/σ_max (NaN when
#: not computed).
STATUS, RESIDUAL, ITERATIONS, BOUND = 0, 1, 2, 3


@njit(**_OPTIONS)
def inverse_one(frames, types, evar, elements, offsets, position, head, known, length, options,
                u, target, tool, info):  # pragma: no cover
    """The inverse model of one target ``target (1, 6)`` (tool point m, unit axis) from ``u
    (1, 6 + n_var)`` (overwritten by the solution), tool length ``tool (1,)``; ``options``
    (max_iter, xtol, atol, gtol, stall, residual_tol, damping); ``info (4,)`` out."""
    status = np.empty(1, dtype=np.int64)
    residual = np.full(1, np.nan)
    iterations = np.zeros(1, dtype=np.int64)
    _solve_rows(frames, types, evar, elements, offsets, position, known, u, length,
                int(options[0]), options[1], options[2], options[3], options[4], options[5],
                options[6], status, residual, iterations, head, target, tool, True)
    info[STATUS], info[RESIDUAL], info[ITERATIONS] = status[0], residual[0], iterations[0]
    info[BOUND] = np.nan


@njit(**_OPTIONS)
def inverse_start(u_home, base, rates, target, tool, u):  # pragma: no cover
    """The inverse model's first-order start into ``u (1, 6 + n_var)`` for ``target (1, 6)``
    and tool length ``tool (1,)``: the operations of
    :func:`pkmkit.machines.chain_starts.inverse_starts` on one row (the same bits)."""
    t = target[0]
    d = np.empty(6)
    for i in range(3):
        d[i] = (t[i] - tool[0] * t[3 + i]) - base[i]
        d[3 + i] = t[3 + i] - base[3 + i]
    for i in range(u_home.shape[0]):
        s = d[0] * rates[i, 0]
        for j in range(1, 6):
            s = s + d[j] * rates[i, j]
        u[0, i] = u_home[i] + s


@njit(**_OPTIONS)
def inverse_first_one(frames, types, evar, elements, offsets, position, head, known, length,
                      options, u_home, base, rates, slides, signs, turns, homes, u, target,
                      tool, info):  # pragma: no cover
    """:func:`inverse_one` from the first-order start of :func:`inverse_start` (``u`` out),
    then ``info[BOUND]`` 1.0 where the solution is in the legs' home modes, else 0.0
    (:func:`in_home_modes`)."""
    inverse_start(u_home, base, rates, target, tool, u)
    inverse_one(frames, types, evar, elements, offsets, position, head, known, length, options,
                u, target, tool, info)
    info[BOUND] = 1.0 if in_home_modes(u[0], slides, signs, turns, homes) else 0.0


@njit(**_OPTIONS)
def inverse_from_one(frames, types, evar, elements, offsets, position, head, known, length,
                     options, u_home, base, rates, slides, signs, turns, homes, u, target,
                     tool, info):  # pragma: no cover
    """:func:`inverse_first_one` from the start in ``u`` (a caller's)."""
    inverse_one(frames, types, evar, elements, offsets, position, head, known, length, options,
                u, target, tool, info)
    info[BOUND] = 1.0 if in_home_modes(u[0], slides, signs, turns, homes) else 0.0


@njit(**_OPTIONS)
def in_home_modes(u, slides, signs, turns, homes):  # pragma: no cover
    """The closure ``u (6 + n_var)`` in the legs' home assembly modes: each slide ``u[slides]``
    with the sign ``signs``, each revolute leg joint ``u[turns]`` within a quarter turn of
    ``homes`` (the test of :meth:`~pkmkit.machines.warm_starts.ChainWarmStart.in_home_modes`;
    libm's cosine, whose sign is NumPy's but a last-place rounding a quarter turn from home)."""
    for k in range(slides.shape[0]):
        if not u[slides[k]] * signs[k] > 0:
            return False
    for k in range(turns.shape[0]):
        if not math.cos(u[turns[k]] - homes[k]) > 0:
            return False
    return True


@njit(**_OPTIONS)
def _start(frames, types, evar, elements, offsets, position, values, u_home, rates,
           residual_rates, delta, length, u):  # pragma: no cover
    """The direct model's start into ``u (1, n_u)``: home moved to first order by ``delta``
    (the actuators' change from home), or home where the legs close worse from there than
    from home to first order (``_default_start``)."""
    n_u = u_home.shape[0]
    du = np.empty(n_u)
    for i in range(n_u):
        s = 0.0
        for j in range(delta.shape[0]):
            s += delta[j] * rates[i, j]
        du[i] = s
    pred = np.empty(n_u)
    _retract(u_home, du, pred)
    m = residual_rates.shape[0]
    r, jac = np.empty(m), np.empty((m, n_u))
    trial = values.copy()
    _evaluate(frames, types, evar, elements, offsets, position, trial, pred, length, r, jac,
              _scratch(elements.shape[0]))
    home_cost = 0.0
    for i in range(m):
        s = 0.0
        for j in range(delta.shape[0]):
            s += delta[j] * residual_rates[i, j]
        home_cost += s * s
    worse = not (np.dot(r, r) <= home_cost)
    for i in range(n_u):
        u[0, i] = u_home[i] if worse else pred[i]


@njit(**_OPTIONS)
def _factor(a, low):  # pragma: no cover
    """``low`` the Cholesky factor of ``aᵀa`` (NaN where not positive definite); returns
    ``‖a‖²_F``."""
    m, n = a.shape
    fro = 0.0
    for i in range(m):
        for j in range(n):
            fro += a[i, j] * a[i, j]
    for j in range(n):
        for i in range(j, n):
            s = 0.0
            for k in range(m):
                s += a[k, i] * a[k, j]
            for p in range(j):
                s -= low[i, p] * low[j, p]
            if i == j:
                low[j, j] = math.sqrt(s) if s > 0.0 else math.nan
            else:
                low[i, j] = s / low[j, j]
    return fro


@njit(**_OPTIONS)
def _bound(low, fro):  # pragma: no cover
    """Lower bound of σ_min/σ_max of ``a`` from :func:`_factor`'s ``low`` and ``‖a‖²_F``:
    ``1 / sqrt(‖a‖²_F ‖L⁻¹‖²_F)`` (module docstring); NaN if ``low`` is."""
    n = low.shape[0]
    inv = np.zeros((n, n))
    total = 0.0
    for j in range(n):  # columns of L⁻¹ by forward substitution
        for i in range(j, n):
            s = 1.0 if i == j else 0.0
            for p in range(j, i):
                s -= low[i, p] * inv[p, j]
            inv[i, j] = s / low[i, i]
            total += inv[i, j] * inv[i, j]
    return 1.0 / math.sqrt(fro * total)


@njit(**_OPTIONS)
def _closure_solve(frames, types, evar, elements, offsets, position, u_home, rates,
                   residual_rates, length, options, home_values, act, values, delta, q, u,
                   info, given=False):  # pragma: no cover
    """Start (:func:`_start`; ``given``: the start already in ``u``, the kind's closed form,
    session 35) and closure of configuration ``q (n,)`` (actuators ``act`` of the variables):
    ``u (1, n_u)`` the solution, ``values (1, n_var)`` every joint (home's with the actuators
    set, then the passive joints found), ``delta (n,)`` the actuators' change from
    ``home_values``, ``info`` filled."""
    values[0, :] = home_values
    for j in range(act.shape[0]):
        values[0, act[j]] = q[j]
        delta[j] = q[j] - home_values[act[j]]
    if not given:
        _start(frames, types, evar, elements, offsets, position, values[0], u_home, rates,
               residual_rates, delta, length, u)
    status = np.empty(1, dtype=np.int64)
    residual = np.full(1, np.nan)
    iterations = np.zeros(1, dtype=np.int64)
    _solve_rows(frames, types, evar, elements, offsets, position, values, u, length,
                int(options[0]), options[1], options[2], options[3], options[4], options[5],
                options[6], status, residual, iterations, _NO_HEAD, _NO_TARGETS,
                _NO_TARGETS[:, 0], False)
    info[STATUS], info[RESIDUAL], info[ITERATIONS] = status[0], residual[0], iterations[0]
    info[BOUND] = np.nan
    for v in range(position.shape[0]):
        if position[v] >= 0:
            values[0, v] = u[0, position[v]]


@njit(**_OPTIONS)
def direct_one(frames, types, evar, elements, offsets, position, head, u_home, rates,
               residual_rates, length, tool, options, home_values, act, values, delta, q,
               check, u, pose, info, given=False):  # pragma: no cover
    """The direct model of configuration ``q (n,)`` (module docstring; ``values``, ``delta``
    work arrays, see :func:`_closure_solve`): ``u (1, n_u)`` out (``given``: in, the start —
    the kind's closed form, as the batch path's), ``pose (6,)`` out (tool point ``tool`` along
    the tool axis, the axis), ``info (4,)`` out; ``check``: compute the bound."""
    _closure_solve(frames, types, evar, elements, offsets, position, u_home, rates,
                   residual_rates, length, options, home_values, act, values, delta, q, u, info,
                   given)
    if info[STATUS] != 0:
        return
    n_u = u.shape[1]
    scratch = _scratch(elements.shape[0] + head.shape[0])
    row = values[0].copy()
    if check:
        m = residual_rates.shape[0]
        r, jac, low = np.empty(m), np.empty((m, n_u)), np.empty((n_u, n_u))
        _evaluate(frames, types, evar, elements, offsets, position, row, u[0], length, r, jac,
                  scratch)
        info[BOUND] = _bound(low, _factor(jac, low))
    _head_walk(frames, types, evar, head, position, row, u[0], scratch)
    rot, pos = scratch[0][1], scratch[1]
    for i in range(3):
        pose[i] = pos[i] + tool * rot[i, 2]
        pose[3 + i] = rot[i, 2]


@njit(**_OPTIONS)
def velocity_one(frames, types, evar, elements, offsets, position, head, u_home, rates,
                 residual_rates, length, tool, options, home_values, act, vel_position,
                 head_position, loop_columns, values, delta, q, u, jac_out, passive_rates,
                 info):  # pragma: no cover
    """The velocity model at one configuration (module docstring): the closure as
    :func:`direct_one`, then ``jac_out (6, n)`` (tool point velocity, angular velocity per
    actuator rate) and ``passive_rates (n_p, n)``. ``vel_position (n_var,)``: the column of
    the platform-and-passive-then-loop-actuator closure Jacobian of each variable (−1 for
    none), ``head_position (n_var,)`` the actuator index of each head actuator (−1 for none),
    ``loop_columns (n_loop,)`` the actuator index of each leg actuator; ``info[BOUND]`` the
    bound of σ_min/σ_max of C_U."""
    _closure_solve(frames, types, evar, elements, offsets, position, u_home, rates,
                   residual_rates, length, options, home_values, act, values, delta, q, u, info)
    if info[STATUS] != 0:
        return
    n_u = u.shape[1]
    n_loop = loop_columns.shape[0]
    m = residual_rates.shape[0]
    row = values[0].copy()
    full_u = np.empty(n_u + n_loop)
    full_u[:6] = u[0, :6]
    for v in range(vel_position.shape[0]):
        if vel_position[v] >= 0:
            full_u[vel_position[v]] = row[v]
    r, jac = np.empty(m), np.empty((m, n_u + n_loop))
    scratch = _scratch(elements.shape[0] + head.shape[0])
    _evaluate(frames, types, evar, elements, offsets, vel_position, row, full_u, length, r, jac,
              scratch)
    cu = jac[:, :n_u]
    low = np.empty((n_u, n_u))
    info[BOUND] = _bound(low, _factor(cu, low))
    if not info[BOUND] > 0.0:
        return
    du = np.empty((n_u, n_loop))
    _closure_rates(cu, jac[:, n_u:], low, du)
    # the tool frame and the head actuators' twists
    n_twist = _head_walk(frames, types, evar, head, head_position, row, u[0], scratch)
    rot, pos, tw, tw_col = scratch[0][1], scratch[1], scratch[2], scratch[3]
    point = np.empty(3)
    for i in range(3):
        point[i] = pos[i] + tool * rot[i, 2]
    jac_out[:, :] = 0.0
    passive_rates[:, :] = 0.0
    twist = np.empty(6)
    for j in range(n_loop):  # a leg actuator: the platform's twist (δp + p_X × δω, δω)
        c = loop_columns[j]
        w0, w1, w2 = du[3, j], du[4, j], du[5, j]
        twist[0] = du[0, j] + (u[0, 1] * w2 - u[0, 2] * w1)
        twist[1] = du[1, j] + (u[0, 2] * w0 - u[0, 0] * w2)
        twist[2] = du[2, j] + (u[0, 0] * w1 - u[0, 1] * w0)
        twist[3], twist[4], twist[5] = w0, w1, w2
        _point_column(twist, point, jac_out, c)
        for a in range(n_u - 6):
            passive_rates[a, c] = du[6 + a, j]
    for k in range(n_twist):
        for i in range(6):
            twist[i] = tw[k, i]
        _point_column(twist, point, jac_out, tw_col[k])


@njit(**_OPTIONS)
def _closure_rates(cu, cq, low, du):  # pragma: no cover
    """``du = −(C_UᵀC_U)⁻¹ C_Uᵀ C_q`` (``low``: the Cholesky factor of C_UᵀC_U), one step of
    refinement on the residual ``C_q + C_U du``."""
    m, n_u = cu.shape
    rhs, fix = np.empty(n_u), np.empty(n_u)
    for j in range(cq.shape[1]):
        for a in range(n_u):
            s = 0.0
            for i in range(m):
                s += cu[i, a] * cq[i, j]
            rhs[a] = -s
        _cholesky_apply(low, rhs, fix)
        for a in range(n_u):
            du[a, j] = fix[a]
        for a in range(n_u):
            s = 0.0
            for i in range(m):
                res = cq[i, j]
                for b in range(n_u):
                    res += cu[i, b] * du[b, j]
                s += cu[i, a] * res
            rhs[a] = -s
        _cholesky_apply(low, rhs, fix)
        for a in range(n_u):
            du[a, j] += fix[a]


@njit(**_OPTIONS)
def _point_column(twist, point, jac_out, c):  # pragma: no cover
    """Column ``c`` of J: the velocity ``v + ω × point`` and ``ω`` of a spatial twist."""
    w0, w1, w2 = twist[3], twist[4], twist[5]
    jac_out[0, c] = twist[0] + (w1 * point[2] - w2 * point[1])
    jac_out[1, c] = twist[1] + (w2 * point[0] - w0 * point[2])
    jac_out[2, c] = twist[2] + (w0 * point[1] - w1 * point[0])
    jac_out[3, c], jac_out[4, c], jac_out[5, c] = w0, w1, w2
