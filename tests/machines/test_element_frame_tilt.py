"""A joint-chain element whose axis a parameter vector tilts keeps its frame continuous
(``parameter_vector.element_frame``): the new frame is the old one turned by the smallest
rotation taking the old axis onto the new one (oracle: Rodrigues' formula written here, about
old z × new z by the angle between them), not spun about the axis. Checked on every revolute
and prismatic element of both joint-chain machines, each axis tilted by 0.02 rad about a
direction across it."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.parameter_vector import element_frame


def _rodrigues(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation by the angle between unit vectors a, b about a × b."""
    k = np.cross(a, b)
    s, c = np.linalg.norm(k), float(a @ b)
    k = k / s
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_a_tilted_axis_turns_the_frame_by_the_smallest_rotation(name):
    m = pkmkit.machine(name)
    model = m.model
    checked = 0
    rng = np.random.default_rng(7)
    for e, spec in enumerate(model.elements):
        if spec.type not in ("R", "P") or spec.rotation is not None:
            continue
        frame = np.asarray(model.nominal_frames[e], dtype=float)
        z = frame[:3, 2]
        across = np.cross(z, rng.normal(size=3))
        across /= np.linalg.norm(across)
        new_z = np.cos(0.02) * z + np.sin(0.02) * across
        values = np.array([*new_z, *spec.point])
        got = element_frame(spec, frame, values)[:3, :3]
        want = _rodrigues(z, new_z) @ frame[:3, :3]
        np.testing.assert_allclose(got, want, atol=1e-12, err_msg=f"element {e}")
        checked += 1
    assert checked >= 5
