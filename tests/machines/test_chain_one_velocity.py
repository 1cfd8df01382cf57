"""``m.jacobian(x)`` of one pose of a joint-chain machine through the C kernel at the inverse
solution (machines/chain_one_velocity.py, native/chain_one_velocity.c; issue 22 §1): every field
the batch row's (``m.jacobian(X)`` with X of one row: the direct model solved again, LAPACK's
pseudo-inverse and SVD) to :data:`TOL` of its largest entry, J and the passive rates against
finite differences of the direct model (an oracle that shares no code with either path), the
fall-backs (near a singular closure, an inconsistent closure, another assembly mode, no C
extension), and planted wrong constants that the comparison catches."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects  # noqa: F401  (the defects' module, loaded)
from pkmkit.exceptions import SingularConfigurationError, StrokeWarning
from pkmkit.geometric_errors.model import defect_set
from pkmkit.machines import chain_one
from pkmkit.machines import chain_one_velocity as cov
from pkmkit.model.defect_rule import add_defects
from pkmkit.numerics import jit

native = jit.native_kernels()
pytestmark = pytest.mark.skipif(
    not jit.numba_available() or jit.mode() == "0" or native is None
    or not hasattr(native, "chain_one_velocity"),
    reason="the one-pose path runs the compiled inverse and the C velocity kernel")

NAMES = ("tripteor-x7", "trimule-600")
#: Every field against the batch row, relative to its largest entry: the same configuration to
#: the solvers' tolerances, the rates by a QR against LAPACK's pseudo-inverse (measured over
#: 1,000 workspace poses of each machine: 1.5e-13 at most; docs/benchmarks.md).
TOL = 1e-12
FIELDS = ("J", "J_homogeneous", "singular_values", "passive_rates")


def fresh(name: str):
    m = pkmkit.machine(name)
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(m, tag)
    return m


@pytest.fixture(scope="module", params=NAMES)
def machine(request):
    return fresh(request.param)


def poses(m, n: int, seed: int, margin: float = 0.02) -> np.ndarray:
    """Tool poses of ``n`` random configurations across the actuators' strokes."""
    rng = np.random.default_rng(seed)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * (margin + (1 - 2 * margin) * rng.random((n, len(act))))
    x = m.fk(q, strokes="ignore")
    return x[np.isfinite(x).all(axis=1)]


def through_c(record) -> bool:
    return isinstance(record, cov.OnePoseChainJacobians)


def stage_run(record) -> bool:
    """Whether the record's array holds the singular stage's answer (its condition slot not
    NaN: the record layout's or the flat one's)."""
    out, p = record.__dict__["_out"], record.__dict__["_pack"]
    return not np.isnan(out[p.condition_at] if out.ndim == 2 else out[p.sv_stop])


def mismatch(m, xs) -> tuple[int, float]:
    """``(records through the C kernel, the largest difference of a field from the batch row's
    relative to its largest entry)``."""
    count, worst = 0, 0.0
    for x in xs:
        one = m.jacobian(x)
        if not through_c(one):
            continue
        count += 1
        ref = m.jacobian(x[None])
        for name in FIELDS:
            a, b = getattr(one, name), getattr(ref, name)[0]
            assert a.shape == b.shape and a.dtype == b.dtype, name
            worst = max(worst, float(np.abs(a - b).max() / np.abs(b).max()))
        worst = max(worst, abs(one.condition / ref.condition[0] - 1))
        assert one.status == ref.status[0] and one.closure_rank == ref.closure_rank[0]
        assert one.expected_rank == ref.expected_rank
        # q from the C inverse (chain_one_native): the batch row to rounding
        np.testing.assert_allclose(one.q, ref.q[0], rtol=0, atol=1e-12)
    return count, worst


def test_every_field_is_the_batch_row(machine):
    xs = poses(machine, 60, seed=11)
    count, worst = mismatch(machine, xs)
    assert count >= 0.9 * len(xs)
    assert worst <= TOL


def test_j_and_the_passive_rates_are_the_direct_models_derivatives(machine):
    """Central differences of ``fk`` (tool point, axis, passive joints) in each actuator: the
    point's velocity is J's rows 0–2, the axis turns as ω × axis with ω J's rows 3–5."""
    h = 1e-6
    for x in poses(machine, 4, seed=12, margin=0.2):
        one = machine.jacobian(x)
        assert through_c(one)
        q = one.q
        for j in range(len(q)):
            step = np.zeros(len(q))
            step[j] = h
            plus = machine.fk(q + step, full_output=True, strokes="ignore")
            minus = machine.fk(q - step, full_output=True, strokes="ignore")
            d_pose = (plus.pose - minus.pose) / (2 * h)
            d_passive = (plus.passive - minus.passive) / (2 * h)
            axis = machine.fk(q, strokes="ignore")[3:]
            np.testing.assert_allclose(one.J[:3, j], d_pose[:3], atol=2e-6)
            np.testing.assert_allclose(np.cross(one.J[3:, j], axis), d_pose[3:], atol=2e-6)
            np.testing.assert_allclose(one.passive_rates[:, j], d_passive, atol=2e-5)
        length = machine.model.characteristic_length
        np.testing.assert_array_equal(one.J_homogeneous[:3], one.J[:3])
        np.testing.assert_allclose(one.J_homogeneous[3:], length * one.J[3:], rtol=1e-15)
        sv = np.linalg.svd(one.J_homogeneous, compute_uv=False)
        np.testing.assert_allclose(one.singular_values, sv, rtol=1e-13)
        assert one.condition == one.singular_values[0] / one.singular_values[-1]


def test_planted_wrong_constants_are_caught():
    """A wrong column map, a leg's column taken for another's, a shared joint taken for one
    leg's own, a transposed frame, swapped actuator places: each gives other numbers."""
    m = fresh("trimule-600")
    xs = poses(m, 6, seed=13)
    assert mismatch(m, xs)[1] <= TOL
    good = cov.pack_arguments(m)

    def planted(name, change):
        args = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in good.items()}
        change(args[name])
        object.__setattr__(m, "_chain_one_velocity", cov.VelocityPack(m, native, args))

    passive = m.passive_variables

    def swap_columns(a):
        a[[passive[1], passive[2]]] = a[[passive[2], passive[1]]]

    def shared_as_own(a):
        a[a == -1] = np.where(np.arange(len(a)) >= 6, 0, -1)[a == -1]

    def other_leg(a):
        a[np.flatnonzero(a == 1)[0]] = 2

    def transposed(a):
        e = int(good["elements"][2])  # a leg's third element
        a[e, :3, :3] = a[e, :3, :3].T.copy()

    plants = [("position", swap_columns), ("column_leg", shared_as_own),
              ("column_leg", other_leg), ("frames", transposed),
              ("loop_columns", lambda a: a.__setitem__(slice(None), a[::-1].copy())),
              ("head_position", lambda a: a.__setitem__(a >= 0, a[a >= 0][::-1].copy()))]
    try:
        for name, change in plants:
            planted(name, change)
            count, worst = mismatch(m, xs)
            assert count == 0 or worst > 1e-6, name
    finally:
        object.__setattr__(m, "_chain_one_velocity", None)
    assert mismatch(m, xs)[1] <= TOL


def test_every_column_global_is_the_same_answer(machine):
    """The leg-blocked QR against the same QR with no column given to a leg (one dense QR of
    C_U): the same fields to rounding."""
    xs = poses(machine, 5, seed=14)
    blocked = [machine.jacobian(x) for x in xs]
    args = cov.pack_arguments(machine)
    args["column_leg"] = np.full_like(args["column_leg"], -1)
    object.__setattr__(machine, "_chain_one_velocity", cov.VelocityPack(machine, native, args))
    try:
        for x, a in zip(xs, blocked, strict=True):
            b = machine.jacobian(x)
            assert through_c(a) and through_c(b)
            for name in FIELDS:
                np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0,
                                           atol=1e-13 * np.abs(getattr(b, name)).max())
    finally:
        object.__setattr__(machine, "_chain_one_velocity", None)


def test_a_tolerance_the_bound_cannot_clear_goes_to_the_batch_path(machine):
    x = machine.fk(machine.home_q)
    assert through_c(machine.jacobian(x))
    with pytest.raises(SingularConfigurationError):
        machine.jacobian(x, tol=0.5)


def test_outside_the_home_modes_the_kernel_declines(machine):
    """A configuration with a leg joint a half turn from home: the kernel returns −1 and the
    record comes from the path that solves the direct model again."""
    c = chain_one.constants(machine, "chain_jacobian")
    found = chain_one._inverse_values(c, machine.home_pose.tolist())
    p = cov.pack(machine)
    out = np.empty(p.size)
    assert p.call(p.pack, found[1], out) > 0
    u = list(found[1])
    turn = c.mode_turns[0][0]
    u[turn] += np.pi
    assert p.call(p.pack, u, out) == -1.0
    assert cov.record(machine, c.actuators(found[0]), u, 0.0, 1e-6, 2.0, 0) is False


def test_an_inconsistent_closure_takes_the_direct_solve(machine):
    """Small defects make the legs' closure inconsistent (residuals of ~5e-10 m, within the
    solver's residual_tol): the inverse's residual is beyond RESIDUAL_GUARD, and the record
    comes from the Numba path, which solves the direct model again as the batch row does."""
    rng = np.random.default_rng(4)
    bent = add_defects(machine, rng.normal(0.0, 1.0, len(defect_set(machine)))
                       * np.where(np.array(defect_set(machine).units) == "m", 1e-10, 1e-9))
    for tag in ("chain_ik", "chain_fk", "chain_jacobian"):
        chain_one.usable(bent, tag)
    x = bent.fk(bent.home_q)
    c = chain_one.constants(bent, "chain_jacobian")
    found = chain_one._inverse_values(c, x.tolist())
    assert found[3] > cov.RESIDUAL_GUARD
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        one, ref = bent.jacobian(x), bent.jacobian(x[None])
    assert not through_c(one)
    for name in FIELDS:
        b = getattr(ref, name)[0]
        np.testing.assert_allclose(getattr(one, name), b, rtol=0, atol=TOL * np.abs(b).max())
    # the kernel forced at the inverse's closure: near the batch row (measured: 2e-15 here;
    # not proven for every inconsistent closure, hence the guard)
    forced = cov.record(bent, c.actuators(found[0]), found[1], 0.0, 1e-6, 2.0, 0)
    assert through_c(forced)
    for name in FIELDS:
        b = getattr(ref, name)[0]
        np.testing.assert_allclose(getattr(forced, name), b, rtol=0, atol=1e-9 * np.abs(b).max())


def test_without_the_extension_the_numba_path_answers(machine, monkeypatch):
    x = machine.fk(machine.home_q)
    c_record = machine.jacobian(x)
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    numba_record = machine.jacobian(x)
    assert through_c(c_record) and not through_c(numba_record)
    np.testing.assert_allclose(c_record.J, numba_record.J, rtol=0,
                               atol=TOL * np.abs(c_record.J).max())


def test_records_are_independent_and_pickle_as_the_plain_record(machine):
    import pickle

    xs = poses(machine, 2, seed=15)
    first = machine.jacobian(xs[0])
    j = first.J.copy()
    later = machine.jacobian(xs[1])  # writes its own buffer
    assert not np.array_equal(later.J, j)
    np.testing.assert_array_equal(first.J, j)
    plain = pickle.loads(pickle.dumps(first))
    assert type(plain).__name__ == "ChainJacobians"
    np.testing.assert_array_equal(plain.J, j)
    other = pickle.loads(pickle.dumps(machine))  # the pack is rebuilt
    np.testing.assert_array_equal(other.jacobian(xs[0]).J, j)


def test_threads_get_their_own_answers(machine):
    from concurrent.futures import ThreadPoolExecutor

    xs = poses(machine, 12, seed=16)
    ref = [machine.jacobian(x).J.copy() for x in xs]

    def work(k: int) -> bool:
        return all(np.array_equal(machine.jacobian(xs[k]).J, ref[k]) for _ in range(10))

    with ThreadPoolExecutor(3) as pool:
        assert all(pool.map(work, range(len(xs))))


@pytest.mark.parametrize("name", NAMES)
def test_the_singular_values_are_computed_when_read(name):
    """On a machine whose records' ``condition`` was never read, J alone does not run the
    kernel's singular stage; the first read of ``condition`` or ``singular_values`` runs it
    once, whichever comes first, with the batch row's values — and marks the machine object
    (``cov._FUSED`` in its ``__dict__``): its later calls run the stage in their own C call,
    the record's buffer then bit for bit the lazy record's after its read (and ``condition``
    read there without a second call)."""
    m = fresh(name)
    xs = [x for x in poses(m, 4, seed=16) if through_c(m.jacobian(x))]
    assert len(xs) >= 3
    p = cov.pack(m)
    assert p.fusable and cov._FUSED not in m.__dict__  # this build takes the flag; none read
    lazy = [m.jacobian(x) for x in xs]
    for one in lazy:
        fields = one.__dict__
        assert one.J.shape == (6, len(one.q))
        assert "condition" not in fields and not stage_run(one)
    ref = m.jacobian(xs[0][None])
    assert lazy[0].condition == pytest.approx(ref.condition[0], rel=1e-12)
    assert "condition" in lazy[0].__dict__ and not np.isnan(lazy[0].__dict__["_out"]).any()
    assert m.__dict__[cov._FUSED]  # from now on in the call
    fused = [m.jacobian(x) for x in xs]
    for one, early in zip(fused, lazy, strict=True):
        assert through_c(one) and not np.isnan(one.__dict__["_out"]).any()  # before any read
        np.testing.assert_array_equal(early.singular_values, one.singular_values)
        np.testing.assert_array_equal(one.__dict__["_out"], early.__dict__["_out"])
        assert one.condition == early.condition
    np.testing.assert_allclose(fused[0].singular_values, ref.singular_values[0], rtol=1e-12)


def test_each_field_read_first_is_the_same(machine):
    """Each field read first on a fresh record (its own view or singular stage) equals it read
    after every other, bit for bit; a field read twice is the same object; equality is
    identity; ``dataclasses.replace`` gives a record with every field given."""
    import dataclasses

    names = (*FIELDS, "condition", "q", "status", "closure_rank", "expected_rank")
    for x in poses(machine, 3, seed=17):
        full = machine.jacobian(x)
        assert through_c(full)
        for name in reversed(names):
            getattr(full, name)
        for name in names:
            one = machine.jacobian(x)
            value = getattr(one, name)
            np.testing.assert_array_equal(value, getattr(full, name))
            assert getattr(one, name) is value
            assert one != full and one == one and hash(one) == object.__hash__(one)
        assert "1 pose" in repr(full)
        copy = dataclasses.replace(full, status=full.status)
        for name in names:
            np.testing.assert_array_equal(getattr(copy, name), getattr(full, name))


def test_at_solution_is_the_record_with_the_margin(machine):
    """``at_solution`` (the per-call path of ``m.jacobian(x)``) on the C inverse's answer: the
    record of :func:`~pkmkit.machines.chain_one_velocity.record` at the same solution bit for
    bit; the threshold BOUND_MARGIN × max(tol, RANK_RCOND) on either side of a pose's bound;
    a residual beyond the guard declines."""
    from pkmkit.machines.chain_one_native import packed
    from pkmkit.machines.chain_velocity_record import RANK_RCOND

    c = packed(machine)
    p = cov.pack(machine)
    out = np.empty(p.size)
    for x in poses(machine, 4, seed=18):
        solved = c.ik(c.capsule, x, True, True)
        one = cov.at_solution(machine, solved, 1e-6)
        ref = cov.record(machine, solved[0], solved[1].tolist(), solved[3], 1e-6,
                         cov.BOUND_MARGIN, 6 + len(machine.passive_variables))
        for name in (*FIELDS, "condition", "q", "status", "closure_rank", "expected_rank"):
            a, b = getattr(one, name), getattr(ref, name)
            np.testing.assert_array_equal(a, b)
            assert type(a) is type(b), name
        bound = p.call(p.pack, solved[1].tolist(), out, False)
        above, below = bound / cov.BOUND_MARGIN * 1.001, bound / cov.BOUND_MARGIN * 0.999
        assert cov.at_solution(machine, solved, above) is None
        assert through_c(cov.at_solution(machine, solved, below))
        assert through_c(cov.at_solution(machine, solved, RANK_RCOND / 10))
        far = (*solved[:3], 2 * cov.RESIDUAL_GUARD)
        assert cov.at_solution(machine, far, 1e-6) is False


@pytest.mark.parametrize("name", NAMES)
def test_a_read_on_one_copy_changes_no_other_copys_calls(name):
    """Copies of a machine share its velocity pack (``copy.copy``: a shallow copy of its
    ``__dict__``); a thread that reads ``condition`` on one copy's records makes that copy's
    later calls run the singular stage inside their C call, and changes nothing for the
    other copy (its records' buffers still without the singular stage until read) nor for
    the pack; either way the same bits (the lazy record after its read, the fused one)."""
    import copy
    import threading

    m = fresh(name)
    xs = [x for x in poses(m, 5, seed=19) if through_c(m.jacobian(x))]
    assert len(xs) >= 3
    a, b = copy.copy(m), copy.copy(m)
    assert cov.pack(a) is cov.pack(b) is cov.pack(m)
    before = {k for k in vars(cov.pack(m).__class__) if not k.startswith("__")}
    state = [getattr(cov.pack(m), k) for k in cov.VelocityPack.__slots__]

    def read_condition_on_a() -> None:
        for x in xs:
            assert a.jacobian(x).condition > 1.0

    reader = threading.Thread(target=read_condition_on_a)
    reader.start()
    plain = [b.jacobian(x) for x in xs for _ in range(3)]  # while a's thread reads
    reader.join()
    assert a.__dict__[cov._FUSED] and cov._FUSED not in b.__dict__ | m.__dict__
    assert [getattr(cov.pack(m), k) for k in cov.VelocityPack.__slots__] == state
    assert {k for k in vars(cov.pack(m).__class__) if not k.startswith("__")} == before
    lazy = [b.jacobian(x) for x in xs] + plain
    fused = [a.jacobian(x) for x in xs]
    for one in lazy:  # b's calls: no singular stage in the call
        assert not stage_run(one)
    for one, late in zip(fused, lazy, strict=False):
        assert not np.isnan(one.__dict__["_out"]).any()  # a's: in the call, before any read
        assert late.condition == one.condition  # b's stage run now: the same bits
        np.testing.assert_array_equal(late.__dict__["_out"], one.__dict__["_out"])
    assert cov._FUSED in b.__dict__ and cov._FUSED not in m.__dict__  # b's own read


def test_q_is_a_read_only_view_made_once(machine):
    """``q`` of a one-pose record: not stored before its first read, then one read-only
    view kept (later reads the same object, not wrapped again); equal to the batch row's;
    the record built from a caller's array (:func:`cov.record`) leaves that array
    writeable; ``dataclasses.replace`` keeps it read-only."""
    import dataclasses

    x = poses(machine, 1, seed=20)[0]
    one = machine.jacobian(x)
    assert through_c(one) and "q" not in one.__dict__
    q = one.q
    assert not q.flags.writeable and one.__dict__["q"] is q and one.q is q
    with pytest.raises(ValueError):
        q[0] = 1.0
    np.testing.assert_allclose(q, machine.jacobian(x[None]).q[0], rtol=0, atol=1e-12)
    from pkmkit.machines.chain_one_native import packed

    c = packed(machine)
    solved = c.ik(c.capsule, x, True, True)
    mine = np.array(solved[0])
    built = cov.record(machine, mine, solved[1], solved[3], 1e-6, 2.0, one.expected_rank)
    assert through_c(built) and built.q.base is mine and mine.flags.writeable
    np.testing.assert_array_equal(built.J, one.J)
    again = dataclasses.replace(built, status=built.status)
    assert not again.q.flags.writeable
    np.testing.assert_array_equal(again.q, mine)
