"""Closed-form kinematics of translational rod-leg machines (one equivalent rod per actuator).

Every machine of this family — Orthoglide, linear Delta, five-bar with prismatic actuators, and
user machines of the same structure — shares these models; the machine modules only build the
geometry. Notation for leg i (actuator i), platform position p (``dims`` coordinates):

- rod centre on the carriage side ``c_i(q) = a0_i − b_i + κs q_i u_i`` (κs = 1 for a slide),
  rod length ``ρ_i(q) = ℓ_i + κt q_i`` (κt = 1 for a strut); closure ``|p − c_i| = ρ_i``;
- for a **crank** (rotary actuator, axis w_i through P_i) the arm tip turns on a circle:
  ``a_i(q) = P_i + h_i w_i + r_i (cos q e1_i + sin q e2_i)`` with ``e1_i`` the arm direction at
  q = 0 (across the axis), ``e2_i = w_i × e1_i``, ``r_i`` the arm length and ``h_i`` the arm-tip
  offset along the axis; ``c_i(q) = a_i(q) − b_i``, ``ρ_i = ℓ_i``.

**Inverse model.** With ``w = p − (a0_i − b_i)`` split along the slide (``s = w·u_i``) and across
it (``w⊥``): ``q_i = s + σ_i sqrt(ℓ_i² − |w⊥|²)`` for a slide (σ_i = ±1, the working branch),
``q_i = |w| − ℓ_i`` for a strut. The pose is out of reach of leg i when ``|w⊥| > ℓ_i``.
For a crank, with ``v = p + b_i − P_i`` written ``(v_w, v_1, v_2)`` in ``(w, e1, e2)``:
``|d|² = K − 2 r (v_1 cos q + v_2 sin q)``, ``K = (v_w − h)² + v_1² + v_2² + r²``, so
``q = φ0 + σ acos((K − ℓ²) / (2 r ρ⊥))`` with ``φ0 = atan2(v_2, v_1)``, ``ρ⊥ = hypot(v_1, v_2)``;
out of reach when ``|K − ℓ²| > 2 r ρ⊥``. In every kind the branch is ``σ = −sign(d·∂a/∂q)``
(``d = p − c_i``): the sign of the serial Jacobian entry picks the root.

**Direct model.** The intersection of ``dims`` spheres (circles in the plane) centred at c_i
with radii ρ_i: subtracting the first equation from the others gives linear equations whose
solution is the point p0 of the centres' plane; the two assembly modes are
``p = p0 ± t n`` with n normal to that plane. ``det A`` (A rows ``p − c_i``) equals
``± t |n|²``, so the two roots are exactly the two signs of det A: the assembly mode *is* the
sign of det A, and the parallel singularity det A = 0 is where they merge (t = 0).

**Velocity model.** Differentiating the closure: ``A ṗ = B q̇`` with A rows ``(p − c_i)ᵀ``
(parallel Jacobian) and ``B = diag((p − c_i)·∂c_i/∂q_i + κt ρ_i)`` (serial Jacobian), as in seeds
000 (J_x, J_q), 001 (eq. 2, J⁻¹ = B⁻¹A) and 004 (A, B); ``∂c_i/∂q_i`` is ``u_i`` for a slide,
``w_i × (a_i − P_i)`` for a crank, 0 for a strut. ``J = A⁻¹B`` maps actuator rates to platform
velocity. Its time derivative: ``J̇ = A⁻¹(Ḃ − ȦJ)`` with Ȧ rows ``(ṗ − q̇_i ∂c_i/∂q_i)ᵀ`` and
``Ḃ = diag(ḋ_i·∂c_i/∂q_i + d_i·∂²c_i/∂q_i² q̇_i + κt q̇_i)`` (``∂²c/∂q² = −r (cos q e1 + sin q e2)``
for a crank, 0 otherwise).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from math import acos, atan2, pi, sqrt
from typing import Any

import numpy as np

from pkmkit.model.rods import CRANK, SLIDE, STRUT, RodModel
from pkmkit.numerics import jit

#: The module of the compiled kernels of :meth:`RodClosedForm._inverse_pass` (and, through
#: :func:`pkmkit.numerics.jit.kernel`, of their C twins).
_KERNELS = "pkmkit.machines.kernels"

#: Relative tolerance (on ℓ²) within which a negative inverse-model radicand is rounding noise at
#: the workspace boundary (leg perpendicular to its slide) and is taken as 0.
BOUNDARY_TOL = 1e-12
#: Largest closure residual (relative to 1 + the size of the configuration) of a direct-model
#: solution; beyond it the row is flagged as (nearly) degenerate rather than returned.
RESIDUAL_TOL = 1e-9
#: Rows whose sphere-centre Gram determinant is below this fraction of size^(2(dims−1)) (size²:
#: the first rod's length² plus the squared centre offsets) get their direct-model solutions
#: checked leg by leg; elsewhere the closed form is well conditioned.
SUSPECT_GRAM = 1e-4
#: A single pose with a coordinate beyond this (m) goes through the batch path, which refuses it.
MAX_ABS = 1e9
_TWO_PI = 2.0 * math.pi
#: Rows per chunk in the inverse model: keeps temporaries in cache (~2× faster than one pass).
CHUNK = 32768


def _orthonormal_basis(u: np.ndarray, dims: int) -> np.ndarray:
    """Rows ``(dims, dims)``: u then unit vectors orthogonal to it (any u for struts)."""
    if not u.any():
        return np.eye(dims)
    if dims == 2:
        return np.array([u, [-u[1], u[0]]])
    # complete u to an orthonormal basis with a QR factorisation
    q, _ = np.linalg.qr(np.column_stack([u, np.eye(3)]))
    basis = q[:, :3].T
    basis[0] = u
    return basis


@dataclass(frozen=True, eq=False)
class RodClosedForm:
    """Precomputed closed-form models of one :class:`~pkmkit.model.rods.RodModel`.

    Built once per machine; all methods are batched over rows.
    """

    model: RodModel

    def __post_init__(self) -> None:
        m = self.model
        dims = m.dims
        centre0 = (m.leg_base - m.leg_platform)[:, :dims]
        axis = m.leg_axis[:, :dims]
        crank = m.leg_kind == CRANK
        # crank frames: axis w, arm direction e1 at q = 0, e2 = w × e1; arm length and offset
        arm = m.leg_base - m.leg_pivot
        along = np.einsum("id,id->i", arm, m.leg_axis)
        across = arm - along[:, None] * m.leg_axis
        radius = np.where(crank, np.linalg.norm(across, axis=1), 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e1 = np.where(crank[:, None], across / radius[:, None], 0.0)
        e2 = np.cross(m.leg_axis, e1)
        blocks = [np.array([m.leg_axis[i], e1[i], e2[i]]) if crank[i]
                  else _orthonormal_basis(axis[i], dims) for i in range(m.n_legs)]
        # projection origin: the carriage centre at q = 0, or the pivot − b for a crank
        origin = np.where(crank[:, None], (m.leg_pivot - m.leg_platform)[:, :dims], centre0)
        projection = np.concatenate([b.T for b in blocks], axis=1)  # (dims, n*dims)
        offset = np.concatenate([b @ origin[i] for i, b in enumerate(blocks)])
        set_ = object.__setattr__
        set_(self, "crank", crank.astype(float))
        set_(self, "crank_radius", radius)
        set_(self, "crank_offset", np.where(crank, along, 0.0))
        set_(self, "crank_e1", e1)
        set_(self, "crank_e2", e2)
        set_(self, "centre0", centre0)
        set_(self, "axis", axis)
        set_(self, "projection", projection)
        set_(self, "offset", offset)
        # the same, leg by leg: basis (n, dims, dims) rows u_i, then across; offset (n, dims)
        set_(self, "basis", np.ascontiguousarray(np.stack(blocks)))
        set_(self, "basis_offset", np.ascontiguousarray(offset.reshape(m.n_legs, dims)))
        set_(self, "slide", (m.leg_kind == SLIDE).astype(float))
        set_(self, "strut", (m.leg_kind == STRUT).astype(float))
        set_(self, "length_sq", m.leg_length**2)
        for value in vars(self).values():  # shared by every copy of a kept machine: read-only
            if isinstance(value, np.ndarray):
                value.flags.writeable = False

    # ------------------------------------------------------------------ inverse
    def inverse(self, x: np.ndarray, branches: np.ndarray) -> np.ndarray:
        """Actuator coordinates ``(N, n)`` of poses ``x (N, dims)``; NaN where a leg cannot
        close. ``branches (n,)`` holds ±1 per leg (ignored for struts).

        Large batches run the compiled kernel :func:`pkmkit.machines.kernels.inverse` (its C
        twin ``rod_inverse_rows`` where :mod:`pkmkit.native` is built: no Numba import, so a
        fresh process's command line takes it too); small ones (and ``PKMKIT_COMPILED=0``)
        the NumPy reference :meth:`inverse_numpy`. The result
        is a Fortran-ordered ``(N, n)`` array (a transposed view of ``(n, N)``).
        """
        return self.inverse_counted(x, branches)[0]

    def inverse_counted(self, x: np.ndarray, branches: np.ndarray,
                        out: np.ndarray | None = None) -> tuple[np.ndarray, int]:
        """:meth:`inverse` and the number of non-finite coordinates in the result (0: every
        pose reached; callers then skip looking for failed rows). ``out``: a caller's
        C-contiguous ``(N, n)`` array the compiled kernels write q into (the NumPy reference's
        result is copied into it), returned as q."""
        q, bad, _, _ = self._inverse_pass(x, branches, False, out)
        return q, bad

    @property
    def fuses(self) -> bool:
        """Whether :meth:`inverse_full` gives the shortfalls and det A in the inverse's pass
        (square machines of slides and struts; cranks take :meth:`shortfall` and
        :meth:`jacobians`)."""
        m = self.model
        return not self.crank.any() and m.n_legs == m.dims and m.dims in (2, 3)

    def inverse_full(self, x: np.ndarray, branches: np.ndarray, out: np.ndarray | None = None
                     ) -> tuple[np.ndarray, int, np.ndarray, np.ndarray]:
        """:meth:`inverse_counted`, :meth:`shortfall` and det A in one pass over ``x (N, dims)``
        (only where :attr:`fuses`): ``(q (N, n), bad, shortfall (N, n), det_a (N,))``, each
        bit for bit what the separate calls give — det A as
        :func:`~pkmkit.numerics.linalg.batched_det` of :meth:`jacobians`' A at ``(x, q)``
        (meaningless on rows with a non-finite q); ``out`` as for :meth:`inverse_counted`."""
        if not self.fuses:
            raise ValueError("inverse_full needs a square machine of slides and struts")
        q, bad, short, det = self._inverse_pass(x, branches, True, out)
        return q, bad, short.T, det

    def _inverse_pass(self, x: np.ndarray, branches: np.ndarray, full: bool,
                      q_out: np.ndarray | None = None) -> tuple:
        """``(q (N, n), bad, shortfall (n, N) | None, det (N,) | None)``: the compiled kernels
        for large batches — their C twins (``rod_inverse_rows``, ``rod_reach_det``) where the
        extension is built, else the Numba kernels once Numba is imported — else the NumPy
        reference. The same bits on every path."""
        n, rows = self.model.n_legs, x.shape[0]
        short = np.empty((n, rows)) if full else None
        det = np.empty(rows) if full else None
        twins = all(jit.native_kernel(_KERNELS, name) is not None
                    for name in ("inverse", "reach_and_det"))
        if jit.use_compiled(rows, imports=False, native=twins) and not self.crank.any():
            inverse = jit.kernel(_KERNELS, "inverse")  # slides, struts
            x = np.ascontiguousarray(x, dtype=float)
            out = np.empty((n, rows)) if q_out is None else q_out.T  # (n, N) either way
            slide = self.model.leg_kind == SLIDE
            c = np.ascontiguousarray
            bad = inverse(x, c(self.basis), c(self.basis_offset), c(self.model.leg_length),
                          slide, np.array(branches, dtype=float), BOUNDARY_TOL, out)
            if full:
                jit.kernel(_KERNELS, "reach_and_det")(
                    x, out, c(self.basis), c(self.basis_offset), c(self.centre0), c(self.axis),
                    c(self.model.leg_length), slide, short, det)
            return out.T if q_out is None else q_out, int(bad), short, det
        q = self._inverse_numpy(x, branches, short, det)
        if q_out is not None:
            np.copyto(q_out, q)
            q = q_out
        return q, int(np.count_nonzero(~np.isfinite(q))), short, det

    def inverse_numpy(self, x: np.ndarray, branches: np.ndarray) -> np.ndarray:
        """The NumPy reference of :meth:`inverse`: cache-sized chunks in a transposed layout
        (one contiguous row per projection), projections written out (no BLAS: a
        multi-threaded BLAS on tiny inner dimensions collapses when another process holds a
        core)."""
        return self._inverse_numpy(x, branches, None, None)

    def _inverse_numpy(self, x: np.ndarray, branches: np.ndarray, short: np.ndarray | None,
                       det: np.ndarray | None) -> np.ndarray:
        """:meth:`inverse_numpy`, also filling ``short (n, N)`` (:meth:`shortfall`, from the
        same projections) and ``det (N,)`` (det A) when given."""
        n, dims = self.model.n_legs, self.model.dims
        out = np.empty((n, x.shape[0]))
        kinds = self.model.leg_kind
        with np.errstate(invalid="ignore", over="ignore"):
            for start in range(0, x.shape[0], CHUNK):
                stop = start + CHUNK
                xt = np.ascontiguousarray(x[start:stop].T)  # rows of one coordinate
                for i in range(n):
                    y = [self._project(xt, i, r) for r in range(dims)]
                    perp_sq = y[1] * y[1]
                    if dims == 3:
                        perp_sq += y[2] * y[2]
                    if short is not None:  # as _reach, from the same projections
                        if kinds[i] == STRUT:
                            short[i, start:stop] = -np.inf
                        else:
                            np.sqrt(perp_sq, out=short[i, start:stop])
                            short[i, start:stop] -= self.model.leg_length[i]
                    if kinds[i] == SLIDE:
                        np.subtract(self.length_sq[i], perp_sq, out=perp_sq)
                        # a boundary pose's radicand may round slightly below 0: clamp it
                        np.maximum(perp_sq, 0.0, out=perp_sq,
                                   where=perp_sq > -BOUNDARY_TOL * self.length_sq[i])
                        root = np.sqrt(perp_sq, out=perp_sq)
                        if branches[i] < 0:
                            np.negative(root, out=root)
                        np.add(y[0], root, out=out[i, start:stop])
                    elif kinds[i] == CRANK:
                        out[i, start:stop] = self._crank_angle(y[0], y[1], y[2], perp_sq, i,
                                                               branches[i])
                    else:
                        perp_sq += y[0] * y[0]
                        np.sqrt(perp_sq, out=out[i, start:stop])
                        out[i, start:stop] -= self.model.leg_length[i]
                if det is not None:
                    det[start:stop] = self._det_rows(xt, out[:, start:stop])
        return out.T

    def _det_rows(self, xt: np.ndarray, qt: np.ndarray) -> np.ndarray:
        """det A of the columns of ``xt (dims, k)``, ``qt (n, k)`` (slides and struts): the
        operations of :meth:`rod_vectors` and :func:`~pkmkit.numerics.linalg.batched_det`,
        in their order (so the same bits)."""
        dims = self.model.dims
        a = [[xt[d] - (self.centre0[i, d] + (qt[i] if self.slide[i] > 0 else 0.0)
                       * self.axis[i, d]) for d in range(dims)] for i in range(dims)]
        if dims == 2:
            return a[0][0] * a[1][1] - a[0][1] * a[1][0]
        return (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
                - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
                + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))

    def inverse_one(self, x: Any, branches: Sequence[float]) -> list[float] | None:
        """The inverse model of one pose in plain Python floats: the same operations in the same
        order as :meth:`inverse_numpy` (so the same bits), without array machinery — a few
        microseconds where a batch call of one row costs a hundred.

        Args:
            x: ``dims`` finite numbers (a list, a tuple or a 1-D array), m.
            branches: ±1 per leg.

        Returns:
            ``n`` actuator coordinates (m, rad for cranks), or None when the pose is not plain
            finite numbers of the right length or a leg cannot close: the caller then takes
            the batch path, which gives the same numbers and the typed errors.
        """
        last = self.__dict__.get("_single_last")  # (branches, legs) of the previous call
        # the previous call's constants only for the same tuple (immutable: the machine's
        # default branches); a list or an array may have been changed in place since
        legs = (last[1] if last is not None and last[0] is branches and type(branches) is tuple
                else self._single_legs(branches))
        if type(x) is not list:
            if isinstance(x, np.ndarray):
                if x.ndim != 1 or x.dtype.kind not in "fi":
                    return None
                x = x.tolist()
            elif not isinstance(x, (list, tuple)):
                return None
        if len(x) != self.model.dims:
            return None
        for v in x:
            if type(v) is not float and (not isinstance(v, (float, int)) or isinstance(v, bool)):
                return None  # bools, strings: the batch path
            if not -MAX_ABS <= v <= MAX_ABS:
                return None  # NaN, ±inf, absurd magnitudes: the batch path
        if len(x) == 3:
            x0, x1, x2 = float(x[0]), float(x[1]), float(x[2])
        else:
            x0, x1, x2 = float(x[0]), float(x[1]), None
        out = []
        for (kind, a0, a1, a2, b0, b1, b2, d0, d1, d2, o0, o1, o2, length_sq, length, limit,
             radius_sq, diameter, offset, branch) in legs:
            if x2 is not None:
                y0 = a0 * x0 + a1 * x1 + a2 * x2 - o0
                y1 = b0 * x0 + b1 * x1 + b2 * x2 - o1
                y2 = d0 * x0 + d1 * x1 + d2 * x2 - o2
                perp_sq = y1 * y1 + y2 * y2
            else:
                y0 = a0 * x0 + a1 * x1 - o0
                y1 = b0 * x0 + b1 * x1 - o1
                y2 = 0.0
                perp_sq = y1 * y1
            if kind == SLIDE:
                radicand = length_sq - perp_sq
                if radicand < 0.0:
                    if radicand <= -limit:
                        return None
                    radicand = 0.0
                root = sqrt(radicand)
                out.append(y0 - root if branch < 0 else y0 + root)
            elif kind == CRANK:  # as _crank_angle: rows (w, e1, e2) of the crank frame
                along = y0 - offset
                g = along * along + perp_sq + radius_sq - length_sq
                amplitude = diameter * sqrt(perp_sq)
                if amplitude == 0.0:
                    return None
                cosine = g / amplitude
                if not -1.0 <= cosine <= 1.0:
                    if abs(g) - amplitude > limit:
                        return None
                    cosine = -1.0 if cosine < 0.0 else 1.0  # a boundary pose rounded beyond ±1
                q = atan2(y2, y1) + branch * acos(cosine)
                out.append((q + pi) % _TWO_PI - pi)
            else:  # strut
                out.append(sqrt(perp_sq + y0 * y0) - length)
        return out

    def _single_legs(self, branches: Sequence[float]) -> tuple:
        """Per-leg constants of :meth:`inverse_one` as flat tuples of Python floats (basis rows,
        offsets, ℓ², ℓ, the boundary tolerance ``BOUNDARY_TOL ℓ²``, crank r² and 2r (the
        products the batch path forms first: the same bits), crank offset, branch), computed once
        per branch choice."""
        cache = self.__dict__.get("_single")
        if cache is None:
            cache = {}
            object.__setattr__(self, "_single", cache)
        key = tuple(branches)
        legs = cache.get(key)
        if legs is None:
            m = self.model
            basis = [[[*row, 0.0][:3] for row in leg] + [[0.0] * 3] * (3 - m.dims)
                     for leg in self.basis.tolist()]  # rows padded to 3 × 3 in the plane
            offset = [[*o, 0.0][:3] for o in self.basis_offset.tolist()]
            radius = self.crank_radius.tolist()
            legs = tuple((int(m.leg_kind[i]), *basis[i][0], *basis[i][1], *basis[i][2],
                          *offset[i], float(self.length_sq[i]), float(m.leg_length[i]),
                          float(BOUNDARY_TOL * self.length_sq[i]), radius[i] * radius[i],
                          2.0 * radius[i], float(self.crank_offset[i]),
                          float(b)) for i, b in enumerate(key))
            cache[key] = legs
        object.__setattr__(self, "_single_last", (branches, legs))
        return legs

    def single_legs_packed(self, branches: Sequence[float]) -> bytes:
        """:meth:`_single_legs` as the C kernel ``rod_inverse`` takes them (``n × 20`` float64
        bytes); the previous call's bytes for the same tuple of branches (a tuple is immutable:
        kept for the next call)."""
        last = self.__dict__.get("_one_inverse_native")
        if last is not None and last[0] is branches:
            return last[1]
        legs = np.array(self._single_legs(branches), dtype=float).tobytes()
        if type(branches) is tuple:
            object.__setattr__(self, "_one_inverse_native", (branches, legs))
        return legs

    def _crank_terms(self, v_w, v_1, v_2, perp_sq, i):
        """``(K − ℓ², 2 r ρ⊥)`` of crank leg i (see the module docstring)."""
        radius = self.crank_radius[i]
        along = v_w - self.crank_offset[i]
        k = along * along + perp_sq + radius * radius
        return k - self.length_sq[i], 2.0 * radius * np.sqrt(perp_sq)

    def _crank_angle(self, v_w, v_1, v_2, perp_sq, i, branch):
        """Crank angle of leg i (radians in (−π, π]); NaN out of reach."""
        g, amplitude = self._crank_terms(v_w, v_1, v_2, perp_sq, i)
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = g / amplitude
        # a boundary pose may round slightly beyond ±1: clamp it
        near = np.abs(g) - amplitude <= BOUNDARY_TOL * self.length_sq[i]
        cosine = np.where(near, np.clip(cosine, -1.0, 1.0), cosine)
        q = np.arctan2(v_2, v_1) + branch * np.arccos(cosine)
        return np.remainder(q + np.pi, 2.0 * np.pi) - np.pi

    def _project(self, xt: np.ndarray, leg: int, row: int) -> np.ndarray:
        """``basis[leg, row] · x − offset`` for the columns of ``xt (dims, k)``."""
        coef = self.basis[leg, row]
        y = coef[0] * xt[0]
        for d in range(1, xt.shape[0]):
            y += coef[d] * xt[d]
        y -= self.basis_offset[leg, row]
        return y

    def shortfall(self, x: np.ndarray) -> np.ndarray:
        """``(N, n)``: by how far each leg is out of reach of ``x`` (≤ 0 when it reaches;
        always −inf for struts), metres. A slide leg is too short; a crank leg's rod is too
        short (or too long: see :meth:`too_long`) to join the arm-tip circle to the platform."""
        short, _ = self._reach(x)
        return short

    def too_long(self, x: np.ndarray) -> np.ndarray:
        """``(N, n)`` bool: the leg's rod is out of reach because it is too *long* (a crank
        whose arm-tip circle passes too close to the platform joint)."""
        _, long = self._reach(x)
        return long

    def _reach(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        dims = self.model.dims
        with np.errstate(invalid="ignore", over="ignore"):
            y = (np.einsum("kd,de->ke", x, self.projection) - self.offset).reshape(
                x.shape[0], -1, dims)
            perp_sq = y[:, :, 1] ** 2 if dims == 2 else y[:, :, 1] ** 2 + y[:, :, 2] ** 2
            out = np.sqrt(perp_sq) - self.model.leg_length[None]
            long = np.zeros(out.shape, dtype=bool)
            for i in np.flatnonzero(self.crank):
                g, amplitude = self._crank_terms(y[:, i, 0], y[:, i, 1], y[:, i, 2],
                                                 perp_sq[:, i], i)
                length = self.model.leg_length[i]
                nearest = np.sqrt(np.maximum(g + self.length_sq[i] - amplitude, 0.0))
                farthest = np.sqrt(g + self.length_sq[i] + amplitude)
                out[:, i] = np.maximum(nearest - length, length - farthest)
                long[:, i] = length - farthest > nearest - length
        out[:, self.model.leg_kind == STRUT] = -np.inf
        return out, long & (out > 0)

    def carriage_rates(self, q: np.ndarray) -> np.ndarray:
        """``∂c_i/∂q_i`` ``(N, n, dims)``: the slide axis, the crank-tip velocity per unit
        angle ``r (−sin q e1 + cos q e2)``, zero for struts."""
        out = np.broadcast_to(self.axis * self.slide[:, None], (q.shape[0], *self.axis.shape))
        if not self.crank.any():
            return out
        out = np.array(out)
        for i in np.flatnonzero(self.crank):
            r = self.crank_radius[i]
            out[:, i] = r * (np.cos(q[:, i])[:, None] * self.crank_e2[i, None]
                             - np.sin(q[:, i])[:, None] * self.crank_e1[i, None])
        return out

    def branch_signs(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Inverse-model branch ``(N, n)`` (±1) of each leg at ``(x, q)``: ``−sign`` of the
        serial-Jacobian entry ``(p − c_i)·∂c_i/∂q_i`` (+1 for struts)."""
        d = self.rod_vectors(x, q)
        along = np.einsum("kid,kid->ki", d, self.carriage_rates(q))
        return np.where((self.model.leg_kind != STRUT) & (along > 0), -1, 1)

    # ------------------------------------------------------------------ direct
    def centres(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sphere centres ``(N, n, dims)`` and radii ``(N, n)`` for actuator coordinates q."""
        with np.errstate(invalid="ignore", over="ignore"):
            c = self.centre0[None] + np.where(self.slide > 0, q, 0.0)[:, :, None] * self.axis[None]
            rho = self.model.leg_length[None] + np.where(self.strut > 0, q, 0.0)
            if self.crank.any():
                m = self.model
                for i in np.flatnonzero(self.crank):
                    tip = (m.leg_pivot[i] + self.crank_offset[i] * m.leg_axis[i]
                           + self.crank_radius[i] * (np.cos(q[:, i])[:, None] * self.crank_e1[i]
                                                     + np.sin(q[:, i])[:, None] * self.crank_e2[i]))
                    c[:, i] = tip - m.leg_platform[i]
        return c, rho

    def direct_all(self, q: np.ndarray, rel_tol: float = 1e-12) -> tuple[np.ndarray, np.ndarray]:
        """Both assembly modes of every row.

        Args:
            q: ``(N, n)`` actuator coordinates, m.
            rel_tol: a discriminant within ``rel_tol`` of the radius² (either sign) is taken as
                0 — rounding cannot tell it from a double root, where the two modes merge on a
                parallel singularity.

        Returns:
            ``(poses (N, 2, dims), degenerate (N,))``: ``poses[:, 0]`` is the mode with
            det A < 0, ``poses[:, 1]`` the mode with det A > 0; NaN where no real assembly
            exists. ``degenerate`` flags rows whose sphere centres are aligned (the direct model
            has no isolated solution there) or so nearly aligned that the solution found does
            not close every leg to :data:`RESIDUAL_TOL` (relative); their poses are NaN.
            Computed in cache-sized chunks.
        """
        poses = np.empty((q.shape[0], 2, self.model.dims))
        degenerate = np.empty(q.shape[0], dtype=bool)
        for start in range(0, q.shape[0], CHUNK):
            stop = start + CHUNK
            poses[start:stop], degenerate[start:stop] = self._direct_chunk(q[start:stop], rel_tol)
        return poses, degenerate

    def _direct_chunk(self, q: np.ndarray, rel_tol: float) -> tuple[np.ndarray, np.ndarray]:
        c, rho = self.centres(q)
        c1 = c[:, 0]
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            rho_sq = rho**2
            if self.model.dims == 3:
                e1, e2 = c[:, 1] - c1, c[:, 2] - c1
                g11 = np.einsum("kd,kd->k", e1, e1)
                g12 = np.einsum("kd,kd->k", e1, e2)
                g22 = np.einsum("kd,kd->k", e2, e2)
                h2 = 0.5 * (rho_sq[:, 0] - rho_sq[:, 1] + g11)
                h3 = 0.5 * (rho_sq[:, 0] - rho_sq[:, 2] + g22)
                gram = g11 * g22 - g12 * g12
                alpha = (h2 * g22 - h3 * g12) / gram
                beta = (h3 * g11 - h2 * g12) / gram
                w = alpha[:, None] * e1 + beta[:, None] * e2
                normal = np.cross(e1, e2)
                degenerate = gram <= 1e-20 * g11 * g22
            else:
                e = c[:, 1] - c1
                gram = np.einsum("kd,kd->k", e, e)
                alpha = 0.5 * (rho_sq[:, 0] - rho_sq[:, 1] + gram) / gram
                w = alpha[:, None] * e
                normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
                degenerate = gram <= 1e-24 * rho_sq[:, 0]
            t_sq = (rho_sq[:, 0] - np.einsum("kd,kd->k", w, w)) / gram
            t_sq = np.where(np.abs(t_sq) <= rel_tol * rho_sq[:, 0] / gram, 0.0, t_sq)
            t = np.sqrt(t_sq)
        t[degenerate] = np.nan
        t[(rho <= 0).any(axis=1)] = np.nan  # a strut cannot have a negative length
        with np.errstate(invalid="ignore", over="ignore"):
            centre = c1 + w
            offset = t[:, None] * normal
            poses = np.stack([centre - offset, centre + offset], axis=1)
            # near a parallel singularity (centres nearly together or aligned: a small Gram
            # determinant) rounding can leave a solution that closes no leg. Those rows get
            # every leg checked, and are flagged as degenerate when one is not closed.
            if self.model.dims == 3:  # size² of the configuration: ρ₁² + |e1|² + |e2|²
                size_sq = rho_sq[:, 0] + g11 + g22
                suspect = np.flatnonzero(gram < SUSPECT_GRAM * size_sq * size_sq)
            else:
                suspect = np.flatnonzero(gram < SUSPECT_GRAM * (rho_sq[:, 0] + gram))
        unresolved = np.zeros(q.shape[0], dtype=bool)
        if suspect.size:
            with np.errstate(invalid="ignore", over="ignore"):
                d = poses[suspect][:, :, None, :] - c[suspect][:, None]
                residual = np.abs(np.linalg.norm(d, axis=3) - rho[suspect][:, None, :])
                scale = (1.0 + np.abs(c[suspect]).max(axis=(1, 2))
                         + np.abs(rho[suspect]).max(axis=1))
                unresolved[suspect] = residual.max(axis=(1, 2)) > RESIDUAL_TOL * scale
        poses[unresolved] = np.nan
        return poses, degenerate | unresolved

    # ------------------------------------------------------------------ velocity
    def rod_vectors(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Rows of A: ``p − c_i(q)``, shape ``(N, n, dims)``."""
        c, _ = self.centres(q)
        return x[:, None, :] - c

    def jacobians_t(self, x: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A and the diagonal of B with the batch axis last: ``A (n, dims, N)``, ``b (n, N)``.

        The layout of :mod:`pkmkit.numerics.small` (fast closed forms for many poses).
        """
        m = self.model
        x_t = x.T  # (dims, N)
        q_t = q.T  # (n, N)
        a = np.empty((m.n_legs, m.dims, x.shape[0]))
        b = np.zeros((m.n_legs, x.shape[0]))
        if self.crank.any():
            c, _ = self.centres(q)
            rates = self.carriage_rates(q)
        for i in range(m.n_legs):
            if m.leg_kind[i] == SLIDE:
                for k in range(m.dims):
                    np.subtract(x_t[k], self.centre0[i, k] + q_t[i] * self.axis[i, k],
                                out=a[i, k])
                    if self.axis[i, k]:
                        b[i] += a[i, k] * self.axis[i, k]
            elif m.leg_kind[i] == CRANK:
                for k in range(m.dims):
                    np.subtract(x_t[k], c[:, i, k], out=a[i, k])
                    b[i] += a[i, k] * rates[:, i, k]
            else:
                for k in range(m.dims):
                    np.subtract(x_t[k], self.centre0[i, k], out=a[i, k])
                b[i] = m.leg_length[i] + q_t[i]
        return a, b

    def jacobians(self, x: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Parallel and serial Jacobians ``A (N, n, dims)``, ``B (N, n, n)`` (A ṗ = B q̇)."""
        d = self.rod_vectors(x, q)
        _, rho = self.centres(q)
        diag = np.einsum("kid,kid->ki", d, self.carriage_rates(q)) + self.strut * rho
        b = np.zeros((*diag.shape, diag.shape[1]))
        idx = np.arange(diag.shape[1])
        b[:, idx, idx] = diag
        return d, b

    def jacobian_rates(
        self, xd: np.ndarray, qd: np.ndarray, x: np.ndarray, q: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Time derivatives ``Ȧ (N, n, dims)``, ``Ḃ (N, n, n)`` for platform velocity
        ``xd (N, dims)`` and actuator rates ``qd (N, n)`` at poses ``x (N, dims)`` and actuator
        coordinates ``q (N, n)``."""
        rates = self.carriage_rates(q)
        dd = xd[:, None, :] - qd[:, :, None] * rates
        diag = np.einsum("kid,kid->ki", dd, rates) + self.strut * qd
        if self.crank.any():
            # the crank tip's velocity turns with the arm: d·(∂²c/∂q²) q̇ with ∂²c/∂q² = −radial
            d = self.rod_vectors(x, q)
            for i in np.flatnonzero(self.crank):
                radial = np.cross(self.model.leg_axis[i][None, :self.model.dims], rates[:, i])
                diag[:, i] += np.einsum("kd,kd->k", d[:, i], radial) * qd[:, i]
        b = np.zeros((*diag.shape, diag.shape[1]))
        idx = np.arange(diag.shape[1])
        b[:, idx, idx] = diag
        return dd, b
