"""The start table of the paired position solve (:mod:`pkmkit.machines.position_start`) and its
quaternion steps (``full_pose_position_kernel``'s ``_step_quaternion``, ``_turn``,
``_quaternion_matrix``, ``full_pose_direct_kernel.quaternion_rotvec`` and their C twins in
``native/position.c``, ``native/direct.c``).

Oracles: scipy's ``least_squares`` on the six rod equations |p + R b_j − a_j − q_k e| = ℓ_j (q
and the rotation vector free), scipy's ``Rotation`` for the quaternion algebra, the solve from
the first-order start (``PKMKIT_POSITION_TABLE=0``) for statuses and answers."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import position_start
from pkmkit.machines.common import _valid_rows
from pkmkit.machines.full_pose_position_solve import solve
from pkmkit.status import Status

nk = pytest.importorskip("pkmkit.machines.full_pose_position_kernel")
Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
least_squares = pytest.importorskip("scipy.optimize").least_squares

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler
    _kernels = None


@pytest.fixture(scope="module")
def verne():
    return pkmkit.machine("verne")


def _setup(m):
    """``(geom, opts (10,), home, jt_inv, table)`` of the paired solve of ``m``."""
    from pkmkit.machines import full_pose_position_solve as kernel

    geom = m._paired_geometry()
    data = m.direct_kernel()
    opts = np.concatenate([data.options({"max_iter": 30}), [12, 2e-6], [1.0]])
    jt_inv = np.linalg.inv(m._home_jacobian[:3])
    table = m._position_start(kernel, geom, opts, data.home, jt_inv)
    return geom, opts, data.home, jt_inv, table


def _table_starts(table, p):
    """``(N, 4)`` the table's start quaternion of each row (NaN where it has none)."""
    out = np.full((p.shape[0], 4), np.nan)
    qt = np.empty(4)
    for k in range(p.shape[0]):
        if nk._table_start(p[k], table, qt):
            out[k] = qt
    return out


def _rod_oracle(m, p):
    """``(q (3,), rotation vector (3,))`` of position ``p`` by scipy's least squares on the rod
    equations, from home's q and no rotation."""
    model = m.model

    def residual(u):
        rot = Rotation.from_rotvec(u[3:]).as_matrix()
        joints = p + model.rod_platform @ rot.T
        base = model.rod_base + u[model.rod_actuator][:, None] * model.rod_axis
        return np.linalg.norm(joints - base, axis=1) - model.rod_length

    u0 = np.concatenate([np.asarray(m.home_q, dtype=float) + p[2], np.zeros(3)])
    fit = least_squares(residual, u0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    assert np.abs(fit.fun).max() < 1e-12
    return fit.x[:3], fit.x[3:]


def test_the_table_gives_the_rods_rotation_within_1e_9(verne):
    """Over its square (any height along the slides) the table's start is within 1e-9 of the
    rotation scipy's least squares finds on the rod equations; outside the square it has none."""
    table = _setup(verne)[4]
    assert table is not None and np.isfinite(table).all()
    rng = np.random.default_rng(35)
    p = rng.uniform(-0.29, 0.29, (40, 3))
    starts = _table_starts(table, p)
    assert np.isfinite(starts).all()
    for k in range(p.shape[0]):
        _, rotvec = _rod_oracle(verne, p[k])
        want = Rotation.from_rotvec(rotvec).as_quat()  # x, y, z, w
        want = want if want[3] >= 0 else -want
        np.testing.assert_allclose(starts[k], want, rtol=0, atol=1e-9)
    outside = np.array([[0.31, 0.0, 0.0], [0.0, -0.31, 0.2], [np.nan, 0.0, 0.0]])
    assert np.isnan(_table_starts(table, outside)).all()


def test_the_start_does_not_depend_on_the_height(verne):
    """The rotation is a function of the position across the common slide axis: rows that
    differ only along it start from the same bits."""
    table = _setup(verne)[4]
    rng = np.random.default_rng(3)
    p = rng.uniform(-0.25, 0.25, (200, 3))
    lifted = p + np.array([0.0, 0.0, 0.123])
    np.testing.assert_array_equal(_table_starts(table, p), _table_starts(table, lifted))


def test_the_answers_against_the_rod_equations(verne):
    """q and the rotation vector of ``m.ik`` within 1e-10 of scipy's least squares on the rod
    equations, inside and outside the table's square."""
    rng = np.random.default_rng(7)
    p = np.concatenate([rng.uniform(-0.25, 0.25, (12, 3)), rng.uniform(-0.45, 0.45, (12, 3))])
    res = verne.ik(p, full_output=True, strokes="ignore")
    for k in np.flatnonzero(res.status == Status.OK):
        q, rotvec = _rod_oracle(verne, p[k])
        np.testing.assert_allclose(res.q[k], q, rtol=0, atol=1e-10)
        np.testing.assert_allclose(res.pose[k, 3:], rotvec, rtol=0, atol=1e-10)
    assert (res.status == Status.OK).sum() >= 18


def test_one_newton_step_where_the_table_covers_the_row(verne, monkeypatch):
    """Inside the ±0.25 m box every row takes one Newton step from the table's start (three
    on average from the first-order start), with the same statuses and answers within
    1e-12 as from the first-order start on 2·10⁴ rows reaching beyond the square."""
    rng = np.random.default_rng(11)
    p = rng.uniform(-0.25, 0.25, (20_000, 3))
    p[:5000] = rng.uniform(-0.6, 0.6, (5000, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fresh = pkmkit.machine("verne")
        monkeypatch.setenv("PKMKIT_POSITION_TABLE", "0")
        old = fresh.ik(p, full_output=True, strokes="flag")
        monkeypatch.delenv("PKMKIT_POSITION_TABLE")
        new = verne.ik(p, full_output=True, strokes="flag")
    np.testing.assert_array_equal(new.status, old.status)
    np.testing.assert_array_equal(new.out_of_stroke, old.out_of_stroke)
    ok = new.status == Status.OK
    np.testing.assert_allclose(new.q[ok], old.q[ok], rtol=0, atol=1e-12)
    np.testing.assert_allclose(new.pose[ok], old.pose[ok], rtol=0, atol=1e-12)
    inner = np.zeros(p.shape[0], dtype=bool)
    inner[5000:] = True
    assert (new.iterations[inner] == 1).all()
    assert old.iterations[inner].mean() > 2.5
    assert {Status.OK, Status.UNREACHABLE} <= set(new.status.tolist())


def test_a_cell_the_table_left_starts_from_the_first_order(verne):
    """A cell whose fit is NaN (a node beyond reach) sends its rows to the first-order start:
    the same statuses, answers within 1e-12, more steps there only."""
    geom, opts, home, jt_inv, table = _setup(verne)
    holed = table.copy()
    terms = (position_start.DEGREE + 1) * (position_start.DEGREE + 2) // 2
    cell = 3 * position_start.CELLS + 4  # u in [−0.075, 0] m, v in [0, 0.075] m
    at = position_start.HEADER + cell * terms * 3
    holed[at:at + terms * 3] = np.nan
    rng = np.random.default_rng(2)
    p = rng.uniform(-0.07, 0.07, (3000, 3))
    full = solve(geom, p, None, np.append(opts, table), home=home, jt_inv=jt_inv, paired=True)
    hole = solve(geom, p, None, np.append(opts, holed), home=home, jt_inv=jt_inv, paired=True)
    np.testing.assert_array_equal(full[1], hole[1])
    np.testing.assert_array_equal(full[4], hole[4])
    np.testing.assert_allclose(full[0], hole[0], rtol=0, atol=1e-12)
    more = hole[2] > full[2]
    assert 0.05 < more.mean() < 0.5  # the rows of that cell, about a quarter of this square


@pytest.mark.parametrize("angle", [0.0, 1e-9, 1e-4, 0.0999, 0.1, 0.1001, 0.5, 2.0, 3.1])
def test_the_quaternion_algebra_against_scipy(angle):
    """A step's quaternion (series up to a 0.1 rad angle, the C library beyond), the matrix of
    a quaternion, its rotation vector and the normalised product, against scipy's Rotation."""
    rng = np.random.default_rng(int(angle * 1e4))
    axis = rng.normal(size=3)
    vec = angle * axis / np.linalg.norm(axis)
    qt = np.empty(4)
    nk._step_quaternion(vec[0], vec[1], vec[2], qt)
    np.testing.assert_allclose(qt, Rotation.from_rotvec(vec).as_quat(), rtol=0, atol=4e-16)
    base = Rotation.from_rotvec(rng.normal(size=3) * 0.3)
    start = base.as_quat()
    turned = start.copy()
    nk._turn(qt, turned)
    np.testing.assert_allclose(np.abs(turned @ (Rotation.from_rotvec(vec) * base).as_quat()),
                               1.0, rtol=0, atol=1e-15)
    rot = np.empty(9)
    nk._quaternion_matrix(turned, rot)
    np.testing.assert_allclose(rot.reshape(3, 3), (Rotation.from_rotvec(vec) * base).as_matrix(),
                               rtol=0, atol=1e-15)
    out = np.empty(3)
    nk.quaternion_rotvec(*(-qt), out, 0)  # the sign of a quaternion does not matter
    np.testing.assert_allclose(out, vec, rtol=1e-15, atol=1e-18)


@pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
def test_c_and_numba_write_the_same_bits_from_the_table(verne):
    """The C twin and the Numba kernel from the start table (a NaN cell included): the same
    bits in every output."""
    geom, opts, home, jt_inv, table = _setup(verne)
    holed = table.copy()
    holed[position_start.HEADER + 5] = np.nan
    rng = np.random.default_rng(4)
    p = np.concatenate([rng.uniform(-0.32, 0.32, (3000, 3)), rng.uniform(-0.6, 0.6, (500, 3))])
    p[::101] = np.nan
    for t in (table, holed):
        outs = [solve(geom, p, None, np.append(opts, t), skip=~_valid_rows(p), home=home,
                      jt_inv=jt_inv, function=f, paired=True)
                for f in (_kernels.position_rows, nk.solve_rows)]
        for a, b in zip(*outs, strict=True):
            a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
            np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
            np.testing.assert_array_equal(a[~np.isnan(a)].view(np.int64),
                                          b[~np.isnan(b)].view(np.int64))
        assert outs[0][4].sum() > 2500


@pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
@pytest.mark.parametrize("change", ["short", "long", "degree", "cells", "side", "not paired"])
def test_the_c_kernel_refuses_a_bad_table(verne, change):
    """A table whose size is not the one its header asks for, a degree above 15, a
    fractional cell count, a side that is not positive, or a table without the paired mode:
    ValueError, ``out`` untouched."""
    geom, opts, home, jt_inv, table = _setup(verne)
    table = table.copy()
    if change == "short":
        table = table[:-1]
    elif change == "long":
        table = np.append(table, 0.0)
    elif change == "degree":
        table[1] = 16.0
    elif change == "cells":
        table[0] = 7.5
    elif change == "side":
        table[2] = 0.0
    else:
        opts = opts.copy()
        opts[9] = 0.0
    out = np.full((4, 10), 5.0)
    with pytest.raises(ValueError):
        _kernels.position_rows(np.zeros((4, 3)), np.empty((4, 6)), False,
                               np.zeros(4, dtype=bool), geom, home, jt_inv,
                               np.append(opts, table), out)
    assert (out == 5.0).all()


def test_a_machine_without_a_common_slide_axis_has_no_table():
    """The table is declared by the rods' geometry: a machine whose slides do not share an
    axis has none (and the plane's axes are orthonormal across a skew axis)."""
    m = pkmkit.machine("verne")
    model = m.model
    skewed = model.rod_axis.copy()
    skewed[0] = [0.0, 0.6, 0.8]
    fake = type("Model", (), {"rod_axis": skewed, "rod_kind": model.rod_kind,
                              "rod_length": model.rod_length})()
    assert position_start.start_table(fake, np.zeros(3), None) is None
    u, v = position_start.plane_axes(np.array([0.0, 0.6, 0.8]))
    basis = np.stack([u, v, [0.0, 0.6, 0.8]])
    np.testing.assert_allclose(basis @ basis.T, np.eye(3), rtol=0, atol=1e-15)
    assert np.linalg.det(basis) > 0
