"""One pose per call in one C call (``pkmkit.native.kernels`` ``rod_ik_one``, ``rod_fk_one``,
``rod_jacobian_one``; issue 22 §1) for every translational rod-leg machine: the same bits as the
plain-Python one-pose paths (``PKMKIT_NATIVE=0``), the batch path's row (bit for bit for
slides and struts, to 4 ulp of π for crank angles; the direct model to 1e-12 m, as
tests/machines/test_single_call.py states it), the independent oracle of closure (every rod
at its length between the pose and its actuator's joint), the input types it reads, the
strokes judged as ``Machine.within_strokes`` judges them, and everything else handed to the
batch path (None from the kernel, the typed errors from the machine)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import (
    InputError,
    OutOfStrokeError,
    StrokeWarning,
)
from pkmkit.machines.closed_form_one import direct_one
from pkmkit.machines.machine import Machine

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "rod_ik_one"),
                                reason="pkmkit.native.kernels was not built")

TRANSLATIONAL = [name for name in pkmkit.machines()
                 if pkmkit.machine(name).family == "translational"]


def _poses(m, n, seed):
    lo, hi = m.default_box()
    return lo + (hi - lo) * np.random.default_rng(seed).random((n, m.dims))


def _closure_error(m, x, q):
    """max |‖x − c_i(q)‖ − ρ_i(q)| over the legs: the rods' own geometry, not the formulas."""
    c, rho = m.closed_form.centres(np.asarray(q, dtype=float)[None])
    return float(np.max(np.abs(np.linalg.norm(np.asarray(x)[None] - c[0], axis=1) - rho[0])))


def _python_path(monkeypatch, call):
    monkeypatch.setenv("PKMKIT_NATIVE", "0")
    try:
        return call()
    finally:
        monkeypatch.delenv("PKMKIT_NATIVE")


def _no_batch_path(monkeypatch):
    """Make the batch paths fail: what still answers took the one C call."""
    def refuse(*args, **kwargs):
        raise AssertionError("the batch path was taken")
    monkeypatch.setattr(Machine, "_ik_rows", refuse)
    monkeypatch.setattr(Machine, "_fk_rows", refuse)


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_ik_one_call_is_the_python_path_the_batch_row_and_closes(name, monkeypatch):
    m = pkmkit.machine(name)
    x = _poses(m, 1000, seed=5)
    batch = m.closed_form.inverse_numpy(x, m.model.leg_branch)  # the batch path's rows
    _no_batch_path(monkeypatch)
    pack = m._one_pack
    compared, got, rows = 0, [], []
    for k, p in enumerate(x):
        q = _kernels.rod_ik_one(pack, p, "ignore")
        python = m.closed_form.inverse_one(p, m._default_branches)  # the Python one-pose path
        if q is None:  # out of reach: the batch path's NaN row (and its typed error)
            assert not np.isfinite(batch[k]).all() and python is None
            continue
        assert type(q) is np.ndarray and q.dtype == np.float64 and q.shape == (m.n_actuators,)
        assert q.tobytes() == np.array(python).tobytes(), (name, k)
        assert q.tobytes() == m.ik(p, strokes="ignore").tobytes()
        if m.angular_actuators.any():
            got.append(q)
            rows.append(k)
        else:
            assert q.tobytes() == batch[k].tobytes(), (name, k)
        assert _closure_error(m, p, q) < 1e-12
        compared += 1
    assert compared > 300
    if rows:  # the cranks' angles, to a few ulps of π: every reached row in one comparison
        np.testing.assert_allclose(np.array(got), batch[rows], rtol=0, atol=4 * np.spacing(np.pi))


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_fk_one_call_is_the_python_path_the_batch_row_and_closes(name):
    m = pkmkit.machine(name)
    q = m.ik(_poses(m, 600, seed=6), strokes="ignore")
    q = q[np.isfinite(q).all(axis=1)]
    q[::7] *= 1.6  # some near the edge of the assembly region or beyond
    if not m.angular_actuators.any():  # one slide or strut far away: no assembly
        q[::11, 0] += 10.0 * m.model.leg_length.max()
    compared = refused = 0
    for mode in ("working", "other"):
        sign = m._mode_sign(mode)
        batch = m.fk(q, mode=mode, full_output=True, strokes="ignore")
        solved, at, rows = [], [], []
        for k, v in enumerate(q):
            pose = _kernels.rod_fk_one(m._one_pack, v, sign, "ignore")
            python = direct_one(m.closed_form, v, sign)  # the Python one-pose path
            if pose is None:  # the batch path answers (or raises): no assembly, near-aligned
                assert python is None, (name, k)
                refused += 1
                continue
            assert pose.shape == (m.dims,) and pose.tobytes() == np.array(python).tobytes()
            assert pose.tobytes() == m.fk(v, mode=mode, strokes="ignore").tobytes()
            assert _closure_error(m, pose, v) < 1e-9
            solved.append(pose)
            at.append(v)
            rows.append(k)
            compared += 1
        # the batch rows, in one comparison
        np.testing.assert_allclose(np.array(solved), batch.pose[rows], rtol=0, atol=1e-12)
        # the mode asked: the sign of det A at each solution (one batch call over the rows)
        modes = m.jacobian(np.array(solved), q=np.array(at)).mode
        assert (np.asarray(modes) == sign).all(), (name, mode)
    assert compared > 300
    assert refused > 0 or m.angular_actuators.any()


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_fk_one_call_at_the_edge_of_the_assembly_region(name):
    """Configurations bisected onto the edge of the assembly region (a double root, t² within
    rounding of 0, where both the C and the Python path take t = 0): the same bits."""
    m = pkmkit.machine(name)
    q = m.ik(_poses(m, 40, seed=8), strokes="ignore")
    q = q[np.isfinite(q).all(axis=1)][:12]
    step = 1.5 if m.angular_actuators.any() else 10.0 * m.model.leg_length.max()
    edges = 0
    for inside in q:
        # towards a configuration without assembly (one actuator, else all, moved away)
        away = [inside + step * k * np.eye(len(inside))[0] for k in (1, 2)]
        away += [inside + step * k for k in (1, -1, 2, -2)]
        outside = next((v for v in away if direct_one(m.closed_form, v, 1) is None), None)
        if outside is None:
            continue
        for _ in range(60):
            mid = 0.5 * (inside + outside)
            if direct_one(m.closed_form, mid, 1) is None:
                outside = mid
            else:
                inside = mid
        for v in (inside, outside):
            for sign in (1, -1):
                pose = _kernels.rod_fk_one(m._one_pack, v, sign, "ignore")
                python = direct_one(m.closed_form, v, sign)
                assert (pose is None) == (python is None)
                if pose is not None:
                    assert pose.tobytes() == np.array(python).tobytes()
        edges += 1
    assert edges >= 4


def test_inputs_it_reads_and_those_it_hands_over():
    m = pkmkit.machine("linear-delta")
    x = (m.home_pose + np.array([0.01, -0.02, 0.03])).tolist()
    want = m.ik(np.array(x)[None])[0].tobytes()
    wide = np.zeros((3, 2))
    wide[:, 1] = x  # a strided column
    for given in (x, tuple(x), np.array(x), wide[:, 1], [np.float64(v) for v in x]):
        assert _kernels.rod_ik_one(m._one_pack, given, "flag").tobytes() == want
    ints = [0, 0, round(m.home_pose[2])]  # ints are read as floats
    assert (_kernels.rod_ik_one(m._one_pack, ints, "ignore").tobytes()
            == m.ik(np.array([ints], dtype=float), strokes="ignore")[0].tobytes())
    handed = ([*x, 0.0], x[:2], [np.nan, 0.0, 0.0], [0.0, np.inf, 0.0], [2e9, 0.0, 0.0],
              [True, 0.0, 0.0], [False, *x[1:]], ["0", 0.0, 0.0], np.array(x, dtype=np.float32),
              np.array([x]), np.array(x).astype(">f8"), np.array([0, 0, 1]), "abc", None,
              [10**400, 0.0, 0.0], {0: 0.0, 1: 0.0, 2: 0.0})
    for given in handed:
        assert _kernels.rod_ik_one(m._one_pack, given, "flag") is None, given
        assert _kernels.rod_fk_one(m._one_pack, given, 1, "flag") is None, given
        assert _kernels.rod_jacobian_one(m._one_pack, given, 1e-6) is None, given
    for bad in ([np.nan, 0.0, 0.0], [0.0, 0.0], [1e300, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]):
        with pytest.raises(InputError):  # the batch path's typed errors
            m.ik(bad)
        with pytest.raises(InputError):
            m.fk(bad)
        with pytest.raises(InputError):
            m.jacobian(bad)
    with pytest.raises(InputError):
        m.ik(x, strokes="sideways")
    assert _kernels.rod_ik_one(m._one_pack, x, "sideways") is None
    assert _kernels.rod_ik_one(m._one_pack, x, 3) is None


def test_strokes_judged_as_the_machine_judges_them(monkeypatch):
    """At a stroke's limit the value is inside, one ulp beyond it outside: the kernel hands it
    to the batch path, which judges it with STROKE_TOL (session 33: the band is the batch
    path's, whose q may round otherwise) — inside up to the tolerance, then a StrokeWarning,
    an OutOfStrokeError."""
    m = pkmkit.machine("linear-delta")
    lo, hi = _limits(m)
    q = m.home_q.copy()
    for k, edge, outward in ((0, hi[0], np.inf), (1, lo[1], -np.inf)):
        if not np.isfinite(edge):
            continue
        at = q.copy()
        at[k] = edge
        beyond = at.copy()
        beyond[k] = np.nextafter(edge, outward)
        assert m.within_strokes(at.tolist()) and not m.within_strokes(beyond.tolist())
        for strokes in ("flag", "refuse"):
            assert _kernels.rod_fk_one(m._one_pack, at, m._working_mode, strokes) is not None
            assert _kernels.rod_fk_one(m._one_pack, beyond, m._working_mode, strokes) is None
        assert _kernels.rod_fk_one(m._one_pack, beyond, m._working_mode, "ignore") is not None
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # within the tolerance: the batch path, no warning
            np.testing.assert_allclose(m.fk(beyond), m.fk(beyond, strokes="ignore"),
                                       rtol=0, atol=1e-12)
        past = at.copy()
        past[k] = edge + 2e-12 * (1.0 if outward > 0 else -1.0)
        with pytest.warns(StrokeWarning):
            m.fk(past)
        with pytest.raises(OutOfStrokeError):
            m.fk(past, strokes="refuse")
    pose = [0.0, 0.0, 1.0]  # reachable, beyond the slides' strokes
    assert _kernels.rod_ik_one(m._one_pack, pose, "flag") is None
    assert _kernels.rod_jacobian_one(m._one_pack, pose, 1e-6) is None
    assert _kernels.rod_ik_one(m._one_pack, pose, "ignore") is not None
    with pytest.warns(StrokeWarning):
        m.ik(pose)
    with pytest.raises(OutOfStrokeError):
        m.ik(pose, strokes="refuse")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isfinite(m.ik(pose, strokes="ignore")).all()


def _limits(m):
    from pkmkit.machines.strokes import stroke_limits
    return stroke_limits(m)  # the kernel's window: the strokes themselves


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_jacobian_state_holds_the_pose_and_its_inverse(name):
    m = pkmkit.machine(name)
    for x in _poses(m, 40, seed=7):
        q = m.ik(x, strokes="ignore") if np.isfinite(
            m.closed_form.inverse_numpy(x[None], m.model.leg_branch)).all() else None
        state = _kernels.rod_jacobian_one(m._one_pack, x, 1e-6)
        if state is None:
            assert q is None or not m.within_strokes(q.tolist())
            continue
        assert _kernels.rod_field(state, 12).tobytes() == q.tobytes()  # the state's q
        assert _kernels.rod_field(state, 13).tobytes() == x.tobytes()  # and its x
        record = m.jacobian(x)
        assert record._evaluation.q == q.tolist() and record._evaluation.x == x.tolist()
        assert record.q.tobytes() == q.tobytes()


def test_bad_packs_and_arguments_raise():
    m = pkmkit.machine("orthoglide")
    pack, x = m._one_pack, m.home_pose.tolist()
    calls = [
        (TypeError, lambda: _kernels.rod_ik_one(pack, x)),
        (TypeError, lambda: _kernels.rod_ik_one(bytearray(pack), x, "flag")),
        (ValueError, lambda: _kernels.rod_ik_one(pack[:-8], x, "flag")),
        (ValueError, lambda: _kernels.rod_ik_one(b"", x, "flag")),
        (ValueError, lambda: _kernels.rod_ik_one(np.full(len(pack) // 8, 7.0).tobytes(), x,
                                                 "flag")),
        (TypeError, lambda: _kernels.rod_fk_one(pack, x, 1)),
        (TypeError, lambda: _kernels.rod_fk_one(pack, x, "1", "flag")),
        (TypeError, lambda: _kernels.rod_jacobian_one(pack, x)),
        (TypeError, lambda: _kernels.rod_jacobian_one(pack, x, "1e-6")),
        (ValueError, lambda: _kernels.rod_jacobian_one(pack, x, 0.0)),
        (ValueError, lambda: _kernels.rod_jacobian_one(pack, x, float("inf"))),
    ]
    for error, call in calls:
        with pytest.raises(error):
            call()


def test_machines_without_a_pack_stay_in_python():
    """A machine with other than 2 or 3 legs, one per coordinate, has no pack: its one-pose
    calls take the Python paths (the same numbers)."""
    from pkmkit.machines.closed_form_one import one_pose_pack

    m = pkmkit.machine("five-bar")
    assert one_pose_pack(m.closed_form, m._default_branches, [0.0], [1.0]) is None
    assert m._one_pack is not None and len(m._one_pack) == 8 * (14 + 2 * (20 + 14 + 17))


def test_fk_mode_and_fallback_without_the_extension(monkeypatch):
    m = pkmkit.machine("orthoglide")
    q = m.ik(m.home_pose + np.array([0.01, 0.02, -0.01]))
    for mode in ("working", "other", 1, -1, *m.model.mode_names):
        c_path = m.fk(q, mode=mode)
        python = _python_path(monkeypatch, lambda mode=mode: m.fk(q, mode=mode))
        assert c_path.tobytes() == python.tobytes()
    with pytest.raises(InputError, match="mode"):
        m.fk(q, mode="sideways")
    with pytest.raises(InputError, match="mode"):
        _python_path(monkeypatch, lambda: m.fk(q, mode="sideways"))


def test_nearly_equal_singular_values_by_numpys_lapack_in_c():
    """Near the Orthoglide's isotropic home the closed-form singular values hand the matrix to
    LAPACK; the C state calls NumPy's own ``svd`` gufunc loop there: the batch row's bits,
    every field answered in C."""
    import struct

    m = pkmkit.machine("orthoglide")
    rng = np.random.default_rng(9)
    near = 0
    for scale in (1e-9, 1e-6, 1e-4, 1e-3):
        for x in m.home_pose + scale * rng.standard_normal((6, 3)):
            record = m.jacobian(x)
            if record._state is None:
                continue
            batch = m.jacobian(x[None])
            for field in ("singular_values", "condition", "parallel_measure", "J"):
                got, want = getattr(record, field), getattr(batch, field)[0]
                assert np.asarray(got).tobytes() == np.asarray(want).tobytes(), (field, x)
            answered = struct.unpack_from("iI", record._state)[1]
            assert answered == (1 << 14) - 1, hex(answered)  # every field, in C
            sv = record.singular_values
            near += bool(sv[0] - sv[-1] < 1e-3 * sv[0])
    assert near >= 6


@pytest.mark.parametrize("name", ["orthoglide", "delta", "five-bar"])
def test_each_field_read_first_is_answered_in_c(name):
    """The state computes its fields in stages (J and the flags first; J's singular values,
    the condition number and the parallel measure when one of them is read): each field read
    first on a fresh record is answered in C, the batch row's bits."""
    import struct

    m = pkmkit.machine(name)
    codes = {"A": 0, "B": 1, "J": 2, "J_inv": 3, "singular_values": 4, "condition": 5,
             "det_A": 6, "det_B": 7, "parallel_measure": 8, "serial_measure": 9,
             "singularity": 10, "mode": 11, "q": 12}
    poses = [x for x in _poses(m, 60, seed=10)
             if _kernels.rod_jacobian_one(m._one_pack, x, 1e-6) is not None][:8]
    assert len(poses) >= 4
    batch = m.jacobian(np.array(poses))
    for k, x in enumerate(poses):
        for field, code in codes.items():
            record = m.jacobian(x)
            got = getattr(record, field)
            answered = struct.unpack_from("iI", record._state)[1]
            assert answered & (1 << code), (field, hex(answered))
            want = getattr(batch, field)[k]
            assert np.asarray(got).tobytes() == np.asarray(want).tobytes(), (field, k)
        lazy = m.jacobian(x)
        _ = lazy.J  # J alone: the singular values not computed yet
        answered = struct.unpack_from("iI", lazy._state)[1]
        assert not answered & (1 << codes["condition"]), hex(answered)
