"""The velocity model of one plain pose of a translational machine (issue 22 §1,
:mod:`pkmkit.machines.velocity_one`): the same fields, shapes, types and numbers (bit for bit
at the same actuator values) as the batch path's row — at random poses, near serial and parallel
singularities, with the flags — and the batch path's refusals for anything else."""

from __future__ import annotations

import dataclasses
import importlib.util
import pickle
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, StrokeWarning, UnreachablePoseError
from pkmkit.machines.velocity_one import OnePoseJacobians, OnePoseVelocity

TRANSLATIONAL = [name for name in pkmkit.machines()
                 if pkmkit.machine(name).family == "translational"]
FIELDS = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
          "parallel_measure", "serial_measure", "singularity", "tolerance", "q", "mode",
          "exists", "reachable", "status")


def _machine(name):
    return pkmkit.machine(name)


def _assert_same(fast, batch, where="", exact=False):
    """The same fields; ``exact``: bit for bit (the same q), else to 1e-12 (the Delta robot's
    crank angles from ``m.ik`` differ from the one-pose inverse's by an ulp)."""
    for name in FIELDS:
        got, want = getattr(fast, name), getattr(batch, name)
        if name == "status":
            assert got == want, where
            continue
        if exact:
            assert np.array_equal(got, want, equal_nan=True), (name, where)
        assert type(got) is type(want) or (isinstance(got, np.ndarray)
                                           and isinstance(want, np.ndarray)), (name, where)
        got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
        assert got.shape == want.shape, (name, where)
        if np.array_equal(got, want, equal_nan=True):
            continue  # the same numbers, NaN where NaN: what follows holds (and costs ≈ 0.3 ms)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(want), err_msg=f"{name} {where}")
        finite = np.abs(want[np.isfinite(want)])
        scale = max(1.0, float(finite.max(initial=0.0)))
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * scale,
                                   err_msg=f"{name} {where}")


def _batch_rows(m, x, q=None, tol=1e-6):
    """The batch path's velocity model of every row of ``x`` (n, dims), one model of a single
    pose per row, from **one** batch call (one call of n rows costs about what one of one row
    costs: docs/testing.md, "Sixth round (session 34, suite3a)"). The NumPy batch's rows do not
    depend on their batch (``pkmkit.numerics.rowwise``), so the comparisons stay bit for bit;
    a batch whose rows did would fail them."""
    jac = m.jacobian(x, q=q, tol=tol)
    return [dataclasses.replace(jac, **{f.name: getattr(jac, f.name)[k] if np.ndim(
        getattr(jac, f.name)) else getattr(jac, f.name) for f in dataclasses.fields(jac)})
        for k in range(len(x))]


def _one(m, x, tol):
    """The one-pose model of pose x (whatever its strokes), and its configuration."""
    q = m._closed.inverse_one(list(x), tuple(m.model.leg_branch.tolist()))
    if q is None:
        return None, None
    return OnePoseJacobians(OnePoseVelocity(m._closed, list(map(float, x)), q, tol), True), q


def _poses(m, n, seed):
    lo, hi = m.default_box()
    return lo + (hi - lo) * np.random.default_rng(seed).random((n, m.dims))


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_one_pose_is_the_batch_row(name, monkeypatch):
    """Against the batch row of the NumPy path and of the compiled one (``PKMKIT_COMPILED=1``:
    the velocity kernel, whose hard rows go to the NumPy path), alternately pose by pose (one
    test for both: the one-pose side is the same, 20 poses against each batch path)."""
    paths = ["auto", "1"] if importlib.util.find_spec("numba") else ["auto"]
    m = _machine(name)
    x = _poses(m, 400, seed=3)
    q = m.ik(x, strokes="ignore")
    within = np.flatnonzero(np.isfinite(q).all(axis=1) & ~m.ik(
        x, full_output=True, strokes="flag").out_of_stroke)
    assert within.size >= 5
    within = within[:40]
    want = {}  # the batch rows of each path, one batch call per path and tolerance
    for j, path in enumerate(paths):
        monkeypatch.setenv("PKMKIT_COMPILED", path)
        ks = within[j::len(paths)]
        rows = zip(_batch_rows(m, x[ks]), _batch_rows(m, x[ks], tol=0.3), strict=True)
        want[path] = dict(zip(ks, rows, strict=True))
    for i, k in enumerate(within):
        monkeypatch.setenv("PKMKIT_COMPILED", paths[i % len(paths)])
        row, row_03 = want[paths[i % len(paths)]][k]
        fast = m.jacobian(x[k])
        assert isinstance(fast, OnePoseJacobians)  # the fast path answered
        _assert_same(fast, row, f"{name} pose {k} {paths[i % len(paths)]}")
        for given in (x[k].tolist(), tuple(x[k].tolist())):
            _assert_same(m.jacobian(given, tol=0.3), row_03)


TOLS = (1e-6, 0.05, 0.4)


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_every_reachable_pose_and_the_flags(name):
    """Every reachable pose of the box (out of stroke too), with tolerances that flag some:
    the three tolerances in turn, pose by pose (150 poses, 50 per tolerance)."""
    m = _machine(name)
    x = _poses(m, 150, seed=4)
    flagged = dict.fromkeys(TOLS, 0)
    for j, tol in enumerate(TOLS):
        ones = [(k, *_one(m, x[k], tol)) for k in range(j, len(x), len(TOLS))]
        ones = [(k, fast, q) for k, fast, q in ones if fast is not None]
        ks = [k for k, _, _ in ones]
        rows = _batch_rows(m, x[ks], np.array([q for _, _, q in ones]), tol)
        for (k, fast, _), row in zip(ones, rows, strict=True):
            _assert_same(fast, row, f"{name} pose {k} tol {tol}", exact=True)
            flagged[tol] += int(fast.singularity) != 0
    assert flagged[0.4] > 0


def _bisect(inside, a, b, steps=60):
    """The end of [a, b] (``inside(a)`` true, ``inside(b)`` false) reached by bisection."""
    for _ in range(steps):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if inside(mid) else (a, mid)
    return a


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_near_serial_and_parallel_singularities(name):
    """Poses bisected onto the boundary of reach (a leg perpendicular to its slide: serial) and
    onto a change of sign of det A (parallel), and poses just beside them: the one-pose model
    (or the batch path it hands them to) is the batch row, flags included."""
    m = _machine(name)
    home = m.home_pose
    rng = np.random.default_rng(5)
    closed, branches = m._closed, tuple(m.model.leg_branch.tolist())
    near = []
    for _ in range(30):
        far = home + rng.normal(size=m.dims) * float(m.model.leg_length.max()) * 2

        def reach(t, far=far):
            return closed.inverse_one((home + t * (far - home)).tolist(), branches) is not None

        if not reach(1.0):
            t = _bisect(reach, 0.0, 1.0)
            near.append(home + t * (far - home))
    x = _poses(m, 300, seed=6)
    q = m.ik(x, strokes="ignore")
    det = m.jacobian(x, q=q, tol=1e-9).det_A
    crossings = [k for k in range(len(x) - 1)
                 if np.isfinite(det[k:k + 2]).all() and det[k] * det[k + 1] < 0]
    ks = np.array(crossings[:12], dtype=int)  # 12 parallel crossings beside the serial ones
    a, b, sign = x[ks], x[ks + 1], np.sign(det[ks])

    def same_sign(t):
        """Row j: a_j + t_j (b_j − a_j) reached with det A of a_j's sign (the crossings bisected
        together: one batch Jacobian a step, the batch's rows independent of each other)."""
        p = a + t[:, None] * (b - a)
        qs = [closed.inverse_one(row.tolist(), branches) for row in p]
        reached = np.array([qq is not None for qq in qs], dtype=bool)
        out = np.zeros(len(p), dtype=bool)
        if reached.any():
            qq = np.array([qq for qq in qs if qq is not None], dtype=float)
            out[reached] = np.sign(m.jacobian(p[reached], q=qq).det_A) == sign[reached]
        return out

    lo, hi = np.zeros(len(ks)), np.ones(len(ks))
    for _ in range(60):  # as _bisect, every crossing at once
        mid = 0.5 * (lo + hi)
        ok = same_sign(mid)
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    near += list(a + lo[:, None] * (b - a))
    assert len(near) >= 10
    serial = parallel = 0
    points = [p - shift * (p - home) for p in near for shift in (0.0, 1e-7, 1e-4)]
    ones = [(p, *_one(m, p, 1e-3)) for p in points]
    ones = [(p, fast, qq) for p, fast, qq in ones if fast is not None]
    rows = _batch_rows(m, np.array([p for p, _, _ in ones]),
                       np.array([qq for _, _, qq in ones]), 1e-3)
    for (p, fast, _), row in zip(ones, rows, strict=True):
        _assert_same(fast, row, f"{name} {p}", exact=True)
        serial += bool(fast.singularity & 1)
        parallel += bool(fast.singularity & 2)
    assert serial > 0


def test_refusals_are_those_of_the_batch_path():
    m = pkmkit.machine("linear-delta")
    with pytest.raises(UnreachablePoseError):
        m.jacobian([2.0, 0.0, 0.0])
    for bad in ([np.nan, 0.0, 0.0], [0.0, 0.0], [1e300, 0.0, 0.0], [0.0, np.inf, 0.0],
                ["a", 0.0, 0.0]):
        with pytest.raises(InputError):
            m.jacobian(bad)
    for tol in (-1.0, 0.0, float("nan"), float("inf"), "0.1"):
        with pytest.raises(InputError, match="tol"):
            m.jacobian(m.home_pose, tol=tol)
    with pytest.warns(StrokeWarning):  # beyond the strokes: the batch path, which warns
        jac = m.jacobian([0.0, 0.0, 1.0])
    assert not isinstance(jac, OnePoseJacobians)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isinstance(m.jacobian(m.home_pose), OnePoseJacobians)


def test_replace_and_repr_of_a_one_pose_model():
    """``dataclasses.replace`` (analysis.indices uses it) keeps the other fields."""
    m = pkmkit.machine("orthoglide")
    jac = m.jacobian(m.home_pose + 0.01)
    changed = dataclasses.replace(jac, condition=np.float64(7.0))
    assert changed.condition == 7.0
    np.testing.assert_array_equal(changed.J, jac.J)
    assert "1 pose" in repr(jac)


def test_pickles():
    m = pkmkit.machine("linear-delta")
    jac = m.jacobian(m.home_pose + 0.01)
    _assert_same(pickle.loads(pickle.dumps(jac)), jac)
