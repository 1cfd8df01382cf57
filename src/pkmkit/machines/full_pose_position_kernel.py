"""Compiled (Numba) inverse model of a full-pose machine commanded by its position alone (three
actuators, the rods setting the orientation: the Verne-type module): one Levenberg–Marquardt
solve per position, fused, with the batched engine's rules (issue 22 §3).

:func:`pkmkit.solve.rod_closure.solve_position_inverse` over
:func:`pkmkit.solve.least_squares.solve_least_squares` is the reference this kernel is tested
against (tests/machines/test_full_pose_position_kernel.py). Unknowns ``u = (q_0, q_1, q_2, δ)``:
the actuator coordinates, then the rotation (left increment ``R ← exp(δ) R``); the position
``p`` is given. Per rod ``r_j = |p + R b_j − a_j(q)| − ℓ_j(q)``, ``∂r_j/∂q_k = −(d̂_j·∂a_j/∂q_k +
κt_j)`` in the column of the rod's actuator, ``∂r_j/∂δ = (R b_j × d̂_j)ᵀ``. The iteration and
its stopping rules are :func:`pkmkit.machines.full_pose_direct_kernel.solve_row`'s (the
engine's), only the unknowns differ, and the engine's ``crawl`` limit: options ``opts (9,)``
are the direct kernel's seven, then ``crawl = (k, ρ)`` (k = 0: none). Geometry ``geom (m, 16)``
as there. No temporaries per iteration, no BLAS, single-threaded.

A machine whose every actuator carries two slide rods (the Verne-type module) runs
:func:`solve_paired` instead (``opts[9]`` = 1): Newton's method on the rotation alone, each
rod's coordinate closed form on its branch, the two rods of an actuator made to agree (3
equations, 3 unknowns); the machine runs this module's Levenberg–Marquardt solve on the rows
it leaves (:meth:`pkmkit.machines.full_pose_position.PositionInverse._compiled_rows`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from pkmkit.machines.full_pose_direct_kernel import (
    INVALID_INPUT,
    NOT_CONVERGED,
    OK,
    _rods,
    _stationary,
    _step,
    compose,
    quaternion_rotvec,
    scratch,
)
from pkmkit.machines.full_pose_kernels import rotation_entries

_OPTIONS = {"nogil": True, "boundscheck": False, "error_model": "numpy", "cache": True}

INCONSISTENT = 7
#: Actuators of the machines this kernel serves (3 actuators + 3 rotation unknowns = 6).
N_ACTUATORS = 3
#: The paired Newton solve (:func:`solve_paired`): its step limit, the step (rad) below which it
#: has converged (quadratic convergence: the error after it is ≈ its square), and the largest
#: rod residual (m) it accepts — else the row runs the Levenberg–Marquardt solve as before.
PAIRED_ITER = 8
PAIRED_STEP = 1e-9
PAIRED_TOL = 1e-12
#: The half angle (rad) up to which a step's quaternion takes its sine and cosine by their series.
PAIRED_SERIES = 0.05
#: Values of a start table's header (:mod:`pkmkit.machines.position_start`).
START_HEADER = 13


@njit(**_OPTIONS)
def _evaluate(u, p, geom, base, length, r, jac):  # pragma: no cover
    """Residuals ``r (m,)`` and Jacobian ``jac (m, 6)`` at unknowns ``u (6,)`` = (q, rotation
    vector) for position ``p (3,)``; returns the cost ½|r|² (NaN or inf when not finite, the
    Jacobian included). ``base``, ``length``: scratch for the base joints and rod lengths."""
    _rods(u[:3], geom, base, length)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation_entries(u[3], u[4], u[5])
    cost = 0.0
    check = 0.0
    for j in range(geom.shape[0]):
        bx, by, bz = geom[j, 3], geom[j, 4], geom[j, 5]
        sx = r00 * bx + r01 * by + r02 * bz
        sy = r10 * bx + r11 * by + r12 * bz
        sz = r20 * bx + r21 * by + r22 * bz
        dx = p[0] + sx - base[j, 0]
        dy = p[1] + sy - base[j, 1]
        dz = p[2] + sz - base[j, 2]
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        r[j] = dist - length[j]
        cost += r[j] * r[j]
        ux, uy, uz = dx / dist, dy / dist, dz / dist
        kind = geom[j, 13]
        if kind == 0.0:  # slide: ∂a/∂q = its axis
            along = ux * geom[j, 6] + uy * geom[j, 7] + uz * geom[j, 8]
        elif kind == 1.0:  # strut: ∂ℓ/∂q = 1
            along = 1.0
        else:  # crank: ∂a/∂q = w × (a − pivot)
            wx, wy, wz = geom[j, 6], geom[j, 7], geom[j, 8]
            ax, ay, az = base[j, 0] - geom[j, 9], base[j, 1] - geom[j, 10], base[j, 2] - geom[j, 11]
            along = (ux * (wy * az - wz * ay) + uy * (wz * ax - wx * az)
                     + uz * (wx * ay - wy * ax))
        for k in range(3):
            jac[j, k] = 0.0
        jac[j, int(geom[j, 14])] = -along
        jac[j, 3] = sy * uz - sz * uy
        jac[j, 4] = sz * ux - sx * uz
        jac[j, 5] = sx * uy - sy * ux
        check += jac[j, 3] + jac[j, 4] + jac[j, 5] + along
    return 0.5 * cost + 0.0 * check  # NaN when any Jacobian entry is not finite


@njit(**_OPTIONS)
def _start(u0, u, out):  # pragma: no cover
    """Copy the start ``u0`` into ``u`` and ``out``; False (``out`` INVALID_INPUT) when it is
    not finite."""
    out[6] = INVALID_INPUT
    out[7] = 0.0
    out[8] = math.nan
    valid = True
    for i in range(6):
        u[i] = u0[i]
        out[i] = u0[i]
        if not u0[i] == u0[i] or abs(u0[i]) == math.inf:
            valid = False
    return valid


@njit(**_OPTIONS)
def _take(u, u_new, r, r_new, jac, jac_new):  # pragma: no cover
    """The accepted iterate: ``u, r, jac`` ← ``u_new, r_new, jac_new``."""
    for i in range(6):
        u[i] = u_new[i]
    for j in range(r.shape[0]):
        r[j] = r_new[j]
        for i in range(6):
            jac[j, i] = jac_new[j, i]


@njit(**_OPTIONS)
def _short(step, u, xtol):  # pragma: no cover
    """The engine's small-step test ``|δ| ≤ xtol (1 + |u|)``."""
    step_norm = 0.0
    u_norm = 0.0
    for i in range(6):
        step_norm += step[i] * step[i]
        u_norm += u[i] * u[i]
    return math.sqrt(step_norm) <= xtol * (1.0 + math.sqrt(u_norm))


@njit(**_OPTIONS)
def _largest(r):  # pragma: no cover
    """max |r_j|."""
    largest = 0.0
    for j in range(r.shape[0]):
        largest = max(largest, abs(r[j]))
    return largest


@njit(**_OPTIONS)
def _finish(u, r, iterations, stopped, residual_tol, out):  # pragma: no cover
    """``out (9,)`` of a finished row: u, status (the engine's), iterations, largest |r|."""
    largest = _largest(r)
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
def solve_row(p, u0, geom, opts, out, work):  # pragma: no cover
    """One position ``p (3,)`` from ``u0 (6,)`` = (q, rotation vector): ``out (9,)`` = u (6),
    status, iterations, largest |residual| (NaN when the start is invalid); ``work`` from
    :func:`pkmkit.machines.full_pose_direct_kernel.scratch`."""
    base, rows, jacs, vecs, h = work
    length, r, r_new = rows[0], rows[1], rows[2]
    jac, jac_new = jacs[0], jacs[1]
    u, u_new, step = vecs[0], vecs[1], vecs[2]
    if not _start(u0, u, out):
        return
    max_iter, xtol, atol, gtol = int(opts[0]), opts[1], opts[2], opts[3]
    stall, residual_tol, lam = opts[4], opts[5], opts[6]
    crawl_iter, crawl_residual = int(opts[7]), opts[8]
    cost = _evaluate(u, p, geom, base, length, r, jac)
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
        cost_new = _evaluate(u_new, p, geom, base, length, r_new, jac_new)
        accept = cost_new == cost_new and cost_new < math.inf and cost_new <= cost * (1.0 + 1e-13)
        iterations += 1
        if accept:
            _take(u, u_new, r, r_new, jac, jac_new)
            cost = cost_new
            lam = max(lam * 0.1, 1e-12)
        else:
            lam *= 10.0
        done = (accept and _short(step, u, xtol)) or lam > 1e12
        if iterations % 10 == 0:
            if cost > (1.0 - stall) * checkpoint and cost > 0.5 * residual_tol * residual_tol:
                done = True
            checkpoint = cost
        if done:
            stopped = True
            break
        if iterations == crawl_iter and _largest(r) > crawl_residual:
            break  # far from any solution: NOT_CONVERGED now
    _finish(u, r, iterations, stopped, residual_tol, out)


@njit(**_OPTIONS)
def first_order(p, home, jt_inv, u0):  # pragma: no cover
    """The engine's default start ``u0 (6,)`` for position ``p (3,)``: q = q_home + J_p⁻¹
    (p − p_home) (J_p the linear rows of J(home), ``jt_inv`` its inverse), then the rotation
    of the twist J(home)(q − q_home) composed with home's (the first-order pose)."""
    n = 3
    dq = np.empty(3)
    for i in range(3):
        acc = 0.0
        for k in range(3):
            acc += jt_inv[i, k] * (p[k] - home[k])
        dq[i] = acc
    for i in range(3):
        u0[i] = home[6 + i] + dq[i]
    w = np.empty(3)
    for i in range(3):
        acc = 0.0
        for k in range(n):
            acc += (u0[k] - home[6 + k]) * home[6 + n + (3 + i) * n + k]
        w[i] = acc
    compose(w[0], w[1], w[2], home[3], home[4], home[5], u0, 3)


@njit(**_OPTIONS)
def _paired(p, rot, geom, qrod, f, jac):  # pragma: no cover
    """The reduced closure of a machine whose every actuator carries two slide rods, at
    rotation ``rot (9,)`` (row-major) for position ``p (3,)``: each rod's actuator coordinate on
    its branch (``geom[:, 15]`` = ±1) into ``qrod (m,)`` (as ``rod_coordinates``: ``s + σ√(ℓ² −
    |v|² + s²)``, ``v = p + R b − a0``, ``s = e·v``), the disagreements ``f (3,)`` = q of the
    actuator's first rod − its second's and their derivatives ``jac (3, 3)`` in the rotation
    (left increment: ``∂q_j/∂δ = (R b × d) / (d·e)``, ``d = v − q_j e``). False when a rod
    cannot close (radicand ≤ 0) or a value is not finite."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = (rot[0], rot[1], rot[2], rot[3], rot[4],
                                                   rot[5], rot[6], rot[7], rot[8])
    for k in range(3):
        f[k] = 0.0
        for i in range(3):
            jac[k, i] = 0.0
    seen = np.zeros(3)
    check = 0.0
    for j in range(geom.shape[0]):
        bx, by, bz = geom[j, 3], geom[j, 4], geom[j, 5]
        ex, ey, ez = geom[j, 6], geom[j, 7], geom[j, 8]
        sx = r00 * bx + r01 * by + r02 * bz
        sy = r10 * bx + r11 * by + r12 * bz
        sz = r20 * bx + r21 * by + r22 * bz
        vx = p[0] + sx - geom[j, 0]
        vy = p[1] + sy - geom[j, 1]
        vz = p[2] + sz - geom[j, 2]
        along = ex * vx + ey * vy + ez * vz
        radicand = geom[j, 12] * geom[j, 12] - (vx * vx + vy * vy + vz * vz) + along * along
        if not radicand > 0.0:
            return False
        q = along + geom[j, 15] * math.sqrt(radicand)
        qrod[j] = q
        dx, dy, dz = vx - q * ex, vy - q * ey, vz - q * ez
        cosine = along - q  # d·e
        k = int(geom[j, 14])
        sign = 1.0 if seen[k] == 0.0 else -1.0
        seen[k] = 1.0
        f[k] += sign * q
        scale = sign / cosine  # one division per rod
        jac[k, 0] += scale * (sy * dz - sz * dy)
        jac[k, 1] += scale * (sz * dx - sx * dz)
        jac[k, 2] += scale * (sx * dy - sy * dx)
        check += jac[k, 0] + jac[k, 1] + jac[k, 2] + q
    return check == check and abs(check) < math.inf


@njit(**_OPTIONS)
def _newton_step(f, jac, step):  # pragma: no cover
    """``step (3,)`` = −jac⁻¹ f by Cramer's rule; False when jac is singular or not finite."""
    a, b, c = jac[0, 0], jac[0, 1], jac[0, 2]
    d, e, g = jac[1, 0], jac[1, 1], jac[1, 2]
    h, i, k = jac[2, 0], jac[2, 1], jac[2, 2]
    c0, c1, c2 = e * k - g * i, g * h - d * k, d * i - e * h
    det = a * c0 + b * c1 + c * c2
    if not (abs(det) > 1e-300 and abs(det) < math.inf):
        return False
    step[0] = -(f[0] * c0 + f[1] * (c * i - b * k) + f[2] * (b * g - c * e)) / det
    step[1] = -(f[0] * c1 + f[1] * (a * k - c * h) + f[2] * (c * d - a * g)) / det
    step[2] = -(f[0] * c2 + f[1] * (b * h - a * i) + f[2] * (a * e - b * d)) / det
    return True


@njit(**_OPTIONS)
def _step_quaternion(dx, dy, dz, qt):  # pragma: no cover
    """``qt (4,)`` = (x, y, z, w), the unit quaternion of rotation vector (dx, dy, dz): the half
    angle's cosine and sine / angle by their Taylor series up to a half angle of
    PAIRED_SERIES (the first term left out below 1e-20 of the sum), the C library's above."""
    angle = math.sqrt(dx * dx + dy * dy + dz * dz)
    h = 0.5 * angle
    if h <= PAIRED_SERIES:
        h2 = h * h
        c = 1.0 - h2 * (0.5 - h2 * (1.0 / 24.0 - h2 * (1.0 / 720.0 - h2 / 40320.0)))
        s = 0.5 * (1.0 - h2 * (1.0 / 6.0 - h2 * (1.0 / 120.0 - h2 * (1.0 / 5040.0
                                                                     - h2 / 362880.0))))
    else:
        c = math.cos(h)
        s = math.sin(h) / angle
    qt[0] = dx * s
    qt[1] = dy * s
    qt[2] = dz * s
    qt[3] = c


@njit(**_OPTIONS)
def _turn(a, qt):  # pragma: no cover
    """``qt`` ← ``a qt`` (Hamilton product, as :func:`compose`'s), normalised."""
    ax, ay, az, aw = a[0], a[1], a[2], a[3]
    bx, by, bz, bw = qt[0], qt[1], qt[2], qt[3]
    x = aw * bx + ax * bw + ay * bz - az * by
    y = aw * by - ax * bz + ay * bw + az * bx
    z = aw * bz + ax * by - ay * bx + az * bw
    w = aw * bw - ax * bx - ay * by - az * bz
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    qt[0] = x / norm
    qt[1] = y / norm
    qt[2] = z / norm
    qt[3] = w / norm


@njit(**_OPTIONS)
def _quaternion_matrix(qt, rot):  # pragma: no cover
    """``rot (9,)`` row-major of the unit quaternion ``qt``."""
    x, y, z, w = qt[0], qt[1], qt[2], qt[3]
    rot[0] = 1.0 - 2.0 * (y * y + z * z)
    rot[1] = 2.0 * (x * y - z * w)
    rot[2] = 2.0 * (x * z + y * w)
    rot[3] = 2.0 * (x * y + z * w)
    rot[4] = 1.0 - 2.0 * (x * x + z * z)
    rot[5] = 2.0 * (y * z - x * w)
    rot[6] = 2.0 * (x * z - y * w)
    rot[7] = 2.0 * (y * z + x * w)
    rot[8] = 1.0 - 2.0 * (x * x + y * y)


@njit(**_OPTIONS)
def _first_order_quaternion(p, home, jt_inv, qt, a):  # pragma: no cover
    """The first-order start's rotation as a unit quaternion ``qt (4,)`` for position ``p
    (3,)``: the twist J(home)(q − q_home) of :func:`first_order`'s q turned onto home's
    rotation (``a (4,)``: scratch)."""
    n = 3
    dq = np.empty(3)
    for i in range(3):
        acc = 0.0
        for k in range(3):
            acc += jt_inv[i, k] * (p[k] - home[k])
        dq[i] = acc
    w = np.empty(3)
    for i in range(3):
        acc = 0.0
        for k in range(n):
            acc += dq[k] * home[6 + n + (3 + i) * n + k]
        w[i] = acc
    _step_quaternion(home[3], home[4], home[5], qt)
    _step_quaternion(w[0], w[1], w[2], a)
    _turn(a, qt)


@njit(**_OPTIONS)
def _table_start(p, table, qt):  # pragma: no cover
    """The start ``qt (4,)`` of position ``p (3,)`` from the start table ``table``
    (:func:`pkmkit.machines.position_start.pack`): True when p's projection on the table's
    plane falls in a cell whose fit is finite and gives a vector part shorter than 1 (then
    w = √(1 − |v|²)), else False."""
    cells, side, corner = table[0], table[2], table[3]
    c, d = int(cells), int(table[1])
    rx, ry, rz = p[0] - table[4], p[1] - table[5], p[2] - table[6]
    tu = (rx * table[7] + ry * table[8] + rz * table[9] - corner) / side
    tv = (rx * table[10] + ry * table[11] + rz * table[12] - corner) / side
    if not (tu >= 0.0 and tu < cells and tv >= 0.0 and tv < cells):
        return False
    iu, iv = int(tu), int(tv)
    a = tu - float(iu) - 0.5
    b = tv - float(iv) - 0.5
    terms = (d + 1) * (d + 2) // 2
    base = START_HEADER + (iu * c + iv) * terms * 3
    v0 = v1 = v2 = 0.0
    for i in range(d, -1, -1):
        at = base + 3 * (i * (d + 1) - i * (i - 1) // 2)
        in0 = in1 = in2 = 0.0
        for j in range(d - i, -1, -1):
            in0 = in0 * b + table[at + 3 * j]
            in1 = in1 * b + table[at + 3 * j + 1]
            in2 = in2 * b + table[at + 3 * j + 2]
        v0 = v0 * a + in0
        v1 = v1 * a + in1
        v2 = v2 * a + in2
    rest = 1.0 - (v0 * v0 + v1 * v1 + v2 * v2)
    if not rest > 0.0:  # NaN too: a cell the table left
        return False
    qt[0], qt[1], qt[2], qt[3] = v0, v1, v2, math.sqrt(rest)
    return True


@njit(**_OPTIONS)
def solve_paired(p, qt, geom, out, qrod, f, jac):  # pragma: no cover
    """The position inverse of a machine whose every actuator carries two slide rods, by
    Newton's method on the rotation alone (a unit quaternion ``qt (4,)``, turned by left
    increments; 3 unknowns: the two rods of an actuator must give the same coordinate) from
    ``qt``: True and ``out (9,)`` = u (q, rotation vector), OK, Newton steps, largest rod
    residual when it converges (a step ≤ PAIRED_STEP, then every rod closing within
    PAIRED_TOL at the mean of its actuator's pair); False otherwise — a rod that cannot close,
    a singular Jacobian, PAIRED_ITER steps (``out`` untouched)."""
    step = np.empty(3)
    a = np.empty(4)
    rot = np.empty(9)
    steps = 0
    converged = False
    while steps < PAIRED_ITER:
        _quaternion_matrix(qt, rot)
        if not _paired(p, rot, geom, qrod, f, jac) or not _newton_step(f, jac, step):
            return False
        _step_quaternion(step[0], step[1], step[2], a)
        _turn(a, qt)
        steps += 1
        if math.sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2]) <= PAIRED_STEP:
            converged = True
            break
    if not converged:
        return False
    _quaternion_matrix(qt, rot)
    if not _paired(p, rot, geom, qrod, f, jac):
        return False
    q = np.empty(3)
    seen = np.zeros(3)
    for j in range(geom.shape[0]):
        k = int(geom[j, 14])
        if seen[k] == 0.0:
            q[k] = qrod[j]
            seen[k] = 1.0
        else:
            q[k] = q[k] + 0.5 * (qrod[j] - q[k])  # first + mean offset (combine)
    largest = 0.0
    for j in range(geom.shape[0]):
        qk = q[int(geom[j, 14])]
        dx = p[0] - geom[j, 0] - qk * geom[j, 6]
        dy = p[1] - geom[j, 1] - qk * geom[j, 7]
        dz = p[2] - geom[j, 2] - qk * geom[j, 8]
        bx, by, bz = geom[j, 3], geom[j, 4], geom[j, 5]
        dx += rot[0] * bx + rot[1] * by + rot[2] * bz
        dy += rot[3] * bx + rot[4] * by + rot[5] * bz
        dz += rot[6] * bx + rot[7] * by + rot[8] * bz
        largest = max(largest, abs(math.sqrt(dx * dx + dy * dy + dz * dz) - geom[j, 12]))
    if not largest <= PAIRED_TOL:
        return False
    for k in range(3):
        out[k] = q[k]
    quaternion_rotvec(qt[0], qt[1], qt[2], qt[3], out, 3)
    out[6] = OK
    out[7] = steps
    out[8] = largest
    return True


@njit(**_OPTIONS)
def solve_rows(p, u0, has_guess, skip, geom, home, jt_inv, opts, out):  # pragma: no cover
    """:func:`solve_row` for every row: ``p (N, 3)``, ``u0 (N, 6)`` (read when ``has_guess``,
    else :func:`first_order` from ``home``, the direct kernel's home vector), ``skip (N,)``
    rows left INVALID_INPUT (NaN start), ``out (N, 9)`` or ``(N, 10)``. With ``opts (10,)``
    and ``opts[9]`` = 1 (a machine whose every actuator carries two slide rods, branches in
    ``geom[:, 15]``) the rows from the first-order start run :func:`solve_paired` instead:
    the rows it does not answer are left INVALID_INPUT (NaN) for the caller's
    Levenberg–Marquardt pass; ``out[:, 9]`` (when present) = 1 where it answered, else 0.
    Its start: the first order's rotation, or with ``opts (10 + k,)`` the start table
    ``opts[10:]`` (:mod:`pkmkit.machines.position_start`) where it covers the row."""
    work = scratch(geom.shape[0])
    start = np.empty(6)
    paired = opts.shape[0] > 9 and opts[9] == 1.0 and not has_guess
    qrod = np.empty(geom.shape[0])
    f = np.empty(3)
    jac = np.empty((3, 3))
    qt = np.empty(4)
    turn = np.empty(4)
    table = paired and opts.shape[0] > 10
    start_table = opts[10:]
    for k in range(p.shape[0]):
        if has_guess:
            for i in range(6):
                start[i] = u0[k, i]
        elif skip[k]:
            for i in range(6):
                start[i] = math.nan
        elif not paired:
            first_order(p[k], home, jt_inv, start)
        if not paired:
            solve_row(p[k], start, geom, opts, out[k], work)
            if out.shape[1] > 9:
                out[k, 9] = 0.0
            continue
        done = False
        if not skip[k]:
            if not (table and _table_start(p[k], start_table, qt)):
                _first_order_quaternion(p[k], home, jt_inv, qt, turn)
            done = solve_paired(p[k], qt, geom, out[k], qrod, f, jac)
        if not done:  # left to the caller's Levenberg–Marquardt pass
            for i in range(6):
                out[k, i] = math.nan
            out[k, 6] = INVALID_INPUT
            out[k, 7] = 0.0
            out[k, 8] = math.nan
        if out.shape[1] > 9:
            out[k, 9] = 1.0 if done else 0.0

def solve(geom: np.ndarray, positions: np.ndarray, u0: np.ndarray | None, opts: np.ndarray,
          *, skip: np.ndarray | None = None, home: np.ndarray | None = None,
          jt_inv: np.ndarray | None = None
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`pkmkit.machines.full_pose_position_solve.solve` through this module's Numba
    :func:`solve_rows` (never its C twin): the position inverse of ``positions (N, 3)``."""
    from pkmkit.machines.full_pose_position_solve import solve as run

    return run(geom, positions, u0, opts, skip=skip, home=home, jt_inv=jt_inv,
               function=solve_rows)
