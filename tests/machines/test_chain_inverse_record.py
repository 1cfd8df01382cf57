"""A joint chain's batched inverse record computes its direct model only when read (issue 22 §3,
fifth pass): its stroke flags, closure and pose come from the inverse's own solution and must be
those of the direct model at the solution — which, started from that closure, converges there at
once — row by row, passive joints included."""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.chain_results import ChainInverseResult
from pkmkit.machines.joint_chain import JointChainMachine
from pkmkit.machines.strokes import signed_excess


def _targets(m, n: int, seed: int, tilt: float = 0.3) -> np.ndarray:
    """Tool points over the machine's default box, half with the home tool axis, half tilted:
    reachable rows within and beyond the strokes, and some unreachable."""
    lo, hi = m.default_box(5)
    rng = np.random.default_rng(seed)
    points = lo + (hi - lo) * rng.random((n, 3))
    axis = np.tile(m.home_pose[3:], (n, 1))
    axis[1::2] += tilt * rng.standard_normal((len(axis[1::2]), 3))
    return np.hstack([points, axis])


@pytest.fixture(params=["trimule-600", "tripteor-x7"])
def chain(request):
    return pkmkit.machine(request.param)


def test_the_lazy_record_is_the_direct_models_row_by_row(chain):
    m = chain
    x = _targets(m, 1500, seed=3)
    x[::300, 2] = 0.0  # a few out of reach (the legs cannot close with the tool at the
    # base's height; from its first-order start the Tripteor reaches every other row)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inv = m.ik(x, full_output=True)
        flags, start, pose = inv.out_of_stroke, inv.closure_start, inv.pose  # before direct
        direct = inv.direct
    solved = inv.status == pkmkit.Status.OK
    assert solved.sum() > 500 and (~solved).any()
    # the premise: from the inverse's closure the direct model converges at once, there
    assert (direct.iterations[solved] == 0).all()
    assert np.array_equal(flags, direct.out_of_stroke)
    assert np.array_equal(start, np.concatenate([direct.platform, direct.passive], axis=1),
                          equal_nan=True)
    assert np.array_equal(pose, direct.pose, equal_nan=True)
    act = m.model.actuated
    q_in = ~(signed_excess(inv.q, m.model.q_min[act], m.model.q_max[act]) != 0).any(axis=1)
    assert (solved & ~flags).any() and (solved & ~q_in & flags).any()
    if np.isfinite(m.model.q_min[m.passive_variables]).any():  # the TriMule's leg joints
        # rows whose actuators are within their strokes but a passive joint is not: flags
        # from the actuators alone would differ there
        assert (solved & q_in & flags).any()


def test_the_lazy_record_runs_no_direct_model_until_read(monkeypatch):
    m = pkmkit.machine("trimule-600")
    x = _targets(m, 60, seed=4)
    calls = []
    fk = JointChainMachine.fk

    def counted(self, *args, **kwargs):
        calls.append(1)
        return fk(self, *args, **kwargs)

    monkeypatch.setattr(JointChainMachine, "fk", counted)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inv = m.ik(x, full_output=True)
        assert inv.out_of_stroke.shape == (60,) and inv.closure_start.shape[0] == 60
        assert inv.pose.shape == (60, 6)
        assert calls == []
        direct = inv.direct
    assert calls == [1] and inv.direct is direct
    # pickled, it is the plain record with every field computed
    plain = pickle.loads(pickle.dumps(inv))
    assert type(plain) is ChainInverseResult
    assert np.array_equal(plain.direct.pose, direct.pose, equal_nan=True)
    assert np.array_equal(plain.closure_start, inv.closure_start, equal_nan=True)


@pytest.mark.parametrize("strokes", ["refuse", "ignore"])
def test_the_lazy_record_keeps_the_stroke_modes(strokes):
    m = pkmkit.machine("tripteor-x7")
    x = _targets(m, 200, seed=5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inv = m.ik(x, full_output=True, strokes=strokes)
        flagged = m.ik(x, full_output=True)
    if strokes == "ignore":
        assert inv.out_of_stroke is None
        assert np.array_equal(inv.direct.status == pkmkit.Status.OK, np.isfinite(inv.q[:, 0]))
    else:
        refused = inv.status == pkmkit.Status.OUT_OF_STROKE
        assert np.array_equal(refused, flagged.out_of_stroke & (flagged.status == 0))
        assert np.array_equal(inv.out_of_stroke, refused)
        assert np.isnan(inv.pose[refused]).all() and np.isnan(inv.closure_start[refused]).all()
        assert np.array_equal(inv.pose, inv.direct.pose, equal_nan=True)


def test_a_pose_read_after_direct_is_the_direct_records(monkeypatch):
    """``known_fields()`` is the record's live mapping of the fields given or computed: a
    ``pose`` read after ``direct`` takes the direct record's pose (no tool rows computed), one
    read first computes the tool rows."""
    from pkmkit.machines import chain_inverse_record

    m = pkmkit.machine("tripteor-x7")
    x = _targets(m, 40, seed=6)
    calls = []
    tool_pose = chain_inverse_record.tool_pose

    def counted(*args):
        calls.append(1)
        return tool_pose(*args)

    monkeypatch.setattr(chain_inverse_record, "tool_pose", counted)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        inv = m.ik(x, full_output=True)
        known = inv.known_fields()
        assert "q" in known and "direct" not in known
        direct = inv.direct
        assert known["direct"] is direct and inv.known_fields() is known
        pose = inv.pose
        assert calls == []
        assert np.array_equal(pose, direct.pose, equal_nan=True)
        other = m.ik(x, full_output=True)
        assert np.array_equal(other.pose, pose, equal_nan=True)
    assert calls == [1]
