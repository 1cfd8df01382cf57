"""Closed forms of the TriMule 600 (seed 002, Guyon 2021, §3.4, eqs. 3.24–3.36), in the frames of
:mod:`pkmkit.machines.trimule`.

The instrumented leg 4 (ψ1, θ4, L4) fixes the platform, and then everything is explicit:

- :func:`platform_pose` — eq. (3.31): ``P = L4 (−sin θ4, cos θ4 sin ψ1, cos θ4 cos ψ1)`` and the
  platform frame ``R_P = Rx(−ψ1) Rz(π) Ry(θ4)`` (the thesis's Cardan angles x–z–y with
  α_P = −ψ1, β_P = π, γ_P = θ4; the printed α_P = ψ1 contradicts the printed position, see
  docs/seed-errata.md);
- :func:`actuators` — the inverse model of the parallel part: Q1, Q3 from (3.28) squared and
  added ([derived] in the notes, §2.4) and Q2 = |A2B2|;
- :func:`passive_joints` — every passive joint: (3.28) for legs 1 and 3 (η = κ = 0,
  φ1 = θ4 − θ1, φ3 = θ3 − θ4), the direction of leg 2 for ψ2, θ2 and a z–y–x decomposition of
  the leg-2 end rotation for η2, κ2, φ2 (which the thesis left to optimisation);
- :func:`measured_leg` — the direct model of the parallel part: from Q1, Q3 (which do not
  depend on ψ1) ``Q1² − Q3² = 2 L L4 sin θ4`` and ``4(Q1² + Q3²) = 2(L² + l²) + 16 L4²
  − 4 L l cos θ4``, one monotonic equation in θ4 on the working mode |θ4| < θ* (< 90°), then
  ``Q2² = L4² + h² + H² + 2H (L4 cos θ4 sin ψ1 − h cos ψ1)`` for ψ1 on the branch through
  ψ1 = 0 at the symmetric configuration;
- :func:`tool_pose` — eq. (3.36): ``T = P + R_P [(c2 + Lo sin Q5) cos Q4, (c2 + Lo sin Q5) sin
  Q4, c1 + Lo cos Q5]`` and tool axis ``R_P (sin Q5 cos Q4, sin Q5 sin Q4, cos Q5)`` with
  ``Lo = spindle + tool length`` (the thesis's L_outil, measured from the Q5 axis); the printed
  (3.33)/(3.36) is this with c1, c2, L_outil of opposite signs (its head points along −z_P).

Every function is batched (leading axis N), SI units (m, rad); ``params`` is the machine's
parameter mapping (``L, H, l, h, c1, c2, spindle``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

#: Names of the passive joints :func:`passive_joints` returns, in the machine's order.
PASSIVE = ("psi1", "theta1", "eta1", "kappa1", "phi1", "psi2", "theta2", "eta2", "kappa2",
           "phi2", "theta3", "eta3", "kappa3", "phi3", "theta4", "L4")


def _rows(*values: Any) -> list[np.ndarray]:
    arrays = np.broadcast_arrays(*[np.atleast_1d(np.asarray(v, dtype=float)) for v in values])
    return [a.reshape(-1) for a in arrays]


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((a.size, 3, 3))
    out[:, 0, 0] = 1.0
    out[:, 1, 1], out[:, 1, 2], out[:, 2, 1], out[:, 2, 2] = c, -s, s, c
    return out


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((a.size, 3, 3))
    out[:, 1, 1] = 1.0
    out[:, 0, 0], out[:, 0, 2], out[:, 2, 0], out[:, 2, 2] = c, s, -s, c
    return out


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros((a.size, 3, 3))
    out[:, 2, 2] = 1.0
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1] = c, -s, s, c
    return out


def platform_pose(L4: Any, psi1: Any, theta4: Any) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (3.31): the platform frame from the measured leg.

    Args:
        L4: ``(N,)`` length of the measured leg (m); psi1, theta4: ``(N,)`` its angles (rad).

    Returns:
        ``R (N, 3, 3)`` and ``p (N, 3)``: the platform frame MPS (origin P, the end of leg 4;
        z along leg 4 away from the base; x from B1 to B3; y towards B2) in the base frame.
    """
    length, psi, theta = _rows(L4, psi1, theta4)
    p = np.stack([-length * np.sin(theta), length * np.cos(theta) * np.sin(psi),
                  length * np.cos(theta) * np.cos(psi)], axis=1)
    rot = _rx(-psi) @ _rz(np.full_like(psi, np.pi)) @ _ry(theta)
    return rot, p


def platform_points(params: Mapping[str, Any], L4: Any, psi1: Any, theta4: Any
                    ) -> dict[str, np.ndarray]:
    """The joint centres ``(N, 3)`` of the parallel part: base points A1–A4 and platform points
    B1, B2, B3, P (m, base frame)."""
    rot, p = platform_pose(L4, psi1, theta4)
    n = p.shape[0]
    half_l, half_big = params["l"] / 2, params["L"] / 2
    return {
        "A1": np.tile([half_big, 0.0, 0.0], (n, 1)), "A2": np.tile([0.0, -params["H"], 0.0],
                                                                   (n, 1)),
        "A3": np.tile([-half_big, 0.0, 0.0], (n, 1)), "A4": np.zeros((n, 3)),
        "B1": p - half_l * rot[:, :, 0], "B2": p + params["h"] * rot[:, :, 1],
        "B3": p + half_l * rot[:, :, 0], "P": p,
    }


def actuators(params: Mapping[str, Any], L4: Any, psi1: Any, theta4: Any) -> np.ndarray:
    """Inverse model of the parallel part: ``(N, 3)`` Q1, Q2, Q3 (m) from the measured leg.

    Q1 and Q3 are (3.28) squared and added (notes §2.4 [derived]):
    ``Q1 = ½ sqrt((L − l cos θ4 + 2 L4 sin θ4)² + (l sin θ4 + 2 L4 cos θ4)²)`` and the same with
    ``L → −L, l → −l`` for Q3; Q2 is the distance A2B2.
    """
    length, psi, theta = _rows(L4, psi1, theta4)
    big, small = params["L"], params["l"]
    c, s = np.cos(theta), np.sin(theta)
    q1 = 0.5 * np.hypot(big - small * c + 2 * length * s, small * s + 2 * length * c)
    q3 = 0.5 * np.hypot(-big + small * c + 2 * length * s, -small * s + 2 * length * c)
    pts = platform_points(params, length, psi, theta)
    q2 = np.linalg.norm(pts["B2"] - pts["A2"], axis=1)
    return np.stack([q1, q2, q3], axis=1)


def passive_joints(params: Mapping[str, Any], L4: Any, psi1: Any, theta4: Any
                   ) -> dict[str, np.ndarray]:
    """Every passive joint ``(N,)`` (rad; ``L4`` in m) from the measured leg (module docstring).
    """
    length, psi, theta = _rows(L4, psi1, theta4)
    big, small = params["L"], params["l"]
    c, s = np.cos(theta), np.sin(theta)
    theta1 = np.arctan2(big - small * c + 2 * length * s, small * s + 2 * length * c)
    theta3 = np.arctan2(-big + small * c + 2 * length * s, -small * s + 2 * length * c)
    pts = platform_points(params, length, psi, theta)
    leg2 = pts["B2"] - pts["A2"]
    leg2 /= np.linalg.norm(leg2, axis=1)[:, None]
    # leg direction (−sin θ2, cos θ2 sin ψ2, cos θ2 cos ψ2)
    theta2 = np.arcsin(np.clip(-leg2[:, 0], -1.0, 1.0))
    psi2 = np.arctan2(leg2[:, 1], leg2[:, 2])
    # leg-2 end rotation Rx(−ψ2) Ry(−θ2) Rz(η2) Ry(−κ2) Rx(φ2) = Rx(−ψ1) Ry(−θ4)
    g = _ry(theta2) @ _rx(psi2 - psi) @ _ry(-theta)
    kappa2 = np.arcsin(np.clip(g[:, 2, 0], -1.0, 1.0))
    eta2 = np.arctan2(g[:, 1, 0], g[:, 0, 0])
    phi2 = np.arctan2(g[:, 2, 1], g[:, 2, 2])
    zero = np.zeros_like(psi)
    return {"psi1": psi, "theta1": theta1, "eta1": zero, "kappa1": zero.copy(),
            "phi1": theta - theta1, "psi2": psi2, "theta2": theta2, "eta2": eta2,
            "kappa2": kappa2, "phi2": phi2, "theta3": theta3, "eta3": zero.copy(),
            "kappa3": zero.copy(), "phi3": theta3 - theta, "theta4": theta, "L4": length}


def _working_limit(a: np.ndarray, b: float) -> np.ndarray:
    """θ* (rad): ``sqrt(A + B cos θ) sin θ`` increases strictly on (−θ*, θ*)."""
    c_star = (-a + np.sqrt(a * a + 3 * b * b)) / (3 * b)
    return np.arccos(np.clip(c_star, -1.0, 1.0))


def measured_leg(params: Mapping[str, Any], q: Any, *, iterations: int = 60
                 ) -> np.ndarray:
    """Direct model of the parallel part: ``(N, 3)`` L4 (m), ψ1, θ4 (rad) from ``q (N, 3)`` =
    Q1, Q2, Q3 (m), on the working mode of :mod:`pkmkit.machines.trimule` (|θ4| < θ*, the
    branch of ψ1 through the symmetric configuration); NaN rows where the actuator lengths
    admit no assembly in that mode.

    θ4 solves ``sqrt(A + B cos θ) sin θ = k`` (``u = 2 L4``, ``u sin θ4 = k = (Q1² − Q3²)/L``,
    ``u² = A + B cos θ4``, ``A = 2(Q1² + Q3²) − L² − l²``, ``B = 2 L l``), strictly increasing
    on the working mode: bisection, then Newton steps to full precision.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    q1, q2, q3 = q[:, 0], q[:, 1], q[:, 2]
    big, small, hb, hs = params["L"], params["l"], params["H"], params["h"]
    k = (q1 * q1 - q3 * q3) / big
    a = 2 * (q1 * q1 + q3 * q3) - big * big - small * small
    b = 2 * big * small
    with np.errstate(invalid="ignore", divide="ignore"):
        limit = _working_limit(a, b)
        lo, hi = -limit, limit.copy()

        def h(t):
            return np.sqrt(np.maximum(a + b * np.cos(t), 0.0)) * np.sin(t) - k

        feasible = (a - b > 0) & (h(lo) <= 0) & (h(hi) >= 0)
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            up = h(mid) > 0
            hi = np.where(up, mid, hi)
            lo = np.where(up, lo, mid)
        theta = 0.5 * (lo + hi)
        for _ in range(2):  # Newton polish: h' = (3B c² + 2A c − B) / (2u)
            u = np.sqrt(a + b * np.cos(theta))
            c = np.cos(theta)
            theta = theta - h(theta) * 2 * u / (3 * b * c * c + 2 * a * c - b)
        length = 0.5 * np.sqrt(a + b * np.cos(theta))
        ca = 2 * hb * length * np.cos(theta)
        cb = -2 * hb * hs
        d = q2 * q2 - length * length - hs * hs - hb * hb
        radius = np.hypot(ca, cb)
        reach = np.abs(d) <= radius
        psi = np.arctan2(ca, cb) - np.arccos(np.clip(d / radius, -1.0, 1.0))
        psi = (psi + np.pi) % (2 * np.pi) - np.pi
    ok = feasible & reach & np.isfinite(q).all(axis=1) & (q > 0).all(axis=1)
    out = np.stack([length, psi, theta], axis=1)
    out[~ok] = np.nan
    return out


def tool_pose(params: Mapping[str, Any], rot: np.ndarray, p: np.ndarray, q4: Any, q5: Any,
              tool_length: Any) -> np.ndarray:
    """Eq. (3.36) in the machine's frames: ``(N, 6)`` tool point (m) and unit tool axis.

    Args:
        rot, p: platform frames ``(N, 3, 3)``, ``(N, 3)`` (:func:`platform_pose`).
        q4, q5: ``(N,)`` head angles (rad); tool_length: ``(N,)`` or scalar (m), from the
            spindle gauge point (the thesis's L_outil is ``spindle + tool_length``).
    """
    q4, q5, tool = _rows(q4, q5, tool_length)
    reach = params["spindle"] + tool
    radial = params["c2"] + reach * np.sin(q5)
    local_point = np.stack([radial * np.cos(q4), radial * np.sin(q4),
                            params["c1"] + reach * np.cos(q5)], axis=1)
    local_axis = np.stack([np.sin(q5) * np.cos(q4), np.sin(q5) * np.sin(q4), np.cos(q5)], axis=1)
    point = p + np.einsum("nij,nj->ni", rot, local_point)
    axis = np.einsum("nij,nj->ni", rot, local_axis)
    return np.concatenate([point, axis], axis=1)


def direct(params: Mapping[str, Any], q: Any, tool_length: Any) -> np.ndarray:
    """Closed-form direct model of the complete machine: ``(N, 6)`` tool point and axis from
    ``q (N, 5)`` = Q1, Q2, Q3 (m), Q4, Q5 (rad); NaN rows without assembly."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    leg = measured_leg(params, q[:, :3])
    rot, p = platform_pose(leg[:, 0], leg[:, 1], leg[:, 2])
    return tool_pose(params, rot, p, q[:, 3], q[:, 4], tool_length)


#: The joint-chain model's variables in its order (:func:`inverse_unknowns`'s columns 6:).
VARIABLES = ("psi1", "theta1", "Q1", "eta1", "kappa1", "phi1", "psi2", "theta2", "Q2", "eta2",
             "kappa2", "phi2", "theta3", "Q3", "eta3", "kappa3", "phi3", "theta4", "L4", "Q4",
             "Q5")
#: Fixed-point sweeps of :func:`inverse_unknowns` at most, and the change of the Q5-axis
#: foot (m) below which a row has converged.
INVERSE_SWEEPS = 40
INVERSE_TOL = 1e-15
#: |sin Q5| below which :func:`inverse_unknowns` declines a row (the wrist singularity: the
#: eccentricity's direction g/|g| undetermined). Each sweep contracts by about
#: c2 / (|W| |sin Q5|): on the TriMule 600 the sweeps stop converging within ~2° of it (2.7 %
#: of poses with the actuators uniform over 5-95 % of their strokes), which the convergence
#: test declines; a converged row is exact whatever |sin Q5|.
INVERSE_SINGULAR = 1e-3


def inverse_unknowns(params: Mapping[str, Any], targets: Any, tool_length: Any,
                     branch: Any) -> np.ndarray:
    """Closed-form inverse of the complete machine on one head branch: ``(N, 27)`` unknowns of
    the joint-chain inverse model — platform point P, the platform's rotation vector (angle in
    [0, π], the engine's convention), then every joint variable in the model's order
    (ψ1, θ1, Q1, η1, κ1, φ1, ψ2, θ2, Q2, η2, κ2, φ2, θ3, Q3, η3, κ3, φ3, θ4, L4, Q4, Q5) — for
    ``targets (N, 6)`` (tool point m, unit tool axis a), tool lengths ``(N,)`` (m, from the
    spindle gauge point) and ``branch (N,)`` (+1: Q5 ≥ 0, −1: Q5 ≤ 0; the head's two
    branches ``(Q4, Q5)`` and ``(Q4 ± π, −Q5)``). NaN rows where it declines: within
    :data:`INVERSE_SINGULAR` of the wrist singularity, not converged, no assembly.

    From :func:`tool_pose`: the foot of the Q5 axis ``W = T − (spindle + ℓ) a`` is
    ``(L4 + c1) d + c2 R_P (cos Q4, sin Q4, 0)`` with ``d = R_P e_z`` the direction of leg 4,
    and ``R_P (cos Q4, sin Q4, 0) = ± g / |g|``, ``g = a − (a·d) d`` (the tool axis's part
    normal to leg 4: ``|g| = |sin Q5|``). So ``d`` is the fixed point of ``v = W − c2 b g/|g|``,
    ``d = v/|v|`` (b the branch; a contraction by about c2 / (|W| |sin Q5|)), then
    ``L4 = |v| − c1``, ``θ4 = asin(−d_x)``, ``ψ1 = atan2(d_y, d_z)``, ``Q5 = b atan2(|g|, a·d)``,
    ``Q4 = atan2(b a·y_P, b a·x_P)``, and the parallel part's joints as
    :func:`passive_joints` and :func:`actuators` (written out term by term here). Every
    operation is elementwise: a row's bits do not depend on the rows beside it (issue 22 §6),
    and ``native/chain_one_trimule.c`` computes the same, statement for statement.
    """
    x = np.atleast_2d(np.asarray(targets, dtype=float))
    n = x.shape[0]
    tool = np.broadcast_to(np.asarray(tool_length, dtype=float), (n,))
    b = np.broadcast_to(np.asarray(branch, dtype=float), (n,))
    c1, c2 = float(params["c1"]), float(params["c2"])
    ax, ay, az = x[:, 3], x[:, 4], x[:, 5]
    reach = float(params["spindle"]) + tool
    wx, wy, wz = x[:, 0] - reach * ax, x[:, 1] - reach * ay, x[:, 2] - reach * az
    vx, vy, vz = wx.copy(), wy.copy(), wz.copy()
    done = np.zeros(n, dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        for _ in range(INVERSE_SWEEPS):
            r = np.sqrt(vx * vx + vy * vy + vz * vz)
            dx, dy, dz = vx / r, vy / r, vz / r
            ad = ax * dx + ay * dy + az * dz
            gx, gy, gz = ax - ad * dx, ay - ad * dy, az - ad * dz
            k = c2 * b / np.sqrt(gx * gx + gy * gy + gz * gz)
            nx, ny, nz = wx - k * gx, wy - k * gy, wz - k * gz
            change = np.abs(nx - vx) + np.abs(ny - vy) + np.abs(nz - vz)
            live = ~done
            vx[live], vy[live], vz[live] = nx[live], ny[live], nz[live]
            done |= change <= INVERSE_TOL
            if done.all():
                break
        r = np.sqrt(vx * vx + vy * vy + vz * vz)
        dx, dy, dz = vx / r, vy / r, vz / r
        ad = ax * dx + ay * dy + az * dz
        gx, gy, gz = ax - ad * dx, ay - ad * dy, az - ad * dz
        gn = np.sqrt(gx * gx + gy * gy + gz * gz)
        length = r - c1
        theta = np.arcsin(-dx)
        psi = np.arctan2(dy, dz)
        ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(psi), np.sin(psi)
        q5 = b * np.arctan2(gn, ad)
        # x_P = (−cos θ4, −sin θ4 sin ψ1, −sin θ4 cos ψ1), y_P = (0, −cos ψ1, sin ψ1)
        q4 = np.arctan2(b * (-cp * ay + sp * az), b * (-ct * ax - st * sp * ay - st * cp * az))
        u = np.empty((n, 27))
        u[:, 0], u[:, 1], u[:, 2] = length * dx, length * dy, length * dz
        u[:, 3:6] = _platform_rotvec(psi, theta)
        u[:, 6:] = _parallel_joints(params, length, psi, theta, ct, st, cp, sp).T
        u[:, 25], u[:, 26] = q4, q5
    bad = ~(done & (gn >= INVERSE_SINGULAR) & np.isfinite(u).all(axis=1))
    u[bad] = np.nan
    return u


def _platform_rotvec(psi: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``(N, 3)`` rotation vectors of ``R_P = Rx(−ψ1) Ry(−θ4) Rz(π)`` (= eq. 3.31's
    ``Rx(−ψ1) Rz(π) Ry(θ4)``) through its unit quaternion, taken with w ≥ 0 (angle in [0, π],
    as :func:`pkmkit.solve.chains.compose_rotvecs`)."""
    ch, sh = np.cos(-0.5 * psi), np.sin(-0.5 * psi)
    ct, st = np.cos(-0.5 * theta), np.sin(-0.5 * theta)
    # (ch, sh, 0, 0) (ct, 0, st, 0) (0, 0, 0, 1)
    w, qx, qy, qz = -sh * st, ch * st, -sh * ct, ch * ct
    flip = np.where(w < 0, -1.0, 1.0)
    w, qx, qy, qz = w * flip, qx * flip, qy * flip, qz * flip
    norm = np.sqrt(qx * qx + qy * qy + qz * qz)
    scale = 2.0 * np.arctan2(norm, w) / norm
    return np.stack([scale * qx, scale * qy, scale * qz], axis=1)


def _parallel_joints(params: Mapping[str, Any], length: np.ndarray, psi: np.ndarray,
                     theta: np.ndarray, ct: np.ndarray, st: np.ndarray, cp: np.ndarray,
                     sp: np.ndarray) -> np.ndarray:
    """``(21, N)`` every joint variable in the model's order (Q4, Q5 left 0) from the measured
    leg: :func:`passive_joints` and :func:`actuators` elementwise."""
    big, small, hb, hs = (float(params[k]) for k in ("L", "l", "H", "h"))
    e1x, e1y = big - small * ct + 2 * length * st, small * st + 2 * length * ct
    e3x, e3y = -big + small * ct + 2 * length * st, -small * st + 2 * length * ct
    # B2 − A2 = P + h y_P − (0, −H, 0)
    lx = -length * st
    ly = length * ct * sp - hs * cp + hb
    lz = length * ct * cp + hs * sp
    q2 = np.sqrt(lx * lx + ly * ly + lz * lz)
    theta2 = np.arcsin(-lx / q2)
    psi2 = np.arctan2(ly, lz)
    # g = Ry(θ2) Rx(ψ2 − ψ1) Ry(−θ4): its entries 00, 10, 20, 21, 22
    ca, sa = np.cos(theta2), np.sin(theta2)
    cb, sb = np.cos(psi2 - psi), np.sin(psi2 - psi)
    cc, sc = ct, -st
    g00 = ca * cc - sa * cb * sc
    g10 = sb * sc
    g20 = -sa * cc - ca * cb * sc
    g21 = ca * sb
    g22 = -sa * sc + ca * cb * cc
    theta1, theta3 = np.arctan2(e1x, e1y), np.arctan2(e3x, e3y)
    zero = np.zeros_like(psi)
    return np.stack([psi, theta1, 0.5 * np.hypot(e1x, e1y), zero, zero, theta - theta1,
                     psi2, theta2, q2, np.arctan2(g10, g00), np.arcsin(np.clip(g20, -1.0, 1.0)),
                     np.arctan2(g21, g22), theta3, 0.5 * np.hypot(e3x, e3y), zero, zero,
                     theta3 - theta, theta, length, zero, zero])


def start_unknowns(params: Mapping[str, Any], targets: Any, tool_length: Any,
                   branch: Any = None) -> np.ndarray:
    """The inverse model's closed-form start (``MachineKind.inverse_start``): the unknowns of
    :func:`inverse_unknowns` on ``branch (N,)`` (±1), or — None — on the branch whose Q4 is
    within a quarter turn of home's (0): the sign of ``a · x_P`` with leg 4 along ``W`` (the
    eccentricity left out; ``native/chain_one_trimule.c`` the same)."""
    x = np.atleast_2d(np.asarray(targets, dtype=float))
    if branch is None:
        tool = np.broadcast_to(np.asarray(tool_length, dtype=float), (x.shape[0],))
        reach = float(params["spindle"]) + tool
        ax, ay, az = x[:, 3], x[:, 4], x[:, 5]
        wx, wy, wz = x[:, 0] - reach * ax, x[:, 1] - reach * ay, x[:, 2] - reach * az
        with np.errstate(invalid="ignore", divide="ignore"):
            r = np.sqrt(wx * wx + wy * wy + wz * wz)
            dx, dy, dz = wx / r, wy / r, wz / r
            ct = np.sqrt(dy * dy + dz * dz)
            # a · x_P, x_P = (−cos θ4, −sin θ4 sin ψ1, −sin θ4 cos ψ1), sin θ4 = −d_x
            along = -ct * ax + dx * (dy * ay + dz * az) / ct
        branch = np.where(along >= 0, 1.0, -1.0)
    return inverse_unknowns(params, x, tool_length, branch)


start_unknowns.variables = VARIABLES  # the model's variables it answers for (chain_starts)


def native_constants(params: Mapping[str, Any]) -> np.ndarray:
    """``(8,)`` :func:`start_unknowns`'s constants for ``native/chain_one.c``: the family's
    code (1, ``PK_CLOSED_TRIMULE``), then ``c1, c2, spindle, L, l, H, h``."""
    return np.array([1.0] + [float(params[k]) for k in ("c1", "c2", "spindle", "L", "l", "H",
                                                        "h")])


start_unknowns.native = native_constants  # its C twin's constants (chain_one_native)
#: its Numba twin (chain_starts.compiled_start): that module's ``inverse_rows``
start_unknowns.compiled = "pkmkit.machines.trimule_start_kernel"


#: Bisection steps of :func:`direct_unknowns` before its two Newton steps (the bracket
#: (−θ*, θ*) narrowed to ~2e-9 rad; Newton's two quadratic steps then reach rounding).
DIRECT_BISECTIONS = 30


def direct_unknowns(params: Mapping[str, Any], q: Any) -> np.ndarray:
    """Closed-form direct model of the parallel part as the joint-chain unknowns: ``(N, 27)``
    platform point P, rotation vector (angle in [0, π]) and every joint variable in the
    model's order (:data:`VARIABLES`; Q1..Q5 the given ``q (N, 5)``) — the direct model's
    start (``MachineKind.direct_start``, :func:`pkmkit.machines.chain_starts.default_start`).
    The measured leg from :func:`measured_leg` (:data:`DIRECT_BISECTIONS` bisections), the
    platform from :func:`platform_pose`, the passive joints as :func:`passive_joints`. NaN rows
    where it declines (no assembly in the working mode). Elementwise: a row's bits its own;
    ``native/chain_one_trimule.c`` computes the same, statement for statement."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[0]
    leg = measured_leg(params, q[:, :3], iterations=DIRECT_BISECTIONS)
    length, psi, theta = leg[:, 0], leg[:, 1], leg[:, 2]
    u = np.empty((n, 27))
    with np.errstate(invalid="ignore", divide="ignore"):
        ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(psi), np.sin(psi)
        u[:, 0], u[:, 1], u[:, 2] = -length * st, length * ct * sp, length * ct * cp
        u[:, 3:6] = _platform_rotvec(psi, theta)
        u[:, 6:] = _parallel_joints(params, length, psi, theta, ct, st, cp, sp).T
    u[:, 25], u[:, 26] = q[:, 3], q[:, 4]
    u[~np.isfinite(u).all(axis=1)] = np.nan
    return u


direct_unknowns.variables = VARIABLES  # the model's variables it answers for (chain_starts)
direct_unknowns.native = native_constants  # the constants of its C and Numba twins
direct_unknowns.compiled = start_unknowns.compiled  # that module's ``direct_rows``
