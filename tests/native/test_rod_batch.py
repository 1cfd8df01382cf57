"""The batched closed-form inverse of rod-leg machines in C (``pkmkit.native.kernels``
``rod_inverse_rows``, ``rod_reach_det``, ``native/rod_batch.c``; issue 22 §5) against the NumPy
reference (:meth:`RodClosedForm._inverse_numpy`, the independent oracle) and the Numba twins
(:func:`pkmkit.machines.kernels.inverse`, ``reach_and_det``) **bit for bit**: q, the count of
non-finite outputs, the shortfalls and det A, on both branches, at poses in and far beyond the
workspace and on invalid rows; ``m.ik(X, full_output=True)`` of a fresh process takes it
without importing Numba; the arguments refused with typed errors."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit
from tests.conftest import PRESETS, random_poses

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler (tests/native/test_kernels.py checks CI)
    _kernels = None

pytestmark = pytest.mark.skipif(_kernels is None or not hasattr(_kernels, "rod_inverse_rows"),
                                reason="pkmkit.native.kernels was not built")

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def _machines() -> dict[str, pkmkit.Machine]:
    out = {name: pkmkit.machine(name) for name in {*PRESETS, "linear-delta", "five-bar"}}
    out["strut-tripod"] = pkmkit.load(EXAMPLES / "strut-tripod.toml")
    # the kernels take slides and struts (machines with cranks keep the NumPy path)
    return {k: m for k, m in out.items() if hasattr(m, "_closed") and not m._closed.crank.any()}


MACHINES = _machines()


def _poses(m: pkmkit.Machine, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = random_poses(m, n, seed)
    spread = 2.0 * float(m.model.leg_length.max())
    x[: n // 3] = m.home_pose + rng.uniform(-spread, spread, (n // 3, m.dims))
    x[5] = np.nan
    x[6, 0] = np.inf
    x[7, -1] = -np.inf
    x[8] = 1e200
    x[9] = 1e-300
    x[10] = m.home_pose
    return x


def _run(inverse, reach, m: pkmkit.Machine, x: np.ndarray, branches: np.ndarray):
    closed, n = m._closed, m._closed.model.n_legs
    c = np.ascontiguousarray
    slide = c(closed.slide > 0)
    out = np.full((n, len(x)), 7.0)
    bad = inverse(c(x), c(closed.basis), c(closed.basis_offset), c(closed.model.leg_length),
                  slide, c(branches, dtype=float), 1e-9, out)
    if not closed.fuses:
        return out, int(bad), None, None
    short, det = np.full((n, len(x)), 7.0), np.full(len(x), 7.0)
    reach(c(x), out, c(closed.basis), c(closed.basis_offset), c(closed.centre0),
          c(closed.axis), c(closed.model.leg_length), slide, short, det)
    return out, int(bad), short, det


@pytest.mark.parametrize("name", sorted(MACHINES))
def test_bits_of_the_numpy_reference_and_of_numba(name):
    m = MACHINES[name]
    closed = m._closed
    x = _poses(m, 3000, seed=len(name))
    legs = closed.model.n_legs
    for branches in (m.model.leg_branch, -m.model.leg_branch):
        got = _run(_kernels.rod_inverse_rows, _kernels.rod_reach_det, m, x, branches)
        full = closed.fuses
        short = np.empty((legs, len(x))) if full else None
        det = np.empty(len(x)) if full else None
        with np.errstate(all="ignore"):
            q_ref = closed._inverse_numpy(x, np.asarray(branches, dtype=float), short, det)
        np.testing.assert_array_equal(got[0], q_ref.T)
        assert got[1] == np.count_nonzero(~np.isfinite(q_ref)) > 0
        if full:
            np.testing.assert_array_equal(got[2], short)
            ok = np.isfinite(q_ref).all(axis=1)
            assert ok.sum() > 100
            np.testing.assert_array_equal(got[3][ok], det[ok])
        numba = pytest.importorskip("numba")
        del numba
        from pkmkit.machines import kernels

        twin = _run(kernels.inverse, kernels.reach_and_det, m, x, branches)
        np.testing.assert_array_equal(got[0], twin[0])
        assert got[1] == twin[1]
        if full:
            np.testing.assert_array_equal(got[2], twin[2])
            np.testing.assert_array_equal(got[3], twin[3])


def test_jit_takes_the_twins_and_ik_gives_the_reference(monkeypatch):
    assert jit.kernel("pkmkit.machines.kernels", "inverse") is _kernels.rod_inverse_rows
    assert jit.kernel("pkmkit.machines.kernels", "reach_and_det") is _kernels.rod_reach_det
    m = MACHINES["linear-delta"]
    x = _poses(m, 3 * jit.MIN_ROWS, seed=4)
    monkeypatch.setenv("PKMKIT_COMPILED", "auto")
    got = m.ik(x, full_output=True, strokes="flag")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    want = m.ik(x, full_output=True, strokes="flag")
    for field in ("q", "status", "shortfall", "mode"):
        np.testing.assert_array_equal(getattr(got, field), getattr(want, field), err_msg=field)


FRESH = r"""
import sys
import numpy as np
import pkmkit
m = pkmkit.machine("linear-delta")
x = m.home_pose + np.random.default_rng(0).uniform(-0.1, 0.1, (20000, 3))
res = m.ik(x, full_output=True)
print("numba" in sys.modules, int((res.status == 0).sum()))
"""


def test_a_fresh_process_solves_a_batch_without_numba():
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(Path(__file__).parents[2] / "src"),
                                                        os.environ.get("PYTHONPATH", "")])}
    env.pop("PKMKIT_COMPILED", None)
    env.pop("PKMKIT_NATIVE", None)
    done = subprocess.run([sys.executable, "-c", FRESH], capture_output=True, text=True,
                          env=env, timeout=300)
    imported, ok = done.stdout.split()
    assert imported == "False", done.stderr
    assert int(ok) > 10000


def test_arguments_refused():
    m = MACHINES["linear-delta"]
    closed = m._closed
    c = np.ascontiguousarray
    x = c(np.zeros((4, 3)))
    args = [x, c(closed.basis), c(closed.basis_offset), c(closed.model.leg_length),
            c(closed.slide > 0), np.ones(3), 1e-9, np.empty((3, 4))]
    assert _kernels.rod_inverse_rows(*args) == 0
    with pytest.raises(TypeError, match="8 positional"):
        _kernels.rod_inverse_rows(*args[:7])
    for k, bad, error, text in [
            (0, np.zeros((4, 3), dtype=np.float32), TypeError, "x: float64"),
            (0, np.zeros((4, 4)), ValueError, "2 or 3 columns"),
            (7, np.empty((3, 5)), ValueError, "out: wrong shape"),
            (7, np.empty((3, 8))[:, ::2], ValueError, "out: wrong shape or layout"),
            (4, np.ones(3), TypeError, "slide: bool"),
            (6, "tol", TypeError, "must be real number")]:
        broken = list(args)
        broken[k] = bad
        with pytest.raises(error, match=text):
            _kernels.rod_inverse_rows(*broken)
    rows = np.empty((4, 3))  # out= of ik (pkmkit.machines.out_arrays): q written row-major
    x_some = c(np.linspace(-0.1, 0.1, 12).reshape(4, 3) + m.home_pose)
    _kernels.rod_inverse_rows(x_some, *args[1:7], rows.T)
    _kernels.rod_inverse_rows(x_some, *args[1:7], args[7])
    assert rows.T.tobytes() == args[7].tobytes() and np.isfinite(rows).all()
    out = np.empty((3, 4))
    out.flags.writeable = False
    with pytest.raises(TypeError, match="out: a C-contiguous writable"):
        _kernels.rod_inverse_rows(*args[:7], out)
    reach = [x, np.zeros((3, 4)), c(closed.basis), c(closed.basis_offset), c(closed.centre0),
             c(closed.axis), c(closed.model.leg_length), c(closed.slide > 0),
             np.empty((3, 4)), np.empty(4)]
    assert _kernels.rod_reach_det(*reach) is None
    with pytest.raises(ValueError, match="det_out: wrong shape"):
        _kernels.rod_reach_det(*reach[:9], np.empty(5))
    five = MACHINES["five-bar"]._closed
    if five.model.n_legs != five.model.dims:  # not square: refused
        with pytest.raises(ValueError, match="square"):
            _kernels.rod_reach_det(*reach)
