"""Tolerance analysis: from defect tolerances, the tool-position error over the workspace — by
first-order propagation and by Monte Carlo on the exact model.

**Tolerances.** Each defect δ_j gets a half-width t_j ≥ 0 (per defect, or per class = kind of
defect); defects without one stay at zero. The distribution is uniform on [−t, t] (variance
t²/3) or normal with σ = t/3 (variance t²/9). Tolerance file (TOML or YAML; see
docs/errors.md)::

    units = "mm"              # lengths of this file: m or mm (default m)
    angle_units = "mrad"      # angle-like defects: rad, mrad, urad, deg (default rad);
                              # direction components count as rad
    distribution = "uniform"  # or "normal" (σ = t/3)
    [classes]                 # one half-width per kind of defect
    length = 0.01
    axis = 0.05
    [parameters]              # per defect name or shell pattern; overrides the classes
    dL1 = 0.005
    "dA*z" = 0.05

**First order.** At a configuration with tool sensitivity J ``(3, d)``:
covariance ``Σ = J diag(var) Jᵀ``, RMS error ``√tr Σ`` and worst case ``Σ_j |J_j| t_j`` per axis.

**Monte Carlo.** S defect samples; for each configuration and sample the exact direct model of
the defected machine at the nominal actuator coordinates (the tool error is actual − nominal
tool point). Rod machines use the batched per-sample solver :mod:`pkmkit.solve.rod_samples`
(≥ 10⁶ pairs/s on the hexapod, see docs/benchmarks.md); joint-chain machines rebuild the
machine per sample (slower). The first-order prediction ``J δ`` of the same samples is kept
too: percentiles of both, and their largest difference (the nonlinearity).
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, ParameterError, ToleranceFileError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.identifiability import ANGLE_UNITS
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity
from pkmkit.machines.defect_samples import exact_rod_points, nominal_gains
from pkmkit.numerics.magnitudes import MAX_SAMPLED, check_count

__all__ = ["AccuracyMap", "FirstOrderError", "MonteCarloResult", "Tolerances", "accuracy_map",
           "exact_rod_points", "first_order_error", "monte_carlo", "nominal_gains",
           "read_tolerances", "tolerances"]

DISTRIBUTIONS = ("uniform", "normal")
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "µm": 1e-6}
ANGLE_SCALES = {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "µrad": 1e-6, "deg": np.pi / 180.0}
PERCENTILES = (50.0, 95.0, 99.0, 100.0)
#: Largest tolerance half-width of a length-like defect (m) and of an angle-like one (rad):
#: defects are small displacements; beyond these the file is in another unit than it says.
MAX_LENGTH_TOLERANCE = 0.1
MAX_ANGLE_TOLERANCE = 0.1


@dataclass(frozen=True)
class Tolerances:
    """Half-widths of every defect of a machine.

    Attributes:
        names: ``(d,)`` every defect of the machine; half_width: ``(d,)`` SI (0: exact).
        distribution: ``"uniform"`` or ``"normal"`` (σ = t/3).
        source: where they came from (file path or ``"python"``).
    """

    names: tuple[str, ...]
    half_width: np.ndarray
    distribution: str = "uniform"
    source: str = "python"

    @property
    def variance(self) -> np.ndarray:
        """``(d,)`` variance of each defect (SI²)."""
        t2 = self.half_width ** 2
        return t2 / 3.0 if self.distribution == "uniform" else t2 / 9.0

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``(n, d)`` defect samples."""
        d = len(self.names)
        if self.distribution == "uniform":
            return (2.0 * rng.random((n, d)) - 1.0) * self.half_width
        return rng.standard_normal((n, d)) * (self.half_width / 3.0)

    def active(self) -> tuple[str, ...]:
        """Defects with a non-zero tolerance."""
        return tuple(n for n, t in zip(self.names, self.half_width, strict=True) if t > 0)


def tolerances(machine, parameters: dict[str, float] | None = None,
               classes: dict[str, float] | None = None, *,
               distribution: str = "uniform") -> Tolerances:
    """Tolerances from half-widths in SI units per defect name/pattern and per class (kind);
    names override classes.

    Raises:
        ParameterError: unknown names, patterns or classes; negative or non-finite widths; an
            unknown distribution.
    """
    ds = defect_set(machine)
    if distribution not in DISTRIBUTIONS:
        raise ParameterError(f"unknown distribution {distribution!r}; valid: "
                             f"{', '.join(DISTRIBUTIONS)}", "distribution")
    width = np.zeros(len(ds))
    kinds = np.asarray(ds.kinds)
    for cls, value in (classes or {}).items():
        t = _width(value, f"class {cls!r}")
        if cls not in set(ds.kinds):
            raise ParameterError(f"unknown defect class {cls!r} for {machine.id!r}; classes: "
                                 f"{', '.join(sorted(set(ds.kinds)))}", cls)
        width[kinds == cls] = t
    for name, value in (parameters or {}).items():
        t = _width(value, f"parameter {name!r}")
        width[_matches(ds.names, name)] = t
    return Tolerances(names=ds.names, half_width=width, distribution=distribution)


def _width(value: Any, what: str) -> float:
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{what}: the tolerance must be a number, got {value!r}") from None
    if not np.isfinite(t) or t < 0:
        raise ParameterError(f"{what}: the tolerance (half-width) must be finite and ≥ 0, got "
                             f"{value!r}")
    return t


def _matches(names: tuple[str, ...], pattern: str) -> np.ndarray:
    if set("*?[") & set(pattern):
        hit = np.array([fnmatch.fnmatchcase(n, pattern) for n in names])
    else:
        hit = np.array([n == pattern for n in names])
    if not hit.any():
        preview = ", ".join(names[:12]) + (", …" if len(names) > 12 else "")
        raise ParameterError(f"unknown defect {pattern!r}; defects are named like {preview}",
                             pattern)
    return hit


def _tolerance_header(data: dict, fail) -> tuple[str, str, str]:
    """``(units, angle_units, distribution)`` of a tolerance file; unknown keys raise."""
    allowed = {"units", "angle_units", "distribution", "classes", "parameters"}
    for key in data:
        if key not in allowed:
            raise fail(f"unknown key {key!r}; valid keys: {', '.join(sorted(allowed))}", (key,))
    units = data.get("units", "m")
    if units not in LENGTH_UNITS:
        raise fail(f"unknown length unit {units!r}; valid: {', '.join(LENGTH_UNITS)}",
                   ("units",))
    angle_units = data.get("angle_units", "rad")
    if angle_units not in ANGLE_SCALES:
        raise fail(f"unknown angle unit {angle_units!r}; valid: {', '.join(ANGLE_SCALES)}",
                   ("angle_units",))
    distribution = data.get("distribution", "uniform")
    if distribution not in DISTRIBUTIONS:
        raise fail(f"unknown distribution {distribution!r}; valid: "
                   f"{', '.join(DISTRIBUTIONS)}", ("distribution",))
    return units, angle_units, distribution


def _half_width(section: str, key: str, value: Any, fail) -> float:
    """One tolerance value: a finite number ≥ 0 (in the file's units)."""
    where = (section, key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise fail(f"{section}.{key}: the tolerance must be a number, got {value!r}", where)
    try:  # an integer too large for a float (400 digits) is not finite
        number = float(value)
    except OverflowError:
        number = np.inf
    if not np.isfinite(number) or number < 0:
        raise fail(f"{section}.{key}: the tolerance is a half-width and must be ≥ 0, "
                   f"got {value!r}", where)
    return number


def read_tolerances(path: str, machine) -> Tolerances:
    """Tolerances from a file (module docstring).

    Raises:
        ToleranceFileError: unreadable file, unknown key, unit, class or defect, negative or
            non-numeric width — with the file line.
    """
    from pkmkit.exceptions import MachineFileError
    from pkmkit.model.machine_file import read_machine_document

    try:
        doc = read_machine_document(path)
    except MachineFileError as exc:
        raise ToleranceFileError(exc.path, str(exc).split(": ", 1)[-1], exc.line) from None

    def fail(message: str, key: tuple) -> ToleranceFileError:
        return ToleranceFileError(str(path), message, doc.line_of(key))

    data = doc.data
    units, angle_units, distribution = _tolerance_header(data, fail)
    ds = defect_set(machine)
    scale_len, scale_ang = LENGTH_UNITS[units], ANGLE_SCALES[angle_units]

    def to_si(unit: str, value: float) -> float:
        return value * (scale_ang if unit in ANGLE_UNITS else scale_len)

    width = np.zeros(len(ds))
    kinds = np.asarray(ds.kinds)
    for section in ("classes", "parameters"):
        table = data.get(section, {})
        if not isinstance(table, dict):
            raise fail(f"[{section}] must be a table of name = half-width", (section,))
        for key, value in table.items():
            where = (section, key)
            number = _half_width(section, key, value, fail)
            if section == "classes":
                if key not in set(ds.kinds):
                    raise fail(f"unknown defect class {key!r} for {machine.id!r}; classes: "
                               f"{', '.join(sorted(set(ds.kinds)))}", where)
                hit = np.flatnonzero(kinds == key)
            else:
                try:
                    hit = np.flatnonzero(_matches(ds.names, str(key)))
                except ParameterError as exc:
                    raise fail(str(exc), where) from None
            for i in hit:
                width[i] = to_si(ds.units[i], number)
                _check_size(width[i], ds.units[i] in ANGLE_UNITS, units, angle_units, fail,
                            where, value)
    return Tolerances(names=ds.names, half_width=width, distribution=distribution,
                      source=str(path))


def _check_size(si: float, angle: bool, units: str, angle_units: str, fail, where: tuple,
                value: float) -> None:
    """Refuse a half-width beyond :data:`MAX_LENGTH_TOLERANCE` / :data:`MAX_ANGLE_TOLERANCE`
    (a file in another unit than it states: 1e300, or millimetres read as metres)."""
    limit = MAX_ANGLE_TOLERANCE if angle else MAX_LENGTH_TOLERANCE
    if si <= limit:
        return
    unit = angle_units if angle else units
    shown = limit / (ANGLE_SCALES[unit] if angle else LENGTH_UNITS[unit])
    hint = ('; did you mean units = "mm"?' if not angle and units == "m"
            and si * 1e-3 <= limit else "")
    raise fail(f"{'.'.join(where)}: a half-width of {value!r} {unit} is beyond {shown:g} {unit}, "
               f"the largest tolerance of {'an angle' if angle else 'a length'}-like defect "
               f"(defects are small displacements){hint}", where)


@dataclass(frozen=True)
class FirstOrderError:
    """First-order tool-point error at N configurations.

    Attributes:
        rms: ``(N,)`` √tr Σ (m). covariance: ``(N, 3, 3)`` (m²).
        worst_case: ``(N, 3)`` Σ_j |J_j| t_j per axis (m); worst_norm: ``(N,)`` its norm.
    """

    rms: np.ndarray
    covariance: np.ndarray
    worst_case: np.ndarray
    worst_norm: np.ndarray


@single_blas
def first_order_error(machine, q: Any, tol: Tolerances, *, tool_length: Any = None
                      ) -> FirstOrderError:
    """First-order propagation of ``tol`` to the tool point at configurations q (module
    docstring)."""
    sens = tool_sensitivity(machine, q, tool_length=tool_length)
    j = sens.point  # (N, 3, d)
    cov = np.einsum("nad,d,nbd->nab", j, tol.variance, j)
    worst = np.abs(j) @ tol.half_width
    return FirstOrderError(rms=np.sqrt(np.trace(cov, axis1=1, axis2=2)), covariance=cov,
                           worst_case=worst, worst_norm=np.linalg.norm(worst, axis=1))


@dataclass(frozen=True)
class MonteCarloResult:
    """Monte Carlo tolerance analysis at N configurations with S samples.

    Attributes:
        error: ``(N, S, 3)`` exact tool-point errors (m; NaN where the defected machine does not
            assemble); norm: ``(N, S)`` their norms.
        linear: ``(N, S, 3)`` first-order prediction of the same samples.
        percentiles: ``(N, len(levels))`` of the norm per configuration (m); levels: the
            percentile levels; overall: ``{level: value}`` over every pair.
        nonlinearity: largest |exact − first order| (m).
        failed: pairs that did not assemble. samples: ``(S, d)`` the defects drawn.
        rate: (configuration, sample) evaluations per second of the exact model.
    """

    error: np.ndarray
    norm: np.ndarray
    linear: np.ndarray
    percentiles: np.ndarray
    levels: tuple[float, ...]
    overall: dict[float, float]
    linear_overall: dict[float, float]
    nonlinearity: float
    failed: int
    rate: float
    samples: np.ndarray = field(repr=False)


@single_blas
def monte_carlo(machine, q: Any, tol: Tolerances, n_samples: int, *, seed: int | None = 0,
                levels: tuple[float, ...] = PERCENTILES, tool_length: Any = None
                ) -> MonteCarloResult:
    """Monte Carlo tolerance analysis on the exact model (module docstring).

    Raises:
        InputError: n_samples < 1, bad q.
    """
    import time

    qb = np.atleast_2d(np.asarray(q, dtype=float))
    n_samples = check_count(n_samples, "n_samples", max(MAX_SAMPLED // max(len(qb), 1), 1),
                            lower=f"{len(qb)} configurations × n_samples must not exceed "
                                  f"{MAX_SAMPLED:.3g} sampled machines")
    rng = np.random.default_rng(seed)
    samples = tol.sample(int(n_samples), rng)
    sens = tool_sensitivity(machine, qb, tool_length=tool_length)
    nominal = sens.pose[:, :3]
    start = time.perf_counter()
    actual = machine.sampled_tool_points(qb, samples, tool_length=tool_length)
    elapsed = time.perf_counter() - start
    error = actual - nominal[:, None, :]
    linear = np.einsum("nad,sd->nsa", sens.point, samples)
    norm = np.linalg.norm(error, axis=2)
    failed = int(np.isnan(norm).sum())
    with np.errstate(invalid="ignore"):
        pct = np.nanpercentile(norm, levels, axis=1).T if norm.size else np.zeros((0,))
        overall = dict(zip(levels, np.nanpercentile(norm, levels).tolist(), strict=True))
        lin_norm = np.linalg.norm(linear, axis=2)
        lin_overall = dict(zip(levels, np.percentile(lin_norm, levels).tolist(), strict=True))
        nonlin = float(np.nanmax(np.linalg.norm(error - linear, axis=2)))
    return MonteCarloResult(error=error, norm=norm, linear=linear, percentiles=pct,
                            levels=tuple(levels), overall=overall, linear_overall=lin_overall,
                            nonlinearity=nonlin, failed=failed,
                            rate=qb.shape[0] * samples.shape[0] / max(elapsed, 1e-12),
                            samples=samples)


@dataclass(frozen=True)
class AccuracyMap:
    """Tool-position error percentile over a plane of the region.

    Attributes:
        axes: the two region coordinates mapped (names); x, y: ``(nx,)``, ``(ny,)`` values.
        fixed: ``{name: value}`` of the other region coordinates.
        exact: ``(ny, nx)`` percentile ``level`` of the exact Monte Carlo error norm (m; NaN
            where unreachable); first_order: the same for the first-order prediction of the
            same samples; rms: ``(ny, nx)`` first-order RMS (m).
        level: the percentile; n_samples: samples per point; result: the Monte Carlo result of
            the reachable points.
    """

    axes: tuple[str, str]
    x: np.ndarray
    y: np.ndarray
    fixed: dict[str, float]
    exact: np.ndarray
    first_order: np.ndarray
    rms: np.ndarray
    level: float
    n_samples: int
    result: MonteCarloResult = field(repr=False)


@single_blas
def accuracy_map(machine, tol: Tolerances, *, n_samples: int = 200, resolution: int = 21,
                 region: Any = None, axes: tuple[int, int] = (0, 1),
                 fixed: dict[int, float] | None = None, level: float = 95.0,
                 seed: int | None = 0, tool_length: Any = None) -> AccuracyMap:
    """Percentile ``level`` of the tool-point error over a grid of two region coordinates
    (others at the middle of the region, or ``fixed``), exact (Monte Carlo) and first order.

    Raises:
        InputError: bad axes, resolution or level; no reachable grid point.
    """
    from pkmkit.geometric_errors.configurations import check_region, configurations_at, region_names

    lo, hi = check_region(machine, region)
    names = region_names(machine)
    if len(set(axes)) != 2 or not all(0 <= a < lo.size for a in axes):
        raise InputError(f"axes must be two distinct indices among {lo.size} region "
                         f"coordinates ({', '.join(names)})")
    if not 2 <= check_count(resolution, "resolution", 501):
        raise InputError(f"resolution must be in [2, 501], got {resolution}")
    check_count(n_samples, "n_samples", max(MAX_SAMPLED // int(resolution) ** 2, 1),
                lower=f"n_samples × resolution² must not exceed {MAX_SAMPLED:.3g} sampled "
                      "machines")
    if not 0 < level <= 100:
        raise InputError(f"level must be in (0, 100], got {level}")
    xs = np.linspace(lo[axes[0]], hi[axes[0]], int(resolution))
    ys = np.linspace(lo[axes[1]], hi[axes[1]], int(resolution))
    mid = (lo + hi) / 2.0
    for k, v in (fixed or {}).items():
        mid[k] = float(v)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.tile(mid, (gx.size, 1))
    pts[:, axes[0]] = gx.ravel()
    pts[:, axes[1]] = gy.ravel()
    with np.errstate(invalid="ignore"):
        q = configurations_at(machine, pts)
    ok = np.isfinite(q).all(axis=1)
    if not ok.any():
        raise InputError("no point of the map's plane is reachable; choose another region")
    levels = tuple(sorted({*PERCENTILES, float(level)}))
    mc = monte_carlo(machine, q[ok], tol, n_samples, seed=seed, levels=levels,
                     tool_length=tool_length)
    fo = first_order_error(machine, q[ok], tol, tool_length=tool_length)
    exact = np.full(gx.size, np.nan)
    lin = np.full(gx.size, np.nan)
    rms = np.full(gx.size, np.nan)
    exact[ok] = mc.percentiles[:, levels.index(float(level))]
    lin[ok] = np.percentile(np.linalg.norm(mc.linear, axis=2), level, axis=1)
    rms[ok] = fo.rms
    shape = gx.shape
    return AccuracyMap(axes=(names[axes[0]], names[axes[1]]), x=xs, y=ys,
                       fixed={names[k]: float(mid[k]) for k in range(lo.size)
                              if k not in axes},
                       exact=exact.reshape(shape), first_order=lin.reshape(shape),
                       rms=rms.reshape(shape), level=level, n_samples=int(n_samples), result=mc)
