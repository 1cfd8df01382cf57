"""A full-pose machine's batched inverse record computes its assembly mode when read
(machines/full_pose_inverse_record.py): the same modes as one pose at a time and as the sign of
det A built here from the rod vectors, unaffected by later changes to the inputs."""

import pickle

import numpy as np
import pytest

from pkmkit.machines.registry import machine
from pkmkit.machines.results import InverseResult
from pkmkit.solve.rod_closure import rod_base_points


def _poses(m, rows: int, seed: int) -> np.ndarray:
    """Poses around home: positions only for a machine whose rods set its orientation."""
    home = np.asarray(m.home_pose, dtype=float)
    width = 3 if m.id == "verne" else 6
    rng = np.random.default_rng(seed)
    scale = np.array([0.02, 0.02, 0.02, 0.05, 0.05, 0.05])[:width]
    return home[:width] + rng.uniform(-1, 1, (rows, width)) * scale


def _det_a_sign(m, pose: np.ndarray, q: np.ndarray) -> int:
    """Oracle: the sign of det A with A's rows (d_j, r_j × d_j), d_j the rod vector from its
    base joint (the machine's rod geometry at ``q``) to its platform joint r_j = R b_j + p."""
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_rotvec(pose[3:6]).as_matrix()
    r = np.asarray(m.model.rod_platform) @ rot.T
    base = rod_base_points(m.model, q[:, None])[:, :, 0].T  # (6, 3)
    d = pose[:3] + r - base
    return int(np.sign(np.linalg.det(np.hstack([d, np.cross(r, d)]))))


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod", "verne"])
def test_batch_mode_is_one_pose_at_a_time(name):
    m = machine(name)
    x = _poses(m, 40, 1)
    batch = m.ik(x, full_output=True)
    assert "mode" not in batch.known_fields()  # not computed with the inverse
    singles = [int(m.ik(row, full_output=True).mode) for row in x]
    assert batch.mode.tolist() == singles
    ok = batch.status == 0
    assert ok.sum() >= 30 and set(batch.mode[ok].tolist()) <= {-1, 1}
    assert (batch.mode[~ok] == 0).all()


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod"])
def test_batch_mode_is_the_sign_of_det_a(name):
    m = machine(name)
    x = _poses(m, 12, 2)
    batch = m.ik(x, full_output=True)
    for k in np.flatnonzero(batch.status == 0):
        assert batch.mode[k] == _det_a_sign(m, x[k], batch.q[k])


def test_mode_read_late_ignores_changes_to_the_poses_and_q():
    m = machine("gough-stewart")
    x = _poses(m, 20, 3)
    expected = m.ik(x.copy(), full_output=True).mode.copy()
    late = m.ik(x, full_output=True)
    x[:] = 0.0
    with pytest.raises(ValueError):  # read-only (docs/kinematics.md)
        late.q[:] = np.nan
    assert np.array_equal(late.mode, expected)


def test_pickled_batch_record_is_the_plain_record_with_its_mode():
    m = machine("gough-stewart")
    batch = m.ik(_poses(m, 5, 4), full_output=True)
    back = pickle.loads(pickle.dumps(batch))
    assert type(back) is InverseResult
    assert np.array_equal(back.mode, batch.mode) and back.iterations is None
