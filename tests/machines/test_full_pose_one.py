"""One full pose per call takes a plain-Python path (issue 22 §1): the numbers of the batch
path (its NumPy reference and its compiled kernel, to rounding) and its refusals."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, OutOfStrokeError, StrokeWarning, UnreachablePoseError
from pkmkit.model.rods import STRUT
from pkmkit.spatial import pose_from_angles
from tests.machines.test_full_pose import _full_pose_delta

NAMES = ["gough-stewart", "verne", "dietmaier-hexapod", "delta6"]


def _machine(name):
    return _full_pose_delta() if name == "delta6" else pkmkit.machine(name)


def _poses(m, n, seed):
    """Full poses around home; for machines with fewer than six actuators, the poses their
    rods impose at random positions (and a few they cannot take)."""
    rng = np.random.default_rng(seed)
    if m.position_controlled:
        positions = m.home_pose[:3] + rng.uniform(-0.15, 0.15, (n, 3))
        poses = np.asarray(m.ik(positions, full_output=True, strokes="ignore").pose)
        poses = poses[np.isfinite(poses).all(axis=1)]
        poses[:5, 3:] += 0.01  # orientations the rods do not impose
        return poses
    lo, hi = m.home_pose[:3] - 0.2, m.home_pose[:3] + 0.2
    return pose_from_angles(rng.uniform(lo, hi, (n, 3)), rng.uniform(-20, 20, (n, 3)), "xyz",
                            degrees=True)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("compiled", ["0", "1"])
def test_one_pose_is_the_batch_row(name, compiled, monkeypatch):
    """Against the NumPy reference (PKMKIT_COMPILED=0) and the compiled kernel (=1): equal to
    1e-12 (m, rad) where the batch path has a configuration, None (→ the batch path) where
    it has none."""
    m = _machine(name)
    x = _poses(m, 300, seed=1)
    monkeypatch.setenv("PKMKIT_COMPILED", compiled)
    batch = m.ik(x, strokes="ignore")
    one = m.one_pose_inverse()
    got, rows = [], []
    for k in range(len(x)):
        for given in (x[k], x[k].tolist()):
            q = one(given)
            if q is None:
                assert not np.isfinite(batch[k]).all()
                continue
            got += [np.asarray(q, dtype=float), m.ik(given, strokes="ignore")]
            rows += [k, k]
    assert len(rows) > 2 * 400
    # every answer against its batch row in one comparison (docs/testing.md, "Sixth round
    # (session 34, suite3a)")
    np.testing.assert_allclose(np.array(got), batch[rows], rtol=0, atol=1e-12)
    assert not np.isfinite(batch).all() or not m.position_controlled


def test_one_pose_refusals_are_those_of_the_batch_path():
    verne = pkmkit.machine("verne")
    tilted = verne.home_pose + np.array([0.0, 0.0, 0.0, 0.0, 0.02, 0.0])
    with pytest.raises(UnreachablePoseError, match="orientations"):
        verne.ik(tilted)
    far = verne.home_pose + np.array([3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(UnreachablePoseError):
        verne.ik(far)
    hexapod = pkmkit.machine("gough-stewart")
    for bad in ([np.nan] * 6, [0.0] * 5, [1e300] * 6, np.full(6, np.inf), np.zeros((1, 1, 6))):
        with pytest.raises(InputError):
            hexapod.ik(bad)
    high = hexapod.home_pose + np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])  # struts too long
    with pytest.warns(StrokeWarning):
        hexapod.ik(high)
    with pytest.raises(OutOfStrokeError):
        hexapod.ik(high, strokes="refuse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isfinite(hexapod.ik(high, strokes="ignore")).all()
        hexapod.ik(hexapod.home_pose)


@pytest.mark.parametrize("name", ["gough-stewart", "orthoglide"])
def test_an_unknown_stroke_mode_is_refused_also_for_a_plain_pose(name):
    """The single-pose paths returned before checking ``strokes``: a misspelt mode at a pose
    within the strokes went unnoticed."""
    m = pkmkit.machine(name)
    with pytest.raises(InputError, match="strokes"):
        m.ik(m.home_pose, strokes="flagg")
    with pytest.raises(InputError, match="strokes"):
        m.fk(m.home_q, strokes="Ignore")


# the first machine in the ordinary run, the others marked ci (.ci/run): 0.35 s each
@pytest.mark.parametrize("name", [pytest.param(n, marks=[pytest.mark.ci] if k else [])
                                  for k, n in enumerate(NAMES)])
@pytest.mark.parametrize("threads", ["1", "2"])
def test_fused_compiled_inverse_is_the_numpy_path(name, threads, monkeypatch):
    """The one-pass compiled inverse (statuses included) against the NumPy reference path on
    poses in reach, out of reach, with orientations the rods do not impose, and invalid rows;
    on one thread and on two (chunks of 2¹⁶ rows)."""
    from pkmkit.numerics import jit

    m = _machine(name)
    x = _poses(m, 400, seed=2)
    rng = np.random.default_rng(3)
    x = np.resize(x, (2 * jit.THREAD_ROWS + 999, 6))
    x[::7, :3] += rng.uniform(-1.0, 1.0, (len(x[::7]), 3))  # some out of reach
    x[5], x[6, 2], x[8, 4] = np.nan, 2e9, np.inf
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    reference = m.ik(x, full_output=True, strokes="ignore")
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    monkeypatch.setenv("PKMKIT_THREADS", threads)
    q, status = m._forms.inverse_compiled(x, m._branches(None), m._consistency_tol())
    np.testing.assert_array_equal(status, reference.status)
    assert set(status.tolist()) >= {0, 4}
    assert (status == 1).any() == (m.model.rod_kind != STRUT).any()  # struts always reach
    np.testing.assert_allclose(q, reference.q, rtol=0, atol=1e-12, equal_nan=True)
    np.testing.assert_array_equal(np.asarray(m.ik(x, strokes="ignore")), q)
