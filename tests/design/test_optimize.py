import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.workspace import Criteria
from pkmkit.design.metrics import Region, evaluate_metrics
from pkmkit.design.optimize import (
    Constraint,
    DesignProblem,
    Objective,
    Variable,
    optimize,
    pareto_front,
)
from pkmkit.errors import InputError

REGION = Region(0.5, (0.0, 0.0, 0.25))
CRITERIA = Criteria(bounds=(0.4, 2.5))


def delta_problem(objectives, **kwargs):
    return DesignProblem(base=pkmkit.machine("linear-delta"),
                         variables=[Variable("R", 0.45, 1.0), Variable("L", 0.9, 1.6)],
                         objectives=objectives, region=REGION, criteria=CRITERIA, samples=7,
                         **kwargs)


def test_metrics_against_direct_computation():
    m = pkmkit.machine("linear-delta")
    metrics = evaluate_metrics(m, REGION, CRITERIA, samples=7)
    g = np.linspace(-0.25, 0.25, 7)
    pts = np.stack(np.meshgrid(g, g, g + 0.25, indexing="ij"), axis=-1).reshape(-1, 3)
    q = m.ik(pts)
    sv = np.linalg.svd(m.jacobian(pts).J, compute_uv=False)
    assert metrics["stroke"] == pytest.approx(np.max(q.max(0) - q.min(0)))
    assert metrics["compactness"] == pytest.approx(0.5 / metrics["stroke"])
    assert metrics["lambda_min"] == pytest.approx(sv[:, -1].min())
    assert metrics["gci"] == pytest.approx(np.mean(sv[:, -1] / sv[:, 0]))
    assert metrics["violation"] == 0.0
    # footprint: the slides' triangle of circumradius R (carriages above the x-y plane)
    assert metrics["footprint"] == pytest.approx(3 * np.sqrt(3) / 4 * 0.7**2)
    tight = evaluate_metrics(m, REGION, Criteria(bounds=(0.6, 2.5)), ("violation",), 7)
    assert tight["violation"] == pytest.approx(0.6 / sv[:, -1].min() - 1)


def test_single_objective_matches_a_brute_force_scan():
    """Maximise compactness: differential evolution against a fine grid over (R, L)."""
    problem = delta_problem([Objective("compactness", "max")])
    result = optimize(problem, seed=2, generations=25, population=20)
    grid = [problem.evaluate(np.array([r, ell])) for r in np.linspace(0.45, 1.0, 23)
            for ell in np.linspace(0.9, 1.6, 29)]
    best_grid = max((g for g in grid if g["feasible"]), key=lambda g: g["compactness"])
    assert result.best["feasible"]
    assert result.best["compactness"] >= best_grid["compactness"] - 2e-3
    # reproducible
    again = optimize(problem, seed=2, generations=25, population=20)
    assert again.best["compactness"] == result.best["compactness"]


def test_pareto_front_is_non_dominated_and_feasible(tmp_path):
    problem = delta_problem([Objective("compactness", "max"), Objective("gci", "max")])
    result = optimize(problem, seed=1, generations=10, population=24)
    front = result.pareto
    assert len(front) > 5 and all(r["feasible"] for r in front)
    f = np.array([[r["compactness"], r["gci"]] for r in front])
    for i in range(len(f)):
        assert not ((f >= f[i]).all(axis=1) & (f > f[i]).any(axis=1)).any()
    assert pareto_front(result.records) == front
    result.write_csv(tmp_path / "r.csv")
    result.write_json(tmp_path / "s.json")
    assert (tmp_path / "r.csv").read_text().startswith("R,L,compactness,gci,violation,feasible")


def test_cmaes_and_constraints():
    problem = delta_problem([Objective("stroke", "min")],
                            constraints=[Constraint.parse("gci>=0.35")])
    result = optimize(problem, method="cmaes", seed=0, generations=15, population=8)
    assert result.best is not None and result.best["gci"] >= 0.35


def test_infeasible_problem_reports_no_best():
    problem = delta_problem([Objective("compactness", "max")],
                            constraints=[Constraint.parse("gci>=0.99")])
    result = optimize(problem, seed=0, generations=3, population=8)
    assert result.best is None and not any(r["feasible"] for r in result.records)


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Variable("R", 1.0, 0.5), "empty range"),
        (lambda: Objective.parse("maximise:gci"), "min:METRIC"),
        (lambda: Constraint.parse("gci=0.3"), "METRIC<=VALUE"),
        (lambda: delta_problem([Objective("beauty", "max")]), "unknown metric"),
        (lambda: DesignProblem(base=pkmkit.machine("linear-delta"),
                               variables=[Variable("Q", 0, 1)],
                               objectives=[Objective("gci", "max")], region=REGION),
         "unknown parameter"),
        (lambda: DesignProblem(base=pkmkit.machine("linear-delta"),
                               variables=[Variable("angles[5]", 0, 1)],
                               objectives=[Objective("gci", "max")], region=REGION),
         "3 components"),
        (lambda: optimize(delta_problem([Objective("gci", "max"), Objective("stroke", "min")]),
                          method="de"), "one objective"),
        (lambda: Region(-1.0), "must be > 0"),
    ],
)
def test_bad_problems(make, message):
    with pytest.raises(InputError, match=message):
        make()


def test_vector_component_variable():
    problem = DesignProblem(base=pkmkit.machine("linear-delta"),
                            variables=[Variable("angles[1]", 1.8, 2.4)],
                            objectives=[Objective("gci", "max")], region=REGION,
                            criteria=CRITERIA, samples=5)
    record = problem.evaluate(np.array([2.0]))
    assert record["angles[1]"] == 2.0 and np.isfinite(record["gci"])
