"""Tool-point uncertainty (k = 2) of a calibration: the covariance propagated to the tool
points with the free rigid motion removed, checked against a Monte Carlo of re-identifications
with re-sampled noise, against the residual scale (a bound of linear least squares), and the
projection against a least-squares rigid alignment (Kabsch)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects, simulate
from pkmkit.calibration.identify import calibrate
from pkmkit.calibration.registration import Registration
from pkmkit.calibration.uncertainty import (
    over_workspace,
    rigid_motion_basis,
    tool_point_uncertainty,
    without_rigid_motion,
)
from pkmkit.model.defects_table import apply_defect_vector
from pkmkit.spatial.rotation import rotvec_to_matrix

SIGMA = 1e-5
POINTS = 30


def _kabsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a (N, 3)`` moved by the rigid motion that brings it closest to ``b`` (least squares,
    written here independently of pkmkit's registration)."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(u @ vt))
    rot = (u @ np.diag([1.0, 1.0, d]) @ vt).T
    return (a - ca) @ rot.T + cb


@pytest.fixture(scope="module")
def tracker_setup():
    """A linear Delta with random defects measured by a tracker in a frame turned by a few
    degrees (frame identified with the machine)."""
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(3)
    true = apply_defect_vector(m, random_defects(m, rng))
    exact = simulate(true, m, "point", POINTS, rng, noise="none")
    rot = rotvec_to_matrix(np.array([[0.02, -0.01, 0.03]]))[0]
    frame = Registration(rot, np.array([0.4, -1.2, 0.3]), np.zeros((0, 3)), np.zeros(0))
    rough = Registration(np.eye(3), frame.translation, np.zeros((0, 3)), np.zeros(0))

    def readings(seed: int | None):
        data = exact if seed is None else simulate(
            true, m, "point", POINTS, np.random.default_rng(seed), q=exact.q, noise=SIGMA)
        return replace(data, values=frame.inverse().apply(data.values))

    ref = calibrate(m, readings(None), frame=(rough, "identify"), sigma=SIGMA)
    return m, readings, rough, ref


def test_rigid_motion_removal_is_the_linearised_kabsch_alignment():
    """A small rigid motion of a point cloud is removed entirely; a rigid motion plus a
    deformation leaves what a least-squares rigid alignment leaves (to first order)."""
    rng = np.random.default_rng(0)
    pts = rng.normal(size=(12, 3))
    basis = rigid_motion_basis(pts)
    # a rigid motion (rotation not about the centroid) is in the span
    rot = rotvec_to_matrix(np.array([[3e-7, -2e-7, 5e-7]]))[0]
    moved = pts @ rot.T + np.array([1e-7, 2e-7, -3e-7])
    d = (moved - pts)[:, :, None]
    assert np.abs(without_rigid_motion(pts, d)).max() < 1e-6 * np.abs(d).max()
    # rigid motion + deformation: the remainder is Kabsch's residual
    deform = 1e-7 * rng.normal(size=pts.shape)
    target = moved + deform
    kabsch = _kabsch(target, pts) - pts
    ours = without_rigid_motion(pts, (target - pts)[:, :, None])[:, :, 0]
    np.testing.assert_allclose(ours, kabsch, atol=1e-4 * np.abs(deform).max())
    assert np.abs(ours).max() > 0.2 * np.abs(deform).max()
    # a projector: idempotent, and orthogonal to the six motions
    twice = without_rigid_motion(pts, without_rigid_motion(pts, d + deform[:, :, None]))
    once = without_rigid_motion(pts, d + deform[:, :, None])
    np.testing.assert_allclose(twice, once, atol=1e-20)
    assert np.abs(basis.T @ once.reshape(-1)).max() < 1e-12 * np.abs(once).max() * len(pts)


@pytest.mark.ci
def test_monte_carlo_scatter_matches_the_predicted_band(tracker_setup):
    """Re-identify with 60 re-sampled noise draws: the scatter of the identified tool points
    (each draw aligned rigidly on the reference, the frame being free) matches the predicted
    k = 2 band point by point. The machine-parameter covariance alone, without the free rigid
    motion removed (pkmkit ≤ 0.x), predicted a band ~12× too wide here."""
    m, readings, rough, ref = tracker_setup
    draws = 60
    points, predicted = [], []
    for seed in range(draws):
        res = calibrate(m, readings(100 + seed), frame=(rough, "identify"),
                        parameters=list(ref.names), prune=False)
        assert res.names == ref.names and res.tool_uncertainty_rigid_removed
        points.append(_kabsch(res.tool_points, ref.tool_points))
        predicted.append(res.tool_uncertainty)
    dev = np.array(points) - np.mean(points, axis=0)
    cov = np.einsum("kni,knj->nij", dev, dev) / (draws - 1)
    scatter = 2.0 * np.sqrt(np.linalg.eigvalsh(cov)[:, -1])
    band = np.sqrt(np.mean(np.array(predicted) ** 2, axis=0))
    ratio = np.sqrt(np.mean(scatter**2)) / np.sqrt(np.mean(band**2))
    # 60 draws: one point's standard deviation within ≈ ±9 % (1σ), their RMS within ≈ ±5 %;
    # a factor √2 error gives 0.71 or 1.41
    assert 0.8 < ratio < 1.25
    assert (scatter / band > 0.6).all() and (scatter / band < 1.6).all()


def test_uncertainty_is_consistent_with_the_residual_scale(tracker_setup):
    """Linear least squares: the fitted readings' covariance has trace σ̂²·(identified
    unknowns); the tool points without the rigid motion are a projection of the fitted
    readings (the frame is rigid), so mean(u²/4) ≤ σ̂² n / N. Removing the free rigid motion
    is what makes this hold (the marginal machine covariance gave 110 µm against a 10 µm
    reading noise)."""
    m, readings, rough, _ = tracker_setup
    res = calibrate(m, readings(7), frame=(rough, "identify"))
    unknowns = len(res.names) + len(res.setup_names)
    bound = 2.0 * res.sigma_posterior * np.sqrt(unknowns / POINTS)
    rms = float(np.sqrt(np.mean(res.tool_uncertainty**2)))
    assert 0.2 * bound < rms <= 1.01 * bound
    assert res.to_json("mm")["tool_uncertainty_k2"]["rms"] == pytest.approx(rms * 1e3)


def test_fixed_frame_keeps_the_rigid_motion(delta_case):
    """Readings in the machine frame see the machine's rigid motion: nothing is removed, and
    the band is the plain propagation J C Jᵀ of the identified parameters' covariance."""
    res = delta_case.result
    assert not res.tool_uncertainty_rigid_removed
    from pkmkit.geometric_errors.model import tool_sensitivity

    sens = tool_sensitivity(res.machine, delta_case.data.q)
    cols = [list(res.defect_names).index(n) for n in res.names]
    j = np.asarray(sens.point)[:, :, cols]
    p = len(res.names)
    cov = np.einsum("nip,pq,njq->nij", j, res.covariance[:p, :p], j)
    np.testing.assert_allclose(res.tool_uncertainty,
                               2 * np.sqrt(np.linalg.eigvalsh(cov)[:, -1]), rtol=1e-9)
    n = len(res.after.per_pose)
    assert np.sqrt(np.mean(res.tool_uncertainty**2)) <= 2.0 * res.sigma_posterior * np.sqrt(
        (p + len(res.setup_names)) / n) * 1.01


def test_undetermined_directions():
    """A direction the data do not determine makes the points it moves infinitely uncertain,
    unless it only moves them rigidly and the rigid motion is free."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    shift = np.tile(np.eye(3)[:, :1], (4, 1, 1))                  # a translation along x
    bulge = np.zeros((4, 3, 1))
    bulge[3, 2, 0] = 1.0                                          # one point moves alone
    jac = np.concatenate([shift, bulge], axis=2)
    cov = np.diag([1e-12, 1e-12])
    null = np.array([[1.0, 0.0]])
    free = tool_point_uncertainty(pts, jac, cov, rigid_motion_free=True, null=null)
    assert np.isfinite(free).all() and free.max() > 0
    fixed = tool_point_uncertainty(pts, jac, cov, rigid_motion_free=False, null=null)
    assert np.isinf(fixed).all()
    bulging = tool_point_uncertainty(pts, jac, cov, rigid_motion_free=True,
                                     null=np.array([[0.0, 1.0]]))
    assert np.isinf(bulging).all()  # the bulge is not rigid: every point shares its removal


def test_uncertainty_over_the_workspace(tracker_setup):
    """The map over the workspace is the same propagation: at the measured configurations it
    gives the result's own band; over configurations drawn across the workspace (the region
    the measurements were drawn from) it is of the same size."""
    m, readings, rough, _ = tracker_setup
    res = calibrate(m, readings(7), frame=(rough, "identify"))
    again = over_workspace(res.machine, res.propagation, q=readings(7).q)
    np.testing.assert_allclose(again["uncertainty"], res.tool_uncertainty, rtol=1e-9)
    np.testing.assert_allclose(again["points"], res.tool_points, atol=1e-12)
    ws = res.workspace_uncertainty(n=60)
    assert ws["points"].shape == (60, 3) and np.isfinite(ws["uncertainty"]).all()
    rms = np.sqrt(np.mean(ws["uncertainty"] ** 2))
    measured = np.sqrt(np.mean(res.tool_uncertainty**2))
    assert measured / 3 < rms < 3 * measured
