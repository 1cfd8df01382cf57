"""Batched Levenberg–Marquardt for many small, independent least-squares problems.

Direct kinematics, inverse kinematics of whole machines, passive-joint recovery and parameter
identification are all the same problem: find ``u`` with ``r(u; knowns) = 0`` in the
least-squares sense. This module solves N such problems at once, one per row, with vectorised
NumPy (no per-row Python loop):

- each row has its own damping factor, acceptance test and convergence flag; rows that have
  converged leave the active set and cost nothing more;
- steps solve the damped normal equations ``(JᵀJ + λ (D + εI)) δ = −Jᵀr`` with Marquardt's
  diagonal scaling D plus a small isotropic floor ε, so rank-deficient Jacobians (unobservable
  directions, over-constrained closures with redundant rows) give finite steps with no component
  along the null space; the final numerical rank of each row's Jacobian is reported;
- unknowns may live on a manifold: the caller's ``retract(u, δ)`` applies a step (e.g. a
  rotation update ``R ← exp(δ)R``); Jacobians are taken with respect to that local increment;
- warm starts: the caller passes the initial guesses ``u0`` (e.g. the previous solution along a
  path).

**Layout.** Inside the engine and in the ``evaluate`` callback the batch axis is *last*
(structure of arrays): ``u (n, k)``, ``r (m, k)``, ``J (m, n, k)``. Each problem is only a few
dozen scalar operations, so this layout makes every NumPy call one long loop over the batch
(several times faster than stacks of tiny matrices). The normal equations are solved by a
vectorised Cholesky factorisation for up to :data:`SMALL` unknowns, by LAPACK beyond.

**Block structure** (optional, :class:`BlockPattern`). Closures of several legs on one platform,
and identification problems with per-pose unknowns, have *bordered block-diagonal* normal
equations: a few *shared* unknowns (the platform pose) touch every residual row, and each group
of rows (one leg) has *private* unknowns (its passive joints) that no other group's rows see.
Given that pattern, the engine forms only the non-zero blocks of ``JᵀJ`` and solves the damped
system by the Schur complement on the shared unknowns (vectorised Cholesky throughout) — the
same step as the dense path, to rounding, at a fraction of the cost.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.rowwise import einsum
from pkmkit.status import Status

#: ``evaluate(u (n, k), rows (k,)) -> (r (m, k), J (m, n, k))`` for the given rows of the batch.
#: The engine copies what it keeps, so ``evaluate`` may reuse its output arrays between calls.
Evaluate = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
#: ``retract(u (n, k), delta (n, k), rows (k,)) -> u_new (n, k)``.
Retract = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]

#: Largest number of unknowns solved by the vectorised Cholesky factorisation.
SMALL = 8


@dataclass(frozen=True)
class BlockPattern:
    """Sparsity of the Jacobian that makes ``JᵀJ`` bordered block-diagonal.

    Attributes:
        shared: column indices that may be non-zero in any row (e.g. the platform pose).
        groups: one ``(rows, columns)`` pair per group: the group's *private* columns are zero
            outside its rows. Rows of different groups are disjoint; rows in no group may only
            involve shared columns. Every column is shared or private to exactly one group.
    """

    shared: tuple[int, ...]
    groups: tuple[tuple[tuple[int, ...], tuple[int, ...]], ...]

    def check(self, n_rows: int, n_cols: int) -> None:
        """Raise :class:`~pkmkit.exceptions.InputError` when the pattern does not partition the
        columns or its groups' rows overlap."""
        cols = list(self.shared) + [c for _, cs in self.groups for c in cs]
        if sorted(cols) != list(range(n_cols)):
            raise InputError(f"block pattern columns {sorted(cols)} do not partition "
                             f"range({n_cols})")
        rows = [r for rs, _ in self.groups for r in rs]
        if len(set(rows)) != len(rows) or (rows and not 0 <= min(rows) <= max(rows) < n_rows):
            raise InputError("block pattern groups must have disjoint rows within the residual")


def _index(ids) -> slice | list[int]:
    """A slice for contiguous increasing indices (a view, no copy), else the list."""
    ids = list(ids)
    if ids and ids == list(range(ids[0], ids[0] + len(ids))):
        return slice(ids[0], ids[0] + len(ids))
    return ids


class _BlockNormal:
    """``JᵀJ`` of a :class:`BlockPattern`: ``A`` (shared × shared), per group ``B_g`` (shared ×
    private) and ``C_g`` (private × private), batch last."""

    def __init__(self, pattern: BlockPattern, a, b, c):
        self.pattern, self.a, self.b, self.c = pattern, a, b, c

    @classmethod
    def of(cls, jac: np.ndarray, pattern: BlockPattern) -> _BlockNormal:
        n_shared = len(pattern.shared)
        j_s = jac[:, _index(pattern.shared)]
        a = normal_matrix(j_s)
        b, c = [], []
        for rows, cols in pattern.groups:
            r_idx, c_idx = _index(rows), _index(cols)
            j_g = jac[r_idx][:, c_idx]
            j_sg = j_s[r_idx]
            b_g = np.empty((n_shared, len(cols), jac.shape[2]))
            for i in range(n_shared):
                for j in range(len(cols)):
                    b_g[i, j] = einsum("mk,mk->k", j_sg[:, i], j_g[:, j])
            b.append(b_g)
            c.append(normal_matrix(j_g))
        return cls(pattern, a, b, c)

    def diagonal(self) -> np.ndarray:
        """``(n, k)`` diagonal of ``JᵀJ`` in column order."""
        n = len(self.pattern.shared) + sum(len(cs) for _, cs in self.pattern.groups)
        out = np.empty((n, self.a.shape[2]))
        s = np.arange(len(self.pattern.shared))
        out[list(self.pattern.shared)] = self.a[s, s]
        for (_, cols), c_g in zip(self.pattern.groups, self.c, strict=True):
            i = np.arange(len(cols))
            out[list(cols)] = c_g[i, i]
        return out

    def add_diagonal(self, values: np.ndarray) -> None:
        """Add ``values (n, k)`` (column order) to the diagonal, in place."""
        s = np.arange(len(self.pattern.shared))
        self.a[s, s] += values[list(self.pattern.shared)]
        for (_, cols), c_g in zip(self.pattern.groups, self.c, strict=True):
            i = np.arange(len(cols))
            c_g[i, i] += values[list(cols)]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve ``JᵀJ x = rhs`` by the Schur complement on the shared unknowns."""
        shared = _index(self.pattern.shared)
        schur = self.a.copy()
        top = rhs[shared].copy()
        solved = []
        for (_, cols), b_g, c_g in zip(self.pattern.groups, self.b, self.c, strict=True):
            # C_g⁻¹ [B_gᵀ | rhs_g] in one factorisation
            stacked = np.concatenate([np.swapaxes(b_g, 0, 1), rhs[_index(cols)][:, None]],
                                     axis=1)
            z = solve_spd_many(c_g, stacked)
            schur -= einsum("ijk,jlk->ilk", b_g, z[:, :-1])
            top -= einsum("ijk,jk->ik", b_g, z[:, -1])
            solved.append(z)
        x = np.empty_like(rhs)
        x_s = solve_spd(schur, top)
        x[shared] = x_s
        for (_, cols), z in zip(self.pattern.groups, solved, strict=True):
            x[_index(cols)] = z[:, -1] - einsum("jik,ik->jk", z[:, :-1], x_s)
        return x


@dataclass(frozen=True)
class SolveResult:
    """Outcome of :func:`solve_least_squares` for a batch of N problems.

    Attributes:
        u: ``(N, n)`` solutions (the last accepted iterate; check ``status``).
        status: ``(N,)`` int :class:`~pkmkit.status.Status` codes: ``OK`` (converged, residual
            within ``residual_tol``), ``INCONSISTENT`` (converged to a non-zero residual),
            ``NOT_CONVERGED`` (iteration limit), ``INVALID_INPUT`` (non-finite start or
            residual).
        residual: ``(N,)`` largest absolute residual component at the solution.
        iterations: ``(N,)`` iterations used by each row.
        rank: ``(N,)`` numerical rank of each row's final Jacobian.
    """

    u: np.ndarray
    status: np.ndarray
    residual: np.ndarray
    iterations: np.ndarray
    rank: np.ndarray

    @property
    def ok(self) -> np.ndarray:
        """``(N,)`` bool, rows that converged to a zero residual."""
        return self.status == Status.OK


def normal_matrix(jac: np.ndarray) -> np.ndarray:
    """``JᵀJ`` for batch-last Jacobians ``(m, n, k)`` → ``(n, n, k)`` (one pass over the batch
    per entry; a few large problems, where that is n²/2 passes over a short batch, by matrix
    products instead)."""
    n = jac.shape[1]
    if n > 2 * SMALL and jac.shape[2] <= n:
        stacked = np.ascontiguousarray(jac.transpose(2, 0, 1))  # (k, m, n)
        return np.ascontiguousarray((stacked.transpose(0, 2, 1) @ stacked).transpose(1, 2, 0))
    out = np.empty((n, n, jac.shape[2]))
    for i in range(n):
        for j in range(i + 1):
            out[i, j] = out[j, i] = einsum("mk,mk->k", jac[:, i], jac[:, j])
    return out


def solve_spd(h: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``H x = b`` for batch-last symmetric positive-definite ``H (n, n, k)``, ``b (n, k)``.

    Vectorised Cholesky for n ≤ :data:`SMALL`; LAPACK otherwise.
    """
    n = h.shape[0]
    if n > SMALL:
        return np.linalg.solve(h.transpose(2, 0, 1), b.T[:, :, None])[:, :, 0].T
    low = np.zeros_like(h)
    for j in range(n):
        s = h[j, j] - (low[j, :j] ** 2).sum(axis=0)
        low[j, j] = np.sqrt(s)
        for i in range(j + 1, n):
            low[i, j] = (h[i, j] - (low[i, :j] * low[j, :j]).sum(axis=0)) / low[j, j]
    y = np.empty_like(b)
    for i in range(n):
        y[i] = (b[i] - (low[i, :i] * y[:i]).sum(axis=0)) / low[i, i]
    x = np.empty_like(b)
    for i in range(n - 1, -1, -1):
        x[i] = (y[i] - (low[i + 1 :, i] * x[i + 1 :]).sum(axis=0)) / low[i, i]
    return x


def solve_spd_many(h: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve ``H X = B`` for batch-last SPD ``H (n, n, k)`` and ``B (n, r, k)`` (vectorised
    Cholesky for n ≤ :data:`SMALL`, accumulating in place; LAPACK otherwise)."""
    n = h.shape[0]
    if n > SMALL:
        return np.linalg.solve(h.transpose(2, 0, 1), b.transpose(2, 0, 1)).transpose(1, 2, 0)
    low = np.zeros_like(h)
    for j in range(n):
        s = h[j, j].copy()
        for m in range(j):
            s -= low[j, m] * low[j, m]
        low[j, j] = np.sqrt(s)
        inv = 1.0 / low[j, j]
        for i in range(j + 1, n):
            s = h[i, j].copy()
            for m in range(j):
                s -= low[i, m] * low[j, m]
            low[i, j] = s * inv
    x = np.array(b, dtype=float)
    for i in range(n):  # L y = b
        for m in range(i):
            x[i] -= low[i, m] * x[m]
        x[i] /= low[i, i]
    for i in range(n - 1, -1, -1):  # Lᵀ x = y
        for m in range(i + 1, n):
            x[i] -= low[m, i] * x[m]
        x[i] /= low[i, i]
    return x


def _batch(a: np.ndarray, idx: slice | np.ndarray) -> np.ndarray:
    """The batch entries ``idx`` of a batch-last array, contiguous (a fancy index on the last
    axis, ``a[..., idx]``, strides the batch axis and slows every later pass several-fold)."""
    return a[..., idx] if isinstance(idx, slice) else np.take(a, idx, axis=-1)


def _add(u: np.ndarray, delta: np.ndarray, rows: np.ndarray) -> np.ndarray:
    return u + delta


def solve_least_squares(
    evaluate: Evaluate,
    u0: np.ndarray,
    *,
    retract: Retract | None = None,
    max_iter: int = 60,
    xtol: float = 1e-14,
    atol: float = 1e-14,
    gtol: float = 1e-12,
    stall: float = 0.01,
    residual_tol: float = 1e-9,
    damping: float = 1e-4,
    rcond: float = 1e-10,
    compute_rank: bool = True,
    pattern: BlockPattern | None = None,
    crawl: tuple[int, float] | None = None,
) -> SolveResult:
    """Solve N independent nonlinear least-squares problems ``min ½‖r(u)‖²`` in one batch.

    Args:
        evaluate: residuals and Jacobians of a subset of rows, batch axis last (see
            :data:`Evaluate` and the module docstring).
        u0: ``(N, n)`` initial guesses (warm starts).
        retract: how a step is applied (default: addition), batch axis last.
        max_iter: iteration limit per row.
        xtol: a row stops when an accepted step is shorter than ``xtol · (1 + ‖u‖)``.
        atol: a row stops when its residual norm is below ``atol`` (exact solution reached).
        gtol: a row stops when the residual is orthogonal to every Jacobian column within this
            cosine (a least-squares stationary point, exact or not).
        stall: a row whose residual is still above ``residual_tol`` stops when ten iterations
            reduced its cost by less than this fraction (Gauss–Newton crawls on large-residual
            problems, e.g. actuator coordinates with no assembly): it is ``INCONSISTENT``.
        residual_tol: a stopped row is ``OK`` when its largest residual is below this
            (units of the residuals), else ``INCONSISTENT``.
        damping: initial Levenberg–Marquardt factor λ (relative, Marquardt-scaled).
        rcond: singular values below ``rcond · σ_max`` do not count in the reported rank.
        compute_rank: report each row's final Jacobian rank (one eigen-decomposition per row);
            with False, ``rank`` is −1.
        pattern: the Jacobian's block structure, if any (:class:`BlockPattern`): the normal
            equations are then formed and solved block by block (module docstring).
        crawl: ``(k, ρ)``: a row whose largest |residual| after k iterations is still above ρ
            leaves then as ``NOT_CONVERGED`` — an earlier iteration limit for rows nowhere near
            a solution (Newton near a regular solution has long converged), e.g. the positions
            beyond a machine's reach of a workspace grid; None: no such limit.

    Returns:
        :class:`SolveResult` (batch axis first).
    """
    retract = retract or _add
    # (n, N) C-contiguous: batch-last arrays whose batch axis is contiguous, whether every row
    # is active (a view of u) or some (a copy): the same arithmetic for a row either way
    u = np.array(np.asarray(u0, dtype=float).T, order="C", copy=True)
    n, n_rows = u.shape
    rows_all = np.arange(n_rows)
    valid = np.isfinite(u).all(axis=0)
    iterations = np.zeros(n_rows, dtype=int)
    residual = np.full(n_rows, np.nan)
    rank = np.zeros(n_rows, dtype=int)
    status = np.full(n_rows, int(Status.INVALID_INPUT))
    if not valid.any():
        return SolveResult(u.T.copy(), status, residual, iterations, rank)

    live = rows_all[valid]
    r_live, j_live = evaluate(u[:, live], live)
    m = r_live.shape[0]
    if pattern is not None:
        pattern.check(m, n)
    if live.size == n_rows:  # every start valid: the evaluation's arrays, no NaN fill
        r, jac = np.array(r_live), np.array(j_live)
    else:
        r = np.full((m, n_rows), np.nan)
        jac = np.full((m, n, n_rows), np.nan)
        r[:, live], jac[:, :, live] = r_live, j_live
    cost = np.full(n_rows, np.inf)
    cost[live] = 0.5 * einsum("mk,mk->k", r_live, r_live)
    del r_live, j_live  # copied: the evaluation's arrays may be freed when the batch shrinks
    valid &= np.isfinite(cost) & np.isfinite(jac).all(axis=(0, 1))
    lam = np.full(n_rows, float(damping))
    checkpoint = cost.copy()  # cost ten iterations ago, for the stall test
    active = valid.copy()
    stopped = np.zeros(n_rows, dtype=bool)
    diag_idx = np.arange(n)

    for _ in range(max_iter):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        if idx.size == n_rows:  # every row active: slices avoid copies
            idx = slice(None)
        j_a, r_a = _batch(jac, idx), _batch(r, idx)
        grad = einsum("mnk,mk->nk", j_a, r_a)
        # stationary (cosine test) or exact rows stop before stepping (and before JᵀJ)
        columns = einsum("mnk,mnk->nk", j_a, j_a)  # the diagonal of JᵀJ
        with np.errstate(invalid="ignore", divide="ignore"):
            cosine = np.abs(grad) / np.sqrt(columns * (2.0 * cost[idx]))
        stop = (cost[idx] <= 0.5 * atol * atol) | ~(np.nan_to_num(cosine, nan=0.0).max(
            axis=0) > gtol)
        if stop.any():
            rows = rows_all[idx][stop]
            stopped[rows] = True
            active[rows] = False
            keep = ~stop
            if not keep.any():
                break
            idx = rows_all[idx][keep]
            j_a, r_a, grad = (np.compress(keep, j_a, axis=-1), np.compress(keep, r_a, axis=-1),
                              grad[:, keep])
        if pattern is None:
            jtj = normal_matrix(j_a)
            diag = jtj[diag_idx, diag_idx]  # (n, k)
        else:
            jtj = _BlockNormal.of(j_a, pattern)
            diag = jtj.diagonal()
        floor = 1e-9 * diag.max(axis=0) + 1e-300
        if pattern is None:
            jtj[diag_idx, diag_idx] += lam[idx] * (diag + floor)
            step = -solve_spd(jtj, grad)
        else:
            jtj.add_diagonal(lam[idx] * (diag + floor))
            step = -jtj.solve(grad)
        u_new = retract(_batch(u, idx), step, idx)
        # the active rows' Jacobians (a copy when some rows have left) and the previous
        # evaluation's are not needed any more: freed before the evaluation makes new ones
        del j_a, r_a, jtj
        r_new = j_new = None
        r_new, j_new = evaluate(u_new, idx)
        cost_new = 0.5 * einsum("mk,mk->k", r_new, r_new)
        # accept rounding-level increases: near a solution the cost stops being informative
        accept = np.isfinite(cost_new) & (cost_new <= cost[idx] * (1.0 + 1e-13))
        iterations[idx] += 1
        if isinstance(idx, slice):
            idx = rows_all

        took = idx[accept]
        if took.size == idx.size == n_rows:
            u[:], r[:], jac[:], cost[:] = u_new, r_new, j_new, cost_new
        else:
            u[:, took] = u_new[:, accept]
            r[:, took] = r_new[:, accept]
            jac[:, :, took] = np.compress(accept, j_new, axis=-1)
            cost[took] = cost_new[accept]
        lam[took] = np.maximum(lam[took] * 0.1, 1e-12)
        lam[idx[~accept]] *= 10.0

        step_norm = np.sqrt(einsum("nk,nk->k", step, step))
        u_norm = np.sqrt(einsum("nk,nk->k", u[:, idx], u[:, idx]))
        small = step_norm <= xtol * (1.0 + u_norm)
        done = (accept & small) | (lam[idx] > 1e12)
        at_checkpoint = iterations[idx] % 10 == 0
        if at_checkpoint.any():
            rows = idx[at_checkpoint]
            crawling = (cost[rows] > (1.0 - stall) * checkpoint[rows]) & (
                cost[rows] > 0.5 * residual_tol**2
            )
            done[at_checkpoint] |= crawling
            checkpoint[rows] = cost[rows]
        stopped[idx[done]] = True
        active[idx[done]] = False
        if crawl is not None:
            at_limit = (iterations[idx] == crawl[0]) & ~done
            if at_limit.any():  # far from any solution after k iterations: NOT_CONVERGED
                rows = idx[at_limit]
                active[rows[np.abs(r[:, rows]).max(axis=0) > crawl[1]]] = False

    live = rows_all[valid]
    residual[live] = np.abs(r[:, live]).max(axis=0)
    status[valid] = Status.NOT_CONVERGED
    status[stopped & (residual <= residual_tol)] = Status.OK
    status[stopped & ~(residual <= residual_tol)] = Status.INCONSISTENT
    if compute_rank:
        eig = np.linalg.eigvalsh(normal_matrix(jac[:, :, live]).transpose(2, 0, 1))  # σ²
        rank[live] = (eig > (rcond**2) * eig[:, -1:]).sum(axis=1)
    else:
        rank[:] = -1
    return SolveResult(u=u.T.copy(), status=status, residual=residual, iterations=iterations,
                       rank=rank)
