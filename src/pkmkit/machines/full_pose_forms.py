"""Closed-form kinematics of full-pose (6-DOF platform) rod machines, rod by rod.

Each rod j joins its base-side joint a_j(q) to the platform joint ``P_j = p + R b_j`` with
``|P_j − a_j(q)| = ℓ_j(q)`` (see :mod:`pkmkit.solve.rod_closure`). Given a full pose (p, R) every
rod's closure has the actuator coordinate of its actuator k in closed form — the same formulas
as the translational machines' legs (:mod:`pkmkit.machines.closed_form`) with b_j turned by R:

- slide: ``w = P_j − a0_j``, ``q = w·u_k + σ sqrt(ℓ_j² − |w|² + (w·u_k)²)``;
- strut: ``q = |P_j − a0_j| − ℓ0_j``;
- crank: ``v = P_j − P_k`` in the arm frame (w_k, e1_j, e2_j), ``q = atan2(v2, v1) +
  σ acos((K − ℓ_j²) / (2 r_j hypot(v1, v2)))``, ``K = (v_w − h_j)² + v1² + v2² + r_j²``.

σ = ±1 is the rod's branch (−sign of ``d·∂a/∂q``). When several rods hang on one actuator (two
per slide on a Verne-type module) they must agree: a pose for which they do not is not one the
machine can reach (it has fewer than six degrees of freedom).

**Velocity model** (twist t = (v, ω) of the platform reference point, linear part first):
differentiating ``|d_j|² = ℓ_j²`` with ``d_j = P_j − a_j`` gives ``A t = B q̇`` with

    A_j = (d_jᵀ, (R b_j × d_j)ᵀ)      (rows, m × 6; units m and m²)
    B_jk = d_j·∂a_j/∂q_k + κt ℓ_j(q)  (m × n_act; only the rod's own actuator column)

and ``J = A⁺B`` (``A⁻¹B`` for six rods) maps actuator rates to the platform twist: rows 0–2 are
linear velocity per unit actuator rate, rows 3–5 angular velocity (rad/s per m/s for linear
actuators, i.e. 1/m). The homogenised Jacobian multiplies the angular rows by a characteristic
length L: ``J_h = diag(1, 1, 1, L, L, L) J``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.model.rods import CRANK, SLIDE, STRUT, RodModel
from pkmkit.numerics import jit
from pkmkit.solve.rod_closure import actuator_rates, rod_base_points
from pkmkit.spatial.rotation import rotvec_to_matrix

#: Relative tolerance (on ℓ²) within which a negative radicand at the workspace boundary is
#: rounding noise and is taken as 0 (as for the translational closed forms).
BOUNDARY_TOL = 1e-12
#: Rows per chunk of the inverse model (keeps the temporaries in cache).
CHUNK = 16384


@dataclass(frozen=True, eq=False)
class FullPoseForms:
    """Precomputed per-rod closed forms of a full-pose :class:`RodModel` (``dims = 6``)."""

    model: RodModel

    def __post_init__(self) -> None:
        m = self.model
        kind = m.rod_kind
        crank = kind == CRANK
        arm = m.rod_base - m.rod_pivot
        along = np.einsum("jd,jd->j", arm, m.rod_axis)
        across = arm - along[:, None] * m.rod_axis
        radius = np.where(crank, np.linalg.norm(across, axis=1), 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e1 = np.where(crank[:, None], across / radius[:, None], 0.0)
        set_ = object.__setattr__
        set_(self, "crank_e1", e1)
        set_(self, "crank_e2", np.cross(m.rod_axis, e1))
        set_(self, "crank_radius", radius)
        set_(self, "crank_offset", np.where(crank, along, 0.0))
        set_(self, "length_sq", m.rod_length**2)
        set_(self, "rod_branch", m.leg_branch[m.rod_leg])
        for value in vars(self).values():  # shared by every copy of a kept machine: read-only
            if isinstance(value, np.ndarray):
                value.flags.writeable = False

    # ------------------------------------------------------------------ geometry
    def platform_points(self, x: np.ndarray) -> np.ndarray:
        """Platform joint centres ``P_j = p + R b_j`` ``(N, m, 3)`` of pose rows ``x (N, 6)``."""
        rot = rotvec_to_matrix(x[:, 3:6])
        return x[:, None, :3] + np.einsum("kab,jb->kja", rot, self.model.rod_platform)

    def rod_vectors(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Rod vectors ``d_j = P_j − a_j(q)`` ``(N, m, 3)``."""
        return self.platform_points(x) - rod_base_points(self.model, q.T).transpose(2, 1, 0)

    def closure_errors(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``(N, m)`` how far each rod misses its length at poses ``x (N, 6)`` with actuator
        coordinates ``q (N, n)``: ``| |P_j − a_j(q)| − ℓ_j(q) |`` (m; NaN rows stay NaN)."""
        from pkmkit.solve.rod_closure import rod_vectors

        rot = rotvec_to_matrix(x[:, 3:6]).transpose(1, 2, 0)
        v = rod_vectors(self.model, x[:, :3].T, q.T, rot)
        return np.abs(v.dist - v.length).T

    # ------------------------------------------------------------------ inverse
    def rod_coordinates(self, x: np.ndarray, branches: np.ndarray | None = None) -> np.ndarray:
        """The actuator coordinate each rod's closure implies ``(N, m)`` (NaN where the rod
        cannot close); ``branches (m,)`` ±1 per rod (default: the working branches).

        Large batches run the compiled kernel :func:`pkmkit.machines.full_pose_kernels.
        rod_coordinates` (the result is then a transposed view of ``(m, N)``); small ones the
        NumPy reference :meth:`rod_coordinates_numpy`, and so do large ones while Numba is not
        imported (``imports=False``: its callers — the position inverse's branch check, one
        pose's inverse — stay within milliseconds on NumPy, and a fresh process does not pay
        Numba's import for them)."""
        sigma = self.rod_branch if branches is None else branches
        if jit.use_compiled(x.shape[0], imports=False):
            from pkmkit.machines import full_pose_kernels

            m = self.model
            out = np.empty((m.n_rods, x.shape[0]))
            full_pose_kernels.rod_coordinates(
                np.ascontiguousarray(x, dtype=float), m.rod_kind.astype(np.int64), m.rod_base,
                m.rod_platform, m.rod_axis, m.rod_pivot, self.crank_e1, self.crank_e2,
                self.length_sq, m.rod_length, self.crank_radius, self.crank_offset,
                np.asarray(sigma, dtype=float), BOUNDARY_TOL, out)
            return out.T
        return self.rod_coordinates_numpy(x, sigma)

    def inverse_compiled(self, x: np.ndarray, sigma: np.ndarray, consistency_tol: float,
                         statuses: bool = True, q: np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray | None]:
        """The inverse model of pose rows ``x (N, 6)`` in one compiled pass
        (:func:`pkmkit.machines.full_pose_kernels.inverse_poses`, or its C twin: see
        :func:`pkmkit.numerics.jit.kernel`): ``q (N, n_act)`` (NaN rows
        where not OK) and ``status (N,)`` — OK, UNREACHABLE (a rod cannot close, or the rods
        of one actuator disagree by more than ``consistency_tol``) or INVALID_INPUT; the same
        as :meth:`rod_coordinates` then :meth:`combine` and the machine's checks. With
        ``statuses=False`` the status is None: each piece's statuses go to a scratch array of
        the piece's size (reused memory, in cache) instead of a fresh ``(N,)`` one whose pages
        a plain ``m.ik(X)`` would fault in and never read (issue 22 §2). ``q``: the caller's
        ``(N, n_act)`` C-contiguous float64 array the kernel writes into (``ik(X, out=Q)``,
        :mod:`pkmkit.machines.out_arrays`), else a new one."""
        inverse_poses = jit.kernel("pkmkit.machines.full_pose_kernels", "inverse_poses")
        m = self.model
        act = m.rod_actuator
        counts = np.bincount(act, minlength=m.n_actuators)
        groups = np.zeros((m.n_actuators, int(counts.max())), dtype=np.int64)
        for k in range(m.n_actuators):
            groups[k, :counts[k]] = np.flatnonzero(act == k)
        angular = np.array([m.rod_kind[groups[k, 0]] == CRANK for k in range(m.n_actuators)])
        q = jit.batch_output(x.shape[0], m.n_actuators) if q is None else q
        status = np.empty(x.shape[0] if statuses else 0, dtype=np.int64)
        x = np.ascontiguousarray(x, dtype=float)
        rods = (m.rod_kind.astype(np.int64), *_plain(m.rod_base, m.rod_platform, m.rod_axis,
                m.rod_pivot, self.crank_e1, self.crank_e2, self.length_sq, m.rod_length,
                self.crank_radius, self.crank_offset, sigma), BOUNDARY_TOL, groups,
                counts.astype(np.int64), angular, float(consistency_tol))

        shared = _shared_inverse(x.shape[0], inverse_poses)
        if shared is not None:  # every thread on one plan: no held piece (jit.run_together)
            kernel, plan = shared
            args = [x, *rods, q, status, plan]

            def run(wait: bool) -> None:
                held = args.copy()  # one step under the GIL: all the arguments or none
                if held:
                    kernel(*held, wait)

            try:
                jit.run_together(run)
            finally:  # a helper not started yet holds no array (a recycled q is freed on time)
                args.clear()
            return q, status if statuses else None

        def work(start: int, stop: int) -> None:
            out = status[start:stop] if statuses else np.empty(stop - start, dtype=np.int64)
            inverse_poses(x[start:stop], *rods, q[start:stop], out)

        jit.run_chunks(work, x.shape[0])
        return q, status if statuses else None

    def rod_coordinates_numpy(self, x: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """The NumPy reference of :meth:`rod_coordinates` (cache-sized chunks)."""
        out = np.empty((x.shape[0], self.model.n_rods))
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            for start in range(0, x.shape[0], CHUNK):
                part = slice(start, start + CHUNK)
                out[part] = self._rod_coordinates_chunk(self.platform_points(x[part]), sigma)
        return out

    def _rod_coordinates_chunk(self, points: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        m = self.model
        out = np.empty(points.shape[:2])
        for j in range(m.n_rods):
            kind = m.rod_kind[j]
            if kind == CRANK:
                v = points[:, j] - m.rod_pivot[j]
                v_w = v @ m.rod_axis[j] - self.crank_offset[j]
                v1, v2 = v @ self.crank_e1[j], v @ self.crank_e2[j]
                perp = np.hypot(v1, v2)
                r = self.crank_radius[j]
                g = v_w * v_w + perp * perp + r * r - self.length_sq[j]
                amplitude = 2.0 * r * perp
                cosine = g / amplitude
                near = np.abs(g) - amplitude <= BOUNDARY_TOL * self.length_sq[j]
                cosine = np.where(near, np.clip(cosine, -1.0, 1.0), cosine)
                angle = np.arctan2(v2, v1) + sigma[j] * np.arccos(cosine)
                out[:, j] = np.remainder(angle + np.pi, 2.0 * np.pi) - np.pi
                continue
            w = points[:, j] - m.rod_base[j]
            if kind == STRUT:
                out[:, j] = np.sqrt(np.einsum("kd,kd->k", w, w)) - m.rod_length[j]
                continue
            s = w @ m.rod_axis[j]
            radicand = self.length_sq[j] - np.einsum("kd,kd->k", w, w) + s * s
            radicand = np.where(radicand > -BOUNDARY_TOL * self.length_sq[j],
                                np.maximum(radicand, 0.0), radicand)
            out[:, j] = s + sigma[j] * np.sqrt(radicand)
        return out

    def combine(self, q_rod: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Actuator coordinates ``(N, n_act)`` from the rods' values ``(N, m)`` and the largest
        disagreement between rods of one actuator ``(N,)`` (0 with one rod per actuator;
        angle differences wrapped to (−π, π])."""
        m = self.model
        n_act = m.n_actuators
        act = m.rod_actuator
        if m.n_rods == n_act and (act == np.arange(n_act)).all():
            return q_rod.copy(), np.zeros(q_rod.shape[0])
        q = np.empty((q_rod.shape[0], n_act))
        spread = np.zeros(q_rod.shape[0])
        for k in range(n_act):
            rods = np.flatnonzero(act == k)
            first = q_rod[:, rods[0]]
            if len(rods) == 1:
                q[:, k] = first
                continue
            angular = m.rod_kind[rods[0]] == CRANK
            diffs = [q_rod[:, j] - first for j in rods[1:]]
            if angular:  # the same angle modulo a turn
                diffs = [np.remainder(d + np.pi, 2.0 * np.pi) - np.pi for d in diffs]
            mean_offset = sum(diffs) / len(rods)
            q[:, k] = first + mean_offset
            for d in [np.zeros_like(first), *diffs]:
                np.maximum(spread, np.abs(d - mean_offset), out=spread)
        return q, spread

    def shortfall(self, x: np.ndarray) -> np.ndarray:
        """``(N, m)``: by how far each rod is out of reach of the pose (≤ 0 when it reaches;
        −inf for struts), m."""
        m = self.model
        points = self.platform_points(x)
        out = np.full(points.shape[:2], -np.inf)
        with np.errstate(invalid="ignore", over="ignore"):
            for j in range(m.n_rods):
                kind = m.rod_kind[j]
                if kind == SLIDE:
                    w = points[:, j] - m.rod_base[j]
                    s = w @ m.rod_axis[j]
                    perp = np.sqrt(np.maximum(np.einsum("kd,kd->k", w, w) - s * s, 0.0))
                    out[:, j] = perp - m.rod_length[j]
                elif kind == CRANK:
                    v = points[:, j] - m.rod_pivot[j]
                    v_w = v @ m.rod_axis[j] - self.crank_offset[j]
                    perp = np.hypot(v @ self.crank_e1[j], v @ self.crank_e2[j])
                    r = self.crank_radius[j]
                    nearest = np.hypot(v_w, perp - r)
                    farthest = np.hypot(v_w, perp + r)
                    out[:, j] = np.maximum(nearest - m.rod_length[j], m.rod_length[j] - farthest)
        return out

    # ------------------------------------------------------------------ velocity
    def jacobians(self, x: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``A (N, m, 6)`` and ``B (N, m, n_act)`` of the velocity model ``A t = B q̇`` (see
        the module docstring) at pose rows ``x (N, 6)`` and actuator coordinates ``q``."""
        m = self.model
        rot = rotvec_to_matrix(x[:, 3:6])
        rb = np.einsum("kab,jb->kja", rot, m.rod_platform)
        d = x[:, None, :3] + rb - rod_base_points(m, q.T).transpose(2, 1, 0)
        a = np.concatenate([d, np.cross(rb, d)], axis=2)
        rates = actuator_rates(m, q.T).transpose(2, 1, 0)  # (N, m, 3)
        diag = np.einsum("kjd,kjd->kj", d, rates)
        strut = m.rod_kind == STRUT
        if strut.any():
            diag[:, strut] = (m.rod_length[strut] + q[:, m.rod_actuator[strut]])
        b = np.zeros((x.shape[0], m.n_rods, m.n_actuators))
        b[:, np.arange(m.n_rods), m.rod_actuator] = diag
        return a, b

    def jacobian_rates(self, x: np.ndarray, q: np.ndarray, twist: np.ndarray,
                       qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Ȧ (N, m, 6), Ḃ (N, m, n_act))`` along a motion with platform twist
        ``twist (N, 6)`` = (v, ω) and actuator rates ``qd (N, n_act)``, at pose rows ``x`` and
        actuator coordinates ``q``.

        With ``r_j = R b_j`` (ṙ = ω × r) and ``ḋ = v + ω × r − ∂a/∂q q̇``:
        ``Ȧ_j = (ḋᵀ, (ṙ × d + r × ḋ)ᵀ)``; ``Ḃ_jk = ḋ·∂a/∂q + d·∂²a/∂q² q̇`` (slide: the second
        term is zero; crank: ``∂²a/∂q² = w × (w × arm)``; strut: ``Ḃ = q̇``)."""
        m = self.model
        rot = rotvec_to_matrix(x[:, 3:6])
        rb = np.einsum("kab,jb->kja", rot, m.rod_platform)
        d = x[:, None, :3] + rb - rod_base_points(m, q.T).transpose(2, 1, 0)
        rates = actuator_rates(m, q.T).transpose(2, 1, 0)  # (N, m, 3)
        v, w = twist[:, None, :3], twist[:, None, 3:]
        qd_rod = qd[:, m.rod_actuator]  # (N, m)
        rb_dot = np.cross(np.broadcast_to(w, rb.shape), rb)
        d_dot = v + rb_dot - rates * qd_rod[:, :, None]
        a_dot = np.concatenate([d_dot, np.cross(rb_dot, d) + np.cross(rb, d_dot)], axis=2)
        diag = np.einsum("kjd,kjd->kj", d_dot, rates)
        crank = m.rod_kind == CRANK
        if crank.any():
            axis = np.broadcast_to(m.rod_axis[None], rates.shape)
            second = np.cross(axis, rates)  # w × (w × arm): rates = w × arm
            diag[:, crank] += (np.einsum("kjd,kjd->kj", d, second) * qd_rod)[:, crank]
        strut = m.rod_kind == STRUT
        if strut.any():
            diag[:, strut] = qd_rod[:, strut]
        b_dot = np.zeros((x.shape[0], m.n_rods, m.n_actuators))
        b_dot[:, np.arange(m.n_rods), m.rod_actuator] = diag
        return a_dot, b_dot


def _shared_inverse(rows: int, inverse_poses: object) -> tuple | None:
    """``(inverse_poses_shared, plan)`` of the C extension for a batch of ``rows`` rows when
    the kernel chosen, ``inverse_poses``, is the C one and runs on several threads
    (:data:`pkmkit.numerics.jit.SHARED_INVERSE`; two blocks and two of
    :func:`~pkmkit.numerics.jit.run_chunks`' pieces or more, as it spreads), else None
    (:func:`pkmkit.numerics.jit.run_chunks`' pieces)."""
    slice_rows, block = jit.SHARED_SLICE_ROWS, jit.SHARED_BLOCK_SLICES
    native = jit.native_kernels()
    if (not jit.SHARED_INVERSE or rows < 2 * max(slice_rows * block, jit.THREAD_ROWS)
            or jit.thread_count() == 1
            or native is None or inverse_poses is not getattr(native, "inverse_poses", None)):
        return None
    kernel = getattr(native, "inverse_poses_shared", None)  # None: an older build
    return None if kernel is None else (kernel, native.inverse_plan(rows, slice_rows, block))


def _plain(*arrays: np.ndarray) -> list[np.ndarray]:
    """C-contiguous float64 copies where needed (what the C kernels take)."""
    return [np.ascontiguousarray(a, dtype=float) for a in arrays]


def default_characteristic_length(model: RodModel) -> float:
    """The characteristic length (m) of a full-pose machine not given one: the mean distance
    of the rods' platform joints from the platform's origin (1 m when that is 0)."""
    radius = float(np.linalg.norm(model.rod_platform, axis=1).mean())
    return radius if radius > 0 else 1.0
