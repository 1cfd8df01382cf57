"""The stored generic start system: 40 solutions, confirmed by an independent homotopy."""

from __future__ import annotations

import numpy as np
import pytest

from pkmkit.solve.path_tracking import PathStatus, track_paths
from pkmkit.solve.six_rod_start import (
    GENERIC_COUNT,
    SEED,
    check_start_system,
    generate_start_system,
    load_start_system,
    read_start_system,
    save_start_system,
)
from pkmkit.solve.study_rods import StudyHomotopy


def _same_set(u: np.ndarray, v: np.ndarray, tol: float = 1e-8) -> bool:
    gap = np.abs(u[:, None] - v[None]).max(axis=2)
    return bool(len(u) == len(v) and (gap.min(axis=1) <= tol).all()
                and (gap.min(axis=0) <= tol).all())


def test_stored_start_system_is_checked_and_complete():
    start = load_start_system()
    assert start.solutions.shape == (GENERIC_COUNT, 8)
    assert start.residual().max() < 1e-10
    check_start_system(start)  # raises unless regular and distinct


@pytest.mark.ci
def test_total_degree_homotopy_finds_the_same_40_solutions():
    """Ab initio count, independent of the monodromy: a total-degree homotopy (2⁷ = 128 paths)
    on the start system; its finite regular end points must be exactly the stored 40."""
    start = load_start_system()
    system = StudyHomotopy.between(start.parameters, start.parameters, start.patch)
    v = start.patch
    gamma = np.exp(2.1j)

    def evaluate(x, t, rows):
        f, jf, _ = system.evaluate(x, np.zeros(len(x)), None)
        g = x[:, :7] ** 2 - x[:, 7:8] ** 2
        jg = np.zeros_like(jf[:, :7])
        jg[:, np.arange(7), np.arange(7)] = 2 * x[:, :7]
        jg[:, :, 7] = -2 * x[:, 7:8]
        tt = t[:, None]
        res = f.copy()
        res[:, :7] = (1 - tt) * f[:, :7] + gamma * tt * g
        jac = jf.copy()
        jac[:, :7] = (1 - tt)[:, :, None] * jf[:, :7] + gamma * tt[:, :, None] * jg
        d_t = np.zeros_like(f)
        d_t[:, :7] = gamma * g - f[:, :7]
        return res, jac, d_t

    signs = np.array(np.meshgrid(*[[1.0, -1.0]] * 7, indexing="ij")).reshape(7, -1).T
    homog = np.hstack([signs, np.ones((len(signs), 1))]).astype(complex)
    x0 = homog / (homog @ v)[:, None]  # on the patch
    assert np.abs(evaluate(x0, np.ones(len(x0)), None)[0]).max() < 1e-12

    def stop(x, t):  # the other 88 paths go to the set {e = 0, g·g = 0}
        e_norm = np.linalg.norm(x[:, :4], axis=1)
        return (t < 1e-4) & (e_norm < 1e-4 * np.linalg.norm(x, axis=1))

    result = track_paths(evaluate, x0, stop=stop, max_steps=400, predictor_tol=1e-6)
    reached = result.status == PathStatus.REACHED
    _, jac, _ = evaluate(result.x, np.zeros(len(x0)), None)
    regular = reached & (np.linalg.cond(jac) < 1e8)
    ends = result.x[regular]
    assert len(ends) == GENERIC_COUNT
    assert _same_set(ends, start.solutions)


@pytest.mark.ci
def test_monodromy_regenerates_the_stored_file(tmp_path):
    """The documented script (same seed) reproduces the package data, and a file round trip
    keeps it."""
    fresh = generate_start_system(SEED)
    stored = load_start_system()
    assert _same_set(fresh.solutions, stored.solutions, tol=1e-9)
    np.testing.assert_allclose(fresh.parameters.offset, stored.parameters.offset)
    path = tmp_path / "start.npz"
    save_start_system(fresh, path)
    assert _same_set(read_start_system(path).solutions, fresh.solutions, tol=0)


def test_check_rejects_a_corrupted_system(tmp_path):
    stored = load_start_system()
    path = tmp_path / "bad.npz"
    bad = type(stored)(stored.parameters, stored.patch, stored.solutions[:-1])
    save_start_system(bad, path)
    with pytest.raises(RuntimeError, match="39 solutions"):
        read_start_system(path)
    twice = stored.solutions.copy()
    twice[1] = twice[0]
    with pytest.raises(RuntimeError, match="coincide"):
        check_start_system(type(stored)(stored.parameters, stored.patch, twice))
