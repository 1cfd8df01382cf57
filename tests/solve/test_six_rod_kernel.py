"""The compiled six-rod path tracker against the NumPy reference (same rules, same answers).

Oracles: :meth:`StudyHomotopy.evaluate` for the compiled homotopy, its Jacobian and its
t-derivative; ``numpy.linalg.solve`` for the compiled LU; :func:`track_paths` with the six-rod
stop rule for the tracker (statuses, accepted and rejected steps, end points); and
``six_rod_direct_all(..., compiled=False)`` for the whole solver on general configurations,
Dietmaier's 40-real platform and special geometries whose paths end at infinity, on the
exceptional quadric or at a singular point.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.numerics import jit

pytest.importorskip("numba")

from pkmkit.solve import six_rod_kernel as kernel
from pkmkit.solve import six_rod_paths
from pkmkit.solve.path_tracking import PathStatus, track_paths
from pkmkit.solve.six_rod_direct import six_rod_direct_all
from pkmkit.solve.six_rod_paths import TRACKER_OPTIONS, EndKind, use_compiled_tracker
from pkmkit.solve.six_rod_start import load_start_system
from pkmkit.solve.study_rods import (
    BASIS_INDEX,
    BASIS_SCALE,
    RodParameters,
    StudyHomotopy,
)
from pkmkit.status import Status
from tests.solve.test_six_rod_direct import (
    DIETMAIER_BASE,
    DIETMAIER_LENGTHS,
    DIETMAIER_PLATFORM,
    pose_gap,
    random_configurations,
    rod_lengths,
)


def _homotopy(n_conf: int, seed: int) -> tuple[StudyHomotopy, np.ndarray]:
    rng = np.random.default_rng(seed)
    a = rng.uniform(-1, 1, (n_conf, 6, 3))
    b = rng.uniform(-0.5, 0.5, (n_conf, 6, 3))
    target = RodParameters.from_geometry(a - a.mean(axis=1, keepdims=True),
                                         b - b.mean(axis=1, keepdims=True),
                                         rng.uniform(0.6, 1.0, (n_conf, 6)))
    start = load_start_system()
    return StudyHomotopy.between(start.parameters, target, start.patch), start.solutions


def _options(**changes) -> np.ndarray:
    values = {**TRACKER_OPTIONS, "predictor_tol": 1e-3, "diverged": six_rod_paths.DIVERGED_RATIO,
              "late_t": six_rod_paths.LATE_T, "large": six_rod_paths.LARGE_RATIO,
              "null_stop": six_rod_paths.NULL_STOP, **changes}
    return np.array([values[name] for name in kernel.OPTION_NAMES], dtype=float)


# ----------------------------------------------------------------------------- pieces


def test_homotopy_value_jacobian_and_t_derivative_match_numpy():
    """At random points, t and configurations; in the order new t, the same t at another point
    (coefficients reused), the same t for another configuration (recomputed)."""
    homotopy, _ = _homotopy(3, seed=1)
    rng = np.random.default_rng(2)
    x = rng.normal(size=(12, 8)) + 1j * rng.normal(size=(12, 8))
    t = rng.uniform(0, 1, 12)
    point, at, conf = (np.array(v).ravel() for v in zip(
        *[((p, (p + 1) % 12, p), (t[p],) * 3, (p % 3, p % 3, (p + 1) % 3)) for p in range(12)],
        strict=True))
    res_ref, jac_ref, dt_ref = homotopy.evaluate(x[point], at, conf)
    work = np.full((22, BASIS_INDEX.shape[0]), np.nan, dtype=complex)
    res, jac, d_t = np.empty(8, complex), np.empty((8, 8), complex), np.empty(8, complex)
    coeffs = np.ascontiguousarray(homotopy.coeffs)
    for k in range(point.size):
        kernel.evaluate(x[point[k]], at[k], coeffs, conf[k], homotopy.patch, BASIS_INDEX,
                        BASIS_SCALE, work, res, jac, d_t)
        scale = np.abs(jac_ref[k]).max()
        np.testing.assert_allclose(res, res_ref[k], rtol=0, atol=1e-13 * scale * 10)
        np.testing.assert_allclose(jac, jac_ref[k], rtol=0, atol=1e-13 * scale)
        np.testing.assert_allclose(d_t, dt_ref[k], rtol=0, atol=1e-13 * scale * 10)


def test_lu_with_pivoting_matches_numpy_and_flags_a_singular_matrix():
    rng = np.random.default_rng(5)
    for _ in range(20):
        a = rng.normal(size=(8, 8)) + 1j * rng.normal(size=(8, 8))
        a[0, 0] = a[3, 3] = 0.0  # pivoting is needed
        b = rng.normal(size=(8, 2)) + 1j * rng.normal(size=(8, 2))
        expected = np.linalg.solve(a, b)
        lu, y = a.copy(), b.copy()
        assert kernel.lu_solve(lu, y, 2)
        np.testing.assert_allclose(y, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
    singular = rng.normal(size=(8, 8)) + 0j
    singular[5] = 2.0 * singular[1]
    singular[:, 7] = 0.0
    assert not kernel.lu_solve(singular.copy(), np.ones((8, 2), complex), 2)


def _track_both(homotopy, start, n_conf, x_start=None, **changes):
    opts = _options(**changes)
    x0 = np.tile(start, (n_conf, 1)) if x_start is None else x_start
    cols = np.repeat(np.arange(n_conf), start.shape[0])
    reference = track_paths(
        lambda x, t, rows: homotopy.evaluate(x, t, cols[rows]), x0, stop=six_rod_paths._stop,
        predictor_tol=opts[3], **{**TRACKER_OPTIONS, **{k: v for k, v in changes.items()
                                                        if k in TRACKER_OPTIONS}})
    n = x0.shape[0]
    x, t = np.empty((n, 8), complex), np.empty(n)
    status, steps, rejected = (np.empty(n, dtype=np.int64) for _ in range(3))
    # start solutions per configuration: the kernel takes them as (P0, 8), path p → p % P0
    kernel.track_range(np.ascontiguousarray(x0[: start.shape[0]]), n_conf,
                       np.ascontiguousarray(homotopy.coeffs), homotopy.patch, BASIS_INDEX,
                       BASIS_SCALE, opts, 0, n, x, t, status, steps, rejected)
    return reference, (x, t, status, steps, rejected)


def test_tracker_takes_the_same_steps_as_numpy():
    homotopy, start = _homotopy(2, seed=3)
    ref, (x, t, status, steps, rejected) = _track_both(homotopy, start, 2)
    assert (status == PathStatus.REACHED).all()
    np.testing.assert_array_equal(status, ref.status)
    np.testing.assert_array_equal(steps, ref.steps)
    np.testing.assert_array_equal(rejected, ref.rejected)
    np.testing.assert_array_equal(t, ref.t)
    assert np.abs(x - ref.x).max() <= 1e-10 * max(1.0, np.abs(ref.x).max())


def test_step_budget_and_bad_starts_end_paths_as_numpy():
    homotopy, start = _homotopy(1, seed=3)
    ref, (_, t, status, steps, rejected) = _track_both(homotopy, start, 1, max_steps=3)
    assert (status == PathStatus.FAILED).all() and (t > 0).all()
    np.testing.assert_array_equal(steps + rejected, 3)
    np.testing.assert_array_equal(status, ref.status)
    np.testing.assert_array_equal(steps, ref.steps)
    # step sizes come from the predictor error, equal to round-off: t to round-off
    np.testing.assert_allclose(t, ref.t, rtol=0, atol=1e-10)
    bad = start.copy()
    bad[4, 2] = np.nan
    ref, (_, _, status, steps, _) = _track_both(homotopy, bad, 1, x_start=bad)
    assert status[4] == PathStatus.NOT_FINITE and steps[4] == 0
    np.testing.assert_array_equal(status, ref.status)


# ----------------------------------------------------------------------------- whole solver


def _circle(radius, degrees):
    ang = np.radians(degrees)
    return radius * np.c_[np.cos(ang), np.sin(ang), np.zeros(6)]


def _triangle(radius, phase):
    ang = np.radians([0, 120, 240]) + phase
    return np.c_[radius * np.cos(ang), radius * np.sin(ang), np.zeros(3)]


@pytest.fixture(scope="module")
def both():
    """General configurations, Dietmaier's platform, the docs' circle example (paths at
    infinity), an octahedral 3-3 (exceptional ends) and Fichter's singular configuration, solved
    by both trackers in one batch each."""
    base, platform, lengths, _ = random_configurations(8, seed=11)
    cases = [(base[k], platform[k], lengths[k]) for k in range(8)]
    cases.append((DIETMAIER_BASE, DIETMAIER_PLATFORM, DIETMAIER_LENGTHS))
    a, b = _circle(1.0, [0, 100, 120, 220, 240, 340]), _circle(0.5, [50, 70, 170, 190, 290, 310])
    cases.append((a, b, np.linalg.norm(b + np.array([0.0, 0.0, 1.0]) - a, axis=1)))
    a, b = _triangle(1.0, 0.0)[[0, 0, 1, 1, 2, 2]], _triangle(0.5, np.pi / 3)[[0, 1, 1, 2, 2, 0]]
    cases.append((a, b, rod_lengths(a, b, np.array([0.05, -0.02, 0.8, 0.1, -0.05, 0.2]))))
    deg = [-10, 10, 110, 130, 230, 250]
    a, b = _circle(1.0, deg), _circle(0.5, [-50, 50, 70, 170, 190, 290])
    cases.append((a, b, rod_lengths(a, b, np.array([0.0, 0.0, 0.8, 0.0, 0.0, np.pi / 2]))))
    base, platform, lengths = (np.array(v) for v in zip(*cases, strict=True))
    return (six_rod_direct_all(base, platform, lengths, compiled=True),
            six_rod_direct_all(base, platform, lengths, compiled=False))


def test_same_real_solutions_counts_and_certificates_as_numpy(both):
    compiled, reference = both
    for name in ("status", "count", "n_finite", "n_singular", "n_infinite", "n_exceptional",
                 "n_failed", "path_ends", "multiplicity"):
        np.testing.assert_array_equal(getattr(compiled, name), getattr(reference, name), name)
    np.testing.assert_array_equal(compiled.complete, reference.complete)
    # the cases cover every class but FAILED, and Dietmaier's 40 real solutions
    assert {int(k) for k in np.unique(compiled.path_ends)} == {
        EndKind.REGULAR, EndKind.SINGULAR, EndKind.INFINITE, EndKind.EXCEPTIONAL}
    assert compiled.count[8] == 40 and compiled.complete[:11].all()
    assert compiled.status[11] == Status.SINGULAR
    for k in range(compiled.count.shape[0]):
        n = compiled.count[k]
        ours, theirs = compiled.poses[k, :n], reference.poses[k, :n]
        gap = np.array([[pose_gap(u, v)[0] for v in theirs] for u in ours])
        # the same set (equal z may sort either way): each pose has its twin, one to one;
        # a multiple solution (singular configuration) is known to about √ε only, by either
        tol = 1e-10 if compiled.status[k] == Status.OK else 1e-6
        assert gap.min(axis=1).max() <= tol, (k, gap.min(axis=1).max())
        assert len(set(np.argmin(gap, axis=1))) == n
        assert np.isnan(compiled.poses[k, n:]).all()
        assert compiled.residual[k, :n].max() <= 1e-9


def test_same_number_of_steps_as_numpy(both):
    """The same step control: every general configuration (and the docs' example, whose
    diverging paths are stopped) takes exactly the same accepted steps; on the degenerate
    geometries, whose paths end ill-conditioned (exceptional quadric, multiple solution),
    round-off decides a few late steps (measured: 1674 against 1710 on the 3-3 platform)."""
    compiled, reference = both
    np.testing.assert_array_equal(compiled.path_steps[:10], reference.path_steps[:10])
    np.testing.assert_allclose(compiled.path_steps[10:], reference.path_steps[10:], rtol=0.05)


# ----------------------------------------------------------------------------- dispatch


def test_compiled_by_default_numpy_when_asked(monkeypatch):
    monkeypatch.delenv("PKMKIT_COMPILED", raising=False)
    assert use_compiled_tracker(1) and use_compiled_tracker(5)  # Numba imported here
    monkeypatch.setattr(jit, "_available", False)
    assert not use_compiled_tracker(5)  # no Numba
    with pytest.raises(InputError, match="compiled=True needs Numba"):
        six_rod_direct_all(np.eye(6, 3), np.eye(6, 3), np.ones(6), compiled=True)
    monkeypatch.setattr(jit, "_available", True)
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    assert not use_compiled_tracker(5)

    def refuse(*args):
        raise AssertionError("the compiled tracker ran under PKMKIT_COMPILED=0")

    monkeypatch.setattr(six_rod_paths, "_track_compiled", refuse)
    base, platform, lengths, poses = random_configurations(1, seed=9)
    sols = six_rod_direct_all(base[0], platform[0], lengths[0])
    assert sols.complete and pose_gap(sols.poses[: sols.count],
                                      np.broadcast_to(poses[0], (sols.count, 6))).min() < 1e-9
    with pytest.raises(AssertionError, match="compiled tracker ran"):
        six_rod_direct_all(base[0], platform[0], lengths[0], compiled=True)



@pytest.mark.ci  # a fresh process (1-4 s of CPU): .ci/run's second stage
def test_a_one_shot_single_call_does_not_import_numba():
    """In a fresh process the first lone configuration takes the NumPy tracker (no Numba
    import: the command line makes one call), the second the compiled one; a batch of two
    configurations runs compiled at once; the same solutions."""
    code = ("import sys, numpy as np\n"
            "from pkmkit.solve.six_rod_direct import six_rod_direct_all\n"
            "from tests.solve.test_six_rod_direct import random_configurations\n"
            "a, b, ell, _ = random_configurations(2, seed=9)\n"
            "one = six_rod_direct_all(a[0], b[0], ell[0])\n"
            "first = 'numba' in sys.modules\n"
            "two = six_rod_direct_all(a[0], b[0], ell[0])\n"
            "print(first, 'numba' in sys.modules, int(one.count), int(two.count),\n"
            "      float(np.abs(one.poses - two.poses)[:one.count].max()))\n")
    root = Path(__file__).resolve().parents[2]
    env = {"PYTHONPATH": f"{Path(pkmkit.__file__).resolve().parents[1]}:{root}",
           "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         check=True, cwd=root).stdout.split()
    assert out[:2] == ["False", "True"]
    assert out[2] == out[3] and float(out[4]) <= 1e-10
    batch = "import sys\n" + code.split("one = ")[0] + (
        "six_rod_direct_all(a, b, ell)\nprint('numba' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", batch], capture_output=True, text=True, env=env,
                         check=True, cwd=root).stdout.split()
    assert out == ["True"]
