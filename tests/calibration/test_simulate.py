"""Synthetic measurements: compatible random defects, the default regions, noise models."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import default_configurations, random_defects, simulate
from pkmkit.calibration.simulate import Noise
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.model import tool_sensitivity
from pkmkit.machines.strokes import stroke_limits as _strokes
from pkmkit.model.defects_table import apply_defect_vector


def test_tripteor_random_defects_are_compatible_and_realistic():
    m = pkmkit.machine("tripteor-x7")
    delta = random_defects(m, np.random.default_rng(3))
    units = np.array(m.model.defect_index.units)
    assert np.abs(delta[units == "m"]).max() <= 1e-4 * 1.5
    assert np.abs(delta[units == "1"]).max() <= np.sin(np.radians(0.5)) * 1.5
    true = apply_defect_vector(m, delta)
    # the legs close (to second order in the defects), unlike a random incompatible draw
    assert true.home_closure_residual < 1e-7
    q = default_configurations(m, 10, np.random.default_rng(0))
    sens = tool_sensitivity(m, q)
    assert np.abs(sens.closure_defect @ delta).max() < 1e-12
    raw = random_defects(m, np.random.default_rng(3), compatible=False)
    assert apply_defect_vector(m, raw).home_closure_residual > 1e-6


def test_tripteor_protocol_platform_and_wrist_moves():
    m = pkmkit.machine("tripteor-x7")
    q = default_configurations(m, 20, np.random.default_rng(1))
    lo, hi = _strokes(m)
    assert ((q >= lo) & (q <= hi)).all()
    platform, wrist = q[:10], q[10:]
    assert np.all(platform[:, 3] == 0.0) and np.all(platform[:, 4] == 0.0)
    np.testing.assert_allclose(wrist[:, :3], np.tile((lo[:3] + hi[:3]) / 2, (10, 1)))
    data = simulate(m, m, "point", 20, np.random.default_rng(1), q=q, noise="none")
    np.testing.assert_allclose(np.unique(data.tool_length), [0.110006, 0.169889])


@pytest.mark.parametrize("name", ["verne", "gough-stewart", "linear-delta"])
def test_rod_machines_default_region_within_strokes(name):
    m = pkmkit.machine(name)
    q = default_configurations(m, 30, np.random.default_rng(2))
    lo, hi = _strokes(m)
    assert ((q >= lo) & (q <= hi)).all()
    assert np.isfinite(m.fk(q)).all()


def test_tracker_noise_model():
    noise = Noise.parse("tracker", "point")
    pts = np.zeros((4, 3))
    # the tracker 2.5 m from the centre of the points: (15 µm + 6 µm/m × 2.5 m) / 2
    np.testing.assert_allclose(noise.position_sigma(pts), (15e-6 + 6e-6 * 2.5) / 2)
    m = pkmkit.machine("linear-delta")
    q = default_configurations(m, 2000, np.random.default_rng(0))
    exact = simulate(m, m, "point", 2000, np.random.default_rng(0), q=q, noise="none")
    noisy = simulate(m, m, "point", 2000, np.random.default_rng(0), q=q, noise=1e-5)
    assert np.std(noisy.values - exact.values) == pytest.approx(1e-5, rel=0.05)
    with pytest.raises(InputError, match="unknown noise model"):
        Noise.parse("laser", "point")


def test_part_and_ballbar_simulations():
    m = pkmkit.machine("verne")
    part = simulate(m, m, "part", 60, np.random.default_rng(0), noise="none")
    assert len(set(part.path)) == 12
    ball = simulate(m, m, "ballbar", 20, np.random.default_rng(0))
    assert ball.pivot.shape == (20, 3)
    assert np.allclose(ball.values, 0.15, atol=1e-3)  # the true pivots differ by ≤ 0.35 mm
