"""The one-pose velocity kernel of joint chains (``pkmkit.native.kernels.chain_velocity_pack``,
``chain_one_velocity``; native/chain_one_velocity.c) against NumPy oracles built from the
NumPy closure (:func:`pkmkit.solve.chains.closure`): the closure rates against LAPACK's least
squares, the regularity bound against ``1 / (‖C_U‖_F ‖C_U⁺‖_F)`` and below σ_min/σ_max, at
solved configurations and at configurations that close nothing (the Jacobians are defined
anyway); and the argument checks (typed errors)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import chain_one_velocity as cov
from pkmkit.solve.chains import closure
from pkmkit.spatial.rotation import rotvec_to_matrix

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "chain_one_velocity"),
                                reason="pkmkit.native.kernels was not built")

NAMES = ("tripteor-x7", "trimule-600")


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    return pkmkit.machine(request.param)


def configurations(m, n: int, seed: int) -> list[list[float]]:
    """``u`` (platform pose, every variable) of solved closures near home (from ``fk``'s
    record) and of random perturbations of them (closing nothing)."""
    rng = np.random.default_rng(seed)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.2 + 0.6 * rng.random((n, len(act))))
    d = m.fk(q, full_output=True, strokes="ignore")
    values = m.full_values(q)
    values[:, m.passive_variables] = d.passive
    u = np.concatenate([d.platform, values], axis=1)
    noisy = u + rng.normal(0.0, 0.01, u.shape)
    return [row.tolist() for row in np.concatenate([u, noisy]) if np.isfinite(row).all()]


def oracle(m, u: list[float]) -> tuple[np.ndarray, float]:
    """``(passive rates (n_p, n), 1 / (‖C_U‖_F ‖C_U⁺‖_F))`` by the NumPy closure and LAPACK."""
    u = np.array(u)
    model = m.model
    act = np.flatnonzero(model.actuated)
    loop = [v for v in act if model.loop_variables[v]]
    c = closure(model, rotvec_to_matrix(u[None, 3:6]).transpose(1, 2, 0), u[:3, None],
                u[6:, None])
    cu = np.concatenate([c.platform, c.variables[:, m.passive_variables]], axis=1)[:, :, 0]
    cq = c.variables[:, loop][:, :, 0]
    du = -np.linalg.lstsq(cu, cq, rcond=None)[0]
    rates = np.zeros((len(m.passive_variables), len(act)))
    for j, v in enumerate(loop):
        rates[:, list(act).index(v)] = du[6:, j]
    bound = 1.0 / (np.linalg.norm(cu) * np.linalg.norm(np.linalg.pinv(cu)))
    sv = np.linalg.svd(cu, compute_uv=False)
    assert bound <= sv[-1] / sv[0] * (1 + 1e-12)
    return rates, bound


def test_rates_and_bound_are_the_numpy_least_squares(machine):
    p = cov.VelocityPack(machine, _kernels)
    for u in configurations(machine, 8, seed=1):
        out = np.empty(p.size)
        bound = p.call(p.pack, u, out)
        rates, expected = oracle(machine, u)
        assert bound == pytest.approx(expected, rel=1e-10)
        start = p.layout["passive_rates"][0]
        got = out[start:].reshape(rates.shape)
        np.testing.assert_allclose(got, rates, rtol=0, atol=1e-11 * np.abs(rates).max())
        j = out[:6 * p.n].reshape(6, p.n)
        sv = out[12 * p.n:12 * p.n + min(6, p.n)]
        np.testing.assert_allclose(sv, np.linalg.svd(out[6 * p.n:12 * p.n].reshape(6, p.n),
                                                     compute_uv=False), rtol=1e-13)
        assert np.isfinite(j).all()


def test_the_singular_stage_later_is_the_full_call(machine):
    """``chain_one_velocity(pack, u, out, False)`` leaves the singular values and the condition
    NaN and every other entry as the full call's; ``(pack, None, out)`` then fills them as the
    full call does (and returns the condition), against LAPACK's singular values."""
    p = cov.VelocityPack(machine, _kernels)
    k = min(6, p.n)
    stage = slice(12 * p.n, 12 * p.n + k + 1)
    for u in configurations(machine, 4, seed=4):
        full, later = np.empty(p.size), np.empty(p.size)
        assert p.call(p.pack, u, full) == p.call(p.pack, u, later, False)
        assert np.isnan(later[stage]).all()
        rest = np.ones(p.size, dtype=bool)
        rest[stage] = False
        assert (later[rest] == full[rest]).all()
        condition = p.call(p.pack, None, later)
        assert (later == full).all()
        assert condition == full[stage][-1]
        sv = np.linalg.svd(later[6 * p.n:12 * p.n].reshape(6, p.n), compute_uv=False)
        np.testing.assert_allclose(later[stage][:-1], sv, rtol=1e-13)
        assert condition == pytest.approx(sv[0] / sv[-1], rel=1e-12)


def test_argument_checks(machine):
    args = cov.pack_arguments(machine)
    p = cov.VelocityPack(machine, _kernels)
    u = configurations(machine, 1, seed=2)[0]
    out = np.empty(p.size)
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, u)
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, tuple(u), out)  # a list is needed
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, u[:-1], out)
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, [*u[:-1], "a"], out)
    with pytest.raises(ValueError):
        _kernels.chain_one_velocity(p.pack, u, np.empty(p.size + 1))
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, u, bytes(8 * p.size))  # read-only
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, u, np.empty(p.size, dtype=np.float32))
    with pytest.raises(TypeError):  # not a pack
        _kernels.chain_one_velocity(object(), u, out)
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, u, out, True, True)
    with pytest.raises(ValueError):  # the singular stage checks out too
        _kernels.chain_one_velocity(p.pack, None, np.empty(p.size - 1))
    with pytest.raises(TypeError):
        _kernels.chain_one_velocity(p.pack, None, np.empty(p.size, dtype=np.float32))
    with pytest.raises(TypeError):
        _kernels.chain_velocity_pack(*list(args.values())[:-1])
    bad = dict(args, position=args["position"] + 100)
    with pytest.raises(ValueError):
        _kernels.chain_velocity_pack(*bad.values())
    bad = dict(args, column_leg=np.full_like(args["column_leg"], 99))
    with pytest.raises(ValueError):
        _kernels.chain_velocity_pack(*bad.values())
    bad = dict(args, loop_columns=args["loop_columns"].astype(float))
    with pytest.raises(TypeError):
        _kernels.chain_velocity_pack(*bad.values())
    bad = dict(args, signs=args["signs"][:-1])
    with pytest.raises(ValueError):
        _kernels.chain_velocity_pack(*bad.values())


def test_a_zero_pivot_declines(machine):
    """A configuration whose closure Jacobian has a zero column (every revolute joint of a leg
    NaN would be refused; here the pivot vanishes): the bound 0.0, out untouched."""
    args = cov.pack_arguments(machine)
    # a leg's local column read at an element of another leg: zero in its own rows
    args["column_leg"] = args["column_leg"].copy()
    local = np.flatnonzero(args["column_leg"] == 0)
    args["column_leg"][local[0]] = 1
    pack = _kernels.chain_velocity_pack(*args.values())
    p = cov.VelocityPack(machine, _kernels)
    out = np.full(p.size, 7.0)
    assert _kernels.chain_one_velocity(pack, configurations(machine, 1, seed=3)[0], out) == 0.0
    assert (out == 7.0).all()


def test_chain_one_jacobian_is_the_buffer_call(machine):
    """``chain_one_jacobian(pack, u, threshold)``: a new array with ``chain_one_velocity(pack,
    u, out, False)``'s entries bit for bit (singular stage NaN), from a list or from a float64
    array; None where the bound does not clear the threshold; False outside the home modes;
    each call a new array."""
    p = cov.VelocityPack(machine, _kernels)
    for u in configurations(machine, 6, seed=5):
        out = np.empty(p.size)
        bound = p.call(p.pack, u, out, False)
        if bound <= 0.0:
            continue
        got = _kernels.chain_one_jacobian(p.pack, np.array(u), 0.0)
        again = _kernels.chain_one_jacobian(p.pack, u, bound)
        assert got is not again and got.shape == (p.size,) and got.dtype == np.float64
        np.testing.assert_array_equal(got, out)
        np.testing.assert_array_equal(again, out)
        assert _kernels.chain_one_jacobian(p.pack, u, np.nextafter(bound, 1.0)) is None
    u = np.array(configurations(machine, 1, seed=6)[0])  # a solved closure
    assert isinstance(_kernels.chain_one_jacobian(p.pack, u, 1e-6), np.ndarray)
    turn = int(cov.pack_arguments(machine)["turns"][0])
    u[turn] += np.pi  # a leg joint half a turn from home
    assert _kernels.chain_one_jacobian(p.pack, u, 1e-6) is False


def test_the_singular_stage_in_the_call_is_the_later_call(machine):
    """``chain_one_jacobian(pack, u, threshold, True)`` and ``chain_one_ik_jacobian(..., True)``
    fill the singular values and the condition in the same call: the whole array bit for bit
    the lazy call's after ``chain_one_velocity(pack, None, out)``, and those values LAPACK's
    (of the array's own J_homogeneous) to 1e-13 of σ_max."""
    from pkmkit.machines import chain_one_native

    p = cov.VelocityPack(machine, _kernels)
    n, k = p.n, min(6, p.n)
    c = chain_one_native.packed(machine)
    seen = 0
    for u in configurations(machine, 6, seed=21):
        lazy = _kernels.chain_one_jacobian(p.pack, u, 0.0)
        if not isinstance(lazy, np.ndarray):
            continue
        fused = _kernels.chain_one_jacobian(p.pack, u, 0.0, True)
        assert np.isnan(lazy[12 * n:12 * n + k + 1]).all()
        assert not np.isnan(fused).any()
        _kernels.chain_one_velocity(p.pack, None, lazy)
        np.testing.assert_array_equal(fused, lazy)
        sv = np.linalg.svd(fused[6 * n:12 * n].reshape(6, n), compute_uv=False)
        assert np.abs(fused[12 * n:12 * n + k] - sv).max() <= 1e-13 * sv[0]
        assert fused[12 * n + k] == fused[12 * n] / fused[12 * n + k - 1]
        seen += 1
    assert seen >= 3
    if c is None or not hasattr(_kernels, "chain_one_ik_jacobian"):
        return
    act = np.flatnonzero(machine.model.actuated)
    lo, hi = machine.model.q_min[act], machine.model.q_max[act]
    q = lo + (hi - lo) * (0.2 + 0.6 * np.random.default_rng(22).random((4, len(act))))
    poses = machine.fk(q, strokes="ignore")
    for x in poses:
        q, lazy = _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12)
        q2, fused = _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12, True)
        np.testing.assert_array_equal(q, q2)
        _kernels.chain_one_velocity(p.pack, None, lazy)
        np.testing.assert_array_equal(fused, lazy)
    with pytest.raises(ValueError):  # the flag's truth
        _kernels.chain_one_ik_jacobian(c.capsule, p.pack, poses[0], 0.0, 1e-12, np.ones(2))
    with pytest.raises(TypeError):
        _kernels.chain_one_ik_jacobian(c.capsule, p.pack, poses[0], 0.0, 1e-12, True, True, 1)


def test_the_record_layout_is_the_flat_answer_by_rows(machine):
    """``chain_one_ik_jacobian(..., singular, True)`` (the record layout, the array alone): a
    read-only (R, n) float64 array whose rows are the flat answer's pieces bit for bit (J,
    J_homogeneous, the singular values and the condition, zero after them, the passive
    rates) and q (the tuple's) last; with singular false the stage's slots NaN, and the stage
    run on a writeable copy (``chain_one_velocity(pack, None, copy.reshape(-1))``) gives the
    fused array; None where the bound does not clear, False where the inverse declines or
    the guard refuses (where the flat form answers None and ``(q, False)``)."""
    from pkmkit.machines import chain_one_native

    c = chain_one_native.packed(machine)
    p = cov.VelocityPack(machine, _kernels)
    if c is None or not p.records:
        pytest.skip("a build without the record layout")
    n, k, n_p = p.n, min(6, p.n), p.n_p
    s = 1 if k < n else 2
    act = np.flatnonzero(machine.model.actuated)
    lo, hi = machine.model.q_min[act], machine.model.q_max[act]
    q = lo + (hi - lo) * (0.2 + 0.6 * np.random.default_rng(23).random((5, len(act))))
    seen = 0
    for x in machine.fk(q, strokes="ignore"):
        q_flat, flat = _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12, True)
        rec = _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12, True, True)
        if not isinstance(flat, np.ndarray):
            assert rec is flat
            continue
        seen += 1
        assert rec.shape == (13 + s + n_p, n) and rec.dtype == np.float64
        assert not rec.flags.writeable and rec.flags.c_contiguous
        with pytest.raises(ValueError):
            rec[0, 0] = 1.0
        np.testing.assert_array_equal(rec[:12].reshape(-1), flat[:12 * n])
        np.testing.assert_array_equal(rec[12:12 + s].reshape(-1)[:k + 1],
                                      flat[12 * n:12 * n + k + 1])
        assert (rec[12:12 + s].reshape(-1)[k + 1:] == 0.0).all()
        np.testing.assert_array_equal(rec[12 + s:12 + s + n_p].reshape(-1), flat[12 * n + k + 1:])
        np.testing.assert_array_equal(rec[-1], q_flat)
        np.testing.assert_array_equal(rec[p.rows["J"]], flat[:6 * n].reshape(6, n))
        assert rec[p.condition_at] == flat[12 * n + k]
        lazy = _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12, False, True)
        assert np.isnan(lazy[12:12 + s].reshape(-1)[:k + 1]).all()
        late = lazy.copy()
        _kernels.chain_one_velocity(p.pack, None, late.reshape(-1))
        np.testing.assert_array_equal(late, rec)
        assert _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 1e9, 1e-12, False, True) is None
        assert _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, -1.0, False, True) is False
    assert seen >= 3
    assert _kernels.chain_one_ik_jacobian(c.capsule, p.pack, [0.0] * 6, 0.0, 1e-12, False,
                                          True) is False
    with pytest.raises(ValueError):  # the flag's truth
        _kernels.chain_one_ik_jacobian(c.capsule, p.pack, x, 0.0, 1e-12, False, np.ones(2))


def test_chain_one_jacobian_argument_checks(machine):
    p = cov.VelocityPack(machine, _kernels)
    u = configurations(machine, 1, seed=2)[0]
    call = _kernels.chain_one_jacobian
    for bad_args, error in [((p.pack, u), TypeError), ((p.pack, u, 0.0, 1, 2), TypeError),
                            ((p.pack, u, 0.0, np.ones(2)), ValueError),  # its truth
                            ((object(), u, 0.0), TypeError), ((p.pack, u, "a"), TypeError),
                            ((p.pack, u[:-1], 0.0), TypeError),
                            ((p.pack, np.array(u[:-1]), 0.0), TypeError),
                            ((p.pack, np.array(u, dtype=np.float32), 0.0), TypeError),
                            ((p.pack, np.array([u]), 0.0), ValueError),
                            ((p.pack, tuple(u), 0.0), TypeError),
                            ((p.pack, [*u[:-1], "a"], 0.0), TypeError)]:
        with pytest.raises(error):
            call(*bad_args)
    # a vanishing pivot (a leg's column read at another leg's element): None
    args = cov.pack_arguments(machine)
    args["column_leg"] = args["column_leg"].copy()
    args["column_leg"][np.flatnonzero(args["column_leg"] == 0)[0]] = 1
    assert call(_kernels.chain_velocity_pack(*args.values()), u, 0.0) is None
