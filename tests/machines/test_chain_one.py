"""One pose per call on the joint-chain machines (machines/chain_one.py, issue 22 §1): the same
answer as the batch path's row for the same input, the same errors, no dependence on earlier
calls, and no Numba import for a one-shot call."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import (
    InputError,
    OutOfStrokeError,
    SingularConfigurationError,
    StrokeWarning,
)
from pkmkit.machines import chain_one
from pkmkit.numerics import jit

pytestmark = pytest.mark.skipif(not jit.numba_available() or jit.mode() == "0",
                                reason="the one-pose paths run the compiled closure")

NAMES = ("tripteor-x7", "trimule-600")
#: fk's start is formed in the kernel, the batch path's by NumPy (module docstring): the tool
#: point (m) and axis agree to rounding, checked here to 1e-12.
POSE_TOL = 1e-12
#: ``m.ik(x)`` of one plain pose runs the C extension's solve by block elimination
#: (machines/chain_one_native.py) where it is built: the batch row to rounding (measured
#: ≤ 1e-13), checked to 1e-12 m / rad; the Numba one-pose path (``chain_one.inverse``) is the
#: batch row bit for bit.
IK_TOL = 1e-12
#: J and the passive rates: Cholesky with refinement against LAPACK's pseudo-inverse; the
#: singular values then differ as J does (relative to the largest entry).
VELOCITY_TOL = 1e-12



@contextlib.contextmanager
def batch_path():
    """Every single call inside takes the batch path (the one-pose paths find no constants)."""
    saved, packed = chain_one.constants, chain_one.packed
    chain_one.constants = lambda m, tag="chain_ik": None
    chain_one.packed = lambda m: None
    try:
        yield
    finally:
        chain_one.constants, chain_one.packed = saved, packed


def batch_ik(m, x, **options):
    with batch_path():
        return m.ik(x, **options)


def batch_fk(m, q, **options):
    with batch_path():
        return m.fk(q, **options)


def batch_jacobian(m, x, **options):
    with batch_path():
        return m.jacobian(x, **options)


def fresh(name: str, closed: bool = True):
    """A new machine whose single calls run compiled (their first ones already made); with
    ``closed`` False, its kind's closed-form start turned off (the first-order start)."""
    m = pkmkit.machine(name)
    if not closed:
        object.__setattr__(m, "_closed_start_ok", False)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
        assert chain_one.usable(m, tag)
    return m


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    return fresh(request.param)


def within_stroke_poses(m, n: int, seed: int = 0, margin: float = 0.1):
    """``(q, x)`` of ``n`` random configurations inside the actuators' strokes and their poses
    (rows without assembly dropped)."""
    rng = np.random.default_rng(seed)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (margin + (1 - 2 * margin) * rng.random((n, len(act))))
    x = m.fk(q, strokes="ignore")
    keep = np.isfinite(x).all(axis=1)
    return q[keep], x[keep]


def near_wrist_singularity(m, n: int, seed: int = 1):
    """Configurations whose tool axis is within 1e-7 to 1e-2 rad of the first wrist axis (home
    has it along that axis on both machines), the wrist turn anywhere in its stroke."""
    rng = np.random.default_rng(seed)
    q = np.tile(m.home_q, (n, 1))
    lo, hi = m.model.q_min[np.flatnonzero(m.model.actuated)], \
        m.model.q_max[np.flatnonzero(m.model.actuated)]
    q[:, 3] = lo[3] + (hi[3] - lo[3]) * rng.random(n)
    q[:, 4] = np.clip(10.0 ** rng.uniform(-7, -2, n), lo[4], hi[4])
    q[:, :3] += rng.uniform(-0.003, 0.003, (n, 3))
    x = m.fk(q, strokes="ignore")
    return x[np.isfinite(x).all(axis=1)]


def ik_mismatches(m, poses) -> tuple[int, int]:
    """``(fast rows, rows where the Numba one-pose answer differs from the batch path in any
    bit, or m.ik(x) — whichever path it took — by more than IK_TOL)``. The batch rows are
    computed once Numba is imported: without the C extension the batch path's closed-form
    start is the Numba twin the one-pose path runs only from then on
    (:func:`pkmkit.machines.chain_starts.compiled_start`; with it, the C entry in every
    process)."""
    import numba  # the one-pose path's state, before the batch call

    fast = wrong = 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        batch = m.ik(poses)
        for k, x in enumerate(poses):
            numba = chain_one.inverse(m, x, "flag")
            fast += numba is not None
            one = m.ik(x)
            wrong += not (numba is None or np.array_equal(numba, batch[k]))
            wrong += not (np.array_equal(np.isnan(one), np.isnan(batch[k]))
                          and np.nan_to_num(np.abs(one - batch[k])).max() <= IK_TOL
                          and np.array_equal(batch_ik(m, x), batch[k], equal_nan=True))
    return fast, wrong


def test_ik_is_the_batch_row(machine):
    _, x = within_stroke_poses(machine, 40)
    fast, wrong = ik_mismatches(machine, x)
    assert wrong == 0
    assert fast >= len(x) // 3  # the fast path is taken (TriMule: ~45 %, the rest beyond a
    # passive joint's stroke or a turn the batch path weighs against the head's other branch)


def test_ik_near_the_wrist_singularity(machine):
    x = near_wrist_singularity(machine, 30)
    fast, wrong = ik_mismatches(machine, x)
    assert wrong == 0
    assert fast > 0


def test_ik_where_the_batch_path_solves_the_heads_mirror():
    """TriMule: a wrist turn farther than 75° from home's has its mirror (turn + π, tilt
    mirrored) solved and the branch nearer home kept — in the one-pose path as in the batch
    path's rule."""
    m = fresh("trimule-600")
    rng = np.random.default_rng(6)
    q = np.tile(m.home_q, (20, 1))
    q[:, 3] = rng.choice([-1, 1], 20) * rng.uniform(np.radians(80), np.radians(175), 20)
    q[:, 4] = rng.uniform(-0.6, 0.6, 20)
    q[:, :3] += rng.uniform(-0.02, 0.02, (20, 3))
    x = m.fk(q, strokes="ignore")
    x = x[np.isfinite(x).all(axis=1)]
    fast, wrong = ik_mismatches(m, x)
    assert wrong == 0
    assert fast >= len(x) // 2
    assert (np.abs(m.ik(x, strokes="ignore")[:, 3]) < np.pi / 2).any()  # mirrors were taken


def test_fk_is_the_batch_row(machine):
    q, _ = within_stroke_poses(machine, 30, seed=2)
    batch = machine.fk(q, strokes="ignore")
    fast = 0
    for k, v in enumerate(q):
        one = chain_one.direct(machine, v, "ignore", None)
        if one is None:
            continue
        fast += 1
        np.testing.assert_allclose(one, batch[k], rtol=0, atol=POSE_TOL)
        np.testing.assert_allclose(machine.fk(v, strokes="ignore"),
                                   batch_fk(machine, v, strokes="ignore"), rtol=0, atol=POSE_TOL)
    assert fast == len(q)


def test_jacobian_fields_are_the_batch_row(machine):
    _, x = within_stroke_poses(machine, 15, seed=3)
    fast = 0
    for pose in list(x) + list(near_wrist_singularity(machine, 5)):
        one = machine.jacobian(pose)
        if not type(one).__name__.startswith("OnePose"):
            continue
        fast += 1
        ref = batch_jacobian(machine, pose)
        for name in ("J", "J_homogeneous", "passive_rates", "singular_values"):
            a, b = getattr(one, name), getattr(ref, name)
            assert a.shape == b.shape and a.dtype == b.dtype, name
            np.testing.assert_allclose(a, b, rtol=0, atol=VELOCITY_TOL * np.abs(b).max(),
                                       err_msg=name)
        np.testing.assert_allclose(one.condition, ref.condition, rtol=VELOCITY_TOL)
        for name in ("status", "closure_rank", "expected_rank"):
            assert getattr(one, name) == getattr(ref, name), name
        # q from the C inverse (chain_one_native) where built: the batch row to rounding
        np.testing.assert_allclose(one.q, ref.q, rtol=0, atol=IK_TOL)
        assert bool(one.exists) and machine.in_working_mode(one, 1e-6)
    assert fast >= 10


def test_beyond_a_stroke_takes_the_batch_path(machine):
    q = machine.home_q.copy()
    q[0] = machine.model.q_max[np.flatnonzero(machine.model.actuated)[0]] + 0.002
    assert chain_one.direct(machine, q, "flag", None) is None
    with pytest.warns(StrokeWarning):
        machine.fk(q)
    with pytest.raises(OutOfStrokeError):
        machine.fk(q, strokes="refuse")
    x = machine.fk(q, strokes="ignore")
    assert chain_one.inverse(machine, x, "flag") is None
    with pytest.warns(StrokeWarning):
        flagged = machine.ik(x)
    with pytest.raises(OutOfStrokeError):
        machine.ik(x, strokes="refuse")
    np.testing.assert_array_equal(flagged, machine.ik(x[None], strokes="ignore")[0])
    ignored = chain_one.inverse(machine, x, "ignore")  # the fast path keeps it, as the batch
    assert ignored is not None
    np.testing.assert_array_equal(ignored, batch_ik(machine, x, strokes="ignore"))
    np.testing.assert_allclose(machine.ik(x, strokes="ignore"), ignored, rtol=0, atol=IK_TOL)


@pytest.mark.parametrize("bad", [[np.nan, 0, 1, 0, 0, 1], [0.1, 0.2, 1.0, 0, np.inf, 1],
                                 [0.1, 0.2, 1.0, 0, np.nan, 1], [0, 0, 1, 0, 0, 0],
                                 [2e9, 0, 1, 0, 0, 1], [0.1, 0.2, 1.0, 0, 0, 1, 0]])
def test_bad_poses_raise_typed_errors(machine, bad):
    with pytest.raises(InputError):
        machine.ik(bad)
    with pytest.raises(InputError):
        machine.jacobian(np.array(bad, dtype=float))


def test_bad_configurations_raise_typed_errors(machine):
    q = machine.home_q.copy()
    q[1] = np.inf
    with pytest.raises(InputError):
        machine.fk(q)
    with pytest.raises(InputError):
        machine.fk([*list(machine.home_q), 0.0])


def test_a_tolerance_the_bound_cannot_clear_goes_to_the_batch_path(machine):
    # σ_min/σ_max of the closure Jacobian is far below 0.5: the batch path calls it singular
    with pytest.raises(SingularConfigurationError):
        machine.jacobian(machine.fk(machine.home_q), tol=0.5)


@pytest.mark.parametrize("name", NAMES)
def test_a_call_does_not_depend_on_the_previous_one(name):
    q, x = within_stroke_poses(pkmkit.machine(name), 6, seed=4)
    first, second = fresh(name), fresh(name)
    warnings.simplefilter("ignore", StrokeWarning)  # TriMule: a passive joint may be beyond
    alone = (first.ik(x[5]), first.fk(q[5]), first.jacobian(x[5]).J)
    for k in range(5):
        second.ik(x[k]), second.fk(q[k]), second.jacobian(x[k]).J
    after = (second.ik(x[5]), second.fk(q[5]), second.jacobian(x[5]).J)
    for a, b in zip(alone, after, strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_planted_wrong_constant_is_caught():
    # the first-order start's constants: the Tripteor's closed-form start turned off (it starts
    # every pose of this test otherwise, session 34)
    m = fresh("tripteor-x7", closed=False)
    _, x = within_stroke_poses(m, 10, seed=5)
    assert ik_mismatches(m, x)[1] == 0
    c = chain_one.constants(m)
    u_home, base, rates = c.first_args[-7:-4]
    for planted, k in ((u_home, (6 + int(m.passive_variables[0]),)),  # home, slightly off
                       (base, (0,)),  # the flange point at home
                       (rates, (6 + int(m.passive_variables[0]), 3))):  # a rate
        planted[k] += 1e-7
        try:
            assert ik_mismatches(m, x)[1] > 0
        finally:
            planted[k] -= 1e-7
    assert ik_mismatches(m, x)[1] == 0
    c.direct_args = (*c.direct_args[:11], c.tool + 1e-6, *c.direct_args[12:])  # tool length
    with pytest.raises(AssertionError):
        test_fk_is_the_batch_row(m)


@pytest.mark.ci  # a fresh process (1-4 s of CPU): .ci/run's second stage
def test_a_one_shot_call_does_not_import_numba():
    m = pkmkit.machine("tripteor-x7")
    x, q = m.home_pose.tolist(), m.home_q.tolist()
    # with the C extension plain ik, fk and jacobian calls never import Numba
    # (chain_one_native.py, chain_one_velocity.py); without it the second ik does
    native = native_one_pose()
    second = f"m.jacobian({x}).J; m.jacobian({x}).condition" if native else f"m.ik({x})"
    code = (f"import sys, pkmkit; m = pkmkit.machine('tripteor-x7'); m.ik({x}); m.fk({q}); "
            f"pkmkit.machine('tripteor-x7').jacobian({x}).J; m.jacobian({x}).J; "
            f"m.ik({x}); m.fk({q}); "
            f"assert 'numba' not in sys.modules, 'imported'; {second}; {second}; "
            f"assert {'not ' if native else ''}'numba' in sys.modules")
    env = {k: v for k, v in os.environ.items() if k != "PKMKIT_COMPILED"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=False)
    assert out.returncode == 0, out.stderr


@pytest.mark.ci  # a fresh process (1-4 s of CPU): .ci/run's second stage
def test_batch_calls_are_no_single_calls():
    """Batches (a study's frontier, two rows or one) never count as a first single call: the
    second does not build the one-pose constants, which import Numba; a plain pose still
    does from its second call where the C extension is not built (with it, never)."""
    m = pkmkit.machine("tripteor-x7")
    x, q = m.home_pose.tolist(), m.home_q.tolist()
    code = (f"import sys, numpy as np, pkmkit; m = pkmkit.machine('tripteor-x7'); "
            f"X = np.array([{x}, {x}]); Q = np.array([{q}, {q}]); "
            "[m.ik(X), m.ik(X[:1], full_output=True), m.fk(Q), m.fk(Q[:1]), m.jacobian(X).J, "
            "m.jacobian(X[:1]).J, m.ik(X), m.fk(Q), m.jacobian(X).J]; "
            f"assert 'numba' not in sys.modules, 'imported'; "
            + (f"m.ik({x}); m.ik({x}); m.jacobian({x}).J; m.jacobian({x}).J; "
               "assert 'numba' not in sys.modules, 'C'" if native_one_pose()
               else f"m.ik({x}); m.ik({x}); assert 'numba' in sys.modules"))
    env = {k: v for k, v in os.environ.items() if k != "PKMKIT_COMPILED"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=False)
    assert out.returncode == 0, out.stderr


def native_one_pose() -> bool:
    """Whether the C extension's joint-chain one-pose calls are built (chain_one_native.py)."""
    native = jit.native_kernels()
    return native is not None and hasattr(native, "chain_one_pack")


def test_numpy_mode_takes_the_batch_path(monkeypatch):
    m = pkmkit.machine("tripteor-x7")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert chain_one.constants(m) is None
    np.testing.assert_array_equal(m.ik(m.home_pose), batch_ik(m, m.home_pose))


def test_a_one_actuator_machine_keeps_its_shapes():
    m = fresh("crank-slider")
    x, q = m.fk(m.home_q), m.home_q
    assert chain_one.inverse(m, x, "flag") is not None
    one, ref = m.ik(x), batch_ik(m, x)
    assert one.shape == ref.shape == (1,)
    np.testing.assert_allclose(one, ref, rtol=0, atol=IK_TOL)
    assert m.fk(q).shape == batch_fk(m, q).shape == (6,)
    assert m.jacobian(x).J.shape == batch_jacobian(m, x).J.shape


def test_threads_calling_one_machine_get_their_own_answers():
    """The kernels release the GIL: threads calling one machine must not share work arrays."""
    from concurrent.futures import ThreadPoolExecutor

    m = fresh("tripteor-x7")
    q, x = within_stroke_poses(m, 40, seed=7)
    ik_ref, fk_ref = m.ik(x), m.fk(q)

    def work(k: int) -> bool:
        ok = True
        for _ in range(20):
            ok &= bool(np.abs(m.ik(x[k]) - ik_ref[k]).max() <= IK_TOL)
            ok &= bool(np.abs(m.fk(q[k]) - fk_ref[k]).max() <= POSE_TOL)
        return ok

    with ThreadPoolExecutor(4) as pool:
        assert all(pool.map(work, range(len(x))))


def test_a_machine_from_a_chain_file(tmp_path):
    """An element-by-element machine file (no kind, so no declared head pair: the wrist pair
    found from the head) takes the same path with the batch path's bits."""
    from pkmkit.machines.chain_file import machine_file_text

    path = tmp_path / "tripteor.toml"
    path.write_text(machine_file_text(pkmkit.machine("tripteor-x7")))
    m = pkmkit.load(path)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
    q, x = within_stroke_poses(m, 12, seed=8)
    fast, wrong = ik_mismatches(m, x)
    assert wrong == 0 and fast == len(x)
    for k, v in enumerate(q):
        assert chain_one.direct(m, v, "flag", None) is not None
        np.testing.assert_allclose(m.fk(v), batch_fk(m, v), rtol=0, atol=POSE_TOL)
        assert type(m.jacobian(x[k])).__name__ == "OnePoseChainJacobians"


def test_a_machine_pickles_after_one_pose_calls():
    import copy
    import pickle

    m = fresh("tripteor-x7")
    x = m.fk(m.home_q)
    q = m.ik(x)
    for other in (pickle.loads(pickle.dumps(m)), copy.deepcopy(m)):
        np.testing.assert_array_equal(other.ik(x), q)
