"""Batched velocity model of translational rod-leg machines, computed on demand.

:class:`LazyJacobians` is what :meth:`Machine.jacobian` returns: a :class:`Jacobians` whose
fields are computed the first time they are read, in groups that share their work —

- *summary*: det A, singular values of J, condition number, serial measure, singularity flags,
  assembly mode (what maps, workspaces and designs read). Large batches run the compiled kernel
  :func:`pkmkit.machines.kernels.velocity3` (one pass, no temporaries); the rows it leaves (near
  a parallel singularity, nearly equal singular values, overflow) and small batches run the
  NumPy reference :func:`velocity_chunk`;
- *matrices*: A, B, J⁻¹ = B⁻¹A, det B;
- J = A⁻¹B and the exact parallel measure, each on its own.

so that ``m.jacobian(X).condition`` computes neither the matrices nor J. The NumPy path works in
the batch-last layout of :mod:`pkmkit.numerics.small`, in cache-sized chunks, without BLAS.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from pkmkit.machines.closed_form import RodClosedForm
from pkmkit.machines.lazy_records import read_only
from pkmkit.machines.results import Jacobians, Singularity
from pkmkit.numerics import jit, small
from pkmkit.numerics.linalg import condition_number

#: Poses per chunk of the NumPy velocity model (keeps the temporaries in cache).
CHUNK = 16384
#: Below this parallel-singularity measure the factors come from J⁻¹ (see velocity_chunk):
#: above it eps·κ² is below about 1e-11.
NEAR_PARALLEL = 1e-2


def velocity_chunk(a: np.ndarray, b: np.ndarray):
    """det A, J = A⁻¹B, singular values of J and σ_min/σ_max of A with unit rows, for one
    chunk in the batch-last layout (``a (n, n, k)``, ``b (n, k)``) — the NumPy reference —,
    and the serial measure (smallest |b_i| / |a_i|).

    Near a parallel singularity J = adj(A) B / det A loses about eps·κ² of relative accuracy in
    its singular values; there (where A is worse conditioned than B) they are taken instead as
    the reversed reciprocals of those of J⁻¹ = B⁻¹A, which needs no division by det A
    (eps·κ), wherever σ_min/σ_max of A with unit rows is below :data:`NEAR_PARALLEL`."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore", under="ignore"):
        cof = small.cofactors(a)
        det_a = small.det(a, cof)
        inv_det = 1.0 / det_a
        # J = A⁻¹ B = adj(A) B / det A with adj = cofactorsᵀ: J[k, j] = C[j, k] b_j / det A
        j = cof.transpose(1, 0, 2) * (b * inv_det)[None, :, :]
        lengths = small.row_norms(a)
        sv_unit = small.singular_values(a / lengths[:, None, :])
        parallel = sv_unit[-1] / sv_unit[0]
        serial = np.min(np.abs(b) / lengths, axis=0)
        j[:, :, ~np.isfinite(inv_det)] = np.nan
        sv = small.singular_values(j)
        near_parallel = np.flatnonzero((parallel < NEAR_PARALLEL) & (parallel < serial)
                                       & np.isfinite(inv_det))
        if near_parallel.size:
            sv_inv = small.singular_values(a[:, :, near_parallel] / b[:, None, near_parallel])
            sv[:, near_parallel] = 1.0 / sv_inv[::-1]
    return det_a, j, sv, parallel, serial


def _flags(serial: np.ndarray, parallel: np.ndarray, det_a: np.ndarray, tol: float):
    with np.errstate(invalid="ignore"):
        flags = np.where(serial < tol, int(Singularity.SERIAL), 0)
        flags |= np.where((parallel < tol) | (det_a == 0.0), int(Singularity.PARALLEL), 0)
    return flags


class VelocityEvaluation:
    """The velocity model of one batch, evaluated group by group on demand (see module doc).

    Args:
        closed: the machine's closed forms (square: n = dims).
        x: ``(N, dims)`` poses, m. q: ``(N, n)`` actuator coordinates (NaN rows: unreachable).
        tol: threshold of the singularity measures.
    """

    def __init__(self, closed: RodClosedForm, x: np.ndarray, q: np.ndarray, tol: float):
        self.closed = closed
        # copies (in their memory order): the caller may reuse its pose or q arrays before a
        # field is first read
        self.x = x.copy(order="K")
        self.q = q.copy(order="K")
        self.tol = float(tol)
        self.size = x.shape[0]
        self.n = closed.model.n_legs

    # -------------------------------------------------------------- groups
    @cached_property
    def matrices(self) -> tuple[np.ndarray, np.ndarray]:
        """``A (n, dims, N)`` and diag B ``(n, N)``, batch last."""
        with np.errstate(invalid="ignore", over="ignore"):
            return self.closed.jacobians_t(self.x, self.q)

    @cached_property
    def summary(self) -> dict[str, np.ndarray]:
        """det A ``(N,)``, singular values ``(n, N)``, condition, serial measure, singularity
        flags, and the exact parallel measure where it was computed (NaN elsewhere)."""
        if jit.use_compiled(self.size, native=True) and not self.closed.crank.any():  # no cranks
            return self._summary_compiled()
        return self._summary_numpy()

    def _summary_numpy(self, rows: np.ndarray | None = None) -> dict[str, np.ndarray]:
        x = self.x if rows is None else self.x[rows]
        q = self.q if rows is None else self.q[rows]
        size, n = x.shape[0], self.n
        det_a, parallel, serial = np.empty(size), np.empty(size), np.empty(size)
        sv = np.empty((n, size))
        keep_j = rows is None and "J_full" not in self.__dict__
        j_all = np.empty((n, n, size)) if keep_j else None
        for start in range(0, size, CHUNK):
            part = slice(start, start + CHUNK)
            with np.errstate(invalid="ignore", over="ignore"):
                a, b = self.closed.jacobians_t(x[part], q[part])
            det_a[part], j, sv[:, part], parallel[part], serial[part] = velocity_chunk(a, b)
            if j_all is not None:
                j_all[:, :, part] = j
        flags = _flags(serial, parallel, det_a, self.tol)
        at_parallel = (flags & Singularity.PARALLEL).astype(bool)
        sv[:, at_parallel] = np.nan
        condition = np.where(at_parallel, np.nan, condition_number(sv.T))
        if j_all is not None:
            j_all[:, :, at_parallel] = np.nan
            self.__dict__["J_full"] = j_all
        return {"det_A": det_a, "singular_values": sv, "condition": condition,
                "serial": serial, "parallel": parallel, "flags": flags}

    def _summary_compiled(self) -> dict[str, np.ndarray]:
        closed, n, size = self.closed, self.n, self.size
        det_a, condition, serial = np.empty(size), np.empty(size), np.empty(size)
        sv = np.empty((n, size))
        hard = np.empty(size, dtype=bool)
        # the C twin (native/rod_velocity.c) when built, else Numba's
        kernel = jit.kernel("pkmkit.machines.kernels", "velocity3" if n == 3 else "velocity2")
        limit = max(NEAR_PARALLEL, self.tol)
        q_t = self.q.T if self.q.flags.f_contiguous else np.ascontiguousarray(self.q.T)
        legs = [np.ascontiguousarray(a, dtype=float)
                for a in (closed.centre0, closed.axis, closed.model.leg_length)]
        kernel(np.ascontiguousarray(self.x, dtype=float), q_t, legs[0], legs[1],
               np.ascontiguousarray(closed.slide > 0), legs[2], limit, det_a, sv, condition,
               serial, hard)
        # every row not left to the reference has parallel measure ≥ limit ≥ tol
        parallel = np.full(size, np.nan)
        rows = np.flatnonzero(hard)
        if rows.size:
            ref = self._summary_numpy(rows)
            det_a[rows], sv[:, rows] = ref["det_A"], ref["singular_values"]
            condition[rows], serial[rows] = ref["condition"], ref["serial"]
            parallel[rows] = ref["parallel"]
        with np.errstate(invalid="ignore"):
            flags = np.where(serial < self.tol, int(Singularity.SERIAL), 0)
        if rows.size:
            flags[rows] = ref["flags"]
        return {"det_A": det_a, "singular_values": sv, "condition": condition,
                "serial": serial, "parallel": parallel, "flags": flags}

    @cached_property
    def J_full(self) -> np.ndarray:
        """J ``(dims, n, N)`` batch last; NaN at parallel singularities."""
        size, n = self.size, self.n
        j_all = np.empty((n, n, size))
        for start in range(0, size, CHUNK):
            part = slice(start, start + CHUNK)
            a, b = self.closed.jacobians_t(self.x[part], self.q[part])
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                cof = small.cofactors(a)
                inv_det = 1.0 / small.det(a, cof)
                j = cof.transpose(1, 0, 2) * (b * inv_det)[None, :, :]
            j[:, :, ~np.isfinite(inv_det)] = np.nan
            j_all[:, :, part] = j
        at_parallel = (self.summary["flags"] & Singularity.PARALLEL).astype(bool)
        j_all[:, :, at_parallel] = np.nan
        return j_all

    @cached_property
    def parallel_measure(self) -> np.ndarray:
        """σ_min/σ_max of A with unit rows ``(N,)`` (exact, every row)."""
        parallel = self.summary["parallel"]
        missing = np.isnan(parallel) & np.isfinite(self.q).all(axis=1)
        if not missing.any():
            return parallel
        out = parallel.copy()
        rows = np.flatnonzero(missing)
        for start in range(0, rows.size, CHUNK):
            part = rows[start:start + CHUNK]
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                a, _ = self.closed.jacobians_t(self.x[part], self.q[part])
                lengths = small.row_norms(a)
                sv_unit = small.singular_values(a / lengths[:, None, :])
                out[part] = sv_unit[-1] / sv_unit[0]
        return out


class LazyJacobians(Jacobians):
    """A :class:`Jacobians` (same fields, same shapes) whose fields are computed when first
    read — see the module documentation. A single pose gives fields without the batch axis."""

    def __init__(self, evaluation: VelocityEvaluation | None = None, single: bool = False,
                 **fields):
        # ``fields`` (every field, already shaped): what dataclasses.replace passes
        object.__setattr__(self, "_evaluation", evaluation)
        object.__setattr__(self, "_single", single)
        object.__setattr__(self, "_cache", dict(fields))

    def _get(self, name: str, compute):
        cache = self._cache
        if name in cache:
            value = cache[name]
        else:
            value = compute(self._evaluation)
            value = value[0] if self._single and np.ndim(value) else value
        value = cache[name] = read_only(value)  # kept read-only: every later read sees it
        return value

    def __repr__(self) -> str:
        ev = self._evaluation
        if ev is None:
            return f"LazyJacobians(condition={self.condition!r})"
        return (f"LazyJacobians({ev.size} poses, {ev.n} actuators, tolerance {ev.tol:g}; "
                "fields computed when read)")

    def __eq__(self, other: object) -> bool:
        return self is other

    __hash__ = object.__hash__

    @property
    def A(self) -> np.ndarray:
        return self._get("A", lambda e: e.matrices[0].transpose(2, 0, 1))

    @property
    def B(self) -> np.ndarray:
        def build(e):
            b = e.matrices[1]
            out = np.zeros((e.size, e.n, e.n))
            out[:, np.arange(e.n), np.arange(e.n)] = b.T
            return out
        return self._get("B", build)

    @property
    def J(self) -> np.ndarray:
        return self._get("J", lambda e: e.J_full.transpose(2, 0, 1))

    @property
    def J_inv(self) -> np.ndarray:
        def build(e):
            a, b = e.matrices
            with np.errstate(divide="ignore", invalid="ignore"):
                return (a / b[:, None, :]).transpose(2, 0, 1)
        return self._get("J_inv", build)

    @property
    def singular_values(self) -> np.ndarray:
        return self._get("singular_values", lambda e: e.summary["singular_values"].T)

    @property
    def condition(self) -> np.ndarray:
        return self._get("condition", lambda e: e.summary["condition"])

    @property
    def det_A(self) -> np.ndarray:
        return self._get("det_A", lambda e: e.summary["det_A"])

    @property
    def det_B(self) -> np.ndarray:
        def build(e):
            with np.errstate(over="ignore", invalid="ignore"):
                return np.prod(e.matrices[1], axis=0)
        return self._get("det_B", build)

    @property
    def parallel_measure(self) -> np.ndarray:
        return self._get("parallel_measure", lambda e: e.parallel_measure)

    @property
    def serial_measure(self) -> np.ndarray:
        return self._get("serial_measure", lambda e: e.summary["serial"])

    @property
    def singularity(self) -> np.ndarray:
        return self._get("singularity", lambda e: e.summary["flags"])

    @property
    def tolerance(self) -> float:
        return self._get("tolerance", lambda e: e.tol)

    @property
    def q(self) -> np.ndarray:
        return self._get("q", lambda e: e.q)

    @property
    def mode(self) -> np.ndarray:
        return self._get(
            "mode", lambda e: np.sign(np.nan_to_num(e.summary["det_A"])).astype(int))
