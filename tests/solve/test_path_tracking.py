"""Vectorised path tracking on homotopies whose end points are known independently."""

from __future__ import annotations

import numpy as np

from pkmkit.solve.path_tracking import PathStatus, track_paths


def _univariate(target: np.ndarray, gamma: complex):
    """Total-degree homotopy ``(1 − t) p(x) + γ t (xᵈ − 1)`` for the polynomial ``target``."""
    deg = len(target) - 1
    dtarget = np.polyder(target)

    def evaluate(x, t, rows):
        z = x[:, 0]
        p, dp = np.polyval(target, z), np.polyval(dtarget, z)
        q, dq = z**deg - 1.0, deg * z ** (deg - 1)
        res = ((1 - t) * p + gamma * t * q)[:, None]
        jac = ((1 - t) * dp + gamma * t * dq)[:, None, None]
        return res, jac, (gamma * q - p)[:, None]

    start = np.exp(2j * np.pi * np.arange(deg) / deg)[:, None]
    return evaluate, start


def test_total_degree_homotopy_finds_every_root():
    rng = np.random.default_rng(3)
    target = rng.normal(size=8)  # degree 7, real coefficients
    evaluate, start = _univariate(target, np.exp(0.7j))
    result = track_paths(evaluate, start)
    assert (result.status == PathStatus.REACHED).all()
    assert (result.t == 0).all()
    roots = np.roots(target)
    found = result.x[:, 0]
    gap = np.abs(found[:, None] - roots[None]).min(axis=1)
    assert gap.max() < 1e-8
    # distinct: every root reached exactly once
    assert len({int(np.argmin(np.abs(roots - z))) for z in found}) == len(roots)


def test_diverging_paths_are_stopped_and_bad_starts_flagged():
    # degree-3 start, degree-1 target: two paths go to infinity
    target = np.array([0.0, 0.0, 2.0, -1.0])
    evaluate, start = _univariate(target, np.exp(1.1j))
    start = np.vstack([start, [[np.nan]]])
    result = track_paths(evaluate, start, stop=lambda x, t: np.abs(x[:, 0]) > 1e3)
    status = result.status
    assert status[-1] == PathStatus.NOT_FINITE
    assert (status[:3] == PathStatus.STOPPED).sum() == 2
    reached = result.x[:3][status[:3] == PathStatus.REACHED, 0]
    np.testing.assert_allclose(reached, [0.5], atol=1e-10)


def test_step_budget_reports_failure():
    target = np.random.default_rng(0).normal(size=5)
    evaluate, start = _univariate(target, np.exp(0.3j))
    result = track_paths(evaluate, start, max_steps=3)
    assert (result.status == PathStatus.FAILED).all()
    assert (result.t > 0).all()
