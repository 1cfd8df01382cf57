"""Exact direct kinematics of a rod machine for many (configuration, defect sample) pairs at
once, each pair with its own defected geometry — the kernel of Monte Carlo tolerance analysis.

**Geometry per sample.** :func:`sampled_geometry` applies S defect vectors to the rods of the
defect level (:mod:`pkmkit.model.rod_defects`) exactly as :func:`~pkmkit.model.rod_defects.
apply_rod_defects` does for one: points and lengths add, a direction is tilted and
renormalised through its largest component, an actuator offset moves the carriage along the
(tilted) slide, turns the crank arm or lengthens the strut.

**Closure per pair.** With the actuators at q, the platform of sample s satisfies
``|p + R b_j,s − a_j,s(q)| = ℓ_j,s(q)`` for every rod j. The unknowns are the position p
(translational machines: ``dims`` coordinates) or the pose (p, ω) with ``R = exp(ω) R0``
(full-pose machines), R0 the nominal orientation at that configuration. They are found by a
**chord (simplified Newton) iteration** from the nominal pose: ``u ← u − G r(u)`` with G the
pseudo-inverse of the nominal closure Jacobian of that configuration, shared by all its samples.
The residual r is exact, so the fixed point is the exact solution; for small defects the
iteration contracts by about the relative size of the defects per step (3–5 steps to 1e-13 m).
Pairs whose residual does not fall below ``tol`` within ``max_iter`` steps are flagged and set
to NaN.

Layout: every scalar is an array ``(P_chunk, S)`` (configurations × samples), processed in
chunks of about :data:`CHUNK` pairs so that the ~300 vector operations of a step stay in cache.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.rods import CRANK, SLIDE, STRUT, RodModel

#: Pairs per chunk (cache-sized).
CHUNK = 16384


@dataclass(frozen=True)
class SampledGeometry:
    """Rods of S defected machines (defect level of the model).

    Attributes:
        base: ``(S, m, 3)`` base-side joints at q = 0, after offsets (m).
        platform: ``(S, m, 3)`` platform joints in the platform frame (m).
        length: ``(S, m)`` rod lengths at q = 0 (m).
        axis: ``(S, m, 3)`` actuator direction of each rod (slide direction or crank axis).
        pivot: ``(S, m, 3)`` crank pivots (m).
        kind: ``(m,)`` SLIDE / STRUT / CRANK; actuator: ``(m,)``.
        offset: ``(S, m)`` actuator offset of each rod's actuator (m or rad), crank rods only
            (slide and strut offsets are folded into base and length).
    """

    base: np.ndarray
    platform: np.ndarray
    length: np.ndarray
    axis: np.ndarray
    pivot: np.ndarray
    kind: np.ndarray
    actuator: np.ndarray
    offset: np.ndarray


def _tilt(u: np.ndarray, deltas: np.ndarray, comps: list[int]) -> np.ndarray:
    """Directions ``(S, 3)``: unit u tilted by ``deltas (S, len(comps))`` (renormalised through
    its largest component)."""
    major = int(np.argmax(np.abs(u)))
    out = np.tile(u, (deltas.shape[0], 1))
    for k, c in enumerate(comps):
        out[:, c] += deltas[:, k]
    rest = 1.0 - sum(out[:, c] ** 2 for c in range(3) if c != major)
    with np.errstate(invalid="ignore"):
        out[:, major] = np.copysign(np.sqrt(rest), u[major])
    return out


def sampled_geometry(model: RodModel, index, deltas: np.ndarray) -> SampledGeometry:
    """The rods of ``model`` with each row of ``deltas (S, d)`` applied (module docstring).
    Rows whose tilts exceed 90° get NaN directions."""
    from pkmkit.model.rod_defects import rod_set

    rods = rod_set(model)
    delta = np.atleast_2d(np.asarray(deltas, dtype=float))
    s = delta.shape[0]
    base = np.tile(rods.base, (s, 1, 1)).astype(float)
    platform = np.tile(rods.platform, (s, 1, 1)).astype(float)
    length = np.tile(rods.length, (s, 1)).astype(float)
    axis = np.tile(rods.axis, (s, 1, 1)).astype(float)
    pivot = np.tile(rods.pivot, (s, 1, 1)).astype(float)
    n_act = model.n_actuators
    offsets = np.zeros((s, n_act))
    tilts: dict[int, list[tuple[int, int]]] = {}
    for i, (kind, t, c) in enumerate(zip(index.kind, index.target, index.component,
                                         strict=True)):
        col = delta[:, i]
        if kind == "base":
            base[:, t, c] += col
        elif kind == "platform":
            platform[:, t, c] += col
        elif kind == "length":
            length[:, t] += col
        elif kind == "pivot":
            pivot[:, rods.actuator == t, c] += col[:, None]
        elif kind == "axis":
            tilts.setdefault(int(t), []).append((int(c), i))
        else:
            offsets[:, t] = col
    for k, entries in tilts.items():
        mine = np.flatnonzero(rods.actuator == k)
        u = rods.axis[mine[0]]
        tilted = _tilt(u, delta[:, [i for _, i in entries]], [c for c, _ in entries])
        axis[:, mine] = tilted[:, None, :]
    rod_offset = offsets[:, rods.actuator]  # (S, m)
    slide = rods.kind == SLIDE
    strut = rods.kind == STRUT
    base[:, slide] += rod_offset[:, slide, None] * axis[:, slide]
    length[:, strut] += rod_offset[:, strut]
    crank_offset = np.where((rods.kind == CRANK)[None], rod_offset, 0.0)
    return SampledGeometry(base=base, platform=platform, length=length, axis=axis,
                           pivot=pivot, kind=rods.kind, actuator=rods.actuator,
                           offset=crank_offset)


def _rot_apply(axis: np.ndarray, angle: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rodrigues: v turned by ``angle`` about unit ``axis`` (broadcast, last axis 3)."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    dot = np.sum(axis * v, axis=-1, keepdims=True)
    return v * c + np.cross(axis, v) * s + axis * dot * (1.0 - c)


def carriages(geom: SampledGeometry, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Base-side joints ``(P, S, m, 3)`` and rod lengths ``(P, S, m)`` at actuator coordinates
    ``q (P, n_act)`` for every sample."""
    qr = np.asarray(q, dtype=float)[:, geom.actuator]  # (P, m)
    slide = (geom.kind == SLIDE)[None, None, :, None]
    strut = (geom.kind == STRUT)[None, None, :]
    crank = geom.kind == CRANK
    a = geom.base[None] + np.where(slide, qr[:, None, :, None] * geom.axis[None], 0.0)
    if crank.any():
        angle = qr[:, None, :] + geom.offset[None]  # (P, S, m)
        turned = geom.pivot[None] + _rot_apply(geom.axis[None], angle,
                                               (geom.base - geom.pivot)[None])
        a = np.where(crank[None, None, :, None], turned, a)
    length = geom.length[None] + np.where(strut, qr[:, None, :], 0.0)
    return a, length


@dataclass(frozen=True)
class SampledDirect:
    """Exact platform poses of (configuration, sample) pairs.

    Attributes:
        position: ``(P, S, 3)`` platform positions (m).
        rotation: ``(P, S, 3)`` rotation vectors ω of ``R R0ᵀ`` (rad; zero for translational
            machines): the orientation error relative to the nominal pose.
        converged: ``(P, S)`` bool. iterations: steps used (largest over the chunks).
        residual: ``(P, S)`` largest |closure residual| (m).
    """

    position: np.ndarray
    rotation: np.ndarray
    converged: np.ndarray
    iterations: int
    residual: np.ndarray


def _exp_so3(wx, wy, wz):
    """Entries of exp([ω]×) for component arrays (9 arrays, row major). Below |ω| = 1e-2 the
    series of sin θ/θ and (1 − cos θ)/θ² to θ⁴ are exact to 3e-16 and avoid the (slow)
    trigonometric functions."""
    t2 = wx * wx + wy * wy + wz * wz
    if float(np.nanmax(t2, initial=0.0)) < 1e-4:
        a = 1.0 - t2 * (1.0 / 6.0 - t2 / 120.0)
        b = 0.5 - t2 * (1.0 / 24.0 - t2 / 720.0)
    else:
        small = t2 < 1e-8
        with np.errstate(invalid="ignore", divide="ignore"):
            t = np.sqrt(t2)
            a = np.where(small, 1.0 - t2 / 6.0, np.sin(t) / np.where(small, 1, t))
            b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(t)) / np.where(small, 1, t2))
    bx, by, bz = b * wx, b * wy, b * wz
    ax, ay, az = a * wx, a * wy, a * wz
    bxy, bxz, byz = bx * wy, bx * wz, by * wz
    bxx, byy, bzz = bx * wx, by * wy, bz * wz
    return (1.0 - byy - bzz, bxy - az, bxz + ay,
            bxy + az, 1.0 - bxx - bzz, byz - ax,
            bxz - ay, byz + ax, 1.0 - bxx - byy)


def solve_sampled_direct(geom: SampledGeometry, q: np.ndarray, position0: np.ndarray,
                         rotation0: np.ndarray | None, gain: np.ndarray, *,
                         dims: int, tol: float = 1e-12, max_iter: int = 30,
                         chunk: int = CHUNK) -> SampledDirect:
    """Chord iteration for every (configuration, sample) pair (module docstring).

    Args:
        geom: S sampled geometries.
        q: ``(P, n_act)`` actuator coordinates.
        position0: ``(P, 3)`` nominal platform positions at q; rotation0: ``(P, 3, 3)`` nominal
            rotations (None: a translating platform, unknowns are the first ``dims``
            coordinates of p).
        gain: ``(P, k, m)`` pseudo-inverse of the nominal closure Jacobian (k = dims or 6,
            columns per rod of the residual ``|d| − ℓ``).
        tol: residual tolerance (m). max_iter: largest number of steps.
    """
    p_count, s_count = q.shape[0], geom.base.shape[0]
    m = geom.base.shape[1]
    full = rotation0 is not None
    k = 6 if full else dims
    pos = np.empty((p_count, s_count, 3))
    rot = np.zeros((p_count, s_count, 3))
    ok = np.zeros((p_count, s_count), dtype=bool)
    res_out = np.empty((p_count, s_count))
    step = max(1, chunk // max(s_count, 1))
    iters_used = 0
    one = step == 1 and not (geom.kind == CRANK).any()
    if one:  # per-sample components once; each configuration only scales and shifts them
        plat = [[np.ascontiguousarray(geom.platform[:, j, c]) for c in range(3)]
                for j in range(m)]
        base = [[np.ascontiguousarray(geom.base[:, j, c]) for c in range(3)] for j in range(m)]
        axis = [[np.ascontiguousarray(geom.axis[:, j, c]) for c in range(3)] for j in range(m)]
        length0 = [np.ascontiguousarray(geom.length[:, j]) for j in range(m)]
    for start in range(0, p_count, step):
        sl = slice(start, min(start + step, p_count))
        if one:
            qr = q[start, geom.actuator]
            acomp = [[(base[j][c] + qr[j] * axis[j][c])[None] if geom.kind[j] == SLIDE
                      else base[j][c][None] for j in range(m)] for c in range(3)]
            ell_j = [(length0[j] + qr[j])[None] if geom.kind[j] == STRUT else length0[j][None]
                     for j in range(m)]
            if full:
                r0 = rotation0[start]
                wj = [[(r0[c, 0] * plat[j][0] + r0[c, 1] * plat[j][1]
                        + r0[c, 2] * plat[j][2])[None] for c in range(3)] for j in range(m)]
            else:
                bcomp = [np.stack([plat[j][c] for j in range(m)], axis=-1)[None]
                         for c in range(3)]
        else:
            a, ell = carriages(geom, q[sl])  # (Pc, S, m, 3), (Pc, S, m)
            if full:
                w = np.einsum("pab,smb->psma", rotation0[sl], geom.platform)  # R0 b
                wj = [[np.ascontiguousarray(w[..., j, c]) for c in range(3)] for j in range(m)]
            else:
                bcomp = [geom.platform[None, :, :, c] for c in range(3)]
            acomp = [[np.ascontiguousarray(a[..., j, c]) for j in range(m)] for c in range(3)]
            ell_j = [np.ascontiguousarray(ell[..., j]) for j in range(m)]
        p0 = position0[sl]
        u = [np.broadcast_to(p0[:, None, c], (p0.shape[0], s_count)).copy() for c in range(3)]
        om = [np.zeros((p0.shape[0], s_count)) for _ in range(3)] if full else None
        g = gain[sl]  # (Pc, k, m)
        if not full:  # b − a is constant for a translating platform
            fixed = [[np.ascontiguousarray(bcomp[c][..., j] - acomp[c][j])
                      for j in range(m)] for c in range(3)]
        if g.shape[0] == 1:  # one configuration: Python floats broadcast fastest
            gcol = [[float(g[0, i, j]) for j in range(m)] for i in range(k)]
        else:
            gcol = [[g[:, i, j][:, None] for j in range(m)] for i in range(k)]
        for it in range(1, max_iter + 1):
            h = [[u[c] - acomp[c][j] for j in range(m)] for c in range(3)] if full else fixed
            if full:
                e = _exp_so3(*om)
                r = []
                for j in range(m):
                    w0, w1, w2 = wj[j]
                    dx = e[0] * w0
                    dx += e[1] * w1
                    dx += e[2] * w2
                    dx += h[0][j]
                    dy = e[3] * w0
                    dy += e[4] * w1
                    dy += e[5] * w2
                    dy += h[1][j]
                    dz = e[6] * w0
                    dz += e[7] * w1
                    dz += e[8] * w2
                    dz += h[2][j]
                    dx *= dx
                    dy *= dy
                    dz *= dz
                    dx += dy
                    dx += dz
                    np.sqrt(dx, out=dx)
                    dx -= ell_j[j]
                    r.append(dx)
            else:
                r = []
                for j in range(m):
                    dx = u[0] + h[0][j]
                    dy = u[1] + h[1][j]
                    dz = u[2] + h[2][j]
                    dx *= dx
                    dy *= dy
                    dz *= dz
                    dx += dy
                    dx += dz
                    np.sqrt(dx, out=dx)
                    dx -= ell_j[j]
                    r.append(dx)
            worst = np.abs(r[0])
            for j in range(1, m):
                np.maximum(worst, np.abs(r[j]), out=worst)
            with np.errstate(invalid="ignore"):
                done = not np.any(worst >= tol)  # NaN rows do not keep iterating
            if done or it == max_iter:
                break
            for i in range(k):
                delta = gcol[i][0] * r[0]
                for j in range(1, m):
                    delta += gcol[i][j] * r[j]
                if i < dims or (full and i < 3):
                    u[i] -= delta
                else:
                    om[i - 3] -= delta
        iters_used = max(iters_used, it)
        with np.errstate(invalid="ignore"):
            conv = worst < tol
        for c in range(3):
            pos[sl, :, c] = np.where(conv, u[c], np.nan)
            if full:
                rot[sl, :, c] = np.where(conv, om[c], np.nan)
        ok[sl] = conv
        res_out[sl] = worst
    return SampledDirect(position=pos, rotation=rot, converged=ok, iterations=iters_used,
                         residual=res_out)
