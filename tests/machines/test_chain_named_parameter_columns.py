"""Columns of the named parameters of the joint-chain kinds (central differences of the direct
model, the machine rebuilt on either side) against what they must be (issue 18 §9, plausible
bugs: the minus side's tool axis taken for its tool point passed every test of
``tests/machines``): a longer tool moves the tool point along the tool axis and turns
nothing; the characteristic length (a scale of the residuals) moves nothing."""

import numpy as np
import pytest

import pkmkit
from pkmkit.geometric_errors.parameter_sensitivity import parameter_sensitivity


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_tool_length_column_is_the_tool_axis(name):
    m = pkmkit.machine(name)
    q = np.vstack([m.home_q, m.home_q + 0.02 * np.sign(np.arange(m.n_actuators) % 2 - 0.5)])
    pose = m.fk(q, full_output=True, strokes="ignore").pose
    assert np.isfinite(pose).all()
    s = parameter_sensitivity(m, q, names=("tool_length", "characteristic_length"))
    axis = pose[:, 3:6] / np.linalg.norm(pose[:, 3:6], axis=1)[:, None]
    np.testing.assert_allclose(s.point[:, :, 0], axis, atol=1e-7)
    np.testing.assert_allclose(s.rotation[:, :, 0], 0.0, atol=1e-7)
    np.testing.assert_allclose(s.point[:, :, 1], 0.0, atol=1e-7)
    np.testing.assert_allclose(s.rotation[:, :, 1], 0.0, atol=1e-7)
