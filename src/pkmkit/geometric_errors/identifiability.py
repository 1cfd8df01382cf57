"""Identifiability: which defects (or combinations of defects) a set of measurements can see.

**Identification Jacobian.** For a machine, a measurement type (:mod:`pkmkit.geometric_errors.
measurements`: tool point, full pose, ball-bar length, height, machined part) and N
configurations, the rows are the scalar readings of every configuration and the columns the
selected defects: ``J[(k, i), j] = ∂(reading i at configuration k)/∂δ_j``, computed
analytically through the closure. **Scaling** (documented, chosen by ``scaling``):

- ``"length"`` (default): angle-like defects (direction components, rad) are measured as
  ``L·δ`` — metres at the machine's characteristic length L (:func:`characteristic_length`) —
  and rotation readings as ``L·θ``; every column is then in metres of reading per metre of
  defect, so singular values and the observability indices are dimensionless and comparable;
- ``"norm"``: every column divided by its Euclidean norm (unit columns; within √p of the best
  diagonal scaling for the condition number, van der Sluis); a column below ``RTOL`` of the
  largest (a defect with no effect, round-off only) is divided by the largest norm instead, so
  that it stays negligible rather than becoming a unit column;
- ``"none"``: SI units as they are.

**Rank, base parameters and gauges.** The numerical rank counts singular values above
``rtol·σ_max``. QR with column pivoting picks ``rank`` independent columns — the **base
parameters** — in order of decreasing new information; every other column is a combination of
them, ``J_nb = J_b β``, so the measurements see exactly the combinations
``δ_b + β δ_nb`` (the **identifiable combinations**). A defect whose column vanishes is
**unidentifiable** (not seen at all); a defect that is not a base parameter but enters a
combination is **seen only together** with the defects of its group (connected by the
gauges). The null space of J (by SVD) gives the **gauges**: defect directions no measurement
of this type can see (reported reduced, one free defect each). SVD and QR must agree on the
rank; they are both computed and a disagreement is reported.

**Observability indices** (:func:`observability`) of a Jacobian with m rows and L columns and
singular values σ1 ≥ … ≥ σL: O1 = (σ1⋯σL)^(1/L)/√m (Borm & Menq 1991), O2 = σL/σ1 (the inverse
condition number, Driels & Pathre), O3 = σL (Nahvi et al.), O4 = σL²/σ1 (noise amplification,
Nahvi & Hollerbach 1996), O5 = 1/Σ(1/σi) (Sun & Hollerbach 2008); condition κ = σ1/σL. In
:func:`identifiability` they are those of the base parameters' columns (what an identification
of the identifiable combinations faces); the full Jacobian's are 0 when it is rank deficient.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import IdentifiabilityError, InputError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.measurements import measurement_jacobian, measurement_rows
from pkmkit.geometric_errors.model import defect_set
from pkmkit.geometric_errors.selection import select_defects
from pkmkit.numerics.pivoted_qr import pivoted_qr

SCALINGS = ("length", "norm", "none")
INDICES = ("O1", "O2", "O3", "O4", "O5")
#: Default relative rank tolerance.
RTOL = 1e-9
#: Coefficients below this (relative) are reported as zero.
COEF_TOL = 1e-8
#: Angle-like defect units.
ANGLE_UNITS = ("1", "rad")


def characteristic_length(machine) -> float:
    """The length L (m) that turns angle-like defects and rotation readings into metres: the
    closure scale of a joint-chain machine, the homogenising length of a full-pose machine, the
    mean equivalent-leg length of a translational one (``machine.length_scale``)."""
    return machine.length_scale


def default_setup(machine, kind: str, q: np.ndarray, setup: dict | None = None) -> dict:
    """The measurement setup with defaults filled in: for ``"part"``, the machined points are
    the nominal tool points (poses of a six-actuator machine) at q; for ``"ballbar"``, the
    pivot defaults to 0.1 × L below the mean tool point."""
    from pkmkit.geometric_errors.measurements import measure

    out = dict(setup or {})
    if kind == "part" and "points" not in out:
        six = machine.six_dof
        out["points"] = measure(machine, "pose" if six else "point", q)
    if kind == "ballbar" and "pivot" not in out:
        points = measure(machine, "point", q, out)
        out["pivot"] = points.mean(axis=0) - [0.0, 0.0, 0.1 * characteristic_length(machine)]
    return out


@dataclass(frozen=True)
class IdentificationJacobian:
    """A stacked, scaled identification Jacobian.

    Attributes:
        matrix: ``(M, p)`` scaled Jacobian (module docstring), M = N × rows per configuration.
        raw: ``(M, p)`` the same in SI units (rotation readings in rad).
        names, units: ``(p,)`` the defects (columns).
        column_scale: ``(p,)`` ``matrix = raw_rows × column_scale`` (m per SI unit of each
            defect: L for angle-like defects with ``"length"`` scaling).
        row_scale: ``(r,)`` scale of each reading of a configuration (L for rotation rows).
        kind: measurement type; rows: readings per configuration; n_poses: N.
        scaling: the scaling used; length: L (m).
    """

    matrix: np.ndarray
    raw: np.ndarray
    names: tuple[str, ...]
    units: tuple[str, ...]
    column_scale: np.ndarray
    row_scale: np.ndarray
    kind: str
    rows: int
    n_poses: int
    scaling: str
    length: float


@single_blas
def identification_jacobian(machine, kind: str, q: Any, setup: dict | None = None, *,
                            parameters: Any = None, kinds: Any = None, exclude: Any = None,
                            scope: str = "all", scaling: str = "length",
                            length: float | None = None,
                            compatible: bool = False) -> IdentificationJacobian:
    """The stacked identification Jacobian of ``kind`` readings at configurations ``q``
    ``(N, n)`` for the selected defects (module docstring for the scaling). With
    ``compatible``, the defects of the closed loops are restricted to their compatible
    subspace (:func:`compatible_parameters`).

    Raises:
        MeasurementError: a measurement type the machine cannot provide.
        ParameterError: a bad defect selection. InputError: bad q or scaling.
    """
    if scaling not in SCALINGS:
        raise InputError(f"unknown scaling {scaling!r}; valid: {', '.join(SCALINGS)}")
    rows = measurement_rows(machine, kind)
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.ndim != 2 or qb.shape[1] != machine.n_actuators:
        raise InputError(f"configurations must be (N, {machine.n_actuators}) actuator "
                         f"coordinates, got shape {np.shape(q)}")
    if not np.isfinite(qb).all():
        bad = int(np.flatnonzero(~np.isfinite(qb).all(axis=1))[0])
        raise InputError(f"configuration {bad} is not finite: {qb[bad].tolist()}")
    ds = defect_set(machine)
    full_setup = default_setup(machine, kind, qb, setup)
    if compatible:
        transform, names, units = compatible_parameters(machine, parameters, kinds=kinds,
                                                        exclude=exclude, scope=scope)
        jac = measurement_jacobian(machine, kind, qb, full_setup) @ transform
    elif isinstance(parameters, Mapping):
        transform, names, units = combined_parameters(machine, parameters)
        jac = measurement_jacobian(machine, kind, qb, full_setup) @ transform  # (N, r, p)
    else:
        columns = select_defects(machine, parameters, kinds=kinds, exclude=exclude,
                                 scope=scope)
        jac = measurement_jacobian(machine, kind, qb, full_setup)[:, :, columns]
        names = tuple(ds.names[i] for i in columns)
        units = tuple(ds.units[i] for i in columns)
    big_l = float(length) if length is not None else characteristic_length(machine)
    row_scale = np.ones(rows)
    if kind == "pose":
        row_scale[3:] = big_l
    raw = jac.reshape(-1, len(names))
    rows_scaled = (jac * row_scale[None, :, None]).reshape(-1, len(names))
    if scaling == "length":
        col = np.array([1.0 / big_l if u in ANGLE_UNITS else 1.0 for u in units])
    elif scaling == "norm":
        # a column with no effect (round-off only, below RTOL of the largest) is not blown up
        # to a unit column: it keeps the largest column's scale and stays negligible
        norms = np.linalg.norm(rows_scaled, axis=0)
        top = norms.max() if norms.size else 0.0
        alive = norms > RTOL * top
        col = np.where(alive, 1.0 / np.where(alive, norms, 1.0), 1.0 / top if top > 0 else 1.0)
    else:
        col = np.ones(len(names))
        rows_scaled = raw
    return IdentificationJacobian(matrix=rows_scaled * col, raw=raw, names=names, units=units,
                                  column_scale=col, row_scale=row_scale, kind=kind, rows=rows,
                                  n_poses=qb.shape[0], scaling=scaling, length=big_l)


def compatible_parameters(machine, parameters: Any = None, *, kinds: Any = None,
                          exclude: Any = None, scope: str = "all"
                          ) -> tuple[np.ndarray, tuple[str, ...], tuple[str, ...]]:
    """The selected defects restricted to the hyperstatic compatible subspace: the loop
    defects become the compatible basis
    (:func:`pkmkit.geometric_errors.compatibility.compatibility`),
    each named after its free defect (the others follow it through the conditions); head
    defects stay as they are. Returns ``(transform (d, p), names, units)``."""
    from pkmkit.geometric_errors.compatibility import compatibility
    from pkmkit.geometric_errors.selection import loop_defects

    ds = defect_set(machine)
    columns = select_defects(machine, parameters, kinds=kinds, exclude=exclude, scope=scope)
    loops = loop_defects(machine)
    loop_cols = [i for i in columns if loops[i]]
    cols, names, units = [], [], []
    if loop_cols:
        comp = compatibility(machine, [ds.names[i] for i in loop_cols])
        index = {n: ds.index(n) for n in comp.names}
        for j, free in enumerate(comp.free):
            col = np.zeros(len(ds))
            for name, value in zip(comp.names, comp.basis[:, j], strict=True):
                col[index[name]] = value
            cols.append(col)
            names.append(free)
            units.append(ds.units[index[free]])
    for i in columns:
        if not loops[i]:
            col = np.zeros(len(ds))
            col[i] = 1.0
            cols.append(col)
            names.append(ds.names[i])
            units.append(ds.units[i])
    return np.array(cols).T, tuple(names), tuple(units)


def combined_parameters(machine, groups: Mapping[str, Mapping[str, float]]
                        ) -> tuple[np.ndarray, tuple[str, ...], tuple[str, ...]]:
    """Parameters made of defects moving together: ``{"L": {"dL1": 1, "dL2": 1, "dL3": 1}}``
    is one rod length for the three rods (a delta printer's diagonal rod). Returns the map
    ``(d, p)`` from the new parameters to the defects, their names and units (those of their
    first defect).

    Raises:
        ParameterError: an unknown defect, an empty or non-finite group, mixed units.
    """
    from pkmkit.exceptions import ParameterError

    ds = defect_set(machine)
    if not groups:
        raise ParameterError("combined parameters: the mapping is empty")
    transform = np.zeros((len(ds), len(groups)))
    units = []
    for k, (name, members) in enumerate(groups.items()):
        if not isinstance(members, Mapping) or not members:
            raise ParameterError(f"combined parameter {name!r} needs a mapping defect → "
                                 "coefficient", str(name))
        unit_set = set()
        for defect, coef in members.items():
            value = float(coef)
            if not np.isfinite(value):
                raise ParameterError(f"combined parameter {name!r}: coefficient of {defect!r} "
                                     "is not finite", str(name))
            i = ds.index(defect)
            transform[i, k] += value
            unit_set.add(ds.units[i])
        if len(unit_set) > 1:
            raise ParameterError(f"combined parameter {name!r} mixes units "
                                 f"{', '.join(sorted(unit_set))}", str(name))
        units.append(unit_set.pop())
    return transform, tuple(str(n) for n in groups), tuple(units)


@single_blas
def observability(jacobian: Any, *, n_measurements: int | None = None) -> dict[str, float]:
    """The observability indices O1…O5 and the condition number of a Jacobian ``(m, L)``
    (module docstring). ``n_measurements`` is the m of O1 (default: the rows).

    Raises:
        InputError: not a finite 2-D array, or fewer rows than columns.
    """
    j = np.asarray(jacobian, dtype=float)
    if j.ndim != 2 or j.size == 0 or not np.isfinite(j).all():
        raise InputError("observability needs a finite, non-empty 2-D Jacobian")
    m, n_cols = j.shape
    if m < n_cols:
        raise InputError(f"the Jacobian has {m} rows for {n_cols} columns: its smallest "
                         f"{n_cols - m} singular values are 0; add measurements")
    sv = np.linalg.svd(j, compute_uv=False)
    return indices_from_singular_values(sv, n_measurements if n_measurements else m)


def indices_from_singular_values(sv: np.ndarray, m: int) -> dict[str, float]:
    """O1…O5 and the condition number from singular values (descending) and row count m."""
    sv = np.asarray(sv, dtype=float)
    smax, smin = float(sv[0]), float(sv[-1])
    with np.errstate(divide="ignore"):
        o1 = float(np.exp(np.mean(np.log(sv))) / np.sqrt(m)) if smin > 0 else 0.0
        o5 = float(1.0 / np.sum(1.0 / sv)) if smin > 0 else 0.0
    return {"O1": o1, "O2": smin / smax if smax > 0 else 0.0, "O3": smin,
            "O4": smin ** 2 / smax if smax > 0 else 0.0, "O5": o5,
            "condition": smax / smin if smin > 0 else float("inf")}


@dataclass(frozen=True)
class Combination:
    """An identifiable combination ``base + Σ coefficient · other`` (SI units).

    Attributes:
        base: the base parameter; terms: ``{name: coefficient}`` with the base first (1).
    """

    base: str
    terms: dict[str, float]

    def in_units(self, unit_value: Mapping[str, float]) -> Combination:
        """The same combination with each defect counted in another unit: ``unit_value[name]``
        is the SI value of one unit of that defect (1e-3 for a length in mm, π/180 for an
        angle in degrees). ``δ_b + Σ c δ_o`` (SI) becomes ``x_b + Σ c (u_o / u_b) x_o``."""
        ub = unit_value[self.base]
        return Combination(base=self.base, terms={n: c * unit_value[n] / ub
                                                  for n, c in self.terms.items()})

    def text(self, digits: int = 5) -> str:
        """``"dA1x − dB1x"`` style text."""
        out = [self.base]
        for name, c in list(self.terms.items())[1:]:
            mag = abs(c)
            body = name if np.isclose(mag, 1.0, rtol=1e-9, atol=0) else f"{mag:.{digits}g}·{name}"
            out.append(f" {'−' if c < 0 else '+'} {body}")
        return "".join(out)


@dataclass(frozen=True)
class IdentifiabilityResult:
    """Outcome of :func:`identifiability` (module docstring).

    Attributes:
        machine, kind: what was analysed; n_poses, n_measurements: N and M = N × rows.
        names: ``(p,)`` the parameters; rank: numerical rank (SVD); rank_qr: by pivoted QR.
        singular_values: ``(p,)`` of the scaled Jacobian, descending.
        condition: condition number of the base parameters' columns; indices: their O1…O5.
        base: the base parameters (QR order); combinations: what the measurements see.
        unidentifiable: parameters not seen at all (zero column).
        together: groups of parameters seen only in combination (each a tuple of names).
        identifiable: parameters identifiable on their own.
        gauges: ``(p, p − rank)`` SI basis of the invisible directions, reduced;
            gauge_terms: the same as ``{name: coefficient}`` dicts.
        rtol, scaling, length: settings.
        jacobian: the :class:`IdentificationJacobian`.
    """

    machine: str
    kind: str
    n_poses: int
    n_measurements: int
    names: tuple[str, ...]
    rank: int
    rank_qr: int
    singular_values: np.ndarray
    condition: float
    indices: dict[str, float]
    base: tuple[str, ...]
    combinations: tuple[Combination, ...]
    unidentifiable: tuple[str, ...]
    together: tuple[tuple[str, ...], ...]
    identifiable: tuple[str, ...]
    gauges: np.ndarray
    gauge_terms: tuple[dict[str, float], ...]
    rtol: float
    scaling: str
    length: float
    jacobian: IdentificationJacobian = field(repr=False)

    @property
    def n_parameters(self) -> int:
        """Number of parameters (columns)."""
        return len(self.names)

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary."""
        sv = self.singular_values
        return {
            "machine": self.machine, "measure": self.kind, "n_poses": self.n_poses,
            "n_measurements": self.n_measurements, "rank": self.rank,
            "rank_qr": self.rank_qr, "n_parameters": self.n_parameters,
            "parameters": list(self.names), "unidentifiable": list(self.unidentifiable),
            "together": [list(g) for g in self.together],
            "identifiable": list(self.identifiable), "base": list(self.base),
            "combinations": [c.text() for c in self.combinations],
            "combination_terms": [c.terms for c in self.combinations],
            "gauges": [dict(g) for g in self.gauge_terms],
            "indices": {k: self.indices[k] for k in INDICES},
            "condition": self.condition,
            "singular_values": sv.tolist(),
            "scaling": self.scaling, "characteristic_length": self.length,
            "rtol": self.rtol,
        }


@single_blas
def identifiability(machine, kind: str, q: Any, setup: dict | None = None, *,
                    parameters: Any = None, kinds: Any = None, exclude: Any = None,
                    scope: str = "all", scaling: str = "length", rtol: float = RTOL,
                    require_full_rank: bool = False,
                    compatible: bool = False) -> IdentifiabilityResult:
    """Rank, base parameters, identifiable combinations, gauges and observability indices of
    ``kind`` measurements at configurations ``q`` (module docstring).

    Raises:
        IdentifiabilityError: fewer scalar measurements than parameters (with the rank the
            measurements do reach), or a rank-deficient Jacobian with ``require_full_rank``.
        MeasurementError, ParameterError, InputError: as :func:`identification_jacobian`.
    """
    if not 0 < rtol < 1:
        raise InputError(f"rtol must be in (0, 1), got {rtol}")
    ij = identification_jacobian(machine, kind, q, setup, parameters=parameters, kinds=kinds,
                                 exclude=exclude, scope=scope, scaling=scaling,
                                 compatible=compatible)
    j = ij.matrix
    m, p = j.shape
    analysis = analyse_jacobian(j, ij.names, ij.column_scale, rtol=rtol)
    if m < p:
        raise IdentifiabilityError(
            f"{ij.n_poses} poses × {ij.rows} {kind} readings = {m} scalar measurements for {p} "
            f"parameters: at most {m} combinations can be identified (rank {analysis['rank']}); "
            "add poses or fix parameters", rank=analysis["rank"], n_parameters=p,
            n_measurements=m)
    if require_full_rank and analysis["rank"] < p:
        raise IdentifiabilityError(
            f"rank {analysis['rank']} of {p}: unidentifiable "
            f"{', '.join(analysis['unidentifiable']) or '-'}; seen only together: "
            f"{'; '.join(', '.join(g) for g in analysis['together']) or '-'}",
            rank=analysis["rank"], n_parameters=p, n_measurements=m)
    return IdentifiabilityResult(machine=machine.id, kind=kind, n_poses=ij.n_poses,
                                 n_measurements=m, rtol=rtol, scaling=scaling,
                                 length=ij.length, jacobian=ij, **analysis)


def analyse_jacobian(j: np.ndarray, names: tuple[str, ...], column_scale: np.ndarray, *,
                     rtol: float = RTOL) -> dict[str, Any]:
    """The rank analysis of a scaled Jacobian ``(M, p)`` (module docstring); ``column_scale``
    ``(p,)`` maps scaled coordinates x back to SI: ``j = raw · column_scale`` so
    ``δ = x · column_scale``. Combinations and gauges are returned in SI, the same whatever
    the scaling."""
    m, p = j.shape
    if m:
        _, sv_all, vt = np.linalg.svd(j, full_matrices=m < p)
    else:
        sv_all, vt = np.zeros(0), np.eye(p)
    sv = np.zeros(p)
    sv[:min(m, p)] = sv_all[:p]
    top = sv[0] if p and sv[0] > 0 else 0.0
    rank = int((sv > rtol * top).sum()) if top > 0 else 0
    null = vt[rank:].T  # scaled coordinates (p, p − rank)
    # QR with column pivoting: the base parameters
    if m:
        _, r, perm = pivoted_qr(j)
        diag = np.abs(np.diag(r))
        rank_qr = int((diag > rtol * diag[0]).sum()) if diag.size and diag[0] > 0 else 0
    else:
        perm, r, rank_qr = np.arange(p), np.zeros((0, p)), 0
    base_idx = perm[:rank]
    other = perm[rank:]
    col_norm = np.linalg.norm(j, axis=0)
    zero_col = col_norm <= rtol * max(top, 1e-300)
    beta = np.zeros((rank, p - rank))
    if rank and other.size:
        import scipy.linalg  # at first use: ≈ 0.3–0.6 s of imports `register` need not pay

        beta = scipy.linalg.solve_triangular(r[:rank, :rank], r[:rank, rank:], lower=False) \
            if r.shape[0] >= rank else np.linalg.lstsq(j[:, base_idx], j[:, other], rcond=None)[0]
        beta[np.abs(beta) < COEF_TOL * max(np.abs(beta).max(), 1e-300)] = 0.0
    combos = []
    for a, b in enumerate(base_idx):
        terms = {names[b]: 1.0}
        for k, o in enumerate(other):
            if beta[a, k] != 0.0 and not zero_col[o]:
                # scaled x_b + β x_o with δ = x · scale → δ_b + β (scale_b / scale_o) δ_o
                terms[names[o]] = float(beta[a, k] * column_scale[b] / column_scale[o])
        combos.append(Combination(base=names[b], terms=terms))
    # gauges, in SI coordinates, reduced; groups connected through them
    gauges_si = null * column_scale[:, None] if null.size else np.zeros((p, 0))
    from pkmkit.geometric_errors.compatibility import _reduced_basis

    gauges, _ = _reduced_basis(gauges_si)
    gauge_terms = []
    for g in gauges.T:
        big = np.abs(g).max()
        nz = np.flatnonzero(np.abs(g) > COEF_TOL * big)
        gauge_terms.append({names[i]: float(g[i]) for i in nz})
    alone = np.linalg.norm(null, axis=1) < 1e-6 if null.size else np.ones(p, dtype=bool)
    together = _groups([set(t) for t in gauge_terms],
                       {names[i] for i in np.flatnonzero(zero_col)}, names)
    condition_base = np.inf
    indices = dict.fromkeys(INDICES, 0.0)
    if rank:
        jb = j[:, base_idx]
        ind = indices_from_singular_values(np.linalg.svd(jb, compute_uv=False), m)
        condition_base = ind.pop("condition")
        indices = ind
    return {
        "names": names, "rank": rank, "rank_qr": rank_qr, "singular_values": sv,
        "condition": float(condition_base), "indices": indices,
        "base": tuple(names[i] for i in base_idx), "combinations": tuple(combos),
        "unidentifiable": tuple(names[i] for i in np.flatnonzero(zero_col)),
        "together": together,
        "identifiable": tuple(names[i] for i in range(p) if alone[i] and not zero_col[i]),
        "gauges": gauges, "gauge_terms": tuple(gauge_terms),
    }


def _groups(supports: list[set[str]], unseen: set[str], order: tuple[str, ...]
            ) -> tuple[tuple[str, ...], ...]:
    """Connected groups of the gauges' supports, without the parameters not seen at all."""
    groups: list[set[str]] = []
    for s in supports:
        s = s - unseen
        if len(s) < 2:
            continue
        merged = [g for g in groups if g & s]
        for g in merged:
            groups.remove(g)
            s |= g
        groups.append(s)
    rank = {n: i for i, n in enumerate(order)}
    out = [tuple(sorted(g, key=rank.__getitem__)) for g in groups]
    return tuple(sorted(out, key=lambda g: rank[g[0]]))
