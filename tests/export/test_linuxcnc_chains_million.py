"""The joint-chain LinuxCNC modules against pkmkit on 10⁶ random actuator sets and poses
(issue 23: ≤ 1e-9 m, the same assembly mode, the same refusals), behind the ``slow`` marker.

The reference is batched and fast: pkmkit's direct model on the compiled closure
(``fk(..., compiled=True)``, :func:`pkmkit.solve.chains.solve_closure`), ≈ 10–30 µs per
configuration. Through the inverse, a pose reached at an actuator set comes with its own
configuration — pkmkit's direct model put the tool there — so the module must return those
joints (the same assembly mode and head branch) or refuse as pkmkit refuses; wherever its
answer is anything else, and on every pose moved off the reached set, pkmkit's inverse model
itself (the NumPy engine, ≈ 0.1–0.3 ms per pose) is the reference, and on a sample of 10⁴ poses
besides. The ordinary run's checks are in ``test_linuxcnc_chains.py`` (10³ sets and poses).
"""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.status import Status

from .test_linuxcnc_chains import REFUSED, TOL, ChainModule, actuator_draw

#: Poses per machine: 10⁶; the TriMule's module costs ≈ 0.2 ms per forward and 0.6 ms per
#: inverse call from home (22 and 27 unknowns), pkmkit's inverse model ≈ 0.9 ms, and its draws
#: on the head's far branch (|Q4| > π/2, 29 %) go to pkmkit's inverse: 10⁵ keep it to minutes.
COUNTS = {"tripteor-x7": 1_000_000, "crank-slider": 1_000_000, "trimule-600": 100_000}
CHUNK = 50_000


def _direct(m, q: np.ndarray, strokes: str) -> tuple[np.ndarray, np.ndarray]:
    """pkmkit's direct model on the compiled closure, in chunks: ``(pose (N, 6), status)``."""
    pose, status = np.full((len(q), 6), np.nan), np.zeros(len(q), dtype=int)
    for i in range(0, len(q), CHUNK):
        res = m.fk(q[i:i + CHUNK], full_output=True, strokes=strokes, compiled=True)
        pose[i:i + CHUNK], status[i:i + CHUNK] = res.pose, np.asarray(res.status)
    return pose, status


def _inverse(m, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """pkmkit's inverse model from home, refusing strokes: ``(q (N, n), status (N,))``."""
    q, status = np.zeros((len(x), m.n_actuators)), np.zeros(len(x), dtype=int)
    for i in range(0, len(x), CHUNK // 5):  # the engine's Jacobians: ≈ 8 kB a pose
        res = m.ik(x[i:i + CHUNK // 5], full_output=True, strokes="refuse")
        q[i:i + CHUNK // 5], status[i:i + CHUNK // 5] = res.q, np.asarray(res.status)
    return q, status


def _agree(m, x: np.ndarray, q_c: np.ndarray, status_c: np.ndarray) -> int:
    """The module's inverse of poses ``x`` against pkmkit's: the same joints (1e-9 m, rad)
    where both reach a pose, the same refusals — except where one solver stops short from home
    on a pose the other reaches: the module stalling (−5), or pkmkit's engine stalling or
    stopping at a least-squares minimum that is no solution (NOT_CONVERGED, UNREACHABLE) where
    the module's joints are a configuration of pkmkit's direct model within the strokes.
    Returns how many stopped short."""
    q_r, status_r = _inverse(m, x)
    ok_c, ok_r = status_c == 0, status_r == Status.OK
    short = ((status_c == -5) & ok_r) | (
        np.isin(status_r, [Status.NOT_CONVERGED, Status.UNREACHABLE]) & ok_c)
    rows = np.flatnonzero(short & ok_c)
    if rows.size:  # the module's joints where pkmkit's engine stopped short
        pose, status = _direct(m, q_c[rows], "refuse")
        confirmed = (status == Status.OK) & (np.abs(pose - x[rows]).max(axis=1) <= TOL)
        short[rows[~confirmed]] = False
    assert np.array_equal(ok_c[~short], ok_r[~short])
    both = ok_c & ok_r
    assert np.abs(q_c[both] - q_r[both]).max(initial=0.0) <= TOL
    return int(short.sum())


@pytest.mark.slow
@pytest.mark.parametrize("name", list(COUNTS))
def test_a_million_poses(name, tmp_path):
    m = pkmkit.machine(name)
    n = COUNTS[name]
    module = ChainModule(m, tmp_path)
    rng = np.random.default_rng(23)
    q = actuator_draw(m, n, seed=23, beyond=0.02)
    # forward: the same tool point and axis, the same refusals (strokes, no assembly)
    pose, status = _direct(m, q, "refuse")
    ok = status == Status.OK
    assert 0.3 < ok.mean() or m.n_actuators == 1
    pose_c, status_c = module.forward(q)
    assert np.array_equal(status_c == 0, ok)
    assert np.abs(pose_c[ok] - pose[ok]).max() <= TOL

    # inverse: the reached poses (with the configuration they came from) and a tenth moved
    reached, _ = _direct(m, q, "ignore")
    keep = np.isfinite(reached).all(axis=1)
    x, drawn, drawn_ok = reached[keep], q[keep], ok[keep]
    moved = x[: n // 10] + rng.normal(0, 1, (n // 10, 6)) * [0.03, 0.03, 0.03, 0.1, 0.1, 0.1]
    moved[:, 3:] /= np.linalg.norm(moved[:, 3:], axis=1)[:, None]
    q_c, status_c = module.inverse(np.vstack([x, moved]))
    assert set(np.unique(status_c[status_c != 0])) <= REFUSED
    q_m, status_m = q_c[len(x):], status_c[len(x):]
    q_c, status_c = q_c[: len(x)], status_c[: len(x)]

    same = (status_c == 0) & drawn_ok & (np.abs(q_c - drawn).max(axis=1) <= TOL)
    settled = same | ((status_c != 0) & ~drawn_ok)
    rest = np.flatnonzero(~settled)  # anything else: pkmkit's inverse model decides
    # (the TriMule's sets drawn on the head's far branch, |Q4| > π/2, come back on the near one)
    flip = m.chain_tables().head_flip
    far = (np.abs(drawn[:, list(m.chain_tables().actuated).index(flip[0])]) > np.pi / 2
           if flip else np.zeros(len(x), dtype=bool))
    assert rest.size <= 0.01 * len(x) + far.sum()
    stalled = _agree(m, x[rest], q_c[rest], status_c[rest])
    # the refusals of the drawn sets beyond a stroke: pkmkit's inverse refuses them too
    refused = np.flatnonzero((status_c != 0) & ~drawn_ok)
    sample = rng.choice(refused, min(refused.size, 10_000), replace=False)
    stalled += _agree(m, x[sample], q_c[sample], status_c[sample])
    # the moved poses, every one through pkmkit's inverse model
    stalled += _agree(m, moved, q_m, status_m)
    assert (status_m != 0).sum() > 0.3 * len(moved)
    # and a sample of the settled rows, through pkmkit's inverse model as well
    sample = rng.choice(np.flatnonzero(settled), 10_000, replace=False)
    stalled += _agree(m, x[sample], q_c[sample], status_c[sample])
    # measured: none on the Tripteor and the crank–slider; on the TriMule ≈ 0.1 % (poses of
    # small Q5 with Q4 far from home's, where a start at home sits at the wrist singularity)
    assert stalled <= 0.005 * len(x)
