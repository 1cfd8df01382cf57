"""pkmkit's spatial functions take read-only arrays — the fields of its own records (an
``fk(..., full_output=True).pose``, a Jacobians record's arrays are read-only) — and give the
same bits as for a writeable copy. SciPy 1.17's ``Rotation.from_rotvec`` and
``Rotation.apply`` refuse read-only buffers ("buffer source array is read-only"); before this
session ``to_transform(m.fk(q, full_output=True).pose)`` raised that ValueError (the call now
passes SciPy a copy, as ``pose_parts`` already did)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.spatial import poses, rotation, twists


def _read_only(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


ROWS = np.array([[0.01, -0.02, 0.80, 0.10, -0.20, 0.30],
                 [0.03, 0.01, 0.75, -0.05, 0.02, 1.20]])
XI = np.array([[0.1, -0.2, 0.3, 0.4, 0.5, -0.6], [0.0, 0.0, 0.0, 1e-9, 2.0, 0.1]])

CALLS = {
    "to_transform": lambda a: poses.to_transform(a).as_matrix(),
    "to_transform one": lambda a: poses.to_transform(a[0]).as_matrix(),
    "pose_parts": lambda a: poses.pose_parts(a)[1].as_rotvec(),
    "pose_to_angles": lambda a: poses.pose_to_angles(a)[1],
    "pose_matrices": lambda a: poses.pose_matrices(a)[1],
    "compose_poses": lambda a: poses.compose_poses(a, a[::-1]),
    "invert_poses": lambda a: poses.invert_poses(a),
    "pose_difference": lambda a: poses.pose_difference(a, a[::-1]),
    "pose_from_angles": lambda a: poses.pose_from_angles(a[:, :3], a[:, 3:]),
    "rotvec_to_matrix": lambda a: rotation.rotvec_to_matrix(a[:, 3:]),
    "rotation_from_angles": lambda a: rotation.rotation_from_angles(a[:, 3:]).as_rotvec(),
    "rotvec_from_angles": lambda a: rotation.rotvec_from_angles(a[:, 3:]),
    "angles_from_rotvec": lambda a: rotation.angles_from_rotvec(a[:, 3:]),
    "se3_exp": lambda a: twists.se3_exp(a),
    "se3_log": lambda a: twists.se3_log(twists.se3_exp(a)),
}


@pytest.mark.parametrize("name", list(CALLS))
def test_read_only_rows_give_the_writeable_bits(name):
    data = XI if name.startswith("se3") else ROWS
    expected = np.asarray(CALLS[name](np.array(data)))
    got = np.asarray(CALLS[name](_read_only(data)))
    assert got.tobytes() == expected.tobytes()


def test_a_direct_model_record_goes_to_scipy_through_pkmkit():
    m = pkmkit.machine("gough-stewart")
    record = m.fk(m.ik(np.array([ROWS[0], ROWS[1] * [1, 1, 1, 0.1, 0.1, 0.1]])),
                  full_output=True)
    assert not record.pose.flags.writeable  # a record's field: read-only
    matrices = poses.to_transform(record.pose).as_matrix()
    np.testing.assert_array_equal(matrices, poses.to_transform(record.pose.copy()).as_matrix())
