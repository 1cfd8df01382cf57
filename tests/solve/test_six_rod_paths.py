"""End-point classes and completeness checks of the six-rod homotopy paths."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.solve import six_rod_paths
from pkmkit.solve.path_tracking import PathStatus
from pkmkit.solve.six_rod_paths import (
    EndKind,
    classify,
    closed_under_conjugation,
    distinct_regular,
    projective_normal,
    track_configurations,
)
from pkmkit.solve.six_rod_start import load_start_system
from pkmkit.solve.study_rods import RodParameters, pose_to_study, rod_quadrics


@pytest.fixture(scope="module")
def tracked():
    rng = np.random.default_rng(4)
    n = 3
    a = rng.uniform(-1, 1, (n, 6, 3))
    b = rng.uniform(-0.5, 0.5, (n, 6, 3))
    a -= a.mean(axis=1, keepdims=True)
    b -= b.mean(axis=1, keepdims=True)
    ell = rng.uniform(0.6, 1.0, (n, 6))
    target = RodParameters.from_geometry(a, b, ell)
    return target, track_configurations(load_start_system(), target)


def test_general_configurations_end_at_40_distinct_regular_points(tracked):
    target, ends = tracked
    assert (ends.kind == EndKind.REGULAR).all()
    assert ends.certified.all()
    assert (ends.steps > 40).all()
    # every end point solves the target rod equations (in any projective scale)
    for c in range(ends.x.shape[0]):
        x = ends.normal[c]
        f = rod_quadrics(x.T, target.take(np.full(40, c)))
        assert np.abs(f).max() < 1e-9 * np.abs(x).max() ** 2
        assert np.abs((x[:, :4] * x[:, 4:]).sum(axis=1)).max() < 1e-10


def test_checks_detect_a_lost_path(tracked):
    _, ends = tracked
    normal, kind = ends.normal.copy(), ends.kind.copy()
    assert distinct_regular(normal, kind).all() and closed_under_conjugation(normal, kind).all()
    # path jumping: two paths end at the same point
    jumped = normal.copy()
    jumped[0, 1] = jumped[0, 0]
    assert list(distinct_regular(jumped, kind)) == [False, True, True]
    # a lost complex solution: its conjugate is left without a partner
    complex_end = int(np.argmax(np.abs(normal[1].imag).max(axis=1)))
    lost = normal.copy()
    lost[1, complex_end] = np.nan
    kind_lost = kind.copy()
    kind_lost[1, complex_end] = EndKind.INFINITE
    assert list(closed_under_conjugation(lost, kind_lost)) == [True, False, True]


def test_classification_of_end_points():
    rot = Rotation.from_rotvec([0.2, -0.1, 0.4])
    quat = rot.as_quat()[[3, 0, 1, 2]]
    real = pose_to_study(np.array([[0.3, 0.1, 0.8]]), quat[None])[0]
    far = real.copy()
    far[:4] *= 1e-6  # e → 0: translation ~10⁶
    null = np.r_[1.0, 1j, 0.0, 0.0, 0.0, 0.0, 0.3, 0.2]  # e·e = 0
    x = np.array([real, real, far, null, null, real, real], dtype=complex)
    t = np.array([0.0, 0.0, 1e-7, 1e-5, 0.0, 1e-8, 0.3])
    reached, failed = PathStatus.REACHED, PathStatus.FAILED
    status = np.array([reached, reached, failed, failed, reached, failed, failed])
    cond = np.array([10.0, 1e12, np.inf, np.inf, 10.0, np.inf, np.inf])
    kinds = classify(x, t, status, cond)
    assert list(kinds) == [EndKind.REGULAR, EndKind.SINGULAR, EndKind.INFINITE,
                           EndKind.EXCEPTIONAL, EndKind.EXCEPTIONAL, EndKind.SINGULAR,
                           EndKind.FAILED]


def test_projective_normal_is_scale_free():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(5, 8)) + 1j * rng.normal(size=(5, 8))
    scale = rng.normal(size=(5, 1)) + 1j * rng.normal(size=(5, 1))
    np.testing.assert_allclose(projective_normal(x), projective_normal(scale * x), atol=1e-12)


@pytest.mark.ci
def test_uncertified_configurations_are_tracked_again(tracked, monkeypatch):
    target, reference = tracked
    calls = []
    original = six_rod_paths._track

    def first_call_jumps(start, tgt, tol, compiled):
        ends = original(start, tgt, tol, compiled)
        calls.append((tgt.offset.shape[1], tol))
        if len(calls) == 1:  # simulate a path that jumped onto another one in configuration 2
            ends.normal[2, 5] = ends.normal[2, 4]
            ends.certified[2] = False
        return ends

    monkeypatch.setattr(six_rod_paths, "_track", first_call_jumps)
    ends = track_configurations(load_start_system(), target, predictor_tol=1e-4, retries=1)
    assert calls == [(3, 1e-4), (1, pytest.approx(1e-6))]
    assert ends.certified.all()
    np.testing.assert_allclose(ends.normal[2], reference.normal[2], atol=1e-9)
