"""``pose_to_cli`` of rotation-vector poses (the Verne module's ``pkmkit ik --input`` writes
the orientation its rods impose as angles) converts in blocks of ``ANGLE_BLOCK_ROWS`` rows:
the same bits as one pass of ``pose_to_angles`` over the finite rows (the former path), NaN
rows and whole NaN blocks included; scipy's ``Rotation.as_euler`` as the independent oracle."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.boundary import coordinates
from pkmkit.boundary.coordinates import pose_to_cli
from pkmkit.model.parameters import length_scale
from pkmkit.spatial.poses import pose_to_angles

Rotation = pytest.importorskip("scipy.spatial.transform").Rotation


def _former(poses, units, convention):
    out = poses.copy()
    out[:, :3] /= length_scale(units)
    finite = np.isfinite(poses).all(axis=1)
    out[~finite, 3:] = np.nan
    if finite.any():
        out[finite, 3:] = np.atleast_2d(pose_to_angles(poses[finite], convention,
                                                      degrees=True)[1])
    return out


@pytest.mark.parametrize("convention", ["xyz", "ZYX", "zyz"])
def test_blocks_give_the_former_bits(convention, monkeypatch):
    """Blocks of 1,000 rows over 4,321 rows with NaN and inf rows, a block all NaN, gimbal
    locks and zero rotations: the former single pass's bits; finite rows against scipy."""
    monkeypatch.setattr(coordinates, "ANGLE_BLOCK_ROWS", 1000)
    m = pkmkit.machine("verne")
    rng = np.random.default_rng(9)
    poses = np.concatenate([rng.uniform(-0.3, 0.3, (4321, 3)),
                            rng.normal(size=(4321, 3)) * 0.8], axis=1)
    poses[5::97, 4] = np.nan
    poses[11::203, 0] = np.inf
    poses[2000:3000] = np.nan
    poses[3100, 3:] = 0.0
    poses[3101, 3:] = [0.0, np.pi / 2, 0.0]
    for units in ("m", "mm"):
        got = pose_to_cli(poses, m, units, convention)
        want = _former(poses, units, convention)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
        np.testing.assert_array_equal(got[~np.isnan(got)].view(np.int64),
                                      want[~np.isnan(want)].view(np.int64))
    finite = np.isfinite(poses).all(axis=1)
    finite[3100:3102] = False  # gimbal locks (zyz at zero): scipy's split of the angles may differ
    seq = {"xyz": "xyz", "ZYX": "ZYX", "zyz": "zyz"}[convention]
    oracle = Rotation.from_rotvec(poses[finite, 3:]).as_euler(seq, degrees=True)
    np.testing.assert_allclose(got[finite, 3:], oracle, rtol=0, atol=1e-9)
