"""Dimensional optimisation of any machine: variables, objectives, constraints, optimisers.

A :class:`DesignProblem` varies scalar parameters of a machine within bounds — named parameters
of a built-in kind (``R``, ``angles[1]``) or leg fields of a ``rod-legs`` machine
(``legs[0].length``, ``legs[2].base[0]``; see :mod:`pkmkit.design.design_space`) — and scores
each candidate with the metrics of :mod:`pkmkit.design.metrics` (or user functions) evaluated on
a prescribed region. The region must satisfy the criteria (``violation == 0``) unless told
otherwise; further constraints bound any metric. A variable that changes none of the metrics
(e.g. a stroke limit, which the metrics ignore) is refused before the run.

- one objective: SciPy's ``differential_evolution`` (constraints by feasibility rules) or CMA-ES
  (``cma`` package, constraints by penalty);
- several objectives: NSGA-II from ``pymoo``; the result is the Pareto front of the feasible
  designs.

Runs are reproducible (``seed``), show a progress bar (``tqdm``) when asked, and keep every
evaluated design, so the results can be written as CSV/JSON and plotted. Values are SI inside;
the writers convert to command-line units on request (lengths in m or mm, angles in degrees) and
every output names its units.
"""

from __future__ import annotations

import csv
import json
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit import parallel
from pkmkit.analysis.workspace import Criteria
from pkmkit.design.design_space import (
    ScalarParameter,
    boundary_factor,
    boundary_unit,
    check_names,
    with_values,
)
from pkmkit.design.metrics import (
    METRIC_QUANTITIES,
    METRICS,
    ON_REQUEST,
    Region,
    metric_values,
)
from pkmkit.exceptions import InputError, ParameterError
from pkmkit.io.atomic import atomic_path, write_text_atomic
from pkmkit.io.json_io import to_jsonable
from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale

UserMetric = Callable[[Machine], float]


@dataclass(frozen=True)
class Variable:
    """A design variable: a scalar parameter of the machine (``R``, a vector component
    ``angles[1]``, a leg field ``legs[0].length``; see :mod:`pkmkit.design.design_space`),
    varied within ``[lower, upper]`` (SI units)."""

    name: str
    lower: float
    upper: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.lower) and np.isfinite(self.upper)):
            raise InputError(f"variable {self.name}: bounds must be finite")
        if not self.lower < self.upper:
            raise InputError(f"variable {self.name}: empty range [{self.lower:g}, "
                             f"{self.upper:g}] (lower must be below upper)")


@dataclass(frozen=True)
class Objective:
    """Minimise or maximise a metric: ``Objective("stroke", "min")``."""

    metric: str
    sense: str = "min"

    @classmethod
    def parse(cls, text: str) -> Objective:
        """``"min:stroke"`` or ``"max:gci"``."""
        sense, sep, metric = text.partition(":")
        if not sep or sense not in ("min", "max") or not metric:
            raise InputError(f"objective {text!r}: use min:METRIC or max:METRIC")
        return cls(metric.strip(), sense)

    def value(self, metrics: dict[str, float]) -> float:
        """The metric in minimisation form (NaN → +inf)."""
        v = metrics[self.metric]
        v = v if self.sense == "min" else -v
        return float(v) if np.isfinite(v) else float("inf")


@dataclass(frozen=True)
class Constraint:
    """A bound on a metric: ``Constraint("lambda_min", ">=", 0.5)``."""

    metric: str
    op: str
    value: float

    @classmethod
    def parse(cls, text: str) -> Constraint:
        """``"worst_condition<=4"`` or ``"compactness>=0.5"``."""
        m = re.fullmatch(r"\s*(\w+)\s*(<=|>=)\s*(\S+)\s*", text)
        if m is None:
            raise InputError(f"constraint {text!r}: use METRIC<=VALUE or METRIC>=VALUE")
        try:
            value = float(m.group(3))
        except ValueError:
            value = float("nan")
        if not np.isfinite(value):
            raise InputError(f"constraint {text!r}: {m.group(3)!r} is not a finite number")
        return cls(m.group(1), m.group(2), value)

    def excess(self, metrics: dict[str, float]) -> float:
        """> 0 when violated (by how much), ≤ 0 when satisfied; NaN → +inf."""
        v = metrics[self.metric]
        if not np.isfinite(v):
            return float("inf")
        return float(v - self.value if self.op == "<=" else self.value - v)


@dataclass
class DesignProblem:
    """What to vary, what to optimise, and on which region.

    Attributes:
        base: the machine whose parameters are varied (its other parameters stay); a built-in
            kind or a ``rod-legs`` machine from a file.
        variables: design variables (distinct names, see :mod:`pkmkit.design.design_space`).
        objectives: one (single-objective) or more (Pareto) objectives.
        constraints: bounds on metrics; ``violation <= 0`` is added unless ``require_region``
            is False.
        region: the prescribed square/cube.
        criteria: transmission-factor / conditioning bounds over the region.
        user_metrics: extra metrics ``name -> f(machine)``.
        samples: grid points per edge of the region.
        require_region: add the constraint ``violation <= 0``.
        evaluator: computes the metrics of a candidate (default
            :func:`pkmkit.design.metrics.metric_values`, batched over the region's poses).
        parameters: the varied parameters by name, with their quantity (set on creation).

    Raises:
        InputError: no variable or objective, a duplicate or unknown variable, a region whose
            centre does not fit the machine, an unknown metric.
    """

    base: Machine
    variables: Sequence[Variable]
    objectives: Sequence[Objective]
    region: Region
    criteria: Criteria = field(default_factory=Criteria)
    constraints: Sequence[Constraint] = ()
    user_metrics: dict[str, UserMetric] = field(default_factory=dict)
    samples: int = 11
    require_region: bool = True
    evaluator: Callable[..., dict[str, float]] = metric_values
    parameters: dict[str, ScalarParameter] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.variables:
            raise InputError("give at least one design variable")
        if not self.objectives:
            raise InputError("give at least one objective")
        self.parameters = check_names(self.base, [v.name for v in self.variables])
        self.region.check(self.base)
        known = set(METRICS) | set(self.user_metrics)
        for item in [*self.objectives, *self.constraints]:
            if item.metric not in known:
                raise InputError(f"unknown metric {item.metric!r}; valid: "
                                 f"{', '.join(sorted(known))}")
        if self.require_region:
            self.constraints = (*self.constraints, Constraint("violation", "<=", 0.0))

    @property
    def bounds(self) -> np.ndarray:
        """``(n_var, 2)`` lower and upper bounds."""
        return np.array([[v.lower, v.upper] for v in self.variables])

    @property
    def metric_names(self) -> tuple[str, ...]:
        """Built-in metrics the objectives and constraints need."""
        names = {o.metric for o in self.objectives} | {c.metric for c in self.constraints}
        return tuple(sorted(n for n in names if n in METRICS))

    def quantity(self, column: str) -> str:
        """Quantity of a variable or metric column: ``"length"``, ``"area"``, ``"angle"`` or
        ``"number"`` (user metrics: ``"number"``)."""
        if column in self.parameters:
            return self.parameters[column].quantity
        return METRIC_QUANTITIES.get(column, "number")

    def build(self, x: np.ndarray) -> Machine | None:
        """The candidate machine for variable values ``x`` (None if the parameters are
        inconsistent, e.g. rods too short for the home pose)."""
        values = {var.name: float(value) for var, value in zip(self.variables, x, strict=True)}
        try:
            return with_values(self.base, values)
        except ParameterError:
            return None

    def inert_variables(self) -> list[str]:
        """Variables that change none of the metrics.

        Each variable is set to its lower bound, its upper bound and a point at 30 % of its
        range (not the middle, so that a range symmetric about a symmetric design cannot give
        equal values by symmetry), the others at mid-range, and every metric of
        :data:`~pkmkit.design.metrics.METRICS` (``inscribed_side`` and ``min_stiffness`` only
        when requested) and every user metric is computed; a variable is inert when all of
        them are bit-identical at the three points — e.g. a stroke limit or the parallelogram
        width, which the metrics (closed-form kinematics over the region) do not see. A
        variable whose points cannot be evaluated (no machine, region unreachable) is not
        reported.
        """
        names = tuple(n for n in METRICS if n not in ON_REQUEST or n in self.metric_names)
        mid = self.bounds.mean(axis=1)
        inert = []
        for k, var in enumerate(self.variables):
            values = []
            for end in (var.lower, var.upper, var.lower + 0.3 * (var.upper - var.lower)):
                x = mid.copy()
                x[k] = end
                machine = self.build(x)
                if machine is None:
                    break
                metrics = metric_values(machine, self.region, self.criteria, names, self.samples)
                if not np.isfinite(metrics["lambda_min"]):
                    break
                values.append([*metrics.values(),
                               *(float(f(machine)) for f in self.user_metrics.values())])
            else:
                if all(np.array_equal(values[0], v, equal_nan=True) for v in values[1:]):
                    inert.append(var.name)
        return inert

    def evaluate(self, x: np.ndarray) -> dict[str, Any]:
        """Record of one candidate: variables, metrics, objective values, constraint excesses
        and feasibility."""
        candidate = self.build(np.asarray(x, dtype=float))
        metrics = self.evaluator(candidate, self.region, self.criteria, self.metric_names,
                                 self.samples)
        for name, func in self.user_metrics.items():
            metrics[name] = float(func(candidate)) if candidate is not None else float("nan")
        record: dict[str, Any] = {v.name: float(value) for v, value in
                                  zip(self.variables, x, strict=True)}
        record.update(metrics)
        record["_objectives"] = [o.value(metrics) for o in self.objectives]
        record["_excess"] = [c.excess(metrics) for c in self.constraints]
        record["feasible"] = candidate is not None and all(e <= 0 for e in record["_excess"])
        return record


@dataclass
class OptimizationResult:
    """Every evaluated design, and the best one (one objective) or the Pareto front.

    Records hold SI values (m, rad). The writers take ``units``: None for SI, or a command-line
    length unit (``"m"``, ``"mm"``) for lengths in that unit, areas in its square and angles in
    degrees; column headers and the JSON summary name the units either way.

    Attributes:
        problem: the problem solved.
        method: optimiser used.
        records: every evaluated candidate (dicts).
        best: best feasible record (single objective) or None.
        pareto: non-dominated feasible records (several objectives), sorted by the first
            objective.
    """

    problem: DesignProblem
    method: str
    records: list[dict[str, Any]]
    best: dict[str, Any] | None
    pareto: list[dict[str, Any]]

    @property
    def columns(self) -> list[str]:
        """Variables, metrics, then ``feasible``."""
        names = [v.name for v in self.problem.variables]
        metrics = [k for k in self.records[0] if not k.startswith("_") and k not in names
                   and k != "feasible"] if self.records else []
        return [*names, *metrics, "feasible"]

    def unit_of(self, column: str, units: str | None = None) -> str:
        """Unit symbol of a column (``""`` for a dimensionless one); see the class docstring
        for ``units``."""
        quantity = self.problem.quantity(column)
        if units is None:
            return {"length": "m", "area": "m^2", "angle": "rad", "stiffness": "N/m",
                    "number": ""}[quantity]
        length_scale(units)  # validates the unit
        return boundary_unit(quantity, units)

    def to_units(self, column: str, value: Any, units: str | None = None) -> Any:
        """A value of ``column`` converted from SI to ``units`` (see the class docstring)."""
        if units is None or not isinstance(value, float):
            return value
        return value / boundary_factor(self.problem.quantity(column), length_scale(units))

    def record_in(self, record: dict[str, Any], units: str | None = None) -> dict[str, Any]:
        """A record without its private entries, converted to ``units``."""
        return {k: self.to_units(k, v, units) for k, v in record.items()
                if not k.startswith("_")}

    def header(self, units: str | None = None) -> list[str]:
        """Column names with their units, ``"R [mm]"`` (dimensionless columns bare)."""
        out = []
        for c in self.columns:
            unit = self.unit_of(c, units) if c != "feasible" else ""
            out.append(f"{c} [{unit}]" if unit else c)
        return out

    def constraint_text(self, c: Constraint, units: str | None = None) -> str:
        """``"stroke<=750"`` with the value in ``units`` (a unit suffix for dimensional
        metrics)."""
        unit = self.unit_of(c.metric, units)
        return f"{c.metric}{c.op}{self.to_units(c.metric, float(c.value), units):g}" + (
            f" {unit}" if unit else "")

    def infeasibility(self, units: str | None = None) -> str | None:
        """None when some design is feasible; otherwise which requirements no evaluated design
        met, each with the closest value reached (and where), in ``units``."""
        if any(r["feasible"] for r in self.records) or not self.records:
            return None if self.records else "no design was evaluated"
        parts = []
        names = [v.name for v in self.problem.variables]

        def show(name: str, value: float) -> str:
            unit = self.unit_of(name, units)
            return f"{self.to_units(name, value, units):.4g}" + (f" {unit}" if unit else "")

        for k, c in enumerate(self.problem.constraints):
            excess = np.array([r["_excess"][k] for r in self.records])
            if (excess <= 0).any():
                continue
            best = self.records[int(np.argmin(excess))]
            where = ", ".join(f"{n} = {show(n, best[n])}" for n in names)
            parts.append(f"{self.constraint_text(c, units)} (best "
                         f"{show(c.metric, best[c.metric])} at {where})")
        if not parts:
            return "no design satisfies all the constraints together"
        return "no evaluated design satisfies: " + "; ".join(parts)

    def write_csv(self, path: str | Path, records: list[dict[str, Any]] | None = None,
                  units: str | None = None) -> None:
        """All records (or the given ones) as CSV, in ``units``, the header naming them."""
        rows = self.records if records is None else records
        with atomic_path(path) as temp, open(temp, "w", newline="", encoding="utf-8") as handle:
            writer = csv.writer(handle)
            writer.writerow(self.header(units))
            for r in rows:
                values = self.record_in(r, units)
                writer.writerow([f"{values[c]:.10g}" if isinstance(values[c], float)
                                 else values[c] for c in self.columns])

    def summary(self, units: str | None = None) -> dict[str, Any]:
        """JSON-ready summary in ``units``; ``"units"`` and ``"column_units"`` name them."""
        region = self.problem.region
        scale = 1.0 if units is None else length_scale(units)
        length = "m" if units is None else units
        center = None if region.center is None else [float(v) / scale for v in region.center]
        return to_jsonable({
            "machine": self.problem.base.id,
            "method": self.method,
            "units": {"length": length, "area": f"{length}^2",
                      "angle": "rad" if units is None else "deg"},
            "column_units": {c: self.unit_of(c, units) for c in self.columns
                             if c != "feasible"},
            "variables": [{"name": v.name, "lower": self.to_units(v.name, v.lower, units),
                           "upper": self.to_units(v.name, v.upper, units),
                           "unit": self.unit_of(v.name, units)}
                          for v in self.problem.variables],
            "objectives": [f"{o.sense}:{o.metric}" for o in self.problem.objectives],
            "constraints": [self.constraint_text(c, units) for c in self.problem.constraints],
            "region": {"side": region.side / scale, "center": center},
            "criteria": {"bounds": self.problem.criteria.bounds,
                         "kappa_max": self.problem.criteria.kappa_max},
            "evaluations": len(self.records),
            "feasible_evaluations": sum(bool(r["feasible"]) for r in self.records),
            "infeasibility": self.infeasibility(units),
            "best": None if self.best is None else self.record_in(self.best, units),
            "pareto": [self.record_in(r, units) for r in self.pareto],
        })

    def write_json(self, path: str | Path, units: str | None = None) -> None:
        """:meth:`summary` as a JSON file."""
        write_text_atomic(path, json.dumps(self.summary(units), indent=2))


def pareto_front(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Non-dominated feasible records (minimisation of ``_objectives``)."""
    feasible = [r for r in records if r["feasible"]]
    if not feasible:
        return []
    f = np.array([r["_objectives"] for r in feasible])
    keep = np.ones(len(feasible), bool)
    for i in range(len(feasible)):
        dominated = (f <= f[i]).all(axis=1) & (f < f[i]).any(axis=1)
        if dominated.any():
            keep[i] = False
    front = [feasible[i] for i in np.flatnonzero(keep)]
    unique: dict[tuple, dict[str, Any]] = {}
    for r in front:
        unique.setdefault(tuple(np.round(r["_objectives"], 12)), r)
    return sorted(unique.values(), key=lambda r: r["_objectives"][0])


def _progress(total: int, enabled: bool, label: str):
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=label, unit="gen", leave=False)


def _evaluate_block(xs: list[np.ndarray], problem: DesignProblem) -> list[dict[str, Any]]:
    return [problem.evaluate(x) for x in xs]


def evaluate_designs(problem: DesignProblem, xs: Any, *, scheduler: Any = None,
                     executor: Any = None) -> list[dict[str, Any]]:
    """Records (:meth:`DesignProblem.evaluate`) of many candidates — a design sweep or one
    optimiser population — in order, here or on Dask.

    Args:
        problem: the problem.
        xs: ``(P, n_variables)`` variable values (SI).
        scheduler: where to run (see :mod:`pkmkit.parallel`): each task evaluates a block of
            candidates (every candidate is one batched call over the region's poses).
        executor: an open :func:`pkmkit.parallel.executor` instead of ``scheduler`` (reused
            across generations by :func:`optimize`).
    """
    xs = [np.asarray(x, dtype=float) for x in np.atleast_2d(np.asarray(xs, dtype=float))]
    if executor is None:
        with parallel.executor(scheduler) as ex:
            return evaluate_designs(problem, xs, executor=ex)
    workers = getattr(executor, "workers", 1)
    size = max(1, -(-len(xs) // (2 * workers)))  # two blocks per worker
    blocks = [xs[k:k + size] for k in range(0, len(xs), size)]
    return [r for block in executor.map(partial(_evaluate_block, problem=problem), blocks)
            for r in block]


def optimize(problem: DesignProblem, *, method: str | None = None, seed: int = 0,
             generations: int = 30, population: int = 24, progress: bool = False,
             scheduler: Any = None) -> OptimizationResult:
    """Optimise ``problem``.

    Args:
        problem: the problem.
        method: ``"de"`` (differential evolution, default for one objective), ``"cmaes"``
            (one objective; with a single variable it runs in 2-D with a dummy coordinate
            that the objective ignores, as CMA-ES needs at least two), ``"nsga2"`` (default for
            several objectives).
        seed: random seed (runs are reproducible).
        generations: iterations/generations of the optimiser.
        population: population size (NSGA-II, CMA-ES) or DE population multiplier ×
            number of variables.
        progress: show a progress bar on stderr.
        scheduler: evaluate each population on Dask (see :mod:`pkmkit.parallel` and
            :func:`evaluate_designs`); the optimiser itself runs here and the results are
            identical to the serial run. Every method evaluates whole populations (differential
            evolution with ``updating="deferred"``).

    Raises:
        InputError: a method that does not fit the number of objectives, bad sizes, a variable
            that changes none of the metrics (:meth:`DesignProblem.inert_variables`).
    """
    n_obj = len(problem.objectives)
    method = _checked_method(problem, method, generations, population)
    runner = {"de": _run_de, "cmaes": _run_cmaes, "nsga2": _run_nsga2}[method]
    bar = _progress(generations, progress, f"{method} on {problem.base.id}")
    with parallel.executor(scheduler) as ex:
        evaluate = _CachedEvaluation(problem, ex)
        try:
            runner(problem, evaluate, seed, generations, population, bar)
        finally:
            if bar is not None:
                bar.close()
    records = evaluate.records
    feasible = [r for r in records if r["feasible"]]
    best = min(feasible, key=lambda r: r["_objectives"][0]) if (n_obj == 1 and feasible) else None
    return OptimizationResult(problem=problem, method=method, records=records, best=best,
                              pareto=pareto_front(records) if n_obj > 1 else [])


def _checked_method(problem: DesignProblem, method: str | None, generations: int,
                    population: int) -> str:
    """The optimiser (default DE for one objective, NSGA-II for several), checked against the
    number of objectives, the sizes and the problem's inert variables."""
    n_obj = len(problem.objectives)
    method = method or ("de" if n_obj == 1 else "nsga2")
    if generations < 1 or population < 4:
        raise InputError("generations must be >= 1 and population >= 4")
    if method in ("de", "cmaes") and n_obj != 1:
        raise InputError(f"method {method!r} optimises one objective; use nsga2 for "
                         f"{n_obj} objectives")
    if method not in ("de", "cmaes", "nsga2"):
        raise InputError(f"unknown method {method!r}; use de, cmaes or nsga2")
    inert = problem.inert_variables()
    if inert:
        raise InputError(
            f"design variable(s) {', '.join(inert)} change none of the metrics (every metric is "
            "identical across the range): the metrics use the kinematics over the region, which "
            "ignore e.g. the stroke limits and the parallelogram width; remove them")
    return method


class _CachedEvaluation:
    """Evaluates populations of design vectors, each distinct candidate once
    (:func:`evaluate_designs` on ``executor``); :attr:`records` in evaluation order."""

    def __init__(self, problem: DesignProblem, executor: Any) -> None:
        self.problem, self.executor = problem, executor
        self.records: list[dict[str, Any]] = []
        self.cache: dict[bytes, dict[str, Any]] = {}

    def __call__(self, xs: list[np.ndarray]) -> list[dict[str, Any]]:
        """Records of a population, each candidate evaluated once (cached)."""
        keys = [np.asarray(x, dtype=float).tobytes() for x in xs]
        todo = {}
        for key, x in zip(keys, xs, strict=True):
            if key not in self.cache and key not in todo:
                todo[key] = np.asarray(x, dtype=float)
        for key, record in zip(todo, evaluate_designs(self.problem, list(todo.values()),
                                                      executor=self.executor), strict=True):
            self.cache[key] = record
            self.records.append(record)
        return [self.cache[key] for key in keys]


def _penalised(record: dict[str, Any]) -> float:
    excess = sum(max(e, 0.0) for e in record["_excess"])
    value = record["_objectives"][0]
    if not np.isfinite(value) or not np.isfinite(excess):
        return 1e12
    return value + (1e6 * (1.0 + excess) if excess > 0 else 0.0)


def _run_de(problem, evaluate, seed, generations, population, bar) -> None:
    from scipy.optimize import differential_evolution

    def callback(*_args, **_kwargs):
        if bar is not None:
            bar.update(1)

    def population_map(_func, candidates):
        # DE's map over a population: the same values as _func (the penalised objective of
        # each candidate), computed for the whole population at once
        return [_penalised(r) for r in evaluate(list(candidates))]

    differential_evolution(lambda x: _penalised(evaluate([x])[0]), problem.bounds, seed=seed,
                           maxiter=generations, popsize=max(2, population // len(
                               problem.variables)), tol=0.0, polish=False, callback=callback,
                           updating="deferred", workers=population_map)


def _run_cmaes(problem, evaluate, seed, generations, population, bar) -> None:
    import cma

    bounds = problem.bounds
    span = bounds[:, 1] - bounds[:, 0]
    n = len(bounds)
    # CMA-ES needs at least 2 dimensions: one variable gets a dummy coordinate, ignored below
    x0 = np.full(max(n, 2), 0.5)
    opts = {"bounds": [0.0, 1.0], "seed": seed + 1, "popsize": population,
            "maxiter": generations, "verbose": -9}
    es = cma.CMAEvolutionStrategy(x0, 0.3, opts)
    while not es.stop():
        xs = es.ask()
        recs = evaluate([bounds[:, 0] + np.asarray(x)[:n] * span for x in xs])
        es.tell(xs, [_penalised(r) for r in recs])
        if bar is not None:
            bar.update(1)


def _run_nsga2(problem, evaluate, seed, generations, population, bar) -> None:
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.callback import Callback
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    bounds = problem.bounds
    n_con = len(problem.constraints)

    class Wrapped(Problem):
        def __init__(self):
            super().__init__(n_var=len(bounds), n_obj=len(problem.objectives), n_ieq_constr=n_con,
                             xl=bounds[:, 0], xu=bounds[:, 1])

        def _evaluate(self, xs, out, *args, **kwargs):
            recs = evaluate(list(xs))
            out["F"] = np.array([[min(v, 1e12) for v in r["_objectives"]] for r in recs])
            out["G"] = np.array([[min(e, 1e12) for e in r["_excess"]] for r in recs])

    class Tick(Callback):
        def notify(self, algorithm):
            if bar is not None:
                bar.update(1)

    minimize(Wrapped(), NSGA2(pop_size=population), ("n_gen", generations), seed=seed,
             callback=Tick(), verbose=False)
