"""Every kind's closed-form starts (``MachineKind.inverse_start`` / ``direct_start``: the
TriMule's, the Tripteor's, and any kind that declares one — tested here for free), issue 22 §1,
sessions 33-35: against the engine's own direct model, closure and solve (independent oracles:
the joint-chain model, not the forms' geometry), row by row (batch independence), with the start
turned off (the first-order start: the same answers, statuses, modes and head branches), in C
(the one-pose call) and compiled (the Numba twin, ``start.compiled``: the NumPy function's
answers to rounding, the same declined rows, the one-pose Numba path's bits those of the batch
rows). The kinds' own geometry (forward closed forms, mirrors, the wrist's near singularity) is
tested in ``test_<kind>_closed_start.py`` / ``_direct_start.py``."""

from __future__ import annotations

import importlib
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one, chain_one_native, chain_starts, registry
from pkmkit.solve import chain_rows
from pkmkit.solve.chains import closure_residuals, rotvec_matrices


def _declaring(attribute: str) -> list[str]:
    """The built-in machines whose kind declares ``attribute`` (one machine per kind)."""
    found, starts = [], set()
    for name in registry.machines():
        start = getattr(pkmkit.machine(name).kind, attribute, None)
        if start is not None and start not in starts:
            starts.add(start)
            found.append(name)
    return found


INVERSE = _declaring("inverse_start")
DIRECT = _declaring("direct_start")


def test_the_kinds_are_found():
    assert {"tripteor-x7", "trimule-600"} <= set(INVERSE)
    assert {"tripteor-x7", "trimule-600"} <= set(DIRECT)


def _actuators(m, n: int, seed: int, spread: float = 0.9) -> np.ndarray:
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    rng = np.random.default_rng(seed)
    return lo + (hi - lo) * ((1 - spread) / 2 + spread * rng.random((n, len(act))))


def _poses(m, n: int, seed: int, spread: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
    """Actuators and the engine's direct model's tool poses (``m.fk``, the oracle)."""
    q = _actuators(m, n, seed, spread)
    x = m.fk(q, strokes="ignore")
    keep = np.isfinite(x).all(axis=1)
    return q[keep], x[keep]


def _columns(m) -> list[int]:
    """The actuators' places in the start's unknowns (6 + the model's variables)."""
    names = m.kind.inverse_start.variables
    return [6 + names.index(m.model.variables[v]) for v in np.flatnonzero(m.model.actuated)]


def _off(name: str, key: str):
    """The machine with its closed start ``key`` (``_closed_start_ok``,
    ``_closed_direct_ok``) turned off: the first-order start."""
    off = pkmkit.machine(name)
    object.__setattr__(off, key, False)
    return off


# ---------------------------------------------------------------- the inverse model's start
@pytest.mark.parametrize("name", INVERSE)
def test_the_inverse_start_is_the_engines_solution(name):
    """Tool poses of the engine's direct model at known actuators, random tool lengths: the
    engine's direct model of the start's actuators lands on the pose, and the engine's inverse
    solve started from it stops at once (0 iterations on nearly every row, residual within
    tolerance, the same unknowns)."""
    m = pkmkit.machine(name)
    _, x = _poses(m, 300, 1)
    tools = np.random.default_rng(2).uniform(0.0, 0.3, len(x))
    x = x.copy()
    x[:, :3] += (tools - m.tool_length)[:, None] * x[:, 3:]  # the same flange
    u = chain_starts.closed_starts(m, x, tools)
    ok = np.isfinite(u).all(axis=1)
    assert ok.mean() >= 0.95
    # the head's branch nearest home may be the mirror of q's: the same tool pose either way
    back = m.fk(u[ok][:, _columns(m)], tool_length=tools[ok], strokes="ignore")
    np.testing.assert_allclose(back, x[ok], rtol=0, atol=1e-11)
    assert (np.linalg.norm(u[ok, 3:6], axis=1) <= np.pi + 1e-12).all()
    got, status, residual, iterations = chain_rows.solve_inverse(m.model, x[ok], u[ok],
                                                                 tools[ok])[:4]
    assert (status == 0).all() and residual.max() <= 1e-12
    assert (iterations == 0).mean() >= 0.95
    assert np.abs(got - u[ok]).max() <= 1e-11


@pytest.mark.parametrize("name", INVERSE)
def test_declined_inverse_rows(name):
    """A NaN target and a flange point at the base's origin: NaN rows (the first-order start
    there), NumPy and compiled alike."""
    m = pkmkit.machine(name)
    x = np.array([[np.nan, 0, 1, 0, 0, 1], [0, 0, 0, 0, 0, 1]], dtype=float)
    x[1, :3] += (m.params["spindle"] + m.tool_length) * x[1, 3:]
    tools = np.full(2, m.tool_length)
    assert not np.isfinite(m.kind.inverse_start(m.params, x, tools)).any()
    assert not np.isfinite(chain_starts.closed_starts(m, x, tools)).any()


@pytest.mark.parametrize("name", INVERSE)
def test_a_rows_inverse_start_does_not_depend_on_its_batch(name):
    m = pkmkit.machine(name)
    _, x = _poses(m, 80, 5, spread=1.1)
    tools = np.random.default_rng(6).uniform(0.0, 0.3, len(x))
    for start in (lambda *a: m.kind.inverse_start(m.params, *a),
                  lambda *a: chain_starts.closed_starts(m, *a)):
        batch = start(x, tools)
        for k in range(len(x)):
            assert np.array_equal(start(x[k:k + 1], tools[k:k + 1])[0], batch[k],
                                  equal_nan=True)
        assert np.isfinite(batch).all(axis=1).mean() >= 0.8


@pytest.mark.parametrize("name", INVERSE)
def test_the_first_order_start_gives_the_same_answers_and_branches(name):
    """1,000 poses (actuators over 110 % of their strokes): the batch answers from the closed
    start against those of the same machine with it turned off (the first-order start): the
    same statuses but where the first-order start did not reach a pose the closed one solves
    exactly; the same head branch and answers to 1e-11 on every row whose first-order answer
    is in the legs' home modes, and never out of them where it was in (the closed start's
    answer may be in them where the first-order start's is not: the TriMule's 3 of 973, with
    other actuator values); in far fewer iterations."""
    m, off = pkmkit.machine(name), _off(name, "_closed_start_ok")
    _, x = _poses(m, 1000, 7, spread=1.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        new, old = m.ik(x, full_output=True), off.ik(x, full_output=True)
    assert ((new.status == old.status) | ((new.status == 0) & (new.residual <= 1e-12))).all()
    assert (new.status != old.status).sum() <= 2
    ok = (new.status == 0) & (old.status == 0)
    assert ok.mean() >= 0.95
    home_new, home_old = m.in_home_modes(new.solution), m.in_home_modes(old.solution)
    assert not (ok & home_old & ~home_new).any()
    same = ok & home_old
    assert same.sum() >= 0.98 * ok.sum()
    assert np.abs(new.q[same] - old.q[same]).max() <= 1e-11
    moved = ok & (np.abs(new.q - old.q).max(axis=1) > 1e-11)
    assert (moved <= (home_new & ~home_old)).all()  # only into home's modes
    tilt = 6 + m.wrist_pair()[1]
    assert np.array_equal(np.sign(new.solution[same, tilt]), np.sign(old.solution[same, tilt]))
    assert new.iterations[same].mean() < 0.2 * old.iterations[same].mean()


@pytest.mark.parametrize("name", INVERSE)
def test_the_c_call_starts_alike(name):
    """The C call's closed start against the batch path's: the answers to 1e-12 and the
    iteration counts equal, where it answers and where it declines."""
    m = pkmkit.machine(name)
    native = chain_one_native.packed(m)
    if native is None:
        pytest.skip("no C extension")
    _, x = _poses(m, 400, 8, spread=1.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        ref = m.ik(x, strokes="ignore", full_output=True)
    got = 0
    for k in range(len(x)):
        one = native.ik(native.capsule, x[k], True, True)
        if one is not None:
            got += 1
            assert np.abs(one[0] - ref.q[k]).max() <= 1e-12
            assert one[2] == ref.iterations[k]
    assert got >= 0.97 * len(x)


# ---------------------------------------------------------------- the compiled twin
def _twin(m, name_of: str):
    start = getattr(m.kind, name_of)
    if getattr(start, "compiled", None) is None:
        pytest.skip("no compiled twin")
    pytest.importorskip("numba")
    return importlib.import_module(start.compiled), np.ascontiguousarray(
        start.native(m.params)[1:])


@pytest.mark.parametrize("name", INVERSE)
def test_the_compiled_inverse_start_is_the_numpy_functions(name):
    """The Numba twin against the NumPy function on 1,000 poses over 110 % of the strokes
    (the edges, the wrist's near singularity), random tool lengths, on the branch nearest home
    and on both branches: the same declined rows, the answers to 1e-12 (the mirror branch near
    the singularity: 1e-11, measured 4.8e-13)."""
    m = pkmkit.machine(name)
    module, k = _twin(m, "inverse_start")
    _, x = _poses(m, 1000, 11, spread=1.1)
    tools = np.random.default_rng(12).uniform(0.0, 0.3, len(x))
    n = len(x)
    for branch in (None, np.ones(n), -np.ones(n)):
        ref = m.kind.inverse_start(m.params, x, tools, branch)
        got = np.empty_like(ref)
        module.inverse_rows(k, x, tools, np.zeros(n) if branch is None else branch, got)
        ok = np.isfinite(ref).all(axis=1)
        assert np.array_equal(ok, np.isfinite(got).all(axis=1))
        assert ok.mean() >= 0.9
        assert np.abs(got[ok] - ref[ok]).max() <= (1e-12 if branch is None else 1e-11)


@pytest.mark.parametrize("name", DIRECT)
def test_the_compiled_direct_start_is_the_numpy_functions(name):
    m = pkmkit.machine(name)
    module, k = _twin(m, "direct_start")
    q = _actuators(m, 1000, 13, spread=1.2)
    q[0, 0] = np.nan         # declined: NaN,
    q[1, 0] = 3 * q[1, 2]    # no assembly (Q1 far beyond Q3),
    q[2, 1] = 1e-3           # Q2 too short for leg 2
    ref = m.kind.direct_start(m.params, q)
    got = np.empty_like(ref)
    module.direct_rows(k, q, got)
    ok = np.isfinite(ref).all(axis=1)
    assert np.array_equal(ok, np.isfinite(got).all(axis=1))
    assert 0.5 <= ok.mean() < 1.0
    assert np.abs(got[ok] - ref[ok]).max() <= 1e-12


@pytest.mark.parametrize("name", INVERSE)
def test_the_c_rows_are_the_numba_twins_to_the_bit(name):
    """The C extension's batch entries (``chain_closed_rows``, ``chain_closed_direct_rows``:
    what :func:`~pkmkit.machines.chain_starts.compiled_start` runs with the extension) against
    the Numba twins on 1,000 poses over 110 % of the strokes, every branch, and 1,000
    configurations: the same bits (the same libm calls, no contraction) — so a batch row's
    start is the same whether Numba is imported or not, and the one-pose paths' too."""
    from pkmkit.numerics import jit

    m = pkmkit.machine(name)
    module, k = _twin(m, "inverse_start")
    native = jit.native_kernels()
    if native is None or not hasattr(native, "chain_closed_rows"):
        pytest.skip("no C extension")
    full = np.ascontiguousarray(m.kind.inverse_start.native(m.params))
    _, x = _poses(m, 1000, 17, spread=1.1)
    x = np.ascontiguousarray(x)
    n = len(x)
    tools = np.random.default_rng(18).uniform(0.0, 0.3, n)
    for branch in (np.zeros(n), np.ones(n), -np.ones(n)):
        a, b = np.empty((n, 6 + len(m.kind.inverse_start.variables))), None
        b = np.empty_like(a)
        native.chain_closed_rows(full, x, tools, branch, a)
        module.inverse_rows(k, x, tools, branch, b)
        assert np.array_equal(a, b, equal_nan=True)
        assert np.isfinite(a).all(axis=1).mean() >= 0.9
    q = np.ascontiguousarray(_actuators(m, 1000, 19, spread=1.2))
    a = np.empty((len(q), 6 + len(m.kind.direct_start.variables)))
    b = np.empty_like(a)
    native.chain_closed_direct_rows(full, q, a)
    module.direct_rows(k, q, b)
    assert np.array_equal(a, b, equal_nan=True)
    with pytest.raises(ValueError):  # another family's code: refused, not misread
        wrong = full.copy()
        wrong[0] = 9.0
        native.chain_closed_rows(wrong, x, tools, np.zeros(n), a)


@pytest.mark.parametrize("name", INVERSE)
def test_a_wrong_constant_in_the_twin_is_caught(name):
    """Each of the twin's constants moved by 1e-6 (relative) in turn: the twin's starts no
    longer the NumPy function's — the comparison above catches any constant read wrong."""
    m = pkmkit.machine(name)
    module, k = _twin(m, "inverse_start")
    _, x = _poses(m, 30, 14)
    tools = np.full(len(x), m.tool_length)
    ref = m.kind.inverse_start(m.params, x, tools)
    used = 0
    for j in range(len(k)):
        planted = k.copy()
        planted[j] += 1e-6 * max(abs(k[j]), 1.0)
        got = np.empty_like(ref)
        module.inverse_rows(planted, x, tools, np.zeros(len(x)), got)
        used += not np.allclose(got, ref, rtol=0, atol=1e-9, equal_nan=True)
    # measured: the TriMule's 7 of 7; the Tripteor's 21 of 25 — not l (the direct model's)
    # nor three zeros whose terms vanish by the geometry (R_m's (1, 0), (1, 1), b3's z)
    assert used >= len(k) - 4


@pytest.mark.parametrize("name", INVERSE)
def test_the_one_pose_path_is_the_batch_row_with_the_twin(name):
    """Once Numba is imported, the batch rows and the one-pose Numba path (``full_output``)
    start from the twin: the one-pose record's q, solution and iterations are the batch row's
    to the bit; the batch's closed starts are the twin's."""
    m = pkmkit.machine(name)
    _twin(m, "inverse_start")
    _, x = _poses(m, 40, 15)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for _ in range(2):  # the second single call runs compiled
            m.ik(x[0], full_output=True)
        c = chain_one.constants(m)
        assert c is not None and type(c.closed[0]).__name__ == "_Kernel"
        batch = m.ik(x, full_output=True)
        fast = 0
        for j, pose in enumerate(x):
            one = chain_one.inverse_record(m, pose, "flag")
            if one is None:
                continue
            fast += 1
            assert np.array_equal(one.q, batch.q[j])
            assert np.array_equal(one.solution, batch.solution[j])
            assert one.iterations == batch.iterations[j]
    assert fast >= len(x) // 3


# ---------------------------------------------------------------- the direct model's start
@pytest.mark.parametrize("name", DIRECT)
def test_the_direct_start_closes_the_legs(name):
    """The joint-chain model's closure residual at the start (platform, every joint variable)
    is zero to rounding, the given actuators stand in it."""
    m = pkmkit.machine(name)
    q = _actuators(m, 300, 1, spread=1.1)
    u = m.kind.direct_start(m.params, q)
    ok = np.isfinite(u).all(axis=1)
    assert ok.mean() >= 0.95
    np.testing.assert_allclose(u[ok][:, _columns(m)], q[ok], rtol=0, atol=1e-12)
    res = closure_residuals(m.model, rotvec_matrices(u[ok, 3:6].T), u[ok, :3].T,
                            np.ascontiguousarray(u[ok, 6:].T))
    assert np.abs(res).max() <= 1e-12


@pytest.mark.parametrize("name", DIRECT)
def test_the_direct_start_is_the_engines_solution_from_home(name):
    """The first-order start (the closed one turned off) solved by the engine lands where the
    closed start is: poses and passive joints to 1e-11, the same statuses and strokes."""
    m, off = pkmkit.machine(name), _off(name, "_closed_direct_ok")
    q = _actuators(m, 600, 2, spread=1.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        new, old = m.fk(q, full_output=True), off.fk(q, full_output=True)
    assert np.array_equal(new.status, old.status)
    ok = new.status == 0
    assert ok.mean() >= 0.9
    np.testing.assert_allclose(new.pose[ok], old.pose[ok], rtol=0, atol=1e-11)
    np.testing.assert_allclose(new.passive[ok], old.passive[ok], rtol=0, atol=1e-11)
    assert np.array_equal(np.asarray(new.out_of_stroke), np.asarray(old.out_of_stroke))
    closed = chain_starts.closed_direct_starts(m, q)
    np.testing.assert_allclose(closed[ok, 6:], new.passive[ok], rtol=0, atol=1e-11)
    assert new.iterations[ok].mean() < 0.1 * max(old.iterations[ok].mean(), 1.0)


@pytest.mark.parametrize("name", DIRECT)
def test_a_rows_direct_start_does_not_depend_on_its_batch(name):
    m = pkmkit.machine(name)
    q = _actuators(m, 60, 4)
    batch = chain_starts.closed_direct_starts(m, q)
    for k in range(len(q)):
        assert np.array_equal(chain_starts.closed_direct_starts(m, q[k:k + 1])[0], batch[k],
                              equal_nan=True)


@pytest.mark.parametrize("name", DIRECT)
def test_the_c_call_starts_the_direct_model_alike(name):
    m = pkmkit.machine(name)
    native = chain_one_native.packed(m)
    if native is None:
        pytest.skip("no C extension")
    q = _actuators(m, 300, 5)
    full = m.fk(q, strokes="ignore", full_output=True)
    got = 0
    for k in range(len(q)):
        one = native.fk(native.capsule, q[k], True, True, True)
        if one is not None:
            got += 1
            assert np.abs(np.asarray(one[0]) - full.pose[k]).max() <= 1e-12
            assert one[1] == full.iterations[k]
    assert got >= 0.99 * len(q)
    assert full.iterations.mean() < 0.5


# ---------------------------------------------------------------- continuation (§3)
@pytest.mark.parametrize("name", INVERSE)
def test_continuation_takes_the_closed_start_and_keeps_the_answers(name, monkeypatch):
    """A grid's slab continuation (:func:`pkmkit.analysis.continuation.inverse_of_chunk`) with
    the kind's closed start first (``continuation_starts``) against the neighbours' starts
    alone (the protocol's default, patched in): the same statuses and answers (to 1e-11),
    fewer iterations; ``continuation_starts`` keeps a neighbour's start where the closed start
    declines (a NaN target) and takes the closed start elsewhere."""
    from pkmkit.analysis.continuation import inverse_of_chunk
    from pkmkit.machines.protocol import MachineFace

    m = pkmkit.machine(name)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    middle = lo + (hi - lo) * np.array([0.5, 0.5, 0.5, 0.5, 0.8])  # off the wrist singularity
    centre = m.fk(middle, strokes="ignore")
    axes = [np.linspace(-0.03, 0.03, 7)] * 3
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    points = np.tile(centre, (len(grid), 1))
    points[:, :3] += grid
    slab = 49
    new = inverse_of_chunk(m, points, slab)
    with monkeypatch.context() as patch:
        patch.setattr(type(m), "continuation_starts", MachineFace.continuation_starts)
        old = inverse_of_chunk(pkmkit.machine(name), points, slab)
    assert np.array_equal(new.status, old.status) and (new.status == 0).mean() >= 0.9
    ok = new.status == 0
    assert np.abs(new.q[ok] - old.q[ok]).max() <= 1e-11
    assert new.iterations.sum() < old.iterations.sum()
    neighbours = np.tile(new.solution[:1], (3, 1))
    x = points[:3].copy()
    x[0, 0] = np.nan
    got = m.continuation_starts(x, neighbours)
    assert np.array_equal(got[0], neighbours[0])
    closed = chain_starts.closed_starts(m, x[1:], np.full(2, m.tool_length))
    np.testing.assert_array_equal(got[1:], closed)


@pytest.mark.parametrize("name", DIRECT)
def test_the_one_pose_numba_fk_starts_from_the_twin(name):
    """The one-pose Numba ``fk`` (the path without the C extension) starts from the direct
    start's compiled twin, as the batch rows: the batch rows' poses to 1e-12, the closure
    solved at once (0 iterations on nearly every configuration; 2 on the Tripteor from the
    first-order start before)."""
    m = pkmkit.machine(name)
    _twin(m, "direct_start")
    q = _actuators(m, 100, 16)
    for _ in range(2):  # the second single call runs compiled
        chain_one.direct(m, q[0], "ignore", None)
    c = chain_one.constants(m, "chain_fk")
    assert c is not None and c.closed_direct is not None
    batch = m.fk(q, strokes="ignore")
    iterations = []
    for j, v in enumerate(q):
        pose = chain_one.direct(m, v, "ignore", None)
        if pose is not None:
            assert np.abs(pose - batch[j]).max() <= 1e-12
            iterations.append(chain_one._work(c).info[2])
    assert len(iterations) >= 0.9 * len(q)
    assert np.mean(iterations) < 0.2
