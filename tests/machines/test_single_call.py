"""One pose per call takes a plain-Python path (issue 22 §1): the same numbers as the batch path
(bit for bit for slides and struts, which use only +, −, ×, √; to an ulp for cranks, whose
arccos and arctan2 NumPy may vectorise differently from the C library), and the same refusals
(which the batch path raises)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, StrokeWarning, UnreachablePoseError

TRANSLATIONAL = [name for name in pkmkit.machines()
                 if pkmkit.machine(name).family == "translational"]


def _poses(m, n=300, seed=0):
    lo, hi = m.default_box()
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * rng.random((n, m.dims))


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_single_pose_equals_the_batch_reference_bit_for_bit(name):
    m = pkmkit.machine(name)
    x = _poses(m)
    reference = m._closed.inverse_numpy(x, m.model.leg_branch)
    got, rows = [], []
    for k in range(len(x)):
        fast = m._closed.inverse_one(x[k], tuple(m.model.leg_branch.tolist()))
        if fast is None:  # out of reach: the batch path gives NaN there
            assert not np.isfinite(reference[k]).all()
            continue
        got.append(fast)
        rows.append(k)
    assert len(rows) > 100
    # every answer against its row in one comparison (docs/testing.md, "Sixth round (session
    # 34, suite3a)")
    if m.angular_actuators.any():
        np.testing.assert_allclose(np.array(got), reference[rows], rtol=0,
                                   atol=4 * np.spacing(np.pi))
    else:
        np.testing.assert_array_equal(np.array(got), reference[rows])


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_ik_of_one_pose_is_the_batch_row(name):
    m = pkmkit.machine(name)
    x = _poses(m, 50, seed=1)
    batch = m.ik(x, strokes="ignore")
    got, rows = [], []
    for k in np.flatnonzero(np.isfinite(batch).all(axis=1)):
        for given in (x[k], x[k].tolist(), tuple(x[k].tolist())):
            q = m.ik(given, strokes="ignore")
            assert q.shape == (m.n_actuators,)
            got.append(q)
            rows.append(k)
    np.testing.assert_allclose(np.array(got), batch[rows], rtol=0, atol=4 * np.spacing(np.pi))


def test_refusals_are_those_of_the_batch_path():
    m = pkmkit.machine("linear-delta")
    with pytest.raises(UnreachablePoseError):
        m.ik([2.0, 0.0, 0.0])
    for bad in ([np.nan, 0.0, 0.0], [0.0, 0.0], [1e300, 0.0, 0.0], [0.0, np.inf, 0.0]):
        with pytest.raises(InputError):
            m.ik(bad)
    with pytest.warns(StrokeWarning):
        m.ik([0.0, 0.0, 1.0])  # reachable, beyond the slides' strokes
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        q = m.ik([0.0, 0.0, 1.0], strokes="ignore")
    assert np.isfinite(q).all()


@pytest.mark.parametrize("name", TRANSLATIONAL)
@pytest.mark.parametrize("mode", ["working", "other"])
def test_fk_of_one_configuration_is_the_batch_row(name, mode):
    """The plain-Python direct model (closed_form_one) against the batch path's row, in both
    assembly modes, on configurations of random poses and beyond (no assembly)."""
    m = pkmkit.machine(name)
    q = m.ik(_poses(m, 300, seed=2), strokes="ignore")
    q = q[np.isfinite(q).all(axis=1)]
    q[::9] *= 1.7  # some near the boundary of the assembly region, or beyond
    if not m.angular_actuators.any():  # one slide or strut far away: no assembly
        q[::11, 0] += 10.0 * m.model.leg_length.max()
    batch = m.fk(q, mode=mode, full_output=True, strokes="ignore")
    got, rows = [], []
    for k in range(len(q)):
        for given in (q[k], q[k].tolist()):
            if batch.status[k] != 0:
                with pytest.raises(Exception) as raised:
                    m.fk(given, mode=mode, strokes="ignore")
                assert raised.type.__name__ in ("NoAssemblyError", "SingularConfigurationError")
                continue
            one = m.fk(given, mode=mode, strokes="ignore")
            assert one.shape == (m.dims,)
            got.append(one)
            rows.append(k)
    assert len(rows) > 300
    np.testing.assert_allclose(np.array(got), batch.pose[rows], rtol=0, atol=1e-12)
    assert (batch.status != 0).any() or m.angular_actuators.any()  # cranks: angles wrap


def test_fk_of_one_configuration_refusals_are_those_of_the_batch_path():
    from pkmkit.exceptions import NoAssemblyError, OutOfStrokeError, SingularConfigurationError

    m = pkmkit.machine("linear-delta")
    far = m.home_q + np.array([10.0, 0.0, 0.0])  # one carriage far up: the rods cannot meet
    with pytest.raises(NoAssemblyError):
        m.fk(far, strokes="ignore")
    for bad in ([np.nan, 0.0, 0.0], [0.0, 0.0], [1e300, 0.0, 0.0]):
        with pytest.raises(InputError):
            m.fk(bad)
    with pytest.raises(InputError, match="mode"):
        m.fk(m.home_q, mode="sideways")
    five = pkmkit.machine("five-bar")
    c = five.closed_form.centres(five.home_q[None])[0][0]
    if np.allclose(c[0], c[1]):  # coincident circle centres: no isolated solution
        with pytest.raises(SingularConfigurationError):
            five.fk(five.home_q)
    beyond = m.ik([0.0, 0.0, 1.0], strokes="ignore")  # assembles, beyond the slides' strokes
    with pytest.warns(StrokeWarning):
        m.fk(beyond)
    with pytest.raises(OutOfStrokeError):
        m.fk(beyond, strokes="refuse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(m.fk(beyond, strokes="ignore"), [0.0, 0.0, 1.0], atol=1e-12)


def test_inverse_one_follows_branches_changed_in_place():
    """The previous call's leg constants are reused only for the same immutable tuple: a list
    of branches changed in place between two calls gives the new branches' answer."""
    m = pkmkit.machine("linear-delta")
    closed = m._closed
    x = [0.01, -0.02, 0.05]
    branches = [float(b) for b in m.model.leg_branch]
    first = closed.inverse_one(x, branches)
    branches[0] = -branches[0]
    flipped = closed.inverse_one(x, branches)
    reference = m.ik(np.array([x]), branches=np.array(branches), strokes="ignore")[0]
    np.testing.assert_array_equal(flipped, reference)
    assert flipped[0] != first[0] and flipped[1:] == first[1:]
