"""One pose per call from a caller's start and with ``full_output`` on the joint chains (issue
22 §1): ``m.ik(x, start=s)`` and ``m.ik(x, full_output=True)`` of one plain pose take the
one-pose path and give the batch path's row — every field of the record, bit for bit — so a
controller's loop passes each call's ``solution`` to the next."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pkmkit.exceptions import OutOfStrokeError, StrokeWarning
from pkmkit.machines import chain_starts
from pkmkit.machines.chain_results import ChainInverseResult
from pkmkit.numerics import jit
from tests.machines.test_chain_one import NAMES, batch_ik, fresh, within_stroke_poses

pytestmark = pytest.mark.skipif(not jit.numba_available() or jit.mode() == "0",
                                reason="the one-pose paths run the compiled closure")


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    return fresh(request.param)


def toolpath(m, n: int) -> np.ndarray:
    """A circle of radius 4 mm, points 0.5 mm apart, around the pose of mid-stroke actuators
    (the wrist tilted by 0.3 rad), the tool axis swinging by up to 3° about it."""
    act = np.flatnonzero(m.model.actuated)
    centre = 0.5 * (m.model.q_min[act] + m.model.q_max[act])
    centre[4] = 0.3
    pose = m.fk(centre)
    t = np.arange(n) * 0.125
    x = np.tile(pose, (n, 1))
    x[:, 0] += 0.004 * np.cos(t)
    x[:, 1] += 0.004 * np.sin(t)
    side = np.cross(pose[3:], [0.0, 0.0, 1.0])
    x[:, 3:] += np.radians(3.0) * np.sin(t / 3)[:, None] * side / np.linalg.norm(side)
    x[:, 3:] /= np.linalg.norm(x[:, 3:], axis=1)[:, None]
    return x


def is_one_pose(record) -> bool:
    return type(record).__name__.startswith("OnePose")


def assert_same_record(one, ref) -> None:
    """Every field of two inverse records equal, types and shapes too (``direct`` and
    ``pose`` read last: the one-pose record computes them when read)."""
    for name in ChainInverseResult.__dataclass_fields__:
        a, b = getattr(one, name), getattr(ref, name)
        if name == "direct":
            for field in b.__dataclass_fields__:
                x, y = getattr(a, field), getattr(b, field)
                assert type(x) is type(y) and np.array_equal(
                    np.asarray(x, dtype=object), np.asarray(y, dtype=object)), field
            continue
        assert type(a) is type(b), name
        if isinstance(a, str) or a is None:
            assert a == b, name
        else:
            assert np.shape(a) == np.shape(b) and np.array_equal(a, b, equal_nan=True), name
            assert np.array_equal(np.signbit(a), np.signbit(b)), name  # -0.0 is not +0.0


def test_full_output_is_the_batch_record(machine):
    m = machine
    _, x = within_stroke_poses(m, 20, seed=3)
    fast = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for pose in x:
            for strokes in ("flag", "ignore", "refuse"):
                try:
                    ref = batch_ik(m, pose, full_output=True, strokes=strokes)
                except OutOfStrokeError:  # a passive joint beyond its stroke (TriMule)
                    with pytest.raises(OutOfStrokeError):
                        m.ik(pose, full_output=True, strokes=strokes)
                    continue
                one = m.ik(pose, full_output=True, strokes=strokes)
                fast += is_one_pose(one)
                assert_same_record(one, ref)
    assert fast >= len(x)  # the path is taken (TriMule: some rows beyond a passive stroke)


def test_a_loop_from_each_previous_solution_is_the_batch_path(machine):
    """Along a toolpath, each call started from the previous call's ``solution``: the batch
    path's row from the same start, bits and iterations; fewer iterations than the default
    start's."""
    m = machine
    x = toolpath(m, 60)
    solution = m.ik(x[0], full_output=True).solution
    fast = warm = default = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for pose in x[1:]:
            one = m.ik(pose, start=solution, full_output=True)
            fast += is_one_pose(one)
            assert_same_record(one, batch_ik(m, pose, start=solution, full_output=True))
            assert np.array_equal(m.ik(pose, start=solution), one.q)
            assert np.array_equal(m.ik(pose, start=list(solution)), one.q)
            warm += one.iterations
            default += m.ik(pose, full_output=True).iterations
            solution = one.solution
    assert fast == len(x) - 1
    if chain_starts.closed_starts(m, x[:1], np.array([m.tool_length])) is None:
        assert warm < default
    else:  # the TriMule's closed-form start is the solution: no warm start beats it
        assert default < warm


def test_a_start_the_fast_path_does_not_take_goes_to_the_batch_path(machine):
    m = machine
    _, x = within_stroke_poses(m, 3, seed=4)
    start = m.ik(x[0], full_output=True).solution
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for bad in (np.r_[start[:-1], np.nan], start[:-1], [*start[:-1], "1"]):
            try:
                expected = batch_ik(m, x[1], start=bad)
            except Exception as error:
                with pytest.raises(type(error)):
                    m.ik(x[1], start=bad)
                continue
            assert np.array_equal(m.ik(x[1], start=bad), expected)


def test_a_one_pose_record_pickles_as_the_plain_record(machine):
    import copy
    import pickle

    _, x = within_stroke_poses(machine, 3, seed=6)
    one = machine.ik(x[0], full_output=True)
    assert is_one_pose(one)
    for again in (pickle.loads(pickle.dumps(one)), copy.deepcopy(one)):
        assert type(again) is ChainInverseResult
        assert_same_record(again, batch_ik(machine, x[0], full_output=True))
