"""Fuzzing of the kinematic entry points: machine(), with_params(), ik, fk, fk_all, jacobian,
jacobian_dot — random and hostile poses, parameters, options; answers checked."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import pkmkit
from pkmkit.status import Status
from tests.conftest import PRESETS

from .strategies import HOSTILE_FLOATS, NON_NUMBERS, PLAUSIBLE, arrays, call, weighted

MACHINES = {name: pkmkit.machine(name) for name in PRESETS}
machine_names = st.sampled_from(sorted(MACHINES))


def closure_residual(m: pkmkit.Machine, x: np.ndarray, q: np.ndarray) -> np.ndarray:
    """| |p − c_i(q)| − ρ_i(q) | for every leg (the answer's own check)."""
    d = m._closed.rod_vectors(np.atleast_2d(x), np.atleast_2d(q))
    _, rho = m._closed.centres(np.atleast_2d(q))
    return np.abs(np.linalg.norm(d, axis=2) - rho)


@given(machine_names, st.data())
def test_ik_fk_round_trip(name, data):
    m = MACHINES[name]
    x = data.draw(arrays(m.dims), label="pose")
    method = data.draw(st.sampled_from(["closed"] * 4 + ["numeric", "bogus"]))
    branches = data.draw(weighted((6, st.none()), (1, st.lists(
        st.sampled_from([1, -1, 0, 2.5]), min_size=m.n_actuators, max_size=m.n_actuators)),
        (1, NON_NUMBERS)))
    res = call(m.ik, x, method=method, branches=branches, full_output=True)
    if res is None:
        return
    q = np.atleast_2d(res.q)
    xs = np.atleast_2d(np.asarray(x, dtype=float))
    ok = np.atleast_1d(res.status) == Status.OK
    assert np.isfinite(q[ok]).all() and np.isnan(q[~ok]).all()
    if ok.any():
        scale = 1.0 + np.abs(xs[ok]).max()
        assert closure_residual(m, xs[ok], q[ok]).max() <= 1e-9 * scale
        modes = np.atleast_1d(res.mode)[ok]
        for sign in (-1, 1):
            rows = modes == sign
            if rows.any():
                back = m.fk(q[ok][rows], mode=sign)
                good = np.isfinite(back).all(axis=1)
                assert np.abs(back[good] - xs[ok][rows][good]).max(initial=0) <= 1e-6 * scale


@given(machine_names, st.data())
def test_fk_and_fk_all(name, data):
    m = MACHINES[name]
    q = data.draw(arrays(m.n_actuators), label="q")
    mode = data.draw(st.one_of(st.sampled_from(["working", "other", 1, -1, "x", 0, True]),
                               st.sampled_from(m.model.mode_names), st.just("working")))
    method = data.draw(st.sampled_from(["closed", "closed", "numeric"]))
    dof = data.draw(st.sampled_from(["translation", "translation", "full", "rotation"]))
    res = call(m.fk, q, mode=mode, method=method, dof=dof, full_output=True)
    if res is not None:
        pose, qb = np.atleast_2d(res.pose), np.atleast_2d(np.asarray(q, dtype=float))
        ok = np.atleast_1d(res.status) == Status.OK
        if ok.any():
            scale = 1.0 + np.abs(qb[ok]).max()
            assert closure_residual(m, pose[ok], qb[ok]).max() <= 1e-7 * scale
    modes = call(m.fk_all, q)
    if modes is not None:
        poses, valid = np.atleast_3d(modes.poses), np.atleast_2d(modes.valid)
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        for col in range(2):
            rows = valid[..., col].reshape(-1)
            if rows.any():
                p = poses.reshape(-1, 2, m.dims)[rows, col]
                scale = 1.0 + np.abs(qb[rows]).max()
                assert closure_residual(m, p, qb[rows]).max() <= 1e-7 * scale


@given(machine_names, st.data())
def test_jacobian_invariants(name, data):
    m = MACHINES[name]
    x = data.draw(arrays(m.dims), label="pose")
    tol = data.draw(weighted((6, st.just(1e-6)), (1, HOSTILE_FLOATS), (1, NON_NUMBERS)))
    jac = call(m.jacobian, x, tol=tol)
    if jac is None:
        return
    sv = np.atleast_2d(jac.singular_values)
    finite = np.isfinite(sv).all(axis=1)
    assert (sv[finite] >= 0).all()
    assert (np.diff(sv[finite], axis=1) <= 1e-12 * (1 + sv[finite, :1])).all()
    cond = np.atleast_1d(jac.condition)[finite]
    assert (cond[np.isfinite(cond)] >= 1 - 1e-9).all()
    j, j_inv = np.atleast_3d(jac.J), np.atleast_3d(jac.J_inv)
    j = j.reshape(-1, m.dims, m.n_actuators)
    j_inv = j_inv.reshape(-1, m.n_actuators, m.dims)
    good = finite & np.isfinite(j_inv).all(axis=(1, 2)) & (cond_all := np.atleast_1d(
        jac.condition) < 1e6)
    del cond_all
    if good.any():
        product = np.einsum("kij,kjl->kil", j[good], j_inv[good])
        assert np.abs(product - np.eye(m.dims)).max() <= 1e-6
        np.testing.assert_allclose(np.linalg.svd(j[good], compute_uv=False), sv[good],
                                   rtol=1e-8, atol=1e-12)


@given(machine_names, st.data())
def test_jacobian_dot_and_given_q(name, data):
    m = MACHINES[name]
    x = data.draw(arrays(m.dims), label="pose")
    xd = data.draw(arrays(m.dims), label="xd")
    q = data.draw(st.one_of(st.none(), arrays(m.n_actuators)), label="q")
    rates = call(m.jacobian_dot, x, xd, q=q)
    if rates is not None:
        assert np.shape(rates.qd)[-1] == m.n_actuators
    call(m.jacobian, x, q=q)


@given(machine_names, st.dictionaries(
    st.one_of(st.sampled_from(["R", "r", "L", "angles", "parallelogram_width", "q_min",
                               "q_max", "x"]), st.text(max_size=3)),
    st.one_of(HOSTILE_FLOATS, PLAUSIBLE, NON_NUMBERS,
              st.lists(st.one_of(PLAUSIBLE, HOSTILE_FLOATS), min_size=1, max_size=4)),
    max_size=3))
def test_machine_parameters(name, params):
    m = call(pkmkit.machine, name, **params)
    if m is None:
        return
    q = m.ik(m.home_pose)
    np.testing.assert_allclose(m.fk(q), m.home_pose, atol=1e-9)
    again = call(MACHINES[name].with_params, **params)
    if again is not None:
        np.testing.assert_allclose(again.home_q, m.home_q, atol=0)


@given(st.one_of(st.text(max_size=20), NON_NUMBERS))
def test_unknown_machine_names(name):
    call(pkmkit.machine, name)


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_engine_on_hostile_batch(name):
    """The numeric engine on a batch mixing good, unreachable and hostile rows keeps the
    good rows (same answers as the closed form) and flags the others."""
    m = MACHINES[name]
    rng = np.random.default_rng(0)
    x = m.home_pose + rng.uniform(-0.05, 0.05, (30, m.dims))
    x[3] = np.nan
    x[4] = 1e300
    x[5] = m.home_pose + 50.0
    closed = m.ik(x, full_output=True)
    numeric = m.ik(x, method="numeric", full_output=True)
    ok = closed.status == Status.OK
    assert (numeric.status[~ok] != Status.OK).all()
    np.testing.assert_allclose(numeric.q[ok], closed.q[ok], atol=1e-9)
