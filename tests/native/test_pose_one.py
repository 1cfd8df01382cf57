"""One pose per call of a full-pose rod machine in one C call each (``pkmkit.native.kernels``
``pose_one``, ``native/pose_one.c``; issue 22 §1): ``PoseOne.ik`` against
:class:`~pkmkit.machines.full_pose_one.OnePoseInverse` (plain Python: the same bits, the same
refusals) and the batch path's row; ``PoseOne.fk`` against the batch path's compiled solve
(the same function: the same bits) and its NumPy engine (to 1e-12); ``PoseOne.jacobian``'s
fields against the ``pose_velocity`` kernel (the same bits), the Numba kernel and the batch
path (tests/native/test_pose_velocity.py's comparisons run on it too); the strokes judged
inside; a refused row handed to the batch path; typed errors; pickling; threads."""

from __future__ import annotations

import pickle
import subprocess
import sys
import threading

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import full_pose_one
from pkmkit.machines.full_pose_velocity_one import FIELDS
from tests.machines.test_full_pose import _full_pose_delta

try:
    from pkmkit.native import kernels as _kernels
except ImportError:
    _kernels = None

pytestmark = [pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "pose_one"),
                                 reason="pkmkit.native.kernels was not built"),
              pytest.mark.filterwarnings("ignore::pkmkit.exceptions.StrokeWarning")]

NAMES = ["gough-stewart", "verne", "dietmaier-hexapod", "delta6"]


def _machine(name):
    return _full_pose_delta() if name == "delta6" else pkmkit.machine(name)


def _poses(m, n, seed, spread=0.2):
    """Poses around home (the Verne module's and delta6's: those their rods impose, some
    nudged off them), and some far out of reach."""
    rng = np.random.default_rng(seed)
    if m.position_controlled:
        x = m.ik(m.home_pose[:3] + rng.uniform(-spread, spread, (n, 3)), full_output=True,
                 strokes="ignore").pose
        x = x[np.isfinite(x).all(axis=1)]
        x[::9, 3:] += 1e-6  # orientations the rods do not impose
    else:
        x = m.home_pose + rng.uniform(-spread, spread, (n, 6))
    x[::13, :3] += 2.0
    return x


def _one(m):
    one = full_pose_one.native_one(m)
    assert type(one).__name__ == "PoseOne"
    return one


@pytest.mark.parametrize("name", NAMES)
def test_ik_is_one_pose_inverse_bit_for_bit(name):
    """The same q bits and the same refusals as the plain-Python inverse, for lists, tuples,
    float64 (also strided) and int64 vectors; the batch row to 1e-12; None beyond a stroke
    with check exactly where the machine's stroke test says so."""
    m = _machine(name)
    one, inverse = _one(m), m.one_pose_inverse()
    x = _poses(m, 400, seed=1)
    batch = m.ik(x, strokes="ignore")
    strided = np.repeat(x, 2, axis=1)[:, ::2]
    refused = beyond = 0
    for k, pose in enumerate(x.tolist()):
        want = inverse(pose)
        for given in (pose, tuple(pose), x[k], strided[k]):
            got = one.ik(given, False)
            assert (got is None) == (want is None), (k, given)
            if want is not None:
                assert type(got) is np.ndarray and got.shape == (m.n_actuators,)
                assert got.tolist() == want, k
        if want is None:
            refused += 1
            assert not np.isfinite(batch[k]).all()
            continue
        np.testing.assert_allclose(want, batch[k], rtol=0, atol=1e-12)
        inside = m.within_strokes(want)
        beyond += not inside
        checked = one.ik(pose, True)
        assert (checked is None) == (not inside)
    # (struts always close; the hexapod's strokes are unlimited, the Verne's not reached)
    assert refused + beyond > 10 or name == "dietmaier-hexapod"
    home = np.round(m.home_pose).astype(np.int64)
    assert one.ik(home, False) is None or one.ik(home, False).tolist() == inverse(home.tolist())


def test_ik_refusals_and_other_types():
    m = pkmkit.machine("gough-stewart")
    one, x = _one(m), m.home_pose.tolist()
    for pose in ([*x[:5], float("nan")], [*x[:5], float("inf")], [*x[:5], 2e9], [*x[:5], 10**400],
                 x[:5], [*x, 0.0], [True, *x[1:]], ["a", *x[1:]], [np.int64(v) for v in x],
                 "abcdef", None, 3.0, np.zeros(5), np.zeros((1, 6))):
        assert one.ik(pose, False) is None, pose
    for pose in (m.home_pose.astype(np.float32), m.home_pose.astype(np.int32),
                 np.zeros((1, 6), dtype=np.float32), b"abcdefgh"):
        assert one.ik(pose, False) is NotImplemented, pose
        assert one.jacobian(pose, 1e-6, True, print) is NotImplemented
    assert one.ik([np.float64(v) for v in x], False).tobytes() == one.ik(x, False).tobytes()
    assert one.ik([int(v) for v in np.round(x)], False).tolist() == \
        m.one_pose_inverse()([int(v) for v in np.round(x)])
    for error, args in [(TypeError, (x,)), (TypeError, (x, False, 1)), (TypeError, ())]:
        with pytest.raises(error):
            one.ik(*args)


@pytest.mark.parametrize("name", NAMES)
def test_fk_is_the_batch_paths_solve(name, monkeypatch):
    """The pose of the batch path's compiled solve (the same function: the same bits; the
    NumPy engine to 1e-12), None where its status is not OK or, with check, beyond a stroke;
    lists, tuples and arrays alike."""
    m = _machine(name)
    one = _one(m)
    x = _poses(m, 300, seed=2, spread=0.1)
    q = m.ik(x, strokes="ignore")
    q = q[np.isfinite(q).all(axis=1)]
    q[::11] += 0.5  # some far from any assembly near the guess, some beyond a stroke
    full = m.fk(q, full_output=True, strokes="ignore")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    engine = m.fk(q, strokes="ignore")
    monkeypatch.delenv("PKMKIT_COMPILED")
    solved = 0
    for k, v in enumerate(q):
        got = one.fk(v, False)
        for given in (v.tolist(), tuple(v.tolist())):
            again = one.fk(given, False)
            assert (again is None) == (got is None) and (got is None or
                                                         np.array_equal(again, got))
        ok = full.status[k] == 0
        assert (got is not None) == ok, k
        if not ok:
            continue
        solved += 1
        assert got.shape == (6,) and np.array_equal(got, full.pose[k]), k
        np.testing.assert_allclose(got, engine[k], rtol=0, atol=1e-12)
        inside = m.within_strokes(v.tolist())
        assert (one.fk(v, True) is None) == (not inside)
    assert solved > 200


def test_fk_refusals():
    m = pkmkit.machine("verne")
    one, q = _one(m), m.home_q.tolist()
    for v in ([*q[:2], float("nan")], [*q[:2], 2e9], q[:2], [*q, 0.0], [True, *q[1:]],
              np.zeros(2), np.zeros((1, 3)), m.home_q.astype(np.float32), "abc", None):
        assert one.fk(v, False) is None, v
    np.testing.assert_array_equal(one.fk(np.array(q), False), m.fk(np.array([q]))[0])


def _velocity(one, x, tol, batch=None):
    return one.jacobian(x, tol, False, batch or (lambda *a: pytest.fail("refused")))


@pytest.mark.parametrize("name", ["gough-stewart", "verne", "dietmaier-hexapod"])
def test_jacobian_fields_are_the_kernels_bits(name):
    """Every field of PoseOne.jacobian equals pose_velocity's at its highest level (the same
    bits) whatever the order the fields are read in — the first read's pk_pose_fill, then
    the SVDs added from the state (add_singular_values) — at poses within and beyond the
    strokes and far ones; the first read computes only the SVDs its field needs."""
    m = _machine(name)
    one = _one(m)
    geom, length = m.direct_kernel().geom, float(m.characteristic_length)
    rng = np.random.default_rng(3)
    for k, pose in enumerate(_poses(m, 40, seed=3, spread=0.3).tolist()):
        q = m.one_pose_inverse()(pose)
        if q is None:
            assert _velocity(one, pose, 1e-6) is None
            continue
        tol = float(rng.choice([1e-6, 0.05, 0.3]))
        state = _kernels.pose_velocity(geom, pose, q, length, tol, 7)
        want = {}
        for name_ in FIELDS:
            ev = _velocity(one, pose, tol)
            want[name_] = ev.field(name_)
        assert np.array_equal(want["q"], q)
        offsets = full_pose_one_layout(m.n_actuators)
        flat = np.frombuffer(state)
        assert np.array_equal(want["J"].ravel(), flat[offsets["J"]], equal_nan=True)
        assert np.array_equal(want["A"].ravel(), flat[offsets["A"]], equal_nan=True)
        assert want["condition"] == flat[offsets["condition"]] or (
            np.isnan(want["condition"]) and np.isnan(flat[offsets["condition"]]))
        assert int(want["singularity"]) == int(flat[offsets["flags"]])
        ev = _velocity(one, pose, tol)
        order = list(FIELDS)
        rng.shuffle(order)
        levels = []
        for name_ in order:
            got = ev.field(name_)
            assert type(got) is type(want[name_]), name_
            assert np.array_equal(np.asarray(got), np.asarray(want[name_]), equal_nan=True), (
                k, name_)
            levels.append(ev.level)
        assert ev.level == 7
        first = next(f for f in order if f not in ("q", "tolerance", "characteristic_length"))
        assert levels[order.index(first)] == LEVELS.get(first, 0)


def full_pose_one_layout(n):
    """Slices of the fields in pose_velocity's output (full_pose_velocity_one.layout(6, n))."""
    from pkmkit.machines.full_pose_velocity_one import layout

    spot = layout(6, n)
    return {"A": slice(*spot["A"]), "J": slice(*spot["J"]),
            "condition": spot["condition"][0], "flags": spot["flags"][0]}


#: pk_pose_fill's level bits each field needs (pose_one.c's field_level)
LEVELS = {"singular_values": 1, "condition": 1, "parallel_measure": 4,
          "translation_singular_values": 3, "rotation_singular_values": 3}


def test_the_first_field_read_computes_the_matrices_and_flags_in_one_call():
    m = pkmkit.machine("dietmaier-hexapod")
    one, x = _one(m), (m.home_pose + 0.01).tolist()
    ev = _velocity(one, x, 1e-6)
    assert ev.level == -1
    ev.field("J"), ev.field("singularity"), ev.field("det_A"), ev.field("J_inv")
    assert ev.level == 0
    assert 0.0 < ev.field("parallel_measure") <= 1.0 and ev.level == 4
    ev = _velocity(one, x, 1e-6)
    ev.field("condition"), ev.field("J"), ev.field("singular_values")
    assert ev.level == 1
    ev.field("rotation_singular_values")
    assert ev.level == 3
    ev.field("parallel_measure")
    assert ev.level == 7
    with pytest.raises(AttributeError):
        ev.field("nothing")
    with pytest.raises(TypeError):
        ev.field(3)


@pytest.mark.parametrize("name", ["gough-stewart", "verne", "dietmaier-hexapod", "delta6"])
def test_singular_values_against_lapack(name):
    """J_h's and J's rows' singular values (svd.c's round-robin Jacobi: not the Numba
    kernel's cyclic order, nor its bits) against LAPACK's SVD of the record's own J, to
    4e-15 of σ_max, also for the nearly singular J of poses near a parallel singularity;
    6 × 6 and 6 × 3 (an odd count of columns), 3 × 6 and 3 × 3."""
    from tests.conftest import near_parallel_singular_poses

    m = _machine(name)
    one = _one(m)
    x = _poses(m, 150, seed=6, spread=0.3)
    if name == "gough-stewart":
        x = np.vstack([x, near_parallel_singular_poses(60, np.random.default_rng(7))[1]])
    checked = 0
    for pose in x.tolist():
        ev = _velocity(one, pose, 1e-9)
        if ev is None or not np.isfinite(ev.field("J")).all():
            continue
        j, j_h = ev.field("J"), ev.field("J_homogeneous")
        for got, mat in ((ev.field("singular_values"), j_h),
                         (ev.field("translation_singular_values"), j[:3]),
                         (ev.field("rotation_singular_values"), j[3:])):
            want = np.linalg.svd(mat, compute_uv=False)
            np.testing.assert_allclose(got, want, rtol=0, atol=4e-15 * want[0])
        assert ev.field("condition") == ev.field("singular_values")[0] / ev.field(
            "singular_values")[-1]
        checked += 1
    assert checked > 100


def test_a_refused_row_goes_to_the_batch_path_once():
    """A platform joint at 1e300 m in the kernel's copy of the rods (not the inverse's): A's
    moment row overflows, the kernel refuses the row, and batch(x, q, tol) answers every field,
    called once."""
    m = pkmkit.machine("gough-stewart")
    one = _one(m)
    args = list(one.__reduce__()[1])
    x = (m.home_pose + 0.01).tolist()
    geom = np.array(args[8], dtype=float).reshape(6, 16).copy()
    geom[0, 3:6] = 1e300
    args[8] = geom
    broken = _kernels.pose_one(*args)
    calls = []

    class Record:
        J = "batch J"
        condition = "batch condition"

    def batch(x1, q1, tol):
        calls.append((x1, q1, tol))
        return Record()

    ev = broken.jacobian(x, 1e-6, False, batch)
    assert ev.field("J") == "batch J" and ev.field("condition") == "batch condition"
    assert ev.level == -1 and len(calls) == 1
    assert calls[0][0] == x and calls[0][1] == m.one_pose_inverse()(x) and calls[0][2] == 1e-6
    np.testing.assert_array_equal(ev.field("q"), calls[0][1])  # not from the batch record


def test_jacobian_strokes_and_errors():
    m = pkmkit.machine("gough-stewart")
    one = _one(m)
    high = (m.home_pose + np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])).tolist()
    assert not m.within_strokes(m.one_pose_inverse()(high))
    assert one.jacobian(high, 1e-6, True, print) is None
    assert one.jacobian(high, 1e-6, False, print) is not None
    x = m.home_pose.tolist()
    for error, args in [(TypeError, (x, 1, True, print)), (ValueError, (x, 0.0, True, print)),
                        (ValueError, (x, float("inf"), True, print)),
                        (TypeError, (x, 1e-6, True, None)), (TypeError, (x, 1e-6, True))]:
        with pytest.raises(error):
            one.jacobian(*args)


def test_constructor_refusals():
    m = pkmkit.machine("verne")
    args = list(_one(m).__reduce__()[1])
    make = _kernels.pose_one
    assert make(*args).ik(m.home_pose, False).tolist() == m.one_pose_inverse()(
        m.home_pose.tolist())

    def changed(i, value):
        return [*args[:i], value, *args[i + 1:]]

    rods = np.frombuffer(args[0]).copy()
    bad_kind = rods.copy()
    bad_kind[0] = 5.0
    groups = np.frombuffer(args[1]).copy()
    bad_group = groups.copy()
    bad_group[2] = 7.0
    geom = np.array(args[8]).copy()
    bad_actuator = geom.copy()
    bad_actuator[0, 14] = 3.0
    for error, call_args in [
        (TypeError, args[:-1]),
        (ValueError, changed(0, args[0][:-8])),
        (ValueError, changed(0, bad_kind.tobytes())),
        (TypeError, changed(0, list(rods))),
        (ValueError, changed(1, bad_group.tobytes())),
        (ValueError, changed(1, args[1][:-8])),
        (ValueError, changed(6, np.full(3, np.nan))),
        (ValueError, changed(7, np.zeros(2))),
        (ValueError, changed(8, bad_actuator)),
        (ValueError, changed(8, geom[:5])),
        (ValueError, changed(9, np.zeros(5))),
        (ValueError, changed(10, np.zeros(6))),
        (ValueError, changed(11, 0.0)),
        (ValueError, changed(4, float("nan"))),
        (TypeError, changed(11, "1")),
        (ValueError, changed(6, np.zeros(7))),
        (ValueError, changed(2, True)),  # simple: 3 actuators, 6 rods
    ]:
        with pytest.raises(error):
            make(*call_args)


def test_pickles_with_the_machine():
    m = pkmkit.machine("dietmaier-hexapod")
    x = m.home_pose + 0.01
    q = m.ik(x)
    m.fk(q), m.jacobian(x).J
    assert type(m.__dict__["_pose_one"]).__name__ == "PoseOne"
    back = pickle.loads(pickle.dumps(m))
    np.testing.assert_array_equal(back.ik(x), q)
    np.testing.assert_array_equal(back.fk(q), m.fk(q))
    np.testing.assert_array_equal(back.jacobian(x).J, m.jacobian(x).J)


def test_threads_share_a_pose_one_and_a_record():
    """No shared work buffers: two threads calling one PoseOne and reading one record give
    the serial answers."""
    m = pkmkit.machine("gough-stewart")
    one = _one(m)
    x = _poses(m, 200, seed=4, spread=0.05)
    want = [(one.ik(p, False), one.jacobian(p, 1e-6, False, print)) for p in x]
    want = [(q, None if ev is None else ev.field("J"), None if q is None else one.fk(q, False))
            for q, ev in want]
    shared = _velocity(one, x[0].tolist(), 1e-6)
    errors = []

    def work():
        try:
            for _ in range(5):
                for (q, j, pose), p in zip(want, x, strict=True):
                    got = one.ik(p, False)
                    assert (got is None) == (q is None) and (q is None or np.array_equal(got, q))
                    if q is not None:
                        back = one.fk(q, False)
                        assert (back is None) == (pose is None)
                        assert back is None or np.array_equal(back, pose)
                        ev = one.jacobian(p, 1e-6, False, print)
                        assert np.array_equal(ev.field("J"), j, equal_nan=True)
                    assert np.array_equal(shared.field("J"), want[0][1], equal_nan=True)
        except AssertionError as error:  # pragma: no cover (reported below)
            errors.append(error)

    threads = [threading.Thread(target=work) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors


def test_the_machine_takes_pose_one_and_imports_no_numba():
    code = ("import sys, pkmkit\n"
            "m = pkmkit.machine('dietmaier-hexapod')\n"
            "x = (m.home_pose + 0.01).tolist()\n"
            "q = m.ik(x); p = m.fk(q); j = m.jacobian(x)\n"
            "j.J, j.condition, j.singularity\n"
            "print('numba' in sys.modules, type(j._evaluation).__name__, "
            "abs(p - x).max() < 1e-12)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "PoseVelocity", "True"]
