"""Which parameters a calibration can identify, and which directions a hyperstatic machine's
geometry may take — the small linear-algebra interface the identification stands on.

Two questions, both answered on Jacobians evaluated at the measured configurations:

- **compatibility** (hyperstatic machines): a defect vector δ is *compatible* when the legs still
  close exactly, i.e. when its closure residual has no part that a motion can absorb
  (``closure_defect`` of :func:`pkmkit.geometric_errors.model.tool_sensitivity`, stacked over many
  configurations: ``C δ = 0``). :func:`compatible_directions` returns the compatible subspace
  as ``δ = N δ_free``: the *free* defects keep their names and the *dependent* ones (one per
  independent condition, chosen by QR with column pivoting on C) follow from them — so that the
  identified parameters are still named defects (e.g. ``dK21 = 0``, ``dK43 = dK53``);
- **identifiability**: which columns of a (tolerance-scaled) measurement Jacobian are
  independent. :func:`identifiable_parameters` selects them by QR with column pivoting, group by
  group (a priority order: e.g. the measurement frame before the machine, so that the machine
  defects that move the machine rigidly are reported as gauges of the frame), with a rank
  threshold relative to the largest column; every other parameter is left at its nominal value
  and the report says why (no effect on the readings, or the combination of selected
  parameters that it duplicates). :func:`prune_weak` then drops the parameters that the
  measurement noise would leave less known than their tolerance.

This is deliberately a small interface (arrays in, indices and reasons out) so that it can later
delegate to the error-analysis package's identifiability functions (issue 10:
``pkmkit.geometric_errors.identifiability`` — base parameters, gauges, observability indices)
without changing the calibration code that calls it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.pivoted_qr import pivoted_qr

#: Default relative rank threshold on the pivoted-QR diagonal of tolerance-scaled columns.
RCOND = 1e-7
#: Coefficients below this are not listed in a dependency.
_SHOW_COEF = 1e-3


@dataclass(frozen=True)
class CompatibleDirections:
    """The compatible subspace of a hyperstatic machine's defects, ``δ = basis @ δ_free``.

    Attributes:
        basis: ``(d, f)`` maps the free defects to the full defect vector.
        free: ``(f,)`` indices of the free defects (their columns of ``basis`` are unit vectors).
        dependent: ``(k,)`` indices of the defects fixed by a compatibility condition.
        relations: for each dependent defect name, ``{free name: coefficient}`` (empty: the
            defect must be zero).
        singular_values: of the scaled stacked closure matrix (what fixed the rank k).
    """

    basis: np.ndarray
    free: np.ndarray
    dependent: np.ndarray
    relations: dict[str, dict[str, float]]
    singular_values: np.ndarray

    def describe(self, name: str) -> str:
        """A sentence for a dependent defect: what compatibility imposes on it."""
        rel = self.relations[name]
        if not rel:
            return "fixed by compatibility: the legs cannot close with it (must be 0)"
        terms = " ".join(f"{c:+.3g}·{n}" for n, c in rel.items())
        return f"fixed by compatibility: follows {terms}"


def _one_thread():
    """Small dense linear algebra: one BLAS thread (a pool only loses time here, and collapses
    when another process holds a core)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def compatible_directions(closure_defect: np.ndarray, names: Sequence[str], scale: np.ndarray,
                          *, rcond: float = 1e-8) -> CompatibleDirections:
    """The compatible subspace from stacked incompatible closure parts.

    Args:
        closure_defect: ``(N, r, d)`` or ``(M, d)`` incompatible part of each defect's closure
            residual at many configurations (m per SI unit).
        names: ``(d,)`` defect names.
        scale: ``(d,)`` typical magnitude of each defect (its tolerance, SI): columns are
            compared at equal plausibility.
        rcond: singular values of the scaled matrix below ``rcond · σ_max`` do not count.
    """
    with _one_thread():
        return _compatible_directions(closure_defect, names, scale, rcond)


def _compatible_directions(closure_defect, names, scale, rcond) -> CompatibleDirections:
    c = np.asarray(closure_defect, dtype=float)
    c = c.reshape(-1, c.shape[-1])
    d = c.shape[1]
    names = list(names)
    if len(names) != d or np.shape(scale) != (d,):
        raise InputError("compatible_directions: names and scale must match the defects")
    cs = c * scale[None, :]
    if not np.isfinite(cs).all():
        raise InputError("compatible_directions: non-finite closure Jacobian")
    sv = np.linalg.svd(cs, compute_uv=False) if cs.size else np.zeros(0)
    if sv.size == 0 or sv[0] == 0.0:
        return CompatibleDirections(np.eye(d), np.arange(d), np.zeros(0, dtype=int), {}, sv)
    rank = int((sv > rcond * sv[0]).sum())
    # an orthonormal row basis of the conditions, then pivoted QR picks one defect per condition
    _, _, vt = np.linalg.svd(cs, full_matrices=False)
    rows = vt[:rank]
    _, _, piv = pivoted_qr(rows)
    dependent = np.sort(piv[:rank])
    free = np.setdiff1d(np.arange(d), dependent)
    # rows @ δ_scaled = 0  →  δ_D = −rows_D⁻¹ rows_F δ_F (scaled units)
    coef_scaled = -np.linalg.solve(rows[:, dependent], rows[:, free])
    coef = coef_scaled * scale[dependent][:, None] / scale[free][None, :]
    coef[np.abs(coef) < 1e-10] = 0.0
    basis = np.zeros((d, free.size))
    basis[free, np.arange(free.size)] = 1.0
    basis[dependent] = coef
    relations = {}
    for i, k in enumerate(dependent):
        big = np.flatnonzero(np.abs(coef[i]) > _SHOW_COEF)
        relations[names[k]] = {names[free[j]]: float(coef[i, j]) for j in big}
    return CompatibleDirections(basis, free, dependent, relations, sv)


@dataclass(frozen=True)
class IdentifiableSet:
    """Outcome of :func:`identifiable_parameters`.

    Attributes:
        names: ``(p,)`` candidate names.
        selected: indices of the identifiable parameters (ascending).
        rank: number selected (the numerical rank of the scaled Jacobian).
        condition: σ_max/σ_min of the selected scaled columns.
        singular_values: of the selected scaled columns.
        reasons: unselected name → why it is left at its nominal value.
        dependencies: unselected name → ``{selected name: coefficient}`` such that its column
            equals the combination (SI units): the identified values absorb it.
        residual: unselected name → relative norm of the column left after that combination
            (0 for an exact dependence, up to ``rcond`` for a near one).
    """

    names: tuple[str, ...]
    selected: np.ndarray
    rank: int
    condition: float
    singular_values: np.ndarray
    reasons: dict[str, str]
    dependencies: dict[str, dict[str, float]] = field(default_factory=dict)
    residual: dict[str, float] = field(default_factory=dict)

    @property
    def selected_names(self) -> tuple[str, ...]:
        """Names of the selected parameters."""
        return tuple(self.names[i] for i in self.selected)

    def base_values(self, values: np.ndarray) -> np.ndarray:
        """The values the selected parameters take when every candidate has ``values`` (SI):
        each selected parameter absorbs its share of the unselected ones (the identifiable
        combinations, to first order)."""
        values = np.asarray(values, dtype=float)
        out = values[self.selected].copy()
        pos = {self.names[i]: k for k, i in enumerate(self.selected)}
        for name, deps in self.dependencies.items():
            v = values[self.names.index(name)]
            for sel, c in deps.items():
                out[pos[sel]] += c * v
        return out


def identifiable_parameters(jacobian: np.ndarray, names: Sequence[str], scale: np.ndarray, *,
                            groups: Sequence[int] | None = None, rcond: float = RCOND,
                            group_labels: dict[int, str] | None = None) -> IdentifiableSet:
    """Select the identifiable parameters of a measurement Jacobian.

    Args:
        jacobian: ``(M, p)`` readings per unit parameter (SI), rows already weighted.
        names: ``(p,)`` parameter names.
        scale: ``(p,)`` typical magnitude (tolerance) of each parameter, SI.
        groups: ``(p,)`` priority of each column (0 first): columns of a later group are only
            selected for what the earlier groups do not explain. Default: one group.
        rcond: a column is selected when its pivoted-QR diagonal exceeds ``rcond`` times the
            largest scaled column norm.
        group_labels: names of the groups for the reasons (``{0: "the measurement frame"}``).

    Raises:
        InputError: mis-shaped or non-finite input.
    """
    with _one_thread():
        return _identifiable_parameters(jacobian, names, scale, groups, rcond, group_labels)


def _identifiable_parameters(jacobian, names, scale, groups, rcond, group_labels
                             ) -> IdentifiableSet:
    jac = np.asarray(jacobian, dtype=float)
    names = tuple(names)
    p = jac.shape[1] if jac.ndim == 2 else -1
    scale = np.asarray(scale, dtype=float)
    if jac.ndim != 2 or len(names) != p or scale.shape != (p,) or not (scale > 0).all():
        raise InputError("identifiable_parameters: jacobian (M, p), p names and p positive "
                         "scales are required")
    if not np.isfinite(jac).all():
        raise InputError("identifiable_parameters: the Jacobian has non-finite entries (a "
                         "configuration where the model fails)")
    groups = np.zeros(p, dtype=int) if groups is None else np.asarray(groups, dtype=int)
    a = jac * scale[None, :]
    norms = np.linalg.norm(a, axis=0)
    top = float(norms.max()) if p else 0.0
    labels = group_labels or {}
    selected: list[int] = []
    q_basis = np.zeros((a.shape[0], 0))
    for g in sorted(set(groups.tolist())):
        cols = np.flatnonzero(groups == g)
        proj = a[:, cols] - q_basis @ (q_basis.T @ a[:, cols])
        if proj.size == 0 or top == 0.0:
            continue
        qr_q, qr_r, piv = pivoted_qr(proj)
        diag = np.abs(np.diag(qr_r))
        keep = int((diag > rcond * top).sum())
        # pivoted QR diagonals decrease: the first `keep` pivots are independent
        selected += [int(cols[k]) for k in piv[:keep]]
        q_basis = np.concatenate([q_basis, qr_q[:, :keep]], axis=1)
    selected_arr = np.array(sorted(selected), dtype=int)
    sel_a = a[:, selected_arr]
    sv = np.linalg.svd(sel_a, compute_uv=False) if selected_arr.size else np.zeros(0)
    condition = float(sv[0] / sv[-1]) if sv.size and sv[-1] > 0 else float("inf")
    reasons: dict[str, str] = {}
    dependencies: dict[str, dict[str, float]] = {}
    residual: dict[str, float] = {}
    rest = np.setdiff1d(np.arange(p), selected_arr)
    if rest.size:
        coef_s = (np.linalg.lstsq(sel_a, a[:, rest], rcond=None)[0] if selected_arr.size
                  else np.zeros((0, rest.size)))
        left = a[:, rest] - sel_a @ coef_s
    for j, u in enumerate(rest):
        name = names[u]
        if norms[u] <= rcond * top or top == 0.0:
            reasons[name] = "no effect on these measurements"
            residual[name] = 0.0
            continue
        coef = coef_s[:, j] * scale[selected_arr] / scale[u]
        residual[name] = float(np.linalg.norm(left[:, j]) / norms[u])
        big = np.argsort(-np.abs(coef))
        deps = {names[selected_arr[k]]: float(coef[k]) for k in big
                if abs(coef[k]) > _SHOW_COEF}
        dependencies[name] = deps
        gauge_groups = sorted({int(groups[selected_arr[k]]) for k in big
                               if abs(coef[k]) > _SHOW_COEF and groups[selected_arr[k]]
                               < groups[u]})
        shown = list(deps.items())[:4]
        terms = " ".join(f"{c:+.3g}·{n}" for n, c in shown) + (" …" if len(deps) > 4 else "")
        if gauge_groups:
            what = " and ".join(labels.get(gr, f"group {gr}") for gr in gauge_groups)
            reasons[name] = f"gauge: absorbed by {what} ({terms})"
        elif residual[name] > 1e-6:
            reasons[name] = f"nearly a combination of identified parameters ({terms})"
        else:
            reasons[name] = f"a combination of identified parameters ({terms})"
    return IdentifiableSet(names=names, selected=selected_arr, rank=int(selected_arr.size),
                           condition=condition, singular_values=sv, reasons=reasons,
                           dependencies=dependencies, residual=residual)


@dataclass(frozen=True)
class WeakParameters:
    """Outcome of :func:`prune_weak`.

    Attributes:
        kept: indices (into the columns given) still identified.
        dropped: ``{index: (predicted std, scale)}`` of the parameters dropped, in order.
    """

    kept: np.ndarray
    dropped: dict[int, tuple[float, float]]


def prune_weak(jacobian: np.ndarray, scale: np.ndarray, *, sigma: float = 1.0,
               ratio: float = 1.0, keep: Sequence[int] = ()) -> WeakParameters:
    """Drop, worst first, the parameters whose predicted standard deviation (measurement noise
    ``sigma`` propagated through ``(JᵀJ)⁻¹``) exceeds ``ratio`` times their tolerance ``scale``:
    the measurements would know them less than the tolerance already does, so identifying them
    only fits noise.

    Args:
        jacobian: ``(M, p)`` readings per unit parameter (rows in the units of ``sigma``).
        scale: ``(p,)`` tolerances (SI).
        sigma: standard deviation of one reading.
        ratio: threshold on std/scale.
        keep: columns never dropped (e.g. setup parameters).
    """
    jac = np.asarray(jacobian, dtype=float) * np.asarray(scale)[None, :]
    kept = list(range(jac.shape[1]))
    dropped: dict[int, tuple[float, float]] = {}
    protected = set(int(k) for k in keep)
    while kept:
        sub = jac[:, kept]
        try:
            cov = np.linalg.inv(sub.T @ sub)
        except np.linalg.LinAlgError:
            cov = np.linalg.pinv(sub.T @ sub)
        rel = sigma * np.sqrt(np.clip(np.diag(cov), 0.0, None))  # std / scale
        order = [i for i in np.argsort(-rel) if kept[i] not in protected]
        if not order or rel[order[0]] <= ratio:
            break
        worst = order[0]
        dropped[kept[worst]] = (float(rel[worst] * scale[kept[worst]]), float(scale[kept[worst]]))
        kept.pop(worst)
    return WeakParameters(kept=np.array(kept, dtype=int), dropped=dropped)


# the error-analysis package's identifiability and pose selection, under the calibration
# namespace too (one implementation: pkmkit.geometric_errors.identifiability,
# pkmkit.geometric_errors.pose_selection)
from pkmkit.geometric_errors.identifiability import (  # noqa: E402, F401
    INDICES,
    Combination,
    IdentifiabilityResult,
    IdentificationJacobian,
    analyse_jacobian,
    characteristic_length,
    combined_parameters,
    compatible_parameters,
    identifiability,
    identification_jacobian,
    indices_from_singular_values,
    observability,
)
from pkmkit.geometric_errors.pose_selection import PoseSelection, select_poses  # noqa: E402, F401
