"""The joint chains' inverse model from a complete warm start (continuation, issue 22 §3) and the
direct and velocity models started from the closure the inverse found: the same solutions as
from home (to 1e-12), fewer iterations from a neighbour, rows without a usable start solved
from home exactly as without one, revolute actuators on the turn nearest home."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError


@pytest.fixture(scope="module")
def tripteor():
    """The Tripteor with its closed-form starts turned off (session 34: they solve these poses
    at once): what is checked here is a start's solution against the first-order start's and
    home's."""
    m = pkmkit.machine("tripteor-x7")
    object.__setattr__(m, "_closed_start_ok", False)
    object.__setattr__(m, "_closed_direct_ok", False)
    return m


def poses(m, n, seed=5):
    """Tool poses of actuator vectors inside the measured ranges, the wrist away from its
    singularity (θ5 ≥ 10°: the head's two branches are far apart)."""
    rng = np.random.default_rng(seed)
    lo = np.array([0.975, 1.055, 0.975, np.radians(-15.0), np.radians(10.0)])
    hi = np.array([0.995, 1.075, 0.995, np.radians(15.0), np.radians(55.0)])
    return m.fk(lo + (hi - lo) * rng.random((n, 5)))


def test_a_solution_as_start_gives_the_same_solution_in_fewer_iterations(tripteor):
    x = poses(tripteor, 60)
    home = tripteor.ik(x, full_output=True)
    # the neighbour: a point 2 mm away, its complete solution as the start
    near = x.copy()
    near[:, :3] += 0.002
    start = tripteor.ik(near, full_output=True).solution
    assert start.shape == (60, 6 + tripteor.model.n_variables)
    warm = tripteor.ik(x, full_output=True, start=start)
    assert np.isfinite(home.q).all()
    np.testing.assert_allclose(warm.q, home.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(warm.direct.passive, home.direct.passive, rtol=0, atol=1e-12)
    assert (warm.iterations < home.iterations).all()
    # from its own solution a row converges at once
    again = tripteor.ik(x, full_output=True, start=home.solution)
    np.testing.assert_allclose(again.q, home.q, rtol=0, atol=1e-12)
    assert again.iterations.max() <= 2


def test_rows_without_a_usable_start_are_solved_from_home(tripteor):
    x = poses(tripteor, 20)
    home = tripteor.ik(x, full_output=True)
    start = home.solution.copy()
    start[::2] = np.nan  # no start: from home, as without one
    start[1::4, :3] += 0.5  # a start half a metre off
    warm = tripteor.ik(x, full_output=True, start=start)
    # (the engine's rows are independent up to rounding: the batch's make-up moves last bits)
    np.testing.assert_array_equal(warm.iterations[::2], home.iterations[::2])
    np.testing.assert_allclose(warm.q, home.q, rtol=0, atol=1e-12)


def test_rows_that_do_not_converge_or_leave_the_home_modes_are_solved_again_from_home(
        tripteor):
    """The engine's call is replaced by one whose rows started from ``start`` (u0 ≠ home)
    fail (row 0), converge in home's assembly modes (row 1) or converge with a leg slide of
    the opposite sign (row 3: another assembly of the legs): rows 0 and 3, and only those,
    take the solution from home."""
    from types import SimpleNamespace

    from pkmkit.status import Status

    home = np.concatenate([tripteor.home_platform, tripteor.home_values])
    u_home = np.tile(home, (5, 1))
    started = np.array([True, True, False, True, False])
    u0 = u_home.copy()
    u0[started, 0] += 0.01
    slide = 6 + int(np.flatnonzero(tripteor.model.actuated)[0])  # Q1: a leg's slide
    calls = []

    def solve(t, u, tool):
        calls.append(len(u))
        from_start = u[:, 0] != home[0]
        status = np.where(from_start & (t[:, 0] > 1), Status.NOT_CONVERGED, Status.OK)
        out = u.copy()
        out[from_start & (t[:, 0] < 0), slide] *= -1.0  # the other assembly of the leg
        return SimpleNamespace(u=out, status=status, residual=np.where(status == 0, 0.0, 1.0),
                               iterations=np.where(from_start, 30, 7), rank=np.zeros(len(u)))

    targets = np.array([[2.0], [0.5], [2.0], [-1.0], [1.0]])
    res = tripteor._solve_inverse_from(solve, targets, u0, u_home, started, np.ones(5))
    assert calls == [5, 2]  # rows 0 and 3 again
    np.testing.assert_array_equal(res.status, [0, 0, 0, 0, 0])
    np.testing.assert_array_equal(res.u[:, 0], home[0] + np.array([0, 0.01, 0, 0, 0]))
    assert (res.u[:, slide] == home[slide]).all()
    np.testing.assert_array_equal(res.iterations, [7, 30, 7, 7, 7])
    assert tripteor.in_home_modes(u0).all() and not tripteor.in_home_modes(
        np.where(np.arange(u0.shape[1]) == slide, -u0, u0)).any()


def test_revolute_actuators_stay_on_the_turn_nearest_home(tripteor):
    x = poses(tripteor, 10)
    home = tripteor.ik(x, full_output=True)
    start = home.solution.copy()
    turns = 6 + np.flatnonzero(tripteor.model.actuated)[3:]  # the head's two angles
    start[:, turns] += 2 * np.pi
    warm = tripteor.ik(x, start=start)
    np.testing.assert_allclose(warm, home.q, rtol=0, atol=1e-12)


def test_a_start_of_the_wrong_width_is_refused(tripteor):
    with pytest.raises(InputError, match="start"):
        tripteor.ik(poses(tripteor, 3), start=np.zeros((3, 7)))


def test_direct_and_velocity_models_from_the_inverse_closure_agree_with_home(tripteor):
    x = poses(tripteor, 40)
    inv = tripteor.ik(x, full_output=True)
    direct = tripteor.fk(inv.q, full_output=True)  # from home
    for name in ("pose", "platform", "passive"):
        np.testing.assert_allclose(getattr(inv.direct, name), getattr(direct, name), rtol=0,
                                   atol=1e-12)
    # the inverse's direct model starts from its solution: it converges at once
    assert inv.direct.iterations.max() <= 1 < direct.iterations.min()
    assert inv.closure_start.shape == (40, 6 + len(tripteor.passive_names))
    warm = tripteor.jacobian(x, q=inv.q, start=inv.closure_start)
    cold = tripteor.jacobian(x, q=inv.q)
    np.testing.assert_allclose(warm.J, cold.J, rtol=0, atol=1e-12)
    np.testing.assert_allclose(warm.singular_values, cold.singular_values, rtol=0, atol=1e-12)


def test_fk_rows_of_start_that_are_not_finite_start_from_home(tripteor):
    q = tripteor.ik(poses(tripteor, 6))
    ref = tripteor.fk(q, full_output=True)
    start = np.concatenate([ref.platform, ref.passive], axis=1)
    start[[1, 4]] = np.nan
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = tripteor.fk(q, start=start, full_output=True)
    np.testing.assert_array_equal(got.pose[[1, 4]], ref.pose[[1, 4]])
    np.testing.assert_allclose(got.pose, ref.pose, rtol=0, atol=1e-12)
