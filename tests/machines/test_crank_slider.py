"""The crank–slider of seed 002 (§4.3, Table 4.1) as joint chains: its least-squares closure
against the nominal relations (4.8), written here independently, over the full crank turn;
its mobility and degree of hyperstatism; its velocity model by finite differences; and the
thesis's compatibility result (4.18) on exact defects."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pkmkit
from pkmkit.status import Status

L1, L2, L3, L4 = 0.1, 0.3, 0.05, 0.2  # crank-slider.toml (mm there), the notes' rank test


@pytest.fixture(scope="module")
def crank():
    return pkmkit.machine("crank-slider")


def eq_4_8(theta1, theta2, theta3, x4):
    """Residuals of (4.8): θ1+θ2+θ3 = 0 (mod 2π), L1 sinθ1 − L2 sinθ3 = 0,
    L1 cosθ1 + L2 cosθ3 + (L3 − x4) − L4 = 0."""
    turn = theta1 + theta2 + theta3
    return np.stack([np.arctan2(np.sin(turn), np.cos(turn)),
                     L1 * np.sin(theta1) - L2 * np.sin(theta3),
                     L1 * np.cos(theta1) + L2 * np.cos(theta3) + (L3 - x4) - L4])


def wrap(a):
    return np.arctan2(np.sin(a), np.cos(a))


@pytest.mark.ci
def test_closure_reproduces_4_8_over_the_full_crank_turn(crank):
    """Along a full turn of the crank (two degrees apart, each pose warm-started from the
    previous one, as along any path), the closure's passive joints satisfy (4.8) to 1e-12 and
    agree with the elementary solution θ3 = asin(L1 sinθ1 / L2) of the same branch."""
    theta1 = np.radians(np.arange(0.0, 361.0, 2.0)) + crank.home_q[0]
    start = None
    passive = []
    for t in theta1:
        res = crank.fk([t], start=start, full_output=True)
        assert res.status == Status.OK and res.closure_residual < 1e-13
        start = np.concatenate([res.platform, res.passive])
        passive.append(res.passive)
    theta2, theta3, x4 = np.array(passive).T
    assert np.abs(eq_4_8(theta1, theta2, theta3, x4)).max() < 1e-12
    theta3_ref = np.arcsin(L1 * np.sin(theta1) / L2)
    assert np.abs(wrap(theta3 - theta3_ref)).max() < 1e-12
    x4_ref = L1 * np.cos(theta1) + L2 * np.cos(theta3_ref) + L3 - L4
    assert np.abs(x4 - x4_ref).max() < 1e-12
    assert x4.max() - x4.min() == pytest.approx(2 * L1, abs=1e-9)  # the stroke is 2·L1


def test_batched_closure_within_the_half_turn_from_home(crank):
    """One batched call from the home start (30°) over ±80°: every row exact, same as (4.8)."""
    theta1 = crank.home_q[0] + np.radians(np.linspace(-80.0, 80.0, 161))
    res = crank.fk(theta1[:, None], full_output=True)
    assert (res.status == Status.OK).all()
    theta2, theta3, x4 = res.passive.T
    assert np.abs(eq_4_8(theta1, theta2, theta3, x4)).max() < 1e-12
    # the piston frame moves along x only, at L4 + x4 (T_R4^RF has no translation)
    assert np.abs(res.platform[:, :3] - np.c_[L4 + x4, 0 * x4, 0 * x4]).max() < 1e-12


def test_far_starts_never_return_a_half_turn_closure(crank):
    """The rotation residual ½·vee(M − Mᵀ) also vanishes when a leg's end is turned by π from
    the platform: started from home, crank angles past ~90° can reach such points. They must be
    reported as failures (or solved right), never returned as closed."""
    theta1 = np.radians(np.linspace(0.0, 359.0, 72))
    res = crank.fk(theta1[:, None], full_output=True)
    good = res.status == Status.OK
    theta2, theta3, x4 = res.passive[good].T
    assert np.abs(eq_4_8(theta1[good], theta2, theta3, x4)).max() < 1e-12
    assert good.sum() >= 36  # the half turn around home at least


def test_mobility_and_hyperstatism(crank):
    """Planar mechanism in space: 4 one-DOF joints (3 R + 1 P), one loop, mobility 1, degree of
    hyperstatism 6·1 − 4 + 1 = 3 — from the count and from the rank of the closure."""
    count = crank.hyperstatism()
    assert count.joints == 4 and count.joints_by_type == {"R": 3, "P": 1}
    assert count.loops == 1 and count.mobility == 1
    assert count.hyperstatism == 3 and count.rank_hyperstatism == 3
    assert crank.actuator_names == ("theta1",)
    assert crank.passive_names == ("theta2", "theta3", "x4")


def test_velocity_model_against_finite_differences(crank):
    theta1 = crank.home_q[0] + np.radians(np.linspace(-60.0, 60.0, 7))
    jac = crank.jacobian(q=theta1[:, None])
    h = 1e-6
    plus = crank.fk((theta1 + h)[:, None], full_output=True)
    minus = crank.fk((theta1 - h)[:, None], full_output=True)
    rates = (plus.passive - minus.passive) / (2 * h)
    assert np.abs(jac.passive_rates[:, :, 0] - rates).max() < 1e-7
    # closed form of the slider rate: dx4/dθ1 = −L1 sinθ1 − L2 sinθ3 dθ3/dθ1
    theta3 = np.arcsin(L1 * np.sin(theta1) / L2)
    dtheta3 = L1 * np.cos(theta1) / (L2 * np.cos(theta3))
    dx4 = -L1 * np.sin(theta1) - L2 * np.sin(theta3) * dtheta3
    assert np.abs(jac.passive_rates[:, 2, 0] - dx4).max() < 1e-12
    assert np.abs(jac.J[:, 0, 0] - dx4).max() < 1e-12  # the piston point moves along x
    assert np.abs(jac.J[:, 1:, 0]).max() < 1e-12


def test_compatible_and_incompatible_defects_4_18(crank):
    """(4.17)/(4.18): in-plane position defects of pivots 2 and 3 are absorbed by the passive
    joints (exact closure); a pivot tilt out of the plane (dI2) or an out-of-plane slider (dJ4)
    is not (least-squares closure with a residual)."""
    q = crank.home_q[0] + np.radians([-40.0, 0.0, 50.0])
    ok = crank.with_defects({"da2": 1e-3, "db2": -2e-3, "da3": 5e-4, "db3": 1e-3})
    res = ok.fk(q[:, None], full_output=True)
    assert (res.status == Status.OK).all() and res.closure_residual.max() < 1e-13
    for bad in ({"dI2": 1e-3}, {"dJ4": 1e-3}):
        res = crank.with_defects(bad).fk(q[:, None], full_output=True)
        assert (res.status == Status.INCONSISTENT).all()
        assert res.closure_residual.min() > 1e-6


def test_thesis_table_4_1_frames(crank):
    """The nominal element frames are the matrices (4.10) and the junctions (4.12)."""
    model = crank.model
    frames = dict(zip(model.element_names(), model.nominal_frames, strict=True))
    assert np.allclose(frames["theta1"][:3], [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0]])
    assert np.allclose(frames["theta2"][:3], [[1, 0, 0, L1], [0, 1, 0, 0], [0, 0, 1, 0]])
    assert np.allclose(frames["theta3"][:3], [[1, 0, 0, L2], [0, 1, 0, 0], [0, 0, 1, 0]])
    assert np.allclose(frames["x4"][:3], [[0, 0, 1, L4], [1, 0, 0, 0], [0, 1, 0, 0]])
    assert np.allclose(frames["R3_RF"][:3], [[1, 0, 0, L3], [0, 0, 1, 0], [0, -1, 0, 0]])
    assert np.allclose(frames["R4_RF"][:3], [[0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 0]])
    assert math.isclose(crank.params["L2"], L2)
