"""Hyperstatic compatibility: which defect combinations an over-constrained machine can still
assemble and move with — the automated version of seed 002's "stationarity" analysis
(Guyon 2021, §4.2–4.4; notes §3.9).

**Method.** At a configuration the closure, linearised in its unknowns U (platform pose and
passive joints) and in the defects δ, reads ``C_U dU + C_δ δ = 0``. A defect vector is
assemblable there iff ``C_δ δ`` lies in the range of ``C_U``, i.e. iff ``Nᵀ C_δ δ = 0`` with N
a basis of the left null space of ``C_U`` (its dimension is the degree of hyperstatism h). The
machine must assemble *and move*: the condition must hold at every configuration, so the
projected blocks ``Nₖᵀ C_δ,ₖ`` of many configurations are stacked into S and the compatible
defects are the null space of S. Its row space holds the conditions:

- (a) a parameter is **forced to zero** when its unit vector lies in the row space of S;
- (b) the other conditions are linear relations between defects, reported in reduced row
  echelon form (each solved for one defect) with readable coefficients;
- (c) the **compatible subspace** is the null space of S: its dimension and a basis (reduced
  so that each basis vector sets one "free" defect to 1).

Configurations where ``C_U`` loses rank (singular ones, whose left null space is larger) are
left out. Columns of S are scaled by the norm of the defect's unprojected closure columns (its
effect before any absorption), which makes the relative rank tolerance independent of units;
the singular values on either side of the rank and their ratio (the gap) are reported.

First order only: a compatible direction may still become incompatible at second order (not
checked). Machines whose closure is square (every rod machine modelled by its equivalent legs,
an isostatic chain) have no condition: everything is compatible.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.model import closure_linearisation, defect_set
from pkmkit.geometric_errors.selection import select_defects

#: Default relative tolerance on the scaled singular values of S.
RTOL = 1e-8
#: Relative tolerance for the per-configuration rank of C_U.
CLOSURE_RTOL = 1e-9
#: Coefficients below this (relative to the largest of a condition) are printed as zero.
COEF_TOL = 1e-7


@dataclass(frozen=True)
class Condition:
    """One linear condition ``Σ coefficient · defect = 0`` (SI units of the defects).

    Attributes:
        terms: ``{name: coefficient}``, the pivot defect first with coefficient 1.
        unit: unit of the pivot defect; the coefficient of a defect of another unit carries
            ``unit / its unit`` (e.g. m for a direction component in a condition on positions).
    """

    terms: dict[str, float]
    unit: str

    def text(self, digits: int = 5) -> str:
        """``"da21 + db51 − da23 = 0"`` style text."""
        out = []
        for k, (name, c) in enumerate(self.terms.items()):
            mag = abs(c)
            sign = "−" if c < 0 else "+"
            body = name if np.isclose(mag, 1.0, rtol=1e-9, atol=0) else f"{mag:.{digits}g}·{name}"
            out.append((("−" + body) if c < 0 else body) if k == 0 else f" {sign} {body}")
        return "".join(out) + " = 0"


@dataclass(frozen=True)
class CompatibilityResult:
    """Outcome of :func:`compatibility`.

    Attributes:
        machine: machine id.
        names: ``(p,)`` the defects analysed; units: their units.
        forced_zero: defects that must vanish for the machine to assemble and move.
        conditions: the other independent conditions (:class:`Condition`).
        compatible_dimension: dimension of the compatible subspace.
        basis: ``(p, k)`` basis of the compatible subspace (SI), reduced: column j has 1 at
            ``free[j]`` and 0 at every other free defect.
        free: the defects that can be chosen freely (one per basis vector).
        independent: free defects that appear in no condition (compatible on their own).
        no_effect: defects that do not enter the closure at all (always compatible).
        singular_values: ``(p,)`` of the column-scaled stacked matrix S, descending.
        rank: number of independent conditions (len(forced_zero) + len(conditions)).
        gap: ``(σ_rank, σ_rank+1)``: the smallest kept and the largest dropped singular value
            (NaN where there is none); ``gap_ratio`` their ratio.
        rtol: the relative rank tolerance used.
        hyperstatism: dimension of the left null space of C_U (equations the unknowns cannot
            absorb) at the configurations used; configurations: how many were used;
            dropped: how many singular ones were left out.
        scale: ``(p,)`` column scales (m of closure residual per SI unit of defect).
        q: ``(N, n)`` the configurations used.
    """

    machine: str
    names: tuple[str, ...]
    units: tuple[str, ...]
    forced_zero: tuple[str, ...]
    conditions: tuple[Condition, ...]
    compatible_dimension: int
    basis: np.ndarray
    free: tuple[str, ...]
    independent: tuple[str, ...]
    no_effect: tuple[str, ...]
    singular_values: np.ndarray
    rank: int
    gap: tuple[float, float]
    gap_ratio: float
    rtol: float
    hyperstatism: int
    configurations: int
    dropped: int
    scale: np.ndarray = field(repr=False)
    q: np.ndarray = field(repr=False)

    @property
    def clear_gap(self) -> bool:
        """True when the rank is unambiguous: a gap of at least 10⁴ between the kept and the
        dropped singular values (or nothing on one side)."""
        return not np.isfinite(self.gap_ratio) or self.gap_ratio >= 1e4

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary (names, conditions as text and as coefficients)."""
        return {
            "machine": self.machine,
            "n_parameters": len(self.names),
            "parameters": list(self.names),
            "forced_zero": list(self.forced_zero),
            "conditions": [c.text() for c in self.conditions],
            "condition_terms": [{"terms": c.terms, "unit": c.unit} for c in self.conditions],
            "compatible_dimension": self.compatible_dimension,
            "free": list(self.free),
            "independent": list(self.independent),
            "no_effect": list(self.no_effect),
            "rank": self.rank,
            "hyperstatism": self.hyperstatism,
            "configurations": self.configurations,
            "dropped_singular_configurations": self.dropped,
            "singular_value_gap": {"kept": self.gap[0], "dropped": self.gap[1],
                                   "ratio": self.gap_ratio, "clear": self.clear_gap},
            "rtol": self.rtol,
        }


def compatibility_configurations(machine, n: int = 40, *, seed: int | None = 0) -> np.ndarray:
    """``(n, n_act)`` configurations for the compatibility test. Compatibility is a property of
    the mechanism, not of its strokes: joint-chain loop actuators are spread over home ±
    :data:`~pkmkit.geometric_errors.configurations.CHAIN_SPREAD` (strokes ignored), head
    actuators stay
    at home; rod machines use their default region (the machine's own draw,
    ``machine.mechanism_configurations``: :mod:`pkmkit.machines.error_regions`)."""
    return machine.mechanism_configurations(n, seed=seed)


def projected_defects(machine, q: np.ndarray, columns: np.ndarray
                      ) -> tuple[list[np.ndarray], np.ndarray, np.ndarray, int]:
    """Per configuration, ``Nₖᵀ C_δ`` for the selected defect ``columns``.

    Returns:
        (blocks, rank of C_U per configuration, unprojected column norms ``(p,)``, h).
    """
    lin = closure_linearisation(machine, q)
    cu, cd = lin.unknowns, lin.defects[:, :, columns]
    u, s, _ = np.linalg.svd(cu)
    ranks = (s > CLOSURE_RTOL * s[:, :1]).sum(axis=1)
    generic = int(ranks.max())
    blocks = [u[k, :, generic:].T @ cd[k] for k in range(len(q)) if ranks[k] == generic]
    norms = np.sqrt((cd ** 2).sum(axis=(0, 1)) / len(q))
    return blocks, ranks, norms, cu.shape[1] - generic


@single_blas
def compatibility(machine, parameters: Any = None, *, kinds: Any = None, exclude: Any = None,
                  orientation_only: bool = False, reference_nominal: bool = False,
                  q: Any = None, n_configurations: int = 40, seed: int | None = 0,
                  rtol: float = RTOL) -> CompatibilityResult:
    """Hyperstatic compatibility of ``machine``'s defects (module docstring).

    Args:
        machine: any machine (the test is meaningful for over-constrained ones).
        parameters, kinds, exclude: the defects analysed
            (:func:`pkmkit.geometric_errors.selection.select_defects`); default every defect of the
            closed loops (a serial head's defects cannot be incompatible).
        orientation_only: analyse only the orientation defects (axis tilts; positions, spins
            held at zero) — the thesis's setting (its ``DeltaParamNul``).
        reference_nominal: hold the first joint of the first leg nominal, as the thesis does
            (D_ICS^L11 of the Tripteor, D_R0^L1 of the crank–slider).
        q: ``(N, n)`` configurations; default :func:`compatibility_configurations`.
        n_configurations, seed: for the default configurations.
        rtol: relative rank tolerance on the scaled singular values.

    Raises:
        ParameterError: a bad selection. InputError: bad configurations or tolerance.
    """
    if not 0 < rtol < 1:
        raise InputError(f"rtol must be in (0, 1), got {rtol}")
    ds = defect_set(machine)
    if orientation_only:
        kinds = "orientation"
    columns = select_defects(machine, parameters, kinds=kinds, exclude=exclude, scope="loops",
                             reference_nominal=reference_nominal)
    names = tuple(ds.names[i] for i in columns)
    units = tuple(ds.units[i] for i in columns)
    qb = compatibility_configurations(machine, n_configurations, seed=seed) if q is None else (
        np.atleast_2d(np.asarray(q, dtype=float)))
    blocks, _, norms, hyper = projected_defects(machine, qb, columns)
    p = len(columns)
    no_effect = norms <= 1e-12 * max(float(norms.max()), 1e-300)
    scale = np.where(no_effect, 1.0, norms)
    if blocks and blocks[0].shape[0] > 0:
        stacked = np.concatenate(blocks) / scale
    else:
        stacked = np.zeros((0, p))
    if stacked.shape[0]:
        _, sv, vt = np.linalg.svd(stacked, full_matrices=True)
    else:
        sv, vt = np.zeros(0), np.eye(p)
    sv_full = np.zeros(p)
    sv_full[:sv.size] = sv[:p]
    top = sv_full[0] if sv_full.size and sv_full[0] > 0 else 0.0
    rank = int((sv_full > rtol * top).sum()) if top > 0 else 0
    kept = float(sv_full[rank - 1]) if rank > 0 else np.nan
    dropped = float(sv_full[rank]) if rank < p else np.nan
    ratio = kept / dropped if (rank > 0 and rank < p and dropped > 0) else np.inf
    row_space = vt[:rank]  # scaled coordinates
    null = vt[rank:].T  # (p, k) scaled
    # (a) forced to zero: unit vector in the row space ⇔ its null-space row vanishes
    null_rows = np.linalg.norm(null, axis=1) if null.size else np.zeros(p)
    forced = null_rows < 1e-6
    # (b) remaining conditions: the row space with the forced coordinates removed
    rest = row_space[:, ~forced]
    cond_rows = _rref(rest, rank - int(forced.sum()))
    free_idx = np.flatnonzero(~forced)
    conditions = []
    for row in cond_rows:
        coef = np.zeros(p)
        coef[free_idx] = row
        conditions.append(_condition(coef, scale, names, units))
    # (c) compatible basis in SI coordinates, reduced on its own pivots
    basis_si = null / scale[:, None] if null.size else np.zeros((p, 0))
    basis, pivots = _reduced_basis(basis_si)
    involved = set()
    for c in conditions:
        involved |= set(c.terms)
    free = tuple(names[i] for i in pivots)
    independent = tuple(n for i, n in enumerate(names) if not forced[i] and n not in involved)
    return CompatibilityResult(
        machine=machine.id, names=names, units=units,
        forced_zero=tuple(n for i, n in enumerate(names) if forced[i]),
        conditions=tuple(conditions), compatible_dimension=p - rank, basis=basis, free=free,
        independent=independent,
        no_effect=tuple(n for i, n in enumerate(names) if no_effect[i]),
        singular_values=sv_full, rank=rank, gap=(kept, dropped), gap_ratio=float(ratio),
        rtol=rtol, hyperstatism=hyper, configurations=len(blocks),
        dropped=int(len(qb) - len(blocks)), scale=scale, q=qb)


def _rref(rows: np.ndarray, rank: int, tol: float = 1e-9) -> list[np.ndarray]:
    """Reduced row echelon form of the row space of ``rows`` (``rank`` rows expected),
    pivoting on the columns in order (partial pivoting within a column)."""
    if rank <= 0 or rows.size == 0:
        return []
    # an orthonormal basis of the row space first (drops the dependent rows cleanly)
    _, _, vt = np.linalg.svd(rows, full_matrices=False)
    a = vt[:rank].copy()
    m, n = a.shape
    r = 0
    for c in range(n):
        if r == m:
            break
        piv = r + int(np.argmax(np.abs(a[r:, c])))
        if abs(a[piv, c]) < tol:
            a[r:, c] = 0.0
            continue
        a[[r, piv]] = a[[piv, r]]
        a[r] /= a[r, c]
        for i in range(m):
            if i != r:
                a[i] -= a[i, c] * a[r]
        r += 1
    return [row for row in a[:r]]


def _condition(coef_scaled: np.ndarray, scale: np.ndarray, names, units) -> Condition:
    """A condition in SI coordinates from scaled coefficients: Σ c_i (s_i δ_i) = 0."""
    coef = coef_scaled * scale
    nz = np.flatnonzero(np.abs(coef) > COEF_TOL * np.abs(coef).max())
    pivot = int(nz[0])
    coef = coef / coef[pivot]
    order = [pivot, *[int(i) for i in nz if i != pivot]]
    return Condition(terms={names[i]: float(coef[i]) for i in order}, unit=units[pivot])


def _reduced_basis(basis: np.ndarray, tol: float = 1e-9) -> tuple[np.ndarray, list[int]]:
    """Column-reduced basis of span(basis) ``(p, k)`` and its pivot rows (one per column)."""
    if basis.size == 0:
        return basis, []
    t = _rref(basis.T, basis.shape[1], tol)
    out = np.array(t).T
    pivots = [int(np.flatnonzero(np.abs(col) > tol)[0]) for col in out.T]
    out[np.abs(out) < 1e-12] = 0.0
    return out, pivots
