"""The one-pose solve's closure by blocks' panels (native/chain_one_closure.c, issue 22 §1,
session 33) against the batch path's closure — the Numba kernel ``chain_kernel._evaluate_any``
(an independent implementation of chain.c's evaluate and tool rows) — bit for bit, at random
configurations that close nothing (the residual and Jacobian are defined anyway) and at solved
ones, for the inverse model (every joint unknown, the tool rows) and the direct model (the
actuators known); and its argument checks."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import chain_one_native
from pkmkit.solve import chain_kernel

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "chain_one_closure"),
                                reason="pkmkit.native.kernels was not built")

NAMES = ("tripteor-x7", "trimule-600")


@pytest.fixture(scope="module", params=NAMES)
def packed(request):
    m = pkmkit.machine(request.param)
    args = chain_one_native.pack_arguments(m)
    return m, args, _kernels.chain_one_pack(*args)


def _numba(args, m, u, values, inverse, target):
    """chain_kernel._evaluate_any's residual and dense Jacobian (the batch path's closure)."""
    frames, types, evar, elements, offsets, head, inv_position, dir_position, length = args[:9]
    position = inv_position if inverse else dir_position
    rows = 6 * (len(offsets) - 1) + (6 if inverse else 0)
    r, jac = np.empty(rows), np.zeros((rows, len(u)))
    chain_kernel._evaluate_any(frames, types, evar, elements, offsets, position,
                               np.array(values), np.asarray(u, dtype=float), length, r, jac,
                               chain_kernel._scratch(len(elements) + len(head)), head,
                               np.asarray(target, dtype=float), float(m.tool_length), inverse)
    return r, jac


def _random_points(m, args, inverse, count, seed):
    position = args[6] if inverse else args[7]
    unknown = np.flatnonzero(position >= 0)
    rng = np.random.default_rng(seed)
    for _ in range(count):
        values = m.home_values + rng.normal(0.0, 0.2, len(m.home_values))
        u = np.concatenate([m.home_platform, values[unknown]]) + rng.normal(0.0, 0.05,
                                                                            6 + len(unknown))
        axis = rng.normal(size=3)
        yield u, values, np.concatenate([rng.normal(0.0, 0.3, 3), axis / np.linalg.norm(axis)])


@pytest.mark.parametrize("inverse", [True, False])
def test_the_panels_are_the_batch_closures_bits(packed, inverse):
    m, args, cap = packed
    for u, values, target in _random_points(m, args, inverse, 40, 7):
        r, jac = _kernels.chain_one_closure(cap, list(u), values, inverse, list(target))
        r_ref, jac_ref = _numba(args, m, u, values, inverse, target)
        assert jac.shape == jac_ref.shape
        assert np.array_equal(r, r_ref)
        assert np.array_equal(jac, jac_ref)  # every entry, the structural zeros included


def test_the_panels_at_solved_configurations(packed):
    """At the inverse's solutions (the points the solve stops at), both models."""
    m, args, cap = packed
    act = np.flatnonzero(m.model.actuated)
    rng = np.random.default_rng(3)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (0.2 + 0.6 * rng.random((8, len(act))))
    x = m.fk(q, strokes="ignore")
    dir_unknown = np.flatnonzero(args[7] >= 0)
    seen = 0
    for pose in x[np.isfinite(x).all(axis=1)]:
        answer = _kernels.chain_one_ik(cap, list(pose), True, True)
        if answer is None:
            continue
        u = answer[1]
        values = np.array(u[6:])
        for inverse, point in ((True, u), (False, np.concatenate([u[:6], values[dir_unknown]]))):
            r, jac = _kernels.chain_one_closure(cap, list(point), values, inverse, list(pose))
            r_ref, jac_ref = _numba(args, m, point, values, inverse, pose)
            assert np.array_equal(r, r_ref) and np.array_equal(jac, jac_ref)
        assert np.abs(r).max() < 1e-9  # the direct model's closure at a solution closes
        seen += 1
    assert seen >= 4


def test_argument_checks(packed):
    m, args, cap = packed
    n_inv = 6 + int((args[6] >= 0).sum())
    values = list(m.home_values)
    u = [0.0] * n_inv
    with pytest.raises(TypeError):
        _kernels.chain_one_closure(cap, u, values, True)
    with pytest.raises(ValueError, match="u: "):
        _kernels.chain_one_closure(cap, u[:-1], values, True, [0, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="u: "):
        _kernels.chain_one_closure(cap, [np.nan, *u[1:]], values, True, [0, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="values: "):
        _kernels.chain_one_closure(cap, u, values[:-1], True, [0, 0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="target: "):
        _kernels.chain_one_closure(cap, u, values, True, [0, 0, 1])
    with pytest.raises((TypeError, ValueError)):
        _kernels.chain_one_closure(object(), u, values, True, [0, 0, 0, 0, 0, 1])


def _workspace_poses(m, count, seed):
    act = np.flatnonzero(m.model.actuated)
    rng = np.random.default_rng(seed)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    x = m.fk(lo + (hi - lo) * (0.1 + 0.8 * rng.random((count, len(act)))), strokes="ignore")
    return x[np.isfinite(x).all(axis=1)]


def test_the_fused_jacobian_call_is_the_two_calls(packed):
    """chain_one_ik_jacobian (the inverse's last Jacobian handed to the velocity kernel) gives
    chain_one_ik's q and chain_one_jacobian's array at its solution, bit for bit — over
    workspace poses that include the TriMule's mirror solves (the kept solution not the last
    solve's: evaluated again) and the handed-over ones."""
    m, _, cap = packed
    from pkmkit.machines import chain_one_velocity

    vp = chain_one_velocity.pack(m)
    threshold = 2.0 * 1e-9
    checked = 0
    for x in _workspace_poses(m, 120, 11):
        solved = _kernels.chain_one_ik(cap, list(x), True, True)
        fused = _kernels.chain_one_ik_jacobian(cap, vp.pack, list(x), threshold, 1e-12)
        if solved is None:
            assert fused is None
            continue
        q, out = fused
        assert np.array_equal(q, solved[0])
        two = _kernels.chain_one_jacobian(vp.pack, solved[1], threshold)
        if isinstance(two, np.ndarray):
            assert np.array_equal(out, two, equal_nan=True)
            checked += 1
        else:
            assert out is two
    assert checked >= 100


def test_the_fused_jacobian_calls_answers_and_checks(packed):
    m, _, cap = packed
    from pkmkit.machines import chain_one_velocity

    vp = chain_one_velocity.pack(m)
    x = list(_workspace_poses(m, 4, 5)[0])
    q, out = _kernels.chain_one_ik_jacobian(cap, vp.pack, x, 2e-9, 1e-12)
    assert q.shape == (vp.n,)
    assert isinstance(out, np.ndarray) and out.shape == (vp.size,)
    assert _kernels.chain_one_ik_jacobian(cap, vp.pack, x, 1e9, 1e-12)[1] is None  # the bound
    assert _kernels.chain_one_ik_jacobian(cap, vp.pack, x, 2e-9, -1.0)[1] is False  # guard
    assert _kernels.chain_one_ik_jacobian(cap, vp.pack, x[:5], 2e-9, 1e-12) is None
    assert _kernels.chain_one_ik_jacobian(cap, vp.pack, [0, 0, 0, 0, 0, 0], 2e-9, 1e-12) is None
    with pytest.raises(TypeError):
        _kernels.chain_one_ik_jacobian(cap, vp.pack, x, 2e-9)
    with pytest.raises(TypeError):
        _kernels.chain_one_ik_jacobian(cap, object(), x, 2e-9, 1e-12)  # not a velocity pack
    with pytest.raises(TypeError):
        _kernels.chain_one_ik_jacobian(cap, vp.pack, x, "2e-9", 1e-12)


def test_m_jacobian_takes_the_fused_call(packed, monkeypatch):
    """m.jacobian(x) answers through chain_one_ik_jacobian (counted), its record's fields the
    two-call path's."""
    m, _, cap = packed
    from pkmkit.machines import chain_one_velocity

    x = _workspace_poses(m, 4, 6)[1]
    m.jacobian(x)  # packs
    vp = chain_one_velocity.pack(m)
    calls = []
    real = vp.ik_jacobian
    monkeypatch.setattr(vp, "ik_jacobian", lambda *a: calls.append(1) or real(*a))
    record = m.jacobian(x)
    assert calls == [1]
    solved = _kernels.chain_one_ik(cap, list(x), True, True)
    out = _kernels.chain_one_jacobian(vp.pack, solved[1], 2.0 * max(1e-9, 1e-9))
    assert np.array_equal(record.J, out[:6 * vp.n].reshape(6, vp.n))
