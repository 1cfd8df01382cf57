"""The C one-pose velocity model of translational rod-leg machines (``pkmkit.native.kernels``
``rod_inverse``, ``rod_velocity``, ``rod_field``; issue 22 §1) against the Python one-pose path
(:mod:`pkmkit.machines.velocity_one` with ``PKMKIT_NATIVE=0``) and the batch path's row (the
independent oracle: vectorised NumPy over a batch), every field **bit for bit**, at random
poses and at poses bisected onto serial singularities (the edge of the workspace) and parallel
singularities (a change of sign of det A); that the C kernel answered (not the Python pieces
behind it); the Python path when the extension is disabled; the kernels' refusals of bad
arguments; and that a fresh process's first one-pose Jacobian imports no Numba."""

from __future__ import annotations

import struct
import subprocess
import sys
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import velocity_one
from pkmkit.machines.velocity_one import OnePoseJacobians
from pkmkit.numerics import jit

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = [pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "rod_velocity"),
                                 reason="pkmkit.native.kernels was not built"),
              pytest.mark.filterwarnings("ignore::pkmkit.exceptions.StrokeWarning")]

TRANSLATIONAL = [name for name in pkmkit.machines()
                 if pkmkit.machine(name).family == "translational"]
FIELDS = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
          "parallel_measure", "serial_measure", "singularity", "tolerance", "q", "mode")
ALL_FIELDS = (1 << 14) - 1  # every bit of rod_field's codes: the fields, the state's q and x


def _same_bits(got, want, where):
    assert type(got) is type(want), (where, type(got), type(want))
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape and got.dtype == want.dtype, where
    assert np.array_equal(got, want, equal_nan=True), (where, got, want)


def _answered(record) -> int:
    """The fields the C kernel answered for this record (rod_field's bits)."""
    state = record._evaluation._state
    assert isinstance(state, bytearray)
    return struct.unpack_from("iI", state)[1]


def _records(m, poses, tol, monkeypatch):
    """Per pose: a fresh record per field from the C path and from the Python path (a field
    read alone), or None where the pose takes the batch path."""
    out = []
    for p in poses:
        p = [float(v) for v in p]
        first = m.jacobian(p, tol=tol)
        if not isinstance(first, OnePoseJacobians):
            out.append(None)
            continue
        native = {f: getattr(m.jacobian(p, tol=tol), f) for f in FIELDS}
        native["_answered"] = _answered(first) if all(  # every field read: every stage
            getattr(first, f) is not None for f in FIELDS) else 0
        monkeypatch.setenv("PKMKIT_NATIVE", "0")
        try:
            python = {f: getattr(m.jacobian(p, tol=tol), f) for f in FIELDS}
            assert m.jacobian(p, tol=tol)._evaluation.native() is False
        finally:
            monkeypatch.delenv("PKMKIT_NATIVE")
        out.append((native, python))
    return out


def _check(m, poses, monkeypatch, tol=1e-6, name=""):
    """Every field of the C path = the Python path = the batch row (of a batch of all the
    poses that take the one-pose path, at their one-pose q). Returns the C-answered bits."""
    records = _records(m, poses, tol, monkeypatch)
    kept = [k for k, r in enumerate(records) if r is not None]
    if not kept:
        return []
    x = np.array(poses)[kept]
    q = np.array([records[k][0]["q"] for k in kept])
    batch = m.jacobian(x, q=q, tol=tol)
    answered = []
    for row, k in enumerate(kept):
        native, python = records[k]
        for field in FIELDS:
            want = getattr(batch, field)
            want = want[row] if np.ndim(want) else want
            _same_bits(python[field], want, f"{name} pose {k} {field} (Python path)")
            _same_bits(native[field], want, f"{name} pose {k} {field} (C path)")
        answered.append(native["_answered"])
    return answered


def _reachable(m, x):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        return np.isfinite(m.ik(x, strokes="ignore")).all(axis=1)


def _random_poses(m, n, seed):
    """Up to n poses of the default box whose inverse model lies within the strokes."""
    lo, hi = m.default_box()
    x = lo + (hi - lo) * np.random.default_rng(seed).random((20 * n, m.dims))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        q = m.ik(x, strokes="ignore")
    keep = [k for k in range(len(x)) if np.isfinite(q[k]).all()
            and m.within_strokes(q[k].tolist())]
    return x[keep[:n]]


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_random_poses_bit_for_bit_and_answered_in_c(name, monkeypatch):
    m = pkmkit.machine(name)
    x = _random_poses(m, 60, seed=21)
    answered = _check(m, x, monkeypatch, name=name)
    answered += _check(m, x[:20], monkeypatch, tol=0.3, name=name)  # some flagged
    assert len(answered) >= 20
    # the C kernel answered every field of most poses (the rest: LAPACK for nearly equal
    # singular values, in the Python path as in the batch path)
    assert sum(a == ALL_FIELDS for a in answered) >= 0.8 * len(answered), name


def _bisect(m, inside, outside, test, steps=60):
    """Poses on the segment inside → outside where ``test`` holds, closing in on where it
    changes (those of the last ``steps // 2`` bisections: the nearest)."""
    kept = []
    for step in range(steps):
        mid = 0.5 * (inside + outside)
        if test(mid):
            inside = mid
            if step >= steps // 2:
                kept.append(mid)
        else:
            outside = mid
    return kept


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta", "delta", "five-bar"])
def test_bisected_onto_serial_singularities(name, monkeypatch):
    """Toward the edge of the workspace (a leg just closing: B's entry → 0)."""
    m = pkmkit.machine(name)
    lo, hi = m.default_box()
    rng = np.random.default_rng(22)
    inside = _random_poses(m, 40, seed=23)[:6]
    poses = []
    for p in inside:
        far = p + (hi - lo) * 3 * rng.normal(size=m.dims)
        if not _reachable(m, far[None])[0]:
            poses += _bisect(m, p, far, lambda y: bool(_reachable(m, y[None])[0]))
    assert len(poses) >= 20
    x = np.array(poses)
    _check(m, x, monkeypatch, name=name)
    _check(m, x, monkeypatch, tol=1e-3, name=name)
    measures = [m.jacobian(p.tolist()).serial_measure for p in x[-5:]]
    assert min(measures) < 1e-5  # it did reach a serial singularity


@pytest.mark.parametrize("name", ["orthoglide", "five-bar", "five-bar-biglide",
                                  "five-bar-isotropic"])  # (the Deltas': beyond their strokes)
def test_bisected_onto_parallel_singularities(name, monkeypatch):
    """Across a change of sign of det A inside the workspace (the assembly mode's border)."""
    m = pkmkit.machine(name)
    x = _random_poses(m, 300, seed=24)
    q = m.ik(x, strokes="ignore")
    sign = np.sign(m.jacobian(x, q=q).det_A)
    plus, minus = x[sign > 0], x[sign < 0]
    poses = []
    for a in plus[:40]:
        for b in minus[:40]:
            segment = a + np.linspace(0, 1, 41)[:, None] * (b - a)
            if not _reachable(m, segment).all():
                continue
            poses += _bisect(m, a, b, lambda y: m.jacobian(y.tolist()).det_A > 0)
            break
        if len(poses) >= 60:
            break
    assert len(poses) >= 10
    x = np.array(poses)
    _check(m, x, monkeypatch, name=name)
    _check(m, x, monkeypatch, tol=1e-2, name=name)
    flags = [int(m.jacobian(p.tolist()).singularity) for p in x[-5:]]
    assert all(f & 2 for f in flags)  # it did reach a parallel singularity


def test_rod_inverse_is_inverse_one_bit_for_bit():
    for name in TRANSLATIONAL:
        m = pkmkit.machine(name)
        closed, branches = m._closed, m._default_branches
        legs = closed.single_legs_packed(branches)
        lo, hi = m.default_box()
        x = lo + (hi - lo) * (1.6 * np.random.default_rng(25).random((300, m.dims)) - 0.3)
        for p in x.tolist():  # reachable and not
            got = _kernels.rod_inverse(legs, p, velocity_one.MAX_ABS)
            want = closed.inverse_one(p, branches)
            assert got == want and (got is None or [type(v) for v in got] == [float] * len(p))
            assert _kernels.rod_inverse(legs, tuple(p), velocity_one.MAX_ABS) == want


def test_the_python_path_without_the_extension(monkeypatch):
    m = pkmkit.machine("orthoglide")
    p = (m.home_pose + 0.01).tolist()
    native = m.jacobian(p)
    assert native.J is not None and isinstance(native._evaluation._state, bytearray)
    assert native._evaluation._ab is None  # the Python pieces were not needed
    for env in ({"PKMKIT_NATIVE": "0"}, {"PKMKIT_COMPILED": "0"}):
        for key, value in env.items():
            monkeypatch.setenv(key, value)
        assert jit.native_kernels_now() is None and jit.native_kernels() is None
        python = m.jacobian(p)
        _same_bits(python.J, native.J, str(env))
        assert python._evaluation._state is False and python._evaluation._ab is not None
        for key in env:
            monkeypatch.delenv(key)
    assert jit.native_kernels_now() is _kernels


def test_refusals():
    m = pkmkit.machine("orthoglide")
    legs = velocity_one.native_legs(m._closed)
    x, q = (m.home_pose + 0.01).tolist(), m.ik(m.home_pose + 0.01).tolist()
    ok = _kernels.rod_velocity(legs, x, q, 1e-6, 1e-2)
    rv, field = _kernels.rod_velocity, _kernels.rod_field
    bad_calls = [
        (TypeError, lambda: rv(legs, x, q, 1e-6)),
        (TypeError, lambda: rv(bytearray(legs), x, q, 1e-6, 1e-2)),
        (ValueError, lambda: rv(legs[:-8], x, q, 1e-6, 1e-2)),
        (ValueError, lambda: rv(b"\0" * 8 * 14 * 4, [*x, 0.0], [*q, 0.0], 1e-6, 1e-2)),
        (ValueError, lambda: rv(np.full(42, 7.0).tobytes(), x, q, 1e-6, 1e-2)),  # kind 7
        (TypeError, lambda: rv(legs, np.array(x), q, 1e-6, 1e-2)),
        (TypeError, lambda: rv(legs, [1, 2, 3], q, 1e-6, 1e-2)),  # ints
        (ValueError, lambda: rv(legs, x[:2], q, 1e-6, 1e-2)),
        (ValueError, lambda: rv(legs, x, q, 0.0, 1e-2)),
        (ValueError, lambda: rv(legs, x, q, float("nan"), 1e-2)),
        (TypeError, lambda: rv(legs, x, q, "1e-6", 1e-2)),
        (TypeError, lambda: field(ok)),
        (TypeError, lambda: field(bytearray(len(ok) - 1), 0)),
        (TypeError, lambda: field(bytes(ok), 0)),
        (ValueError, lambda: field(ok, 14)),
        (ValueError, lambda: field(ok, -1)),
        (ValueError, lambda: _kernels.rod_inverse(legs, x, 1e9)),  # 14 doubles a leg: no
        (TypeError, lambda: _kernels.rod_inverse(list(legs), x)),
    ]
    for error, call in bad_calls:
        with pytest.raises(error):
            call()
    inv = m._closed.single_legs_packed(m._default_branches)
    with pytest.raises(ValueError):
        _kernels.rod_inverse(inv[:-8], x, 1e9)
    # rod_inverse hands whatever is not a list or tuple of finite exact floats to Python
    for pose in ([1, 2, 3], [True, 0.0, 0.0], np.array(x), [np.float64(v) for v in x], x[:2],
                 [float("nan"), 0.0, 0.0], [2e9, 0.0, 0.0], "abc"):
        assert _kernels.rod_inverse(inv, pose, 1e9) is None
    assert m.jacobian([0, 0, 0]).J.shape == (3, 3)  # ints: the Python inverse, same record


def test_a_fresh_process_imports_no_numba():
    code = ("import sys, pkmkit\n"
            "m = pkmkit.machine('linear-delta')\n"
            "j = m.jacobian((m.home_pose + 0.01).tolist())\n"
            "j.J, j.condition, j.singularity\n"
            "print('numba' in sys.modules, type(j._evaluation._state).__name__)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "bytearray"]


def test_synthetic_strut_legs_every_branch():
    """Strut legs placed by hand (a_i = x − c_i, B_ii = ℓ_i + q_i) give any A and B: nearly
    singular A (parallel measures 1 to 1e-9) with B entries from 1 to 1e-9 (serial measures
    below and above the parallel one, so J's singular values come from J⁻¹ or from J), planes
    and space. Each field the C kernel answers is the Python pieces' bits; where those hand
    the pose on (a ZeroDivisionError, an overflow) the C kernel answers nothing."""
    from types import SimpleNamespace

    from pkmkit.model.rods import STRUT

    rng = np.random.default_rng(26)
    answered = {"sv from J": 0, "sv from J_inv": 0}
    for trial in range(3000):
        n = 2 if trial % 3 == 0 else 3
        a = rng.normal(size=(n, n))
        a[0] = a[1] + 10.0 ** -rng.uniform(0, 9) * a[0]  # nearly parallel rows
        a *= 10.0 ** rng.uniform(-3, 1, (n, 1))
        b = rng.choice([-1.0, 1.0], n) * 10.0 ** -rng.uniform(0, 9, n)
        if trial % 50 == 0:
            b[rng.integers(n)] = 0.0
        length = rng.uniform(0.5, 2.0, n)
        centres = -a
        legs = tuple((STRUT, (*[*c, 0.0][:3], float(ell)))
                     for c, ell in zip(centres.tolist(), length, strict=True))
        stub = SimpleNamespace(_one_velocity=legs)
        x, q = [0.0] * n, (b - length).tolist()
        tol = float(10.0 ** -rng.uniform(1, 8))
        table = np.zeros((n, 14))
        for i, (kind, terms) in enumerate(legs):
            table[i, 0], table[i, 1:1 + len(terms)] = kind, terms
        state = _kernels.rod_velocity(table.tobytes(), x, q, tol, velocity_one.NEAR_PARALLEL)
        for code, name in enumerate(velocity_one._NATIVE_CODES):
            got = _kernels.rod_field(state, code)
            try:
                want = velocity_one._BUILD[name](velocity_one.OnePoseVelocity(stub, x, q, tol))
            except velocity_one._HANDED_OVER:
                assert got is None, (trial, name)
                continue
            if got is not None:
                _same_bits(got, want, f"trial {trial} {name}")
                if name == "singular_values" and np.isfinite(got).all():
                    ev = velocity_one.OnePoseVelocity(stub, x, q, tol)
                    near = ev.parallel() < velocity_one.NEAR_PARALLEL and \
                        ev.parallel() < ev.serial()
                    answered["sv from J_inv" if near else "sv from J"] += 1
    assert min(answered.values()) >= 100, answered
