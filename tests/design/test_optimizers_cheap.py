"""The optimisers on problems whose answer is known by hand, cheap enough for the ordinary run
(the comparisons with scans of real design metrics are marked ``ci``). The metrics are user
metrics of the candidate's parameters, so a candidate costs only its construction; the
region is not required (``require_region=False``)."""

import numpy as np
import pytest

import pkmkit
from pkmkit.design.metrics import Region
from pkmkit.design.optimize import Constraint, DesignProblem, Objective, Variable, optimize

REGION = Region(0.5, (0.0, 0.0, 0.25))


def offset(machine):
    """d = R − r, the slide's offset from the nacelle joint (r = 0.15 m here)."""
    return machine.params["R"] - machine.params["r"]


def test_differential_evolution_stops_at_an_active_constraint():
    """Minimise d subject to d ≥ 0.55 m over R in [0.45, 1] m: the answer is d = 0.55 m
    (R = 0.70 m), on the constraint. The infeasible side scores better, so only the penalty
    (1e6 (1 + excess) added to an infeasible candidate) keeps the search at the boundary:
    seed 0 ends 5e-6 m from it; with a penalty of (1 + excess) / 1e6 it ends 9e-4 m away
    (among trials mostly infeasible)."""
    problem = DesignProblem(base=pkmkit.machine("linear-delta"),
                            variables=[Variable("R", 0.45, 1.0)],
                            objectives=[Objective("d", "min")],
                            constraints=[Constraint("d", ">=", 0.55)],
                            user_metrics={"d": offset}, region=REGION,
                            require_region=False, samples=3)
    result = optimize(problem, method="de", seed=0, generations=15, population=6)
    best = result.best
    assert best["feasible"] and best["d"] >= 0.55
    assert best["d"] - 0.55 < 1e-4
    assert best["R"] == pytest.approx(0.70, abs=1e-4)
    # the record is the candidate's own value, and every record's feasibility is d ≥ 0.55
    assert best["d"] == pytest.approx(best["R"] - 0.15, abs=1e-15)
    assert all(r["feasible"] == (r["d"] >= 0.55) for r in result.records)


def test_nsga2_front_spans_the_pareto_set_between_two_targets():
    """Two objectives (R − 0.6)² and (R − 0.9)² over R in [0.45, 1] m: the Pareto set is
    R in [0.6, 0.9] m (between the two minima one objective can only improve at the other's
    expense; outside, both improve toward the interval). The front found lies in it, covers
    it, and holds the objectives' values at its R."""
    problem = DesignProblem(
        base=pkmkit.machine("linear-delta"), variables=[Variable("R", 0.45, 1.0)],
        objectives=[Objective("near", "min"), Objective("far", "min")],
        user_metrics={"near": lambda m: (m.params["R"] - 0.6) ** 2,
                      "far": lambda m: (m.params["R"] - 0.9) ** 2},
        region=REGION, require_region=False, samples=3)
    result = optimize(problem, seed=0, generations=10, population=12)
    r = np.array([p["R"] for p in result.pareto])
    assert len(r) >= 10
    assert (r >= 0.6 - 1e-9).all() and (r <= 0.9 + 1e-9).all()
    assert r.min() < 0.62 and r.max() > 0.88
    assert all(0.45 <= rec["R"] <= 1.0 for rec in result.records)
    for p in result.pareto:
        assert p["near"] == pytest.approx((p["R"] - 0.6) ** 2, abs=1e-15)
        assert p["far"] == pytest.approx((p["R"] - 0.9) ** 2, abs=1e-15)
