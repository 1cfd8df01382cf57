"""Stiffness indices over many poses, as workspace criteria and as a design metric, against
independent oracles: the Orthoglide's eigen-stiffnesses k_a/ψ² from the singular values of its
Jacobian, single-pose evaluations, the criteria's boolean masks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pkmkit.analysis.criteria import Criteria, evaluate_poses
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.region_check import check_region, criteria_slack
from pkmkit.analysis.workspace import compute_workspace
from pkmkit.design.metrics import Region, evaluate_metrics
from pkmkit.exceptions import InputError
from pkmkit.machines.registry import machine
from pkmkit.stiffness import default_data, stiffness
from pkmkit.stiffness.indices import stiffness_figures, stiffness_index

KA = 1e8  # the Orthoglide's assumed drive stiffness, N/m


def _poses(m, count=200, spread=0.15, seed=0):
    rng = np.random.default_rng(seed)
    return m.home_pose + spread * rng.uniform(-1, 1, (count, m.dims))


def _oracle_smallest(m, x):
    """k_a/ψ_max²: the Orthoglide's smallest eigen-stiffness from its Jacobian alone (NaN where
    the pose is unreachable)."""
    jac = m.jacobian(x)
    return KA / np.asarray(jac.singular_values)[:, 0] ** 2


def test_smallest_stiffness_is_ka_over_the_largest_transmission_factor_squared():
    m = machine("orthoglide")
    x = np.vstack([_poses(m, spread=0.3), [[5.0, 5.0, 5.0]]])
    got = stiffness_index(m, x, "stiffness")
    expected = _oracle_smallest(m, x)
    reach = np.isfinite(expected)
    assert reach.sum() > 50 and (~reach).any()
    np.testing.assert_allclose(got[reach], expected[reach], rtol=1e-10)
    assert np.isnan(got[~reach]).all()


def test_deflection_is_the_norm_of_j_cq_jt_w_and_batches_match_single_poses():
    m = machine("orthoglide")
    x = _poses(m, 30, spread=0.08)
    w = np.array([100.0, -250.0, -500.0])
    fig = stiffness_figures(m, x, wrench=w)
    jac = np.asarray(m.jacobian(x).J)
    expected = np.linalg.norm(np.einsum("nia,nja,j->ni", jac, jac, w) / KA, axis=1)
    np.testing.assert_allclose(fig.deflection, expected, rtol=1e-10)
    for k in (0, 7, 29):
        one = stiffness(m, x[k], wrench=w)
        assert fig.smallest[k] == pytest.approx(one.translational[0], rel=1e-12)
        np.testing.assert_allclose(fig.vectors[k], one.deflection, rtol=1e-12)


def test_chain_machine_batch_matches_single_configurations():
    m = machine("tripteor-x7")
    q = m.home_q + np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [0.02, -0.01, 0.015, 0.05, -0.03]])
    by_q = stiffness_figures(m, q=q, wrench=[0, 0, -1000, 0, 0, 0])
    single = [stiffness(m, q=row, wrench=[0, 0, -1000, 0, 0, 0]) for row in q]
    np.testing.assert_allclose(by_q.smallest, [r.translational[0] for r in single], rtol=1e-10)
    np.testing.assert_allclose(by_q.vectors, [r.deflection for r in single], rtol=1e-9)


def test_index_refusals():
    m = machine("orthoglide")
    with pytest.raises(InputError, match="wrench"):
        stiffness_index(m, m.home_pose[None], "deflection")
    with pytest.raises(InputError, match="unknown stiffness index"):
        stiffness_index(m, m.home_pose[None], "softness")
    with pytest.raises(InputError, match="3 finite components"):
        stiffness_figures(m, m.home_pose[None], wrench=[1.0, 2.0, 3.0, 4.0])
    with pytest.raises(InputError, match="max_deflection needs"):
        Criteria(max_deflection=1e-5)
    with pytest.raises(InputError, match="min_stiffness"):
        Criteria(min_stiffness=-1.0)


def test_stiffness_mask_is_the_bound_on_the_oracle():
    m = machine("orthoglide")
    x = _poses(m, 400)
    bound = 60e6
    ev = evaluate_poses(m, x, Criteria(min_stiffness=bound))
    plain = evaluate_poses(m, x, Criteria())
    assert "stiffness" in ev.masks and "stiffness" not in plain.masks
    expected = _oracle_smallest(m, x)
    with np.errstate(invalid="ignore"):
        oracle = np.isfinite(expected) & (expected >= bound * (1 - 1e-9))
    np.testing.assert_array_equal(ev.masks["stiffness"], oracle)
    assert 0 < ev.masks["stiffness"].sum() < plain.masks["reachable"].sum()
    np.testing.assert_array_equal(ev.feasible, plain.feasible & oracle)
    np.testing.assert_allclose(ev.stiffness[np.isfinite(expected)],
                               expected[np.isfinite(expected)], rtol=1e-10)


def test_deflection_mask_and_slack_agree_with_the_boolean_criteria():
    m = machine("orthoglide")
    x = _poses(m, 300, spread=0.12, seed=4)
    crit = Criteria(min_stiffness=55e6, wrench=(0.0, 0.0, -500.0), max_deflection=6e-6)
    ev = evaluate_poses(m, x, crit)
    slack = criteria_slack(m, x, crit, 1.0)
    margin = np.abs(slack) > 1e-6  # away from a bound (rounding allowance there)
    np.testing.assert_array_equal((slack >= 0)[margin], ev.feasible[margin])
    # the deflection part alone decides somewhere
    loose = evaluate_poses(m, x, dataclasses.replace(crit, max_deflection=1.0))
    assert (loose.feasible & ~ev.feasible).any()


def test_check_region_names_the_stiffness_failure():
    m = machine("orthoglide")
    center = np.full(3, -0.0267446)
    check = check_region(m, center, 0.199, Criteria(bounds=(0.5, 2.0), min_stiffness=60e6))
    assert not check.feasible and "stiffness" in check.failures
    assert "smallest translational stiffness" in check.worst["stiffness"]
    assert check_region(m, center, 0.199, Criteria(bounds=(0.5, 2.0))).feasible


def test_refined_workspace_box_meets_the_stiffness_criterion():
    m = machine("orthoglide")
    lower, upper = m.default_box()
    grid = make_grid(lower[:2], upper[:2], free=(0, 1), base=m.home_pose, names=m.pose_names,
                     resolution=31)  # the plane z = 0
    crit = Criteria(min_stiffness=50e6)
    wmap = compute_workspace(m, grid, crit, refine=True)
    plain = compute_workspace(m, grid, Criteria())
    assert wmap.feasible.sum() < plain.feasible.sum()
    assert wmap.inscribed.side < plain.inscribed.side
    assert check_region(m, wmap.inscribed.center, wmap.inscribed.side, crit,
                        free=grid.free).feasible
    feasible = wmap.stiffness[wmap.feasible]
    assert feasible.min() >= 50e6 * (1 - 1e-9)
    # the workspace figure names the points that fail the stiffness criterion alone
    from pkmkit.plot.maps import classify

    classes = classify(wmap)
    others = np.logical_and.reduce([v for k, v in wmap.masks.items() if k != "stiffness"])
    only_stiffness = others & ~wmap.masks["stiffness"]
    assert only_stiffness.any()
    assert (classes[only_stiffness] == 5).all() and (classes[~only_stiffness] != 5).all()


def test_min_stiffness_metric_is_the_least_over_the_region():
    m = machine("orthoglide")
    region = Region(0.1)
    metrics = evaluate_metrics(m, region, Criteria(), ("min_stiffness", "lambda_max"), 5)
    points = region.points(m, 5)
    assert metrics["min_stiffness"] == pytest.approx(_oracle_smallest(m, points).min(),
                                                     rel=1e-10)
    assert metrics["min_stiffness"] == pytest.approx(KA / metrics["lambda_max"] ** 2, rel=1e-10)
    stiff = dataclasses.replace(default_data(m), actuator_stiffness=np.full(3, 2 * KA))
    doubled = evaluate_metrics(m, region, Criteria(stiffness_data=stiff), ("min_stiffness",), 5)
    assert doubled["min_stiffness"] == pytest.approx(2 * metrics["min_stiffness"], rel=1e-12)


def test_joint_chain_criterion_is_the_vjm_at_the_solved_configurations():
    m = machine("tripteor-x7")
    q = m.home_q + np.array([[0.0] * 5, [0.006, -0.005, 0.004, 0.1, 0.05],
                             [-0.005, 0.005, -0.008, -0.08, 0.1]])  # within the strokes
    points = np.array([m.fk(row) for row in q])
    direct = np.array([stiffness(m, q=row).translational[0] for row in q])
    bound = float(np.median(direct))
    ev = evaluate_poses(m, points, Criteria(min_stiffness=bound))
    np.testing.assert_allclose(ev.q, q, atol=1e-9)
    np.testing.assert_allclose(ev.stiffness, direct, rtol=1e-7)
    np.testing.assert_array_equal(ev.masks["stiffness"], direct >= bound * (1 - 1e-9))
