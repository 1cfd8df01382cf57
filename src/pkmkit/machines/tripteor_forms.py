"""The Tripteor X7's inverse model in near-closed form (issue 22 §1, session 34), in the frames
of :mod:`pkmkit.machines.tripteor`: the closed-form start of its joint-chain inverse
(``MachineKind.inverse_start``), as the TriMule's (:mod:`pkmkit.machines.trimule_forms`).

The parallel part (Exechon): legs 1 and 3 turn about the common line A1A3 (ψ1 = ψ3 = ψ) and,
with B1, B3 and the platform's φ axes, stay in one plane through that line, of normal
``n = (cos ψ, 0, sin ψ)``; the platform frame R51 (origin B1) is
``R51 = Rx(90°) Rz(ψ) F Rz(σ)`` (``F`` the cyclic axis permutation of the model's frames with
z along x; ``σ = θ1 + φ1 − π/2 = θ3 + φ3 − π/2``), so ``x51 = cos σ e1 + sin σ e2`` with the
plane's ``e1 = (−sin ψ, 0, cos ψ)``, ``e2 = (0, −1, 0)``; leg 2 (spherical at A2, prismatic,
revolute φ2 along B1B3) is normal to x51. Given the platform frame MPS's origin P (``p_m`` in
R51, ``b2`` the point B2 in R51), both constraints are explicit:

- B1 in the plane: ``n(ψ) · P = p_m,z`` — ``ψ = atan2(P_z, P_x) + s_ψ acos(p_m,z / |P_xz|)``;
- leg 2 normal to x51: ``cos σ (P − A2)·e1 + sin σ (P − A2)·e2 = −(b2 − p_m)_x`` — one
  ``atan2``/``acos`` likewise (the signs ``s_ψ, s_σ`` those of home's assembly).

The head (:mod:`pkmkit.machines.tripteor`'s assumptions): the foot of the Q5 axis
``W = T − (spindle + ℓ) a`` is ``P + c1 x'`` with ``x' = R_P Rz(Q4) e_x = −b g/|g|``,
``g = a − (a·z_P) z_P`` (``|g| = |sin Q5|``, b the head's branch: +1 for Q5 ≥ 0). So the
platform solves the two-angle fixed point ``(ψ, σ) = Φ(W − c1 x'(ψ, σ))``: started from
``c1 = 0`` (``P = W``), Newton's chord iterations on ``Φ(z) − z`` with the Jacobian by
differences at the start (:data:`INVERSE_STEPS` at most, until a step is below
:data:`INVERSE_TOL`); then ``Q5 = b atan2(|g|, −a·z_P)``, ``Q4 = atan2(x'·y_P, x'·x_P)`` and
every leg's joints from B1, B2, B3 (:func:`_joints`). Rows within :data:`INVERSE_SINGULAR` of
the wrist singularity (|sin Q5|, where Q4 is undetermined), not converged, or without assembly
are declined (NaN): the caller keeps the first-order start there.

Every operation is elementwise: a row's bits do not depend on the rows beside it (issue 22 §6);
``native/chain_one_tripteor.c`` computes the same, statement for statement.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.model.chains import invariant_frame

#: The joint-chain model's variables in its order (:func:`inverse_unknowns`'s columns 6:).
VARIABLES = ("psi1", "theta1", "Q1", "phi1", "psi2", "theta2", "eta2", "Q2", "phi2", "psi3",
             "theta3", "Q3", "phi3", "Q4", "Q5")
#: Newton (then chord) iterations of :func:`inverse_unknowns` at most — a row converges in
#: 4-6 (measured: 2,924 of 2,925 poses over 110 % of the strokes within 8; more only near the
#: wrist singularity) — and the step (rad, summed over ψ, σ) below which a row has converged.
INVERSE_STEPS = 10
INVERSE_TOL = 1e-15
#: A step (rad, summed) below this that is no smaller than the step before it is rounding: the
#: row has converged (its Φ rounds to ~1e-15 rad, so a step of :data:`INVERSE_TOL` is not
#: always reached; session 35: 4 of 1,466 poses over 110 % of the strokes were declined
#: by NumPy's or libm's last bits alone, while their steps fell to ~1e-14 and stayed).
INVERSE_STALL = 1e-13
#: |sin Q5| below which a row is declined (the wrist singularity: x' undetermined).
INVERSE_SINGULAR = 1e-3
#: The signs ``s_ψ, s_σ`` of the explicit ψ and σ (module docstring): home's assembly
#: (:data:`pkmkit.machines.tripteor.HOME`; tests check that it is found again).
ASSEMBLY = (-1.0, -1.0)
#: The difference step (rad) of the chord Jacobian.
JACOBIAN_STEP = 1e-7
#: Newton's Jacobian is evaluated again after a step above this (rad); below, chord steps.
JACOBIAN_REFRESH = 1e-6


def constants(params: Mapping[str, Any]) -> np.ndarray:
    """``(25,)`` the constants of :func:`inverse_unknowns` and :func:`direct_unknowns` (and of
    ``chain_one_tripteor.c``): c1, spindle, L, D, the rows of R_m (MPS in R51, 9), p_m (3), b2
    (3), b3 (3), the home assembly's signs s_ψ, s_σ (:data:`ASSEMBLY`) and l; cached by the
    dimensions' values (a one-pose call's start must not rebuild the platform's frames)."""
    return _constants(tuple(float(params[k]) for k in _DIMENSIONS))


_DIMENSIONS = ("c1", "spindle", "L", "D", "l", "d", "h")  # l: the constants' last


@functools.lru_cache(maxsize=16)
def _constants(values: tuple[float, ...]) -> np.ndarray:
    params = dict(zip(_DIMENSIONS, values, strict=True))
    mps = mps_frame(params)
    pts = platform_points(params)
    out = np.empty(25)
    out[:4] = values[:4]
    out[24] = values[4]
    out[4:13] = mps[:3, :3].reshape(-1)
    out[13:16] = mps[:3, 3]
    out[16:19] = pts[1]
    out[19:22] = pts[2]
    out[22:24] = ASSEMBLY
    out.flags.writeable = False
    return out


def platform_points(params: Mapping[str, Any]) -> np.ndarray:
    """B1, B2, B3 ``(3, 3)`` in the frame R51 (origin B1), nominal geometry."""
    big = np.eye(4)
    f52 = invariant_frame((1, 0, 0), (params["d"], 0, -params["l"] / 2), -math.pi / 2)
    f53 = invariant_frame((0, 0, 1), (params["l"], 0, 0))
    b2 = np.linalg.inv(f52)[:3, 3]
    b3 = np.linalg.inv(f53)[:3, 3]
    return np.array([big[:3, 3], b2, b3])


def mps_frame(params: Mapping[str, Any]) -> np.ndarray:
    """T_R51^MPS ``(4, 4)``: the platform frame from the B points (module docstring)."""
    b1, b2, b3 = platform_points(params)
    x = (b3 - b1) / np.linalg.norm(b3 - b1)
    normal = np.cross(b3 - b1, b2 - b1)
    z = normal / np.linalg.norm(normal)
    y = np.cross(z, x)
    out = np.eye(4)
    out[:3, :3] = np.column_stack([x, y, z])
    out[:3, 3] = (b1 + b2 + b3) / 3.0 - params["h"] * z
    return out


def _explicit(k: np.ndarray, px, py, pz, s_psi: float, s_sigma: float):
    """ψ, σ of the platform whose MPS origin is P (module docstring); NaN without assembly."""
    ax2, ay2 = -k[3], -0.5 * k[2]  # A2 = (−D, −L/2, 0)
    r = np.sqrt(px * px + pz * pz)
    psi = np.arctan2(pz, px) + s_psi * np.arccos(k[15] / r)
    cp, sp = np.cos(psi), np.sin(psi)
    # (P − A2)·e1, (P − A2)·e2, e1 = (−sin ψ, 0, cos ψ), e2 = (0, −1, 0)
    ea = -sp * (px - ax2) + cp * pz
    eb = -(py - ay2)
    rho = np.sqrt(ea * ea + eb * eb)
    sigma = np.arctan2(eb, ea) + s_sigma * np.arccos(-(k[16] - k[13]) / rho)
    return psi, sigma


def _head(k: np.ndarray, psi, sigma, ax, ay, az, b):
    """For the platform angles ψ, σ: R51's columns, z_P, the part g of the tool axis normal to
    z_P, |g| and the Q5-axis direction x' = −b g/|g|."""
    cp, sp, cs, ss = np.cos(psi), np.sin(psi), np.cos(sigma), np.sin(sigma)
    x51 = (-sp * cs, -ss, cp * cs)
    y51 = (sp * ss, -cs, -cp * ss)
    z51 = (cp, 0.0 * cp, sp)

    def col(j):  # R51 R_m e_j
        return tuple(x51[i] * k[4 + j] + y51[i] * k[7 + j] + z51[i] * k[10 + j]
                     for i in range(3))

    zp = col(2)
    az_dot = ax * zp[0] + ay * zp[1] + az * zp[2]
    gx, gy, gz = ax - az_dot * zp[0], ay - az_dot * zp[1], az - az_dot * zp[2]
    gn = np.sqrt(gx * gx + gy * gy + gz * gz)
    f = -b / gn
    return (x51, y51, z51), zp, az_dot, gn, (f * gx, f * gy, f * gz)


def _step(k: np.ndarray, psi, sigma, wx, wy, wz, ax, ay, az, b):
    """Φ(ψ, σ): the explicit angles of P = W − c1 x'(ψ, σ)."""
    _, _, _, _, xq = _head(k, psi, sigma, ax, ay, az, b)
    c1 = k[0]
    return _explicit(k, wx - c1 * xq[0], wy - c1 * xq[1], wz - c1 * xq[2], k[22], k[23])


def inverse_unknowns(params: Mapping[str, Any], targets: Any, tool_length: Any,
                     branch: Any) -> np.ndarray:
    """Near-closed-form inverse of the complete machine on one head branch: ``(N, 21)``
    unknowns of the joint-chain inverse model — the platform point B1, R51's rotation vector
    (angle in [0, π], the engine's convention), then every joint variable in the model's order
    (:data:`VARIABLES`) — for ``targets (N, 6)`` (tool point m, unit tool axis a), tool lengths
    ``(N,)`` (m, from the spindle gauge point) and ``branch (N,)`` (+1: Q5 ≥ 0, −1: Q5 ≤ 0).
    NaN rows where it declines (module docstring)."""
    return _inverse(constants(params), targets, tool_length, branch)


def _inverse(k: np.ndarray, targets: Any, tool_length: Any, branch: Any) -> np.ndarray:
    k = tuple(k.tolist())  # Python floats: the same operations, cheaper to index
    x = np.atleast_2d(np.asarray(targets, dtype=float))
    n = x.shape[0]
    tool = np.broadcast_to(np.asarray(tool_length, dtype=float), (n,))
    b = np.broadcast_to(np.asarray(branch, dtype=float), (n,))
    ax, ay, az = x[:, 3], x[:, 4], x[:, 5]
    reach = k[1] + tool
    wx, wy, wz = x[:, 0] - reach * ax, x[:, 1] - reach * ay, x[:, 2] - reach * az
    with np.errstate(invalid="ignore", divide="ignore"):
        psi, sigma = _explicit(k, wx, wy, wz, k[22], k[23])  # c1 = 0
        psi, sigma, done = _newton2(
            lambda p, s: _step(k, p, s, wx, wy, wz, ax, ay, az, b), psi, sigma, INVERSE_STEPS,
            1.0)
        u = np.empty((n, 21))
        gn = _fill(k, psi, sigma, wx, wy, wz, ax, ay, az, b, u)
    bad = ~(done & (gn >= INVERSE_SINGULAR) & np.isfinite(u).all(axis=1))
    u[bad] = np.nan
    return u


def _newton2(equations: Any, z0: np.ndarray, z1: np.ndarray, steps: int, shift: float
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Newton's steps on ``F(z) − shift z = 0`` row by row (``equations(z0, z1)`` gives F's
    two components elementwise; shift 1: :func:`_inverse`'s fixed point of Φ, 0:
    :func:`direct_unknowns`'s leg-2 equations) from ``(z0, z1) (N,)``: the Jacobian by
    differences (:data:`JACOBIAN_STEP`), evaluated again after a step above
    :data:`JACOBIAN_REFRESH` (chord steps below), ``steps`` at most, a row done once its step
    (summed over both) is below :data:`INVERSE_TOL`, or below :data:`INVERSE_STALL` and no
    smaller than the step before (rounding). ``(z0, z1, done (N,))``;
    ``native/chain_one_tripteor.c`` (``newton2``) and the Numba twin
    (:mod:`pkmkit.machines.tripteor_start_kernel`) the same."""
    h = JACOBIAN_STEP
    n = z0.shape[0]
    i00, i01, i10, i11 = (np.zeros(n) for _ in range(4))
    f0, f1 = equations(z0, z1)
    done = np.zeros(n, dtype=bool)
    fresh = np.ones(n, dtype=bool)
    last = np.full(n, np.inf)
    for _ in range(steps):
        r0, r1 = f0 - shift * z0, f1 - shift * z1
        if fresh.any():  # the Jacobian by differences
            a0, a1 = equations(z0 + h, z1)
            c0, c1 = equations(z0, z1 + h)
            j00, j10 = (a0 - f0) / h - shift, (a1 - f1) / h
            j01, j11 = (c0 - f0) / h, (c1 - f1) / h - shift
            det = j00 * j11 - j01 * j10
            i00 = np.where(fresh, j11 / det, i00)
            i01 = np.where(fresh, -j01 / det, i01)
            i10 = np.where(fresh, -j10 / det, i10)
            i11 = np.where(fresh, j00 / det, i11)
        d0, d1 = i00 * r0 + i01 * r1, i10 * r0 + i11 * r1
        live = ~done
        z0 = np.where(live, z0 - d0, z0)
        z1 = np.where(live, z1 - d1, z1)
        step = np.abs(d0) + np.abs(d1)
        done |= (step <= INVERSE_TOL) | ((step <= INVERSE_STALL) & (step >= last))
        last = step
        fresh = ~done & (step > JACOBIAN_REFRESH)
        if done.all():
            break
        f0, f1 = equations(z0, z1)
    return z0, z1, done


def _fill(k, psi, sigma, wx, wy, wz, ax, ay, az, b, u) -> np.ndarray:
    """Every unknown into ``u (N, 21)`` from the platform angles; returns |g| (|sin Q5|)."""
    frame, _, az_dot, gn, xq = _head(k, psi, sigma, ax, ay, az, b)
    x51, y51, z51 = frame
    c1 = k[0]
    pm = tuple(x51[i] * k[13] + y51[i] * k[14] + z51[i] * k[15] for i in range(3))
    b1 = (wx - c1 * xq[0] - pm[0], wy - c1 * xq[1] - pm[1], wz - c1 * xq[2] - pm[2])
    _legs(k, psi, sigma, frame, b1, u)
    # the head: x' = R_P (cos Q4, sin Q4, 0), R_P = R51 R_m
    xp = tuple(x51[i] * k[4] + y51[i] * k[7] + z51[i] * k[10] for i in range(3))
    yp = tuple(x51[i] * k[5] + y51[i] * k[8] + z51[i] * k[11] for i in range(3))
    u[:, 19] = np.arctan2(xq[0] * yp[0] + xq[1] * yp[1] + xq[2] * yp[2],
                          xq[0] * xp[0] + xq[1] * xp[1] + xq[2] * xp[2])
    u[:, 20] = b * np.arctan2(gn, -az_dot)
    return gn


def _legs(k, psi, sigma, frame, b1, u) -> None:
    """The platform (B1, R51's rotation vector) and every joint of the legs into ``u[:, :19]``
    from ψ, σ, R51's columns ``frame`` and the point B1."""
    x51, y51, z51 = frame

    def at(v):  # R51 v
        return tuple(x51[i] * v[0] + y51[i] * v[1] + z51[i] * v[2] for i in range(3))

    b2, b3 = at(k[16:19]), at(k[19:22])
    u[:, 0], u[:, 1], u[:, 2] = b1
    u[:, 3:6] = _rotvec(psi, sigma)
    cp, sp = np.cos(psi), np.sin(psi)
    big, dd = k[2], k[3]
    # legs 1 and 3: B − A = Q (cos θ e1 − sin θ e2) in the plane
    e1b1 = -sp * b1[0] + cp * b1[2]
    theta1 = np.arctan2(-b1[1], e1b1)
    d3 = (b1[0] + b3[0], b1[1] + b3[1] + big, b1[2] + b3[2])
    e1b3 = -sp * d3[0] + cp * d3[2]
    theta3 = np.arctan2(-d3[1], e1b3)
    # leg 2: B2 − A2 = Q2 (sin θ2, −sin ψ2 cos θ2, cos ψ2 cos θ2)
    d2 = (b1[0] + b2[0] + dd, b1[1] + b2[1] + 0.5 * big, b1[2] + b2[2])
    q2 = np.sqrt(d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2])
    psi2 = np.arctan2(-d2[1], d2[2])
    theta2 = np.arctan2(d2[0], np.sqrt(d2[1] * d2[1] + d2[2] * d2[2]))
    c2, s2, ct2, st2 = np.cos(psi2), np.sin(psi2), np.cos(theta2), np.sin(theta2)
    # η2 from M2 e_x = (cos θ2, sin ψ2 sin θ2, −cos ψ2 sin θ2), M2 e_y = (0, cos ψ2, sin ψ2)
    mx = ct2 * x51[0] + s2 * st2 * x51[1] - c2 * st2 * x51[2]
    my = c2 * x51[1] + s2 * x51[2]
    eta2 = np.arctan2(-mx, my)
    phi2 = np.arctan2(d2[0] * z51[0] + d2[1] * z51[1] + d2[2] * z51[2],
                      d2[0] * y51[0] + d2[1] * y51[1] + d2[2] * y51[2])
    half = 0.5 * np.pi
    cols = (psi, theta1, np.hypot(e1b1, b1[1]), sigma - theta1 + half, psi2, theta2, eta2, q2,
            phi2, psi, theta3, np.hypot(e1b3, d3[1]), sigma - theta3 + half)
    for j, v in enumerate(cols):
        u[:, 6 + j] = v


def _rotvec(psi: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """``(N, 3)`` rotation vectors of ``R51 = Rx(90°) Rz(ψ) F Rz(σ)`` through its unit
    quaternion (F: (½, ½, ½, ½)), taken with w ≥ 0 (angle in [0, π], as
    :func:`pkmkit.solve.chains.compose_rotvecs`)."""
    r = np.sqrt(0.5)
    cp, sp = np.cos(0.5 * psi), np.sin(0.5 * psi)
    cs, ss = np.cos(0.5 * sigma), np.sin(0.5 * sigma)
    # (r, r, 0, 0) (cp, 0, 0, sp) = (r cp, r cp, −r sp, r sp)
    a = (r * cp, r * cp, -r * sp, r * sp)
    # times (½, ½, ½, ½)
    b = _qmul(a, (0.5, 0.5, 0.5, 0.5))
    w, qx, qy, qz = _qmul(b, (cs, 0.0 * cs, 0.0 * cs, ss))
    flip = np.where(w < 0, -1.0, 1.0)
    w, qx, qy, qz = w * flip, qx * flip, qy * flip, qz * flip
    norm = np.sqrt(qx * qx + qy * qy + qz * qz)
    scale = 2.0 * np.arctan2(norm, w) / norm
    return np.stack([scale * qx, scale * qy, scale * qz], axis=-1)


def _qmul(p, q):
    """Hamilton product of quaternions ``(w, x, y, z)``."""
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return (pw * qw - px * qx - py * qy - pz * qz, pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx, pw * qz + px * qy - py * qx + pz * qw)


def start_unknowns(params: Mapping[str, Any], targets: Any, tool_length: Any,
                   branch: Any = None) -> np.ndarray:
    """The inverse model's closed-form start (``MachineKind.inverse_start``): the unknowns of
    :func:`inverse_unknowns` on ``branch (N,)`` (±1), or — None — on the branch whose Q4 is
    within a quarter turn of home's (0): the sign of ``−a · x_P`` at the ``c1 = 0`` platform
    (``native/chain_one_tripteor.c`` the same)."""
    k = constants(params)
    x = np.atleast_2d(np.asarray(targets, dtype=float))
    if branch is None:
        n = x.shape[0]
        reach = k[1] + np.broadcast_to(np.asarray(tool_length, dtype=float), (n,))
        rows = [x[:, j] - reach * x[:, 3 + j] for j in range(3)] + [x[:, 3 + j] for j in
                                                                  range(3)]
        branch = _nearest_branch(tuple(k.tolist()), *rows)
    return _inverse(k, x, tool_length, branch)


def _nearest_branch(k: tuple, wx, wy, wz, ax, ay, az):
    """:func:`start_unknowns`'s branch rule (elementwise): +1 where ``−a · x_P ≥ 0`` at the
    platform of ``c1 = 0``, else −1."""
    with np.errstate(invalid="ignore", divide="ignore"):
        psi, sigma = _explicit(k, wx, wy, wz, k[22], k[23])
        cp, sp, cs, ss = np.cos(psi), np.sin(psi), np.cos(sigma), np.sin(sigma)
        x51 = (-sp * cs, -ss, cp * cs)
        y51 = (sp * ss, -cs, -cp * ss)
        z51 = (cp, 0.0 * cp, sp)
        xp = [x51[i] * k[4] + y51[i] * k[7] + z51[i] * k[10] for i in range(3)]
        along = -(ax * xp[0] + ay * xp[1] + az * xp[2])
    return np.where(along >= 0, 1.0, -1.0)


start_unknowns.variables = VARIABLES  # the model's variables it answers for (chain_starts)


def native_constants(params: Mapping[str, Any]) -> np.ndarray:
    """``(26,)`` :func:`start_unknowns`'s constants for ``native/chain_one_tripteor.c``: the
    family's code (2, ``PK_CLOSED_TRIPTEOR``), then :func:`constants`."""
    return np.concatenate([[2.0], constants(params)])


start_unknowns.native = native_constants  # its C twin's constants (chain_one_native)
#: its Numba twin (chain_starts.compiled_start): that module's ``inverse_rows``
start_unknowns.compiled = "pkmkit.machines.tripteor_start_kernel"


#: The direct model (:func:`direct_unknowns`): the four-bar A1B1B3A3's assembly (the side of
#: A3B1 that B3 lies on, home's), the start (θ1, ψ) (home's, rad), Newton's steps at most.
FOUR_BAR = 1.0
DIRECT_START = (math.radians(17.7023), math.radians(0.2813))
DIRECT_STEPS = 12


def _platform_of(k, theta, psi, q1, q3):
    """The platform at θ1 and ψ (:func:`direct_unknowns`): ``(σ, B1, R51's columns)``."""
    big, small = k[2], k[24]
    s1, t1 = q1 * np.cos(theta), q1 * np.sin(theta)  # B1 in the plane (e1, e2)
    ds, dt = s1, t1 - big  # B1 − A3, A3 = (0, L)
    rho = np.sqrt(ds * ds + dt * dt)
    ca = (q3 * q3 + rho * rho - small * small) / (2 * q3 * rho)
    alpha = np.arctan2(dt, ds) + FOUR_BAR * np.arccos(ca)
    s3, t3 = q3 * np.cos(alpha), big + q3 * np.sin(alpha)  # B3
    sigma = np.arctan2(t1 - t3, s1 - s3)  # x51 = (B1 − B3) / l
    cp, sp, cs, ss = np.cos(psi), np.sin(psi), np.cos(sigma), np.sin(sigma)
    frame = ((-sp * cs, -ss, cp * cs), (sp * ss, -cs, -cp * ss), (cp, 0.0 * cp, sp))
    return sigma, (-sp * s1, -t1, cp * s1), frame


def _leg2(k, theta, psi, q1, q2, q3):
    """Leg 2's two equations at θ1, ψ: (B2 − A2)·x51 and |B2 − A2| − Q2."""
    _, b1, (x51, y51, z51) = _platform_of(k, theta, psi, q1, q3)
    d = [b1[i] + x51[i] * k[16] + y51[i] * k[17] + z51[i] * k[18] for i in range(3)]
    d[0] = d[0] + k[3]
    d[1] = d[1] + 0.5 * k[2]
    return (d[0] * x51[0] + d[1] * x51[1] + d[2] * x51[2],
            np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - q2)


def direct_unknowns(params: Mapping[str, Any], q: Any) -> np.ndarray:
    """Near-closed-form direct model of the parallel part as the joint-chain unknowns: ``(N,
    21)`` the platform point B1, R51's rotation vector and every joint variable
    (:data:`VARIABLES`; Q1..Q5 the given ``q (N, 5)``) — the direct model's start
    (``MachineKind.direct_start``). In the legs' plane (basis e1, e2; A1 at 0, A3 at (0, L)),
    θ1 places B1 = Q1 (cos θ1, sin θ1) and the four-bar B3 (on the circle of radius Q3 about
    A3, at l from B1, on :data:`FOUR_BAR`'s side), hence x51 and σ; with the plane's angle ψ,
    leg 2's two equations (normal to x51, length Q2) are left in (θ1, ψ): Newton's steps from
    :data:`DIRECT_START` (the Jacobian by differences, chord steps once a step is below 1e-6).
    NaN rows where it declines (no assembly, not converged). Elementwise;
    ``native/chain_one_tripteor.c`` the same."""
    k = tuple(constants(params).tolist())
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[0]
    q1, q2, q3 = q[:, 0], q[:, 1], q[:, 2]
    theta, psi = np.full(n, DIRECT_START[0]), np.full(n, DIRECT_START[1])
    with np.errstate(invalid="ignore", divide="ignore"):
        theta, psi, done = _newton2(lambda t, p: _leg2(k, t, p, q1, q2, q3), theta, psi,
                                    DIRECT_STEPS, 0.0)
        sigma, b1, frame = _platform_of(k, theta, psi, q1, q3)
        u = np.empty((n, 21))
        _legs(k, psi, sigma, frame, b1, u)
    u[:, 19], u[:, 20] = q[:, 3], q[:, 4]
    u[~(done & np.isfinite(u).all(axis=1))] = np.nan
    return u


direct_unknowns.variables = VARIABLES  # the model's variables it answers for (chain_starts)
direct_unknowns.native = native_constants  # the constants of its C and Numba twins
direct_unknowns.compiled = start_unknowns.compiled  # that module's ``direct_rows``
