import math

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
)
from pkmkit.exceptions import InputError

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
    assert metrics["lambda_max"] == pytest.approx(sv[:, 0].max())
    assert metrics["worst_condition"] == pytest.approx(np.max(sv[:, 0] / sv[:, -1]))
    assert metrics["gci"] == pytest.approx(np.mean(sv[:, -1] / sv[:, 0]))
    assert metrics["violation"] == 0.0
    # footprint: the slides' triangle of circumradius R (carriages above the x-y plane)
    assert metrics["footprint"] == pytest.approx(3 * np.sqrt(3) / 4 * 0.7**2)
    tight = evaluate_metrics(m, REGION, Criteria(bounds=(0.6, 2.5)), ("violation",), 7)
    assert tight["violation"] == pytest.approx(0.6 / sv[:, -1].min() - 1)


@pytest.mark.ci
def test_single_objective_matches_a_brute_force_scan():
    """Maximise compactness: differential evolution against a fine grid over (R, L)."""
    problem = delta_problem([Objective("compactness", "max")])
    result = optimize(problem, seed=2, generations=25, population=20)
    grid = [problem.evaluate(np.array([r, ell])) for r in np.linspace(0.45, 1.0, 23)
            for ell in np.linspace(0.9, 1.6, 29)]
    best_grid = max((g for g in grid if g["feasible"]), key=lambda g: g["compactness"])
    assert result.best["feasible"]
    assert result.best["compactness"] >= best_grid["compactness"] - 1e-9
    # reproducible
    again = optimize(problem, seed=2, generations=25, population=20)
    assert again.best["compactness"] == result.best["compactness"]


def dominates(a, b):
    """Maximisation of both coordinates: a is at least as good everywhere, better somewhere."""
    return a[0] >= b[0] and a[1] >= b[1] and (a[0] > b[0] or a[1] > b[1])


@pytest.mark.ci
def test_pareto_front_is_non_dominated_and_feasible(tmp_path):
    problem = delta_problem([Objective("compactness", "max"), Objective("gci", "max")])
    result = optimize(problem, seed=1, generations=10, population=24)
    front = result.pareto
    assert len(front) > 5 and all(r["feasible"] for r in front)
    feasible = [(r["compactness"], r["gci"]) for r in result.records if r["feasible"]]
    points = [(r["compactness"], r["gci"]) for r in front]
    # no feasible record dominates a point of the front ...
    for p in points:
        assert not any(dominates(q, p) for q in feasible), p
    # ... and every feasible record not on the front is dominated by, or equal to, a front point
    for q in feasible:
        assert q in points or any(dominates(p, q) or p == q for p in points), q
    # the records really are the metrics of their designs (not copied from elsewhere)
    sample = front[len(front) // 2]
    direct = evaluate_metrics(pkmkit.machine("linear-delta", R=sample["R"], L=sample["L"]),
                              REGION, CRITERIA, ("compactness", "gci"), 7)
    assert direct["compactness"] == pytest.approx(sample["compactness"], rel=1e-12)
    assert direct["gci"] == pytest.approx(sample["gci"], rel=1e-12)
    result.write_csv(tmp_path / "r.csv")
    result.write_json(tmp_path / "s.json")
    assert (tmp_path / "r.csv").read_text().startswith(
        "R [m],L [m],compactness,gci,violation,feasible")


def test_outputs_in_command_line_units(tmp_path):
    """units="mm": lengths in mm (variables, stroke, constraint values, region), areas in mm²,
    angles in degrees; the header and the summary name the units."""
    problem = DesignProblem(
        base=pkmkit.machine("linear-delta"),
        variables=[Variable("R", 0.6, 0.8), Variable("angles[1]", math.radians(110),
                                                      math.radians(130))],
        objectives=[Objective("gci", "max")], constraints=[Constraint("stroke", "<=", 0.9)],
        region=REGION, criteria=CRITERIA, samples=5)
    result = optimize(problem, seed=0, generations=3, population=8)
    best = result.best
    summary = result.summary("mm")
    assert summary["units"] == {"length": "mm", "area": "mm^2", "angle": "deg"}
    assert summary["column_units"]["R"] == "mm" and summary["column_units"]["angles[1]"] == "deg"
    assert summary["column_units"]["stroke"] == "mm" and summary["column_units"]["gci"] == ""
    assert summary["best"]["R"] == pytest.approx(best["R"] * 1e3)
    assert summary["best"]["angles[1]"] == pytest.approx(math.degrees(best["angles[1]"]))
    assert summary["best"]["stroke"] == pytest.approx(best["stroke"] * 1e3)
    assert summary["best"]["gci"] == best["gci"]
    assert summary["constraints"][0] == "stroke<=900 mm"
    assert summary["region"] == {"side": 500.0, "center": [0.0, 0.0, 250.0]}
    assert summary["variables"][1] == {"name": "angles[1]", "lower": pytest.approx(110),
                                       "upper": pytest.approx(130), "unit": "deg"}
    result.write_csv(tmp_path / "r.csv", units="mm")
    header, first = (tmp_path / "r.csv").read_text().splitlines()[:2]
    assert header == "R [mm],angles[1] [deg],gci,stroke [mm],violation,feasible"
    values = dict(zip(header.split(","), first.split(","), strict=True))
    record = result.records[0]
    assert float(values["R [mm]"]) == pytest.approx(record["R"] * 1e3, rel=1e-9)
    assert float(values["angles[1] [deg]"]) == pytest.approx(math.degrees(record["angles[1]"]),
                                                              rel=1e-9)
    # SI by default, and says so
    assert result.summary()["units"] == {"length": "m", "area": "m^2", "angle": "rad"}


@pytest.mark.ci
def test_cmaes_and_constraints():
    """Shortest stroke with GCI ≥ 0.35: CMA-ES does at least as well as a scan of (R, L), the
    constraint holds and is active at the optimum (a larger GCI costs stroke), and the best
    record is the best feasible record."""
    problem = delta_problem([Objective("stroke", "min")],
                            constraints=[Constraint.parse("gci>=0.35")])
    result = optimize(problem, method="cmaes", seed=0, generations=15, population=8)
    best = result.best
    assert best is not None and best["feasible"] and best["gci"] >= 0.35
    grid = [problem.evaluate(np.array([r, ell])) for r in np.linspace(0.45, 1.0, 12)
            for ell in np.linspace(0.9, 1.6, 15)]
    best_grid = min((g for g in grid if g["feasible"]), key=lambda g: g["stroke"])
    assert best["stroke"] <= best_grid["stroke"] + 1e-9
    assert best["gci"] - 0.35 < 2e-3
    assert best["stroke"] == min(r["stroke"] for r in result.records if r["feasible"])
    direct = problem.evaluate(np.array([best["R"], best["L"]]))
    assert direct["stroke"] == best["stroke"] and direct["gci"] == best["gci"]


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
         "angles\\[0..2\\]"),
        (lambda: DesignProblem(base=pkmkit.machine("linear-delta"),
                               variables=[Variable("angles", 0, 1)],
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
    """angles[1] must change the machine: the candidate is the machine built directly with that
    angle, and its metrics differ from those of the nominal 120°."""
    problem = DesignProblem(base=pkmkit.machine("linear-delta"),
                            variables=[Variable("angles[1]", 1.8, 2.4)],
                            objectives=[Objective("gci", "max")], region=REGION,
                            criteria=CRITERIA, samples=5)
    candidate = problem.build(np.array([2.0]))
    assert candidate.params["angles"] == pytest.approx((0.0, 2.0, math.radians(240)))
    direct = pkmkit.machine("linear-delta", angles=(0.0, 2.0, math.radians(240)))
    pts = REGION.points(direct, 5)
    np.testing.assert_array_equal(candidate.ik(pts), direct.ik(pts))
    record = problem.evaluate(np.array([2.0]))
    assert record["gci"] == evaluate_metrics(direct, REGION, CRITERIA, ("gci",), 5)["gci"]
    nominal = evaluate_metrics(pkmkit.machine("linear-delta"), REGION, CRITERIA, ("gci",), 5)
    assert abs(record["gci"] - nominal["gci"]) > 1e-3
    # the base machine is unchanged (machines are immutable values)
    assert problem.base.params["angles"][1] == pytest.approx(math.radians(120))


def test_cmaes_with_one_variable():
    """CMA-ES needs two dimensions; one variable runs with a dummy coordinate. The optimum of
    GCI over R alone matches a scan."""
    problem = DesignProblem(base=pkmkit.machine("linear-delta"),
                            variables=[Variable("R", 0.45, 1.0)],
                            objectives=[Objective("gci", "max")], region=REGION,
                            criteria=CRITERIA, samples=5)
    result = optimize(problem, method="cmaes", seed=0, generations=12, population=6)
    assert result.best is not None and 0.45 <= result.best["R"] <= 1.0
    scan = [problem.evaluate(np.array([r])) for r in np.linspace(0.45, 1.0, 23)]
    best_scan = max((g for g in scan if g["feasible"]), key=lambda g: g["gci"])
    assert result.best["gci"] >= best_scan["gci"] - 1e-9
    assert result.best["gci"] == max(r["gci"] for r in result.records if r["feasible"])
    for record in result.records[::10]:  # the records are the metrics of their designs
        assert problem.evaluate(np.array([record["R"]]))["gci"] == record["gci"]


def test_duplicate_and_inert_variables():
    base = pkmkit.machine("linear-delta")
    with pytest.raises(InputError, match="given twice"):
        DesignProblem(base=base, variables=[Variable("R", 0.5, 1.0), Variable("R", 0.6, 0.9)],
                      objectives=[Objective("gci", "max")], region=REGION)
    problem = DesignProblem(base=base, variables=[Variable("q_min[0]", 0.1, 0.5),
                                                  Variable("R", 0.5, 1.0),
                                                  Variable("parallelogram_width", 0.05, 0.2)],
                            objectives=[Objective("gci", "max")], region=REGION,
                            criteria=CRITERIA, samples=5)
    assert problem.inert_variables() == ["q_min[0]", "parallelogram_width"]
    with pytest.raises(InputError, match="q_min\\[0\\], parallelogram_width change none"):
        optimize(problem, generations=2, population=4)
    # r changes the kinematics through R − r: not inert
    assert DesignProblem(base=base, variables=[Variable("r", 0.1, 0.2)],
                         objectives=[Objective("gci", "max")], region=REGION,
                         samples=5).inert_variables() == []
    # a metric that changes at the variable's lower end only: not inert (each of the three
    # points is compared with the first, the lower end)
    lower_only = {"narrow": lambda m: float(m.params["parallelogram_width"] <= 0.05)}
    assert DesignProblem(base=base, variables=[Variable("parallelogram_width", 0.05, 0.2)],
                         objectives=[Objective("gci", "max")], region=REGION, samples=5,
                         user_metrics=lower_only).inert_variables() == []


@pytest.mark.parametrize("text", ["gci>=1e", "gci>=1.2.3", "gci>=nan", "stroke<=inf"])
def test_malformed_constraint_values(text):
    with pytest.raises(InputError, match="not a finite number"):
        Constraint.parse(text)


@pytest.mark.parametrize(
    "region, message",
    [(Region(0.5, (1.0, 2.0)), "needs 3 coordinates"),
     (Region(0.5, (0.0, 0.0, 0.0, 0.0)), "needs 3 coordinates")],
)
def test_region_centre_must_fit_the_machine(region, message):
    with pytest.raises(InputError, match=message):
        DesignProblem(base=pkmkit.machine("linear-delta"), variables=[Variable("R", 0.5, 1.0)],
                      objectives=[Objective("gci", "max")], region=region)


def test_non_finite_region_centre():
    with pytest.raises(InputError, match="must be finite"):
        Region(0.5, (float("nan"), 0.0, 0.0))


ROD_DELTA = """
[machine]
kind = "rod-legs"
name = "delta leg by leg"
units = "mm"
[[legs]]
base = [550, 0, 0]
axis = [0, 0, 1]
platform = [0, 0, 0]
length = {L0}
[[legs]]
base = [-275, 476.3139720814412, 0]
axis = [0, 0, 1]
platform = [0, 0, 0]
length = 1300
[[legs]]
base = [-275, -476.3139720814412, 0]
axis = [0, 0, 1]
platform = [0, 0, 0]
length = 1300
"""


def test_rod_legs_machine_can_be_optimised(tmp_path):
    """A machine described leg by leg: its leg fields are design variables (legs[0].length,
    legs[2].base[0], ...). A candidate equals the machine written directly with those values."""
    path = tmp_path / "delta.toml"
    path.write_text(ROD_DELTA.format(L0=1300))
    base = pkmkit.load(path)
    problem = DesignProblem(base=base, variables=[Variable("legs[0].length", 1.2, 1.5),
                                                  Variable("legs[2].base[0]", -0.35, -0.2)],
                            objectives=[Objective("gci", "max")], region=REGION,
                            criteria=CRITERIA, samples=5)
    candidate = problem.build(np.array([1.4, -0.3]))
    written = tmp_path / "direct.toml"
    written.write_text(ROD_DELTA.format(L0=1400).replace("[-275, -476.3", "[-300, -476.3"))
    direct = pkmkit.load(written)
    pts = REGION.points(direct, 5)
    np.testing.assert_allclose(candidate.ik(pts), direct.ik(pts), rtol=0, atol=1e-12)
    np.testing.assert_allclose(candidate.jacobian(pts).J, direct.jacobian(pts).J, atol=1e-12)
    assert base.model.leg_length[0] == pytest.approx(1.3)  # unchanged
    result = optimize(problem, seed=0, generations=3, population=8)
    assert result.best is not None and 1.2 <= result.best["legs[0].length"] <= 1.5
    assert result.summary("mm")["column_units"]["legs[0].length"] == "mm"
    with pytest.raises(InputError, match=r"valid names: legs\[0\]\.length"):
        DesignProblem(base=base, variables=[Variable("R", 0.5, 1.0)],
                      objectives=[Objective("gci", "max")], region=REGION)
