"""Gravity deflection in compensation and in the calibration report
(:mod:`pkmkit.calibration.gravity`)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import pkmkit
import pkmkit.dynamics.defaults as defaults
import pkmkit.stiffness.chain_gravity as chain_gravity
from pkmkit.calibration.compensation import correct_table
from pkmkit.calibration.controller import commanded_q, reached
from pkmkit.calibration.gravity import aim_loaded, gravity_beside_residual, gravity_deflection
from pkmkit.calibration.simulate import random_defects
from pkmkit.exceptions import InputError


def _machines(name):
    """The nominal machine and a calibrated one (random defects of the simulations)."""
    nominal = pkmkit.machine(name)
    return nominal, nominal.with_defects(random_defects(nominal, np.random.default_rng(4)))


def _loaded_error(nominal, identified, targets, aimed, tl):
    """Where the calibrated machine's loaded tool point lands when the nominal controller is
    given the corrected targets of ``aimed``, minus the targets (m)."""
    fixed, flags = correct_table(nominal, identified, aimed, max_correction=0.05,
                                 tool_length=tl)
    assert (flags.status != "out-of-reach").all()
    fixed = reached(nominal, commanded_q(identified, aimed, tl), tl)  # strokes aside
    q = commanded_q(nominal, fixed, tl)
    point = reached(identified, q, tl)[:, :3]
    sag = gravity_deflection(identified, q, tool_length=tl).deflection[:, :3]
    return point + sag - targets[:, :3], sag


_CHAIN, _RODS = chain_gravity.illustrative_masses, defaults.default_masses


def _scale_gravity(monkeypatch, factor):
    """Every gravity model's g multiplied by ``factor`` (the loads scale with it)."""
    chain, rods = _CHAIN, _RODS
    g = np.array([0.0, 0.0, -9.81 * factor])
    monkeypatch.setattr(chain_gravity, "illustrative_masses", lambda m: chain(m, gravity=g))
    monkeypatch.setattr(defaults, "default_masses",
                        lambda m, **kw: dataclasses.replace(rods(m, **kw), gravity=g))


@pytest.mark.parametrize("name, tl", [("tripteor-x7", 0.15), ("orthoglide", None),
                                      ("dietmaier-hexapod", 0.15), ("verne", 0.1)])
def test_the_loaded_tool_point_of_the_compensated_machine_hits_the_target(monkeypatch, name,
                                                                          tl):
    """The error left is of second order in the deflection: a tenth of the weight leaves a
    hundredth of the error (a first-order error would leave a tenth)."""
    nominal, identified = _machines(name)
    rng = np.random.default_rng(3)
    step = rng.uniform(-0.004, 0.004, (12, identified.n_actuators))
    turn = identified.angular_actuators  # head axes: away from their stroke ends at home
    step[:, turn] = rng.uniform(0.1, 0.4, (12, int(turn.sum())))
    targets = reached(identified, identified.home_q + step, tl)
    left = {}
    for factor in (1.0, 0.1):
        _scale_gravity(monkeypatch, factor)
        aimed, sag = aim_loaded(identified, targets, tool_length=tl)
        size = np.linalg.norm(sag.deflection[:, :3], axis=1)
        assert size.min() > 1e-7 * factor  # a deflection worth compensating
        error, _ = _loaded_error(nominal, identified, targets, aimed, tl)
        left[factor] = np.linalg.norm(error, axis=1).max()
        assert left[factor] < 0.01 * size.max()
        # without --gravity the loaded tool point misses by the deflection (what this fixes)
        plain, sag_plain = _loaded_error(nominal, identified, targets, targets, tl)
        assert np.allclose(plain, sag_plain, atol=0.01 * size.max(), rtol=0)
    assert left[0.1] < left[1.0] / 30


def test_the_tool_axis_of_a_joint_chain_is_aimed_too():
    _, identified = _machines("tripteor-x7")
    targets = reached(identified, identified.home_q[None, :])
    aimed, sag = aim_loaded(identified, targets)
    turn = np.cross(sag.deflection[0, 3:], targets[0, 3:])
    assert np.linalg.norm(turn) > 1e-9
    expected = targets[0, 3:] - turn
    assert np.allclose(aimed[0, 3:], expected / np.linalg.norm(expected), atol=1e-15)


def test_the_platform_rotation_of_a_hexapod_is_aimed_too():
    """A six-actuator target's rotation vector is turned back by the sag's rotation:
    exp(−δθ) R."""
    from scipy.spatial.transform import Rotation

    _, identified = _machines("dietmaier-hexapod")
    targets = reached(identified, identified.home_q[None, :], 0.1)
    aimed, sag = aim_loaded(identified, targets, tool_length=0.1)
    turn = sag.deflection[0, 3:]
    assert np.linalg.norm(turn) > 1e-9
    expected = (Rotation.from_rotvec(-turn) * Rotation.from_rotvec(targets[0, 3:])).as_rotvec()
    np.testing.assert_allclose(aimed[0, 3:], expected, atol=1e-15)
    np.testing.assert_allclose(aimed[0, :3], targets[0, :3] - sag.deflection[0, :3], atol=1e-15)


def test_cranks_have_no_gravity_model():
    m = pkmkit.machine("delta")
    with pytest.raises(InputError, match="crank"):
        gravity_deflection(m, m.home_q)


class _Result:
    def __init__(self, machine, rms):
        self.machine = machine
        self.after = type("Stats", (), {"rms": rms})()


class _Measurements:
    def __init__(self, q, tool_length=None):
        self.q = q
        self.tool_length = tool_length


def test_the_report_figure_is_the_deflection_at_the_measured_configurations():
    m = pkmkit.machine("tripteor-x7")
    q = m.home_q + np.random.default_rng(4).uniform(-0.02, 0.02, (8, m.n_actuators))
    out = gravity_beside_residual(_Result(m, 5e-6), _Measurements(q))
    d = gravity_deflection(m, q).deflection[:, :3]
    assert out["available"] and out["configurations"] == 8
    assert out["rms"] == pytest.approx(np.sqrt(np.mean(np.sum(d**2, axis=1))), rel=1e-12)
    centred = d - d.mean(axis=0)
    assert out["rms_varying"] == pytest.approx(np.sqrt(np.mean(np.sum(centred**2, axis=1))),
                                               rel=1e-12)
    assert out["rms_varying"] < out["rms"] and out["residual_rms"] == 5e-6
    assert "illustrative" in out["note"]
    assert gravity_beside_residual(_Result(m, 1e-6), _Measurements(None)) is None
    hexapod = pkmkit.machine("gough-stewart")
    q = hexapod.home_q + np.random.default_rng(5).uniform(-0.01, 0.01, (6, 6))
    out = gravity_beside_residual(_Result(hexapod, 1e-6), _Measurements(q))
    d = gravity_deflection(hexapod, q).deflection[:, :3]
    assert out["available"] and out["configurations"] == 6
    assert out["rms"] == pytest.approx(np.sqrt(np.mean(np.sum(d**2, axis=1))), rel=1e-12)
    delta = pkmkit.machine("delta")
    refused = gravity_beside_residual(_Result(delta, 1e-6), _Measurements(delta.home_q[None]))
    assert refused["available"] is False and "crank" in refused["reason"]
