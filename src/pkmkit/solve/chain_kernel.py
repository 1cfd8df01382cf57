"""Compiled (Numba) closure of joint-chain machines: the legs closed on the platform for many
configurations, one fused Levenberg–Marquardt loop per configuration.

The same problem and the same algorithm as :func:`pkmkit.solve.chains.solve_closure` on the
batched engine (:func:`pkmkit.solve.least_squares.solve_least_squares`): unknowns
``u = (p_X, φ_X, passive joints)``, residual 6 rows per leg (translation, then ``L`` × the Gibbs
vector of the rotation error), analytic Jacobian, rotation increments composed on the left; the
engine's damping rule (Marquardt scaling plus a floor, ×0.1 on an accepted step, ×10 on a
rejected one), acceptance test and stopping tests (exact residual, gradient cosines, step
length, stall every ten iterations, damping beyond 1e12) and statuses. It differs from the
engine only in the linear algebra of each step (a dense Cholesky factorisation of the damped
normal equations instead of the engine's block elimination): the same iterates to rounding.

Also compiled here: the inverse model of a complete machine (:func:`solve_inverse`: the same
loop with the tool rows added, for workspace grids), and for the identification's Jacobians
:func:`linearise` (the closure's Jacobians C_U and C_δ and the tool frame's defect twists at
solved configurations, as :func:`pkmkit.solve.chains.closure` and
:func:`~pkmkit.solve.chains.tool_frame` with ``defects=True``); :func:`absorb` (``dU = −C_U⁺
C_δ`` by the normal equations) is in :mod:`pkmkit.solve.chain_linalg`. Their entry points
(and the velocity model's :func:`closure_jacobian`) are in the Numba-free
:mod:`pkmkit.solve.chain_rows`, which runs their C twins (native/chain_velocity.c,
chain_linearise.c) when built.

Why: the engine runs each iteration as a few hundred NumPy calls over the batch; a residual of
the Tripteor's identification (107 configurations, 10–15 iterations) cost 25–58 ms of such
calls, the kernel about a millisecond (12 µs per configuration). Imported lazily (Numba's import
costs ≈ 0.3 s), used when the caller asks (``solve_closure(..., compiled=True)``,
``tool_sensitivity(..., compiled=True)``) and Numba is available and not disabled
(:func:`pkmkit.solve.chains.compiled_closure_available`); the NumPy code is the reference it is
tested against (``tests/solve/test_chain_kernel.py``). The closure's batch entry points live in
the Numba-free :mod:`pkmkit.solve.chain_rows` (re-exported here), which runs the C twin of
:func:`_solve_rows` in :mod:`pkmkit.native` when it was built (``tests/native/test_chain.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# the closure Jacobians' linear algebra (dU = −C_U⁺ C_δ, −C_U⁺ C_q), re-exported
from pkmkit.solve.chain_linalg import RANK_PIVOT, absorb, closure_rates  # noqa: F401

# the batch entry points, which need no Numba (their C twin may run: pkmkit.native), re-exported
from pkmkit.solve.chain_rows import (  # noqa: F401
    closure_jacobian,
    linearise,
    model_arrays,
    solve,
    solve_inverse,
)
from pkmkit.status import Status

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}
_OK, _INCONSISTENT = int(Status.OK), int(Status.INCONSISTENT)
_NOT_CONVERGED, _INVALID = int(Status.NOT_CONVERGED), int(Status.INVALID_INPUT)


@njit(**_OPTIONS)
def _jacobian_rows(frames, types, evar, elements, offsets, position, values, u, length,
                   out):  # pragma: no cover
    r = np.empty(out.shape[1])
    row = np.empty(values.shape[1])
    scratch = _scratch(elements.shape[0])
    for k in range(u.shape[0]):
        row[:] = values[k]
        _evaluate(frames, types, evar, elements, offsets, position, row, u[k], length, r,
                  out[k], scratch)


@njit(**_OPTIONS)
def _evaluate_any(frames, types, evar, elements, offsets, position, values, u, length, r, jac,
                  scratch, head, target, tool, inverse):  # pragma: no cover
    """The closure (``inverse`` False) or the machine inverse's residual and Jacobian."""
    _evaluate(frames, types, evar, elements, offsets, position, values, u, length, r, jac,
              scratch)
    if inverse:
        _tool_rows(frames, types, evar, head, position, values, u, length, target, tool,
                   6 * (offsets.shape[0] - 1), r, jac, scratch)


@njit(**_OPTIONS)
def _head_walk(frames, types, evar, head, position, values, u, scratch):  # pragma: no cover
    """The tool frame into ``scratch``'s rotation and position, walked along the head from the
    platform pose ``u[:6]``; the spatial twists of the head's unknown variables into its twist
    rows. Returns their count."""
    mats, pos, tw, tw_col = scratch
    rot, tmp = mats[1], mats[2]
    _rotvec_matrix(u[3], u[4], u[5], rot)
    for i in range(3):
        pos[i] = u[i]
    n_twist = 0
    for idx in range(head.shape[0]):
        e = head[idx]
        _apply_frame(rot, pos, frames[e], tmp)
        t = types[e]
        if t == 0:
            continue
        var = evar[e]
        col = position[var]
        q = values[var]
        z0, z1, z2 = rot[0, 2], rot[1, 2], rot[2, 2]
        if t == 1:
            if col >= 0:
                tw[n_twist, 0] = pos[1] * z2 - pos[2] * z1
                tw[n_twist, 1] = pos[2] * z0 - pos[0] * z2
                tw[n_twist, 2] = pos[0] * z1 - pos[1] * z0
                tw[n_twist, 3], tw[n_twist, 4], tw[n_twist, 5] = z0, z1, z2
                tw_col[n_twist] = col
                n_twist += 1
            c, s = math.cos(q), math.sin(q)
            for i in range(3):
                x, y = rot[i, 0], rot[i, 1]
                rot[i, 0] = c * x + s * y
                rot[i, 1] = c * y - s * x
        else:
            if col >= 0:
                tw[n_twist, 0], tw[n_twist, 1], tw[n_twist, 2] = z0, z1, z2
                tw[n_twist, 3] = tw[n_twist, 4] = tw[n_twist, 5] = 0.0
                tw_col[n_twist] = col
                n_twist += 1
            pos[0] += q * z0
            pos[1] += q * z1
            pos[2] += q * z2
    return n_twist


@njit(**_OPTIONS)
def _tool_rows(frames, types, evar, head, position, values, u, length, target, tool, base, r,
               jac, scratch):  # pragma: no cover
    """The tool rows of the inverse model at rows ``base:base + 6`` (``_evaluate`` has filled
    ``values`` from ``u`` and zeroed ``jac``): the head walked from the platform frame, the
    tool point ``tool`` along its z axis; columns: the platform increments (a rigid motion of
    the tool frame) and the head's unknown variables (their spatial twists)."""
    mats, pos, tw, tw_col = scratch
    rot = mats[1]
    n_twist = _head_walk(frames, types, evar, head, position, values, u, scratch)
    a0, a1, a2 = rot[0, 2], rot[1, 2], rot[2, 2]
    p0, p1, p2 = pos[0] + tool * a0, pos[1] + tool * a1, pos[2] + tool * a2
    r[base + 0], r[base + 1], r[base + 2] = p0 - target[0], p1 - target[1], p2 - target[2]
    r[base + 3] = length * (a0 - target[3])
    r[base + 4] = length * (a1 - target[4])
    r[base + 5] = length * (a2 - target[5])
    # platform columns: δp_X moves the point; δω_X (about p_X) moves the point by
    # δω × (point − p_X) and the axis by δω × axis
    d0, d1, d2 = p0 - u[0], p1 - u[1], p2 - u[2]
    for i in range(3):
        jac[base + i, i] = 1.0
    jac[base + 0, 4], jac[base + 0, 5] = d2, -d1
    jac[base + 1, 3], jac[base + 1, 5] = -d2, d0
    jac[base + 2, 3], jac[base + 2, 4] = d1, -d0
    jac[base + 3, 4], jac[base + 3, 5] = length * a2, -length * a1
    jac[base + 4, 3], jac[base + 4, 5] = -length * a2, length * a0
    jac[base + 5, 3], jac[base + 5, 4] = length * a1, -length * a0
    for k in range(n_twist):
        col = tw_col[k]
        w0, w1, w2 = tw[k, 3], tw[k, 4], tw[k, 5]
        jac[base + 0, col] = tw[k, 0] + w1 * p2 - w2 * p1
        jac[base + 1, col] = tw[k, 1] + w2 * p0 - w0 * p2
        jac[base + 2, col] = tw[k, 2] + w0 * p1 - w1 * p0
        jac[base + 3, col] = length * (w1 * a2 - w2 * a1)
        jac[base + 4, col] = length * (w2 * a0 - w0 * a2)
        jac[base + 5, col] = length * (w0 * a1 - w1 * a0)


@njit(**_OPTIONS)
def _solve_rows(frames, types, evar, elements, offsets, position, known, u, length, max_iter,
                xtol, atol, gtol, stall, residual_tol, damping, status, residual,
                iterations, head, targets, tools, inverse):  # pragma: no cover
    n = u.shape[1]
    m = 6 * (offsets.shape[0] - 1) + (6 if inverse else 0)
    values = np.empty(known.shape[1])
    r, jac = np.empty(m), np.empty((m, n))
    r_new, j_new = np.empty(m), np.empty((m, n))
    u_new, step, grad = np.empty(n), np.empty(n), np.empty(n)
    h, low = np.empty((n, n)), np.empty((n, n))
    nz = np.empty(n, dtype=np.int64)
    scratch = _scratch(elements.shape[0] + head.shape[0])
    for k in range(u.shape[0]):
        finite = True
        for i in range(n):
            finite = finite and math.isfinite(u[k, i])
        if not finite:
            status[k] = _INVALID
            continue
        values[:] = known[k if known.shape[0] > 1 else 0]
        row = k if inverse else 0
        target, tool = targets[row], tools[row]
        _evaluate_any(frames, types, evar, elements, offsets, position, values, u[k], length,
                      r, jac, scratch, head, target, tool, inverse)
        cost = 0.5 * _dot(r, r)
        if not (math.isfinite(cost) and np.isfinite(jac).all()):
            status[k] = _INVALID
            continue
        status[k] = _NOT_CONVERGED
        lam = damping
        checkpoint = cost
        count = 0
        stopped = False
        for _ in range(max_iter):
            # gradient, stationarity (cosine) and exact-residual tests
            biggest = 0.0
            for a in range(n):
                g, col = 0.0, 0.0
                for i in range(m):
                    g += jac[i, a] * r[i]
                    col += jac[i, a] * jac[i, a]
                grad[a] = g
                cosine = abs(g) / math.sqrt(col * (2.0 * cost))
                if cosine > biggest:  # NaN compares False: counts as 0, as in the engine
                    biggest = cosine
            if cost <= 0.5 * atol * atol or not biggest > gtol:
                stopped = True
                break
            # damped normal equations (JᵀJ + λ (D + floor)) δ = −Jᵀr
            # JᵀJ row by row over each row's non-zero columns (a leg's rows see the platform
            # and its own joints): the same sums in the same order, the zero terms skipped
            h[:, :] = 0.0
            for i in range(m):
                count_nz = 0
                for a in range(n):
                    if jac[i, a] != 0.0:
                        nz[count_nz] = a
                        count_nz += 1
                for p in range(count_nz):
                    a = nz[p]
                    v = jac[i, a]
                    for t in range(p + 1):
                        h[a, nz[t]] += v * jac[i, nz[t]]
            dmax = 0.0
            for a in range(n):
                for b in range(a):
                    h[b, a] = h[a, b]
                if h[a, a] > dmax:
                    dmax = h[a, a]
            floor = 1e-9 * dmax + 1e-300
            for a in range(n):
                h[a, a] += lam * (h[a, a] + floor)
            _cholesky_solve(h, grad, low, step)
            _retract(u[k], step, u_new)
            _evaluate_any(frames, types, evar, elements, offsets, position, values, u_new,
                          length, r_new, j_new, scratch, head, target, tool, inverse)
            cost_new = 0.5 * _dot(r_new, r_new)
            accept = math.isfinite(cost_new) and cost_new <= cost * (1.0 + 1e-13)
            count += 1
            if accept:
                u[k, :] = u_new
                r[:] = r_new
                jac[:, :] = j_new
                cost = cost_new
                lam = max(lam * 0.1, 1e-12)
            else:
                lam *= 10.0
            step_norm = math.sqrt(_dot(step, step))
            u_norm = math.sqrt(_dot(u[k], u[k]))
            done = (accept and step_norm <= xtol * (1.0 + u_norm)) or lam > 1e12
            if count % 10 == 0:
                if cost > (1.0 - stall) * checkpoint and cost > 0.5 * residual_tol ** 2:
                    done = True
                checkpoint = cost
            if done:
                stopped = True
                break
        iterations[k] = count
        worst = 0.0
        for i in range(m):
            if abs(r[i]) > worst or math.isnan(r[i]):
                worst = abs(r[i])
        residual[k] = worst
        if stopped:
            status[k] = _OK if worst <= residual_tol else _INCONSISTENT


@njit(inline="always", **_OPTIONS)
def _dot(a, b):  # pragma: no cover
    """Σ a_i b_i in order (not BLAS ``ddot``, whose partial sums the C twin could not match)."""
    acc = 0.0
    for i in range(a.shape[0]):
        acc += a[i] * b[i]
    return acc


@njit(**_OPTIONS)
def _fill_unknowns(values, position, u):  # pragma: no cover
    for v in range(position.shape[0]):
        if position[v] >= 0:
            values[v] = u[position[v]]


@njit(**_OPTIONS)
def _cholesky_solve(h, grad, low, step):  # pragma: no cover
    """``step = −H⁻¹ grad`` by Cholesky (NaN when H is not positive definite)."""
    n = h.shape[0]
    for j in range(n):
        s = h[j, j]
        for p in range(j):
            s -= low[j, p] * low[j, p]
        d = math.sqrt(s) if s > 0.0 else math.nan
        low[j, j] = d
        for i in range(j + 1, n):
            t = h[i, j]
            for p in range(j):
                t -= low[i, p] * low[j, p]
            low[i, j] = t / d
    _cholesky_apply(low, grad, step)
    for i in range(n):
        step[i] = -step[i]


@njit(inline="always", **_OPTIONS)
def _cholesky_apply(low, b, x):  # pragma: no cover
    """``x = (LLᵀ)⁻¹ b`` for a vector ``b`` (``low``: the Cholesky factor L); shared with the
    one-row kernels (:mod:`pkmkit.solve.chain_one_kernel`)."""
    n = low.shape[0]
    for i in range(n):
        s = b[i]
        for p in range(i):
            s -= low[i, p] * x[p]
        x[i] = s / low[i, i]
    for i in range(n - 1, -1, -1):
        s = x[i]
        for p in range(i + 1, n):
            s -= low[p, i] * x[p]
        x[i] = s / low[i, i]


@njit(inline="always", **_OPTIONS)
def _quaternion(x, y, z):  # pragma: no cover
    sq = x * x + y * y + z * z
    half = 0.5 * math.sqrt(sq)
    if half < 1e-4:
        scale = 0.5 - sq / 48.0 + sq * sq / 3840.0
    else:
        scale = math.sin(half) / (2 * half)
    return math.cos(half), scale * x, scale * y, scale * z


@njit(**_OPTIONS)
def _retract(u, step, out):  # pragma: no cover
    """``u + step`` with the rotation composed on the left: ``exp(δφ) exp(φ)`` (through unit
    quaternions, as :func:`pkmkit.solve.chains.compose_rotvecs`)."""
    for i in range(u.shape[0]):
        out[i] = u[i] + step[i]
    a0, a1, a2, a3 = _quaternion(step[3], step[4], step[5])
    b0, b1, b2, b3 = _quaternion(u[3], u[4], u[5])
    w = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    x = a0 * b1 + b0 * a1 + a2 * b3 - a3 * b2
    y = a0 * b2 + b0 * a2 + a3 * b1 - a1 * b3
    z = a0 * b3 + b0 * a3 + a1 * b2 - a2 * b1
    if w < 0:
        x, y, z = -x, -y, -z
    w = abs(w)
    norm = math.sqrt(x * x + y * y + z * z)
    if norm < 1e-8:
        scale = 2.0 / w * (1.0 + norm * norm / (3.0 * w * w))
    else:
        scale = 2.0 * math.atan2(norm, w) / norm
    out[3], out[4], out[5] = scale * x, scale * y, scale * z


@njit(**_OPTIONS)
def _rotvec_matrix(x, y, z, out):  # pragma: no cover
    """Rodrigues, with the series of :func:`pkmkit.solve.chains.rotvec_matrices`."""
    sq = x * x + y * y + z * z
    theta = math.sqrt(sq)
    if theta < 1e-4:
        a = 1.0 - sq / 6.0 + sq * sq / 120.0
        b = 0.5 - sq / 24.0 + sq * sq / 720.0
    else:
        a = math.sin(theta) / theta
        b = (1.0 - math.cos(theta)) / sq
    out[0, 0] = 1.0 - b * (y * y + z * z)
    out[1, 1] = 1.0 - b * (x * x + z * z)
    out[2, 2] = 1.0 - b * (x * x + y * y)
    out[0, 1], out[1, 0] = b * x * y - a * z, b * x * y + a * z
    out[0, 2], out[2, 0] = b * x * z + a * y, b * x * z - a * y
    out[1, 2], out[2, 1] = b * y * z - a * x, b * y * z + a * x


@njit(**_OPTIONS)
def _rotation_rows(mm, length, sign, out):  # pragma: no cover
    """``sign · L (½ S(M) / c + v vᵀ / (2c²))`` of ``M`` (``mm``) into ``out (3, 3)``."""
    v0 = 0.5 * (mm[2, 1] - mm[1, 2])
    v1 = 0.5 * (mm[0, 2] - mm[2, 0])
    v2 = 0.5 * (mm[1, 0] - mm[0, 1])
    trace = mm[0, 0] + mm[1, 1] + mm[2, 2]
    c = 0.25 * (1.0 + trace)
    f1 = sign * 0.5 * length / c
    f2 = sign * 0.5 * length / (c * c)
    v = (v0, v1, v2)
    for i in range(3):
        for j in range(3):
            s = -mm[i, j] + (trace if i == j else 0.0)
            out[i, j] = s * f1 + v[i] * v[j] * f2


@njit(inline="always", **_OPTIONS)
def _apply_frame(rot, pos, f, tmp):  # pragma: no cover
    """``(rot, pos) <- (rot, pos) · f`` for an element's invariant frame ``f (4, 4)``:
    ``pos += rot f[:3, 3]``, ``rot <- rot f[:3, :3]`` (``tmp (3, 3)`` scratch)."""
    for i in range(3):
        pos[i] += rot[i, 0] * f[0, 3] + rot[i, 1] * f[1, 3] + rot[i, 2] * f[2, 3]
    for i in range(3):
        for j in range(3):
            tmp[i, j] = rot[i, 0] * f[0, j] + rot[i, 1] * f[1, j] + rot[i, 2] * f[2, j]
    rot[:, :] = tmp


@njit(**_OPTIONS)
def _scratch(n_elements):  # pragma: no cover
    """Work arrays of :func:`_evaluate` (allocated once per kernel call)."""
    return (np.empty((5, 3, 3)), np.empty(3), np.empty((n_elements, 6)),
            np.empty(n_elements, dtype=np.int64))


@njit(**_OPTIONS)
def _evaluate(frames, types, evar, elements, offsets, position, values, u, length, r,
              jac, scratch):  # pragma: no cover
    """Residual ``r (6L,)`` and Jacobian ``jac (6L, n)`` of the closure at ``u`` (module
    docstring of :mod:`pkmkit.solve.chains`; ``scratch`` from :func:`_scratch`)."""
    _fill_unknowns(values, position, u)
    mats, pos, tw, tw_col = scratch
    rx, rot, tmp, mm, rows = mats[0], mats[1], mats[2], mats[3], mats[4]
    _rotvec_matrix(u[3], u[4], u[5], rx)
    jac[:, :] = 0.0
    n_twist = 0
    for leg in range(offsets.shape[0] - 1):
        base = 6 * leg
        for i in range(3):
            pos[i] = 0.0
            for j in range(3):
                rot[i, j] = 1.0 if i == j else 0.0
        n_twist = 0
        for idx in range(offsets[leg], offsets[leg + 1]):
            e = elements[idx]
            _apply_frame(rot, pos, frames[e], tmp)
            t = types[e]
            if t == 0:
                continue
            var = evar[e]
            col = position[var]
            q = values[var]
            z0, z1, z2 = rot[0, 2], rot[1, 2], rot[2, 2]
            if t == 1:
                if col >= 0:
                    tw[n_twist, 0] = pos[1] * z2 - pos[2] * z1
                    tw[n_twist, 1] = pos[2] * z0 - pos[0] * z2
                    tw[n_twist, 2] = pos[0] * z1 - pos[1] * z0
                    tw[n_twist, 3], tw[n_twist, 4], tw[n_twist, 5] = z0, z1, z2
                    tw_col[n_twist] = col
                    n_twist += 1
                c, s = math.cos(q), math.sin(q)
                for i in range(3):
                    x, y = rot[i, 0], rot[i, 1]
                    rot[i, 0] = c * x + s * y
                    rot[i, 1] = c * y - s * x
            else:
                if col >= 0:
                    tw[n_twist, 0], tw[n_twist, 1], tw[n_twist, 2] = z0, z1, z2
                    tw[n_twist, 3] = tw[n_twist, 4] = tw[n_twist, 5] = 0.0
                    tw_col[n_twist] = col
                    n_twist += 1
                pos[0] += q * z0
                pos[1] += q * z1
                pos[2] += q * z2
        # M = R_leg R_Xᵀ; residual (p_leg − p_X, L vee / c)
        for i in range(3):
            for j in range(3):
                mm[i, j] = rot[i, 0] * rx[j, 0] + rot[i, 1] * rx[j, 1] + rot[i, 2] * rx[j, 2]
        c = 0.25 * (1.0 + mm[0, 0] + mm[1, 1] + mm[2, 2])
        for i in range(3):
            r[base + i] = pos[i] - u[i]
        r[base + 3] = length * (0.5 * (mm[2, 1] - mm[1, 2])) / c
        r[base + 4] = length * (0.5 * (mm[0, 2] - mm[2, 0])) / c
        r[base + 5] = length * (0.5 * (mm[1, 0] - mm[0, 1])) / c
        # platform columns: (−I, −rotation_rows(Mᵀ))
        for i in range(3):
            jac[base + i, i] = -1.0
            for j in range(3):
                tmp[i, j] = mm[j, i]
        _rotation_rows(tmp, length, -1.0, rows)
        for i in range(3):
            for j in range(3):
                jac[base + 3 + i, 3 + j] = rows[i, j]
        # unknown joint variables: (v + w × p_leg, rotation_rows(M) w)
        _rotation_rows(mm, length, 1.0, rows)
        for a in range(n_twist):
            col = tw_col[a]
            w0, w1, w2 = tw[a, 3], tw[a, 4], tw[a, 5]
            jac[base + 0, col] = tw[a, 0] + w1 * pos[2] - w2 * pos[1]
            jac[base + 1, col] = tw[a, 1] + w2 * pos[0] - w0 * pos[2]
            jac[base + 2, col] = tw[a, 2] + w0 * pos[1] - w1 * pos[0]
            for i in range(3):
                jac[base + 3 + i, col] = rows[i, 0] * w0 + rows[i, 1] * w1 + rows[i, 2] * w2


@njit(**_OPTIONS)
def _defect_twists(e, rot, pos, local, order, starts, twists, ids, count):  # pragma: no cover
    """Spatial twists of element ``e``'s defects at the frame ``(rot, pos)`` before it, appended
    to ``twists``/``ids`` from ``count``; returns the new count."""
    for s in range(starts[e], starts[e + 1]):
        j = order[s]
        w0 = rot[0, 0] * local[j, 3] + rot[0, 1] * local[j, 4] + rot[0, 2] * local[j, 5]
        w1 = rot[1, 0] * local[j, 3] + rot[1, 1] * local[j, 4] + rot[1, 2] * local[j, 5]
        w2 = rot[2, 0] * local[j, 3] + rot[2, 1] * local[j, 4] + rot[2, 2] * local[j, 5]
        v0 = rot[0, 0] * local[j, 0] + rot[0, 1] * local[j, 1] + rot[0, 2] * local[j, 2]
        v1 = rot[1, 0] * local[j, 0] + rot[1, 1] * local[j, 1] + rot[1, 2] * local[j, 2]
        v2 = rot[2, 0] * local[j, 0] + rot[2, 1] * local[j, 1] + rot[2, 2] * local[j, 2]
        twists[count, 0] = v0 + (pos[1] * w2 - pos[2] * w1)
        twists[count, 1] = v1 + (pos[2] * w0 - pos[0] * w2)
        twists[count, 2] = v2 + (pos[0] * w1 - pos[1] * w0)
        twists[count, 3], twists[count, 4], twists[count, 5] = w0, w1, w2
        ids[count] = j
        count += 1
    return count


@njit(**_OPTIONS)
def _walk(frames, types, evar, values, chain, rot, pos, local, order, starts, twists,
          ids):  # pragma: no cover
    """Move ``(rot, pos)`` along the elements ``chain`` (as :func:`pkmkit.solve.chains.
    chain_pose`), collecting the defects' spatial twists; returns their count."""
    tmp = np.empty((3, 3))
    count = 0
    for idx in range(chain.shape[0]):
        e = chain[idx]
        count = _defect_twists(e, rot, pos, local, order, starts, twists, ids, count)
        _apply_frame(rot, pos, frames[e], tmp)
        t = types[e]
        if t == 0:
            continue
        q = values[evar[e]]
        if t == 1:
            c, s = math.cos(q), math.sin(q)
            for i in range(3):
                x, y = rot[i, 0], rot[i, 1]
                rot[i, 0] = c * x + s * y
                rot[i, 1] = c * y - s * x
        else:
            for i in range(3):
                pos[i] += q * rot[i, 2]
    return count


@njit(**_OPTIONS)
def _linearise_rows(frames, types, evar, elements, offsets, position, local, order, starts,
                    head, values, u, length, cu, cd, tool_r, tool_p,
                    tool_tw):  # pragma: no cover
    m = cu.shape[1]
    r = np.empty(m)
    rx = np.empty((3, 3))
    rot, mm, rows = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))
    pos = np.empty(3)
    twists = np.empty((local.shape[0], 6))
    ids = np.empty(local.shape[0], dtype=np.int64)
    row_values = np.empty(values.shape[1])
    scratch = _scratch(elements.shape[0])
    for k in range(values.shape[0]):
        row_values[:] = values[k]
        _evaluate(frames, types, evar, elements, offsets, position, row_values, u[k], length,
                  r, cu[k], scratch)
        _rotvec_matrix(u[k, 3], u[k, 4], u[k, 5], rx)
        for leg in range(offsets.shape[0] - 1):
            base = 6 * leg
            for i in range(3):
                pos[i] = 0.0
                for j in range(3):
                    rot[i, j] = 1.0 if i == j else 0.0
            count = _walk(frames, types, evar, row_values, elements[offsets[leg]:offsets[leg + 1]],
                          rot, pos, local, order, starts, twists, ids)
            for i in range(3):
                for j in range(3):
                    mm[i, j] = (rot[i, 0] * rx[j, 0] + rot[i, 1] * rx[j, 1]
                                + rot[i, 2] * rx[j, 2])
            _rotation_rows(mm, length, 1.0, rows)
            for a in range(count):
                col = ids[a]
                w0, w1, w2 = twists[a, 3], twists[a, 4], twists[a, 5]
                cd[k, base + 0, col] = twists[a, 0] + (w1 * pos[2] - w2 * pos[1])
                cd[k, base + 1, col] = twists[a, 1] + (w2 * pos[0] - w0 * pos[2])
                cd[k, base + 2, col] = twists[a, 2] + (w0 * pos[1] - w1 * pos[0])
                for i in range(3):
                    cd[k, base + 3 + i, col] = (rows[i, 0] * w0 + rows[i, 1] * w1
                                                + rows[i, 2] * w2)
        # the tool frame: the head from the platform frame
        rot[:, :] = rx
        for i in range(3):
            pos[i] = u[k, i]
        count = _walk(frames, types, evar, row_values, head, rot, pos, local, order, starts,
                      twists, ids)
        tool_r[k] = rot
        tool_p[k] = pos
        for a in range(count):
            for i in range(6):
                tool_tw[k, i, ids[a]] = twists[a, i]

