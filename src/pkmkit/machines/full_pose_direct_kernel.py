"""Compiled (Numba) direct model of full-pose rod machines: one Levenberg–Marquardt solve per
pose, fused, with the batched engine's rules.

:func:`pkmkit.solve.least_squares.solve_least_squares` over the rod closure of
:func:`pkmkit.solve.rod_closure.solve_direct` (``dof="full"``) is the reference this kernel is
tested against. Per pose, the same iteration as the engine, row by row: residuals
``r_j = |p + R b_j − a_j(q)| − ℓ_j(q)`` and their Jacobian ``(d̂_jᵀ, (R b_j × d̂_j)ᵀ)``; stop
before stepping on an exact residual (``atol``) or a stationary one (cosine ``gtol``); damped
normal equations ``(JᵀJ + λ(D + εI)) δ = −Jᵀr`` (Cholesky), the left rotation increment
``R ← exp(δ) R``; acceptance on the cost (rounding-level increases accepted), λ ÷ 10 on
acceptance (≥ 1e-12), × 10 on rejection; stop on a short accepted step (``xtol``), λ > 1e12 or a
crawl (ten iterations that reduced the cost by less than ``stall`` above ``residual_tol``).
Status codes are :class:`pkmkit.status.Status` values. No temporaries per iteration, no BLAS,
single-threaded: it holds beside other work and inside Dask workers.

Geometry ``geom (m, 16)`` per rod: base joint a0 (0:3), platform joint b (3:6), actuator axis
(6:9), crank pivot (9:12), rod length ℓ0 (12), kind (13: 0 slide, 1 strut, 2 crank), actuator
index (14). Options ``opts (7,)``: max_iter, xtol, atol, gtol, stall, residual_tol, damping.
Home ``home (6 + n + 6 n,)``: home pose, home q, J(home) row-major ``(6, n)`` — the default
start is the first-order guess ``home ⊕ J(home)(q − q_home)``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines.full_pose_kernels import rotation_entries

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

OK, NOT_CONVERGED, INVALID_INPUT, INCONSISTENT = 0, 3, 4, 7
MAX_COORDINATE = 1e9


@njit(**_OPTIONS)
def _rotvec_quaternion(wx, wy, wz):  # pragma: no cover
    """(x, y, z, w) of a rotation vector (scipy's series below 1e-3 rad)."""
    angle = math.sqrt(wx * wx + wy * wy + wz * wz)
    if angle <= 1e-3:
        a2 = angle * angle
        scale = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0
    else:
        scale = math.sin(0.5 * angle) / angle
    return wx * scale, wy * scale, wz * scale, math.cos(0.5 * angle)


@njit(**_OPTIONS)
def compose(dx, dy, dz, px, py, pz, out, at):  # pragma: no cover
    """``out[at:at+3]`` = rotation vector of exp(δ)·exp(φ) (angle in [0, π], as scipy)."""
    ax, ay, az, aw = _rotvec_quaternion(dx, dy, dz)
    bx, by, bz, bw = _rotvec_quaternion(px, py, pz)
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    w = aw * bw - ax * bx - ay * by - az * bz
    quaternion_rotvec(x, y, z, w, out, at)


@njit(**_OPTIONS)
def quaternion_rotvec(x, y, z, w, out, at):  # pragma: no cover
    """``out[at:at+3]`` = the rotation vector of the unit quaternion (x, y, z, w), its angle
    in [0, π] (:func:`compose`'s tail; the Verne position solve's answer)."""
    if w < 0.0:
        x, y, z, w = -x, -y, -z, -w
    norm = math.sqrt(x * x + y * y + z * z)
    angle = 2.0 * math.atan2(norm, w)
    if angle <= 1e-3:
        a2 = angle * angle
        scale = 2.0 + a2 / 12.0 + 7.0 * a2 * a2 / 2880.0
    else:
        scale = angle / math.sin(0.5 * angle)
    out[at] = x * scale
    out[at + 1] = y * scale
    out[at + 2] = z * scale


@njit(**_OPTIONS)
def _rods(q, geom, base, length):  # pragma: no cover
    """Base joints ``a_j(q)`` into ``base (m, 3)`` and rod lengths ``ℓ_j(q)`` into ``length``."""
    for j in range(geom.shape[0]):
        qk = q[int(geom[j, 14])]
        kind = geom[j, 13]
        length[j] = geom[j, 12]
        if kind == 0.0:  # slide
            for i in range(3):
                base[j, i] = geom[j, i] + qk * geom[j, 6 + i]
        elif kind == 1.0:  # strut
            for i in range(3):
                base[j, i] = geom[j, i]
            length[j] += qk
        else:  # crank: Rodrigues about the axis through the pivot
            wx, wy, wz = geom[j, 6], geom[j, 7], geom[j, 8]
            rx, ry, rz = geom[j, 0] - geom[j, 9], geom[j, 1] - geom[j, 10], geom[j, 2] - geom[j, 11]
            c, s = math.cos(qk), math.sin(qk)
            along = (wx * rx + wy * ry + wz * rz) * (1.0 - c)
            base[j, 0] = geom[j, 9] + rx * c + (wy * rz - wz * ry) * s + wx * along
            base[j, 1] = geom[j, 10] + ry * c + (wz * rx - wx * rz) * s + wy * along
            base[j, 2] = geom[j, 11] + rz * c + (wx * ry - wy * rx) * s + wz * along


@njit(**_OPTIONS)
def _evaluate(u, geom, base, length, r, jac):  # pragma: no cover
    """Residuals ``r (m,)`` and Jacobian ``jac (m, 6)`` at pose ``u (6,)``; returns the cost
    ½|r|² (NaN or inf when not finite, the Jacobian included)."""
    wx, wy, wz = u[3], u[4], u[5]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(wx, wy, wz)
    cost = 0.0
    check = 0.0
    for j in range(geom.shape[0]):
        bx, by, bz = geom[j, 3], geom[j, 4], geom[j, 5]
        sx = r00 * bx + r01 * by + r02 * bz
        sy = r10 * bx + r11 * by + r12 * bz
        sz = r20 * bx + r21 * by + r22 * bz
        dx = u[0] + sx - base[j, 0]
        dy = u[1] + sy - base[j, 1]
        dz = u[2] + sz - base[j, 2]
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        r[j] = dist - length[j]
        cost += r[j] * r[j]
        ux, uy, uz = dx / dist, dy / dist, dz / dist
        jac[j, 0] = ux
        jac[j, 1] = uy
        jac[j, 2] = uz
        jac[j, 3] = sy * uz - sz * uy
        jac[j, 4] = sz * ux - sx * uz
        jac[j, 5] = sx * uy - sy * ux
        check += jac[j, 3] + jac[j, 4] + jac[j, 5] + ux + uy + uz
    return 0.5 * cost + 0.0 * check  # NaN when any Jacobian entry is not finite


@njit(**_OPTIONS)
def _step(jac, r, lam, step, h):  # pragma: no cover
    """``step (6,)`` = −(JᵀJ + λ(D + εI))⁻¹ Jᵀr by Cholesky (``h (6, 6)``: scratch)."""
    m = jac.shape[0]
    biggest = 0.0
    for i in range(6):
        acc = 0.0
        for j in range(m):
            acc += jac[j, i] * r[j]
        step[i] = acc
        for k in range(i + 1):
            acc = 0.0
            for j in range(m):
                acc += jac[j, i] * jac[j, k]
            h[i, k] = acc
        biggest = max(biggest, h[i, i])
    floor = 1e-9 * biggest + 1e-300
    for i in range(6):
        h[i, i] += lam * (h[i, i] + floor)
    for i in range(6):  # lower Cholesky factor in place, reciprocal diagonal
        for k in range(i + 1):
            acc = h[i, k]
            for p in range(k):
                acc -= h[i, p] * h[k, p]
            if i == k:
                h[i, i] = math.sqrt(acc) if acc > 0.0 else math.nan
            else:
                h[i, k] = acc * h[k, k]
        h[i, i] = 1.0 / h[i, i]
    for i in range(6):
        acc = -step[i]
        for p in range(i):
            acc -= h[i, p] * step[p]
        step[i] = acc * h[i, i]
    for i in range(5, -1, -1):
        acc = step[i]
        for p in range(i + 1, 6):
            acc -= h[p, i] * step[p]
        step[i] = acc * h[i, i]


@njit(**_OPTIONS)
def _stationary(jac, r, cost, gtol):  # pragma: no cover
    """Whether every Jacobian column is orthogonal to r within the cosine ``gtol``."""
    largest = 0.0
    for i in range(6):
        grad = 0.0
        col = 0.0
        for j in range(r.shape[0]):
            grad += jac[j, i] * r[j]
            col += jac[j, i] * jac[j, i]
        cosine = abs(grad) / math.sqrt(col * (2.0 * cost))
        if cosine == cosine and cosine > largest:
            largest = cosine
    return not largest > gtol


@njit(**_OPTIONS)
def scratch(m):  # pragma: no cover
    """Working arrays of :func:`solve_row` for ``m`` rods (allocated once per call)."""
    return (np.empty((m, 3)), np.empty((3, m)), np.empty((2, m, 6)), np.empty((3, 6)),
            np.empty((6, 6)))


@njit(**_OPTIONS)
def solve_row(q, u0, has_guess, geom, home, opts, out, work):  # pragma: no cover
    """One pose: ``out (9,)`` = pose (6), status, iterations, largest |residual| (NaN when the
    start is invalid); ``work`` from :func:`scratch`."""
    m = geom.shape[0]
    n = q.shape[0]
    base, rows, jacs, vecs, h = work
    length, r, r_new = rows[0], rows[1], rows[2]
    jac, jac_new = jacs[0], jacs[1]
    u, u_new, step = vecs[0], vecs[1], vecs[2]
    out[6] = INVALID_INPUT
    out[7] = 0.0
    out[8] = math.nan
    valid = True
    for k in range(n):
        if not abs(q[k]) <= MAX_COORDINATE:
            valid = False
    if has_guess:
        for i in range(6):
            u[i] = u0[i]
    elif valid:  # first-order guess: home ⊕ J(home)(q − q_home)
        for i in range(6):
            acc = 0.0
            for k in range(n):
                acc += home[6 + n + i * n + k] * (q[k] - home[6 + k])
            step[i] = acc
        for i in range(3):
            u[i] = home[i] + step[i]
        compose(step[3], step[4], step[5], home[3], home[4], home[5], u, 3)
    for i in range(6):
        out[i] = u[i] if valid else math.nan
        if not u[i] == u[i] or abs(u[i]) == math.inf:
            valid = False
    if not valid:
        return
    max_iter, xtol, atol, gtol = int(opts[0]), opts[1], opts[2], opts[3]
    stall, residual_tol, lam = opts[4], opts[5], opts[6]
    _rods(q, geom, base, length)
    cost = _evaluate(u, geom, base, length, r, jac)
    if not (cost == cost and cost < math.inf):
        return
    checkpoint = cost
    stopped = False
    iterations = 0
    for _ in range(max_iter):
        if cost <= 0.5 * atol * atol or _stationary(jac, r, cost, gtol):
            stopped = True
            break
        _step(jac, r, lam, step, h)
        for i in range(3):
            u_new[i] = u[i] + step[i]
        compose(step[3], step[4], step[5], u[3], u[4], u[5], u_new, 3)
        cost_new = _evaluate(u_new, geom, base, length, r_new, jac_new)
        accept = cost_new == cost_new and cost_new < math.inf and cost_new <= cost * (1.0 + 1e-13)
        iterations += 1
        if accept:
            for i in range(6):
                u[i] = u_new[i]
            for j in range(m):
                r[j] = r_new[j]
                for i in range(6):
                    jac[j, i] = jac_new[j, i]
            cost = cost_new
            lam = max(lam * 0.1, 1e-12)
        else:
            lam *= 10.0
        step_norm = 0.0
        u_norm = 0.0
        for i in range(6):
            step_norm += step[i] * step[i]
            u_norm += u[i] * u[i]
        done = (accept and math.sqrt(step_norm) <= xtol * (1.0 + math.sqrt(u_norm))) or lam > 1e12
        if iterations % 10 == 0:
            if cost > (1.0 - stall) * checkpoint and cost > 0.5 * residual_tol * residual_tol:
                done = True
            checkpoint = cost
        if done:
            stopped = True
            break
    largest = 0.0
    for j in range(m):
        largest = max(largest, abs(r[j]))
    for i in range(6):
        out[i] = u[i]
    out[7] = iterations
    out[8] = largest
    if not stopped:
        out[6] = NOT_CONVERGED
    elif largest <= residual_tol:
        out[6] = OK
    else:
        out[6] = INCONSISTENT


@njit(**_OPTIONS)
def solve_rows(q, u0, has_guess, geom, home, opts, out):  # pragma: no cover
    """:func:`solve_row` for every row: ``q (N, n)``, ``u0 (N, 6)`` (read when ``has_guess``),
    ``out (N, 9)``."""
    work = scratch(geom.shape[0])
    for k in range(q.shape[0]):
        solve_row(q[k], u0[k], has_guess, geom, home, opts, out[k], work)


@njit(**_OPTIONS)
def solve_one(q, u0, has_guess, geom, home, opts, out):  # pragma: no cover
    """:func:`solve_row` for one pose ``q (n,)``, ``u0 (6,)``, ``out (9,)``."""
    solve_row(q, u0, has_guess, geom, home, opts, out, scratch(geom.shape[0]))
