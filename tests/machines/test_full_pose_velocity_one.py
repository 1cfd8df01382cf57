"""The compiled velocity model of one full pose (issue 22 §1,
:mod:`pkmkit.machines.full_pose_velocity_one`): the batch path's fields, shapes, types and
numbers (to 1e-12 of each field's scale; J, J_h and J⁻¹ near a parallel singularity to
1e-12 × the condition number of A, since NumPy's and Numba's LAPACK solves may round
differently; the mode, the sign of det A, wherever det A is above rounding), flags included,
and the batch path's refusals for anything else."""

from __future__ import annotations

import dataclasses
import pickle
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError, StrokeWarning, UnreachablePoseError
from pkmkit.machines import full_pose
from pkmkit.machines import full_pose_velocity_kernel as kernel
from pkmkit.machines.full_pose import FullPoseJacobians
from pkmkit.machines.full_pose_velocity_one import FIELDS, OnePoseFullVelocity

pytest.importorskip("numba")

FULL_POSE = [name for name in pkmkit.machines()
             if pkmkit.machine(name).family == "full-pose"]


def _row(jac, k=0):
    return {name: getattr(jac, name)[k] if np.ndim(getattr(jac, name)) and name not in (
        "tolerance", "characteristic_length") else getattr(jac, name) for name in FIELDS}


def _assert_same(fast, want, where="", kappa=1.0):
    for name in FIELDS:
        got, ref = getattr(fast, name), want[name]
        if name == "mode" and abs(want["det_A"]) <= 1e-12 * np.abs(want["A"]).max() ** 6:
            continue  # the sign of a determinant at rounding level (an exact singularity)
        assert type(got) is type(ref) or (isinstance(got, np.ndarray)
                                          and isinstance(ref, np.ndarray)), (name, where)
        got, ref = np.asarray(got, dtype=float), np.asarray(ref, dtype=float)
        assert got.shape == ref.shape, (name, where)
        if np.array_equal(got, ref, equal_nan=True):
            continue  # the same numbers, NaN where NaN: what follows holds (and costs ≈ 0.3 ms)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(ref), err_msg=f"{name} {where}")
        scale = max(1.0, float(np.abs(ref[np.isfinite(ref)]).max(initial=0.0)))
        if name in ("J", "J_homogeneous", "J_inv"):
            scale *= max(1.0, kappa)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-12 * scale,
                                   err_msg=f"{name} {where}")


def _poses(m, n, seed, spread=0.05):
    rng = np.random.default_rng(seed)
    if m.position_controlled:
        positions = m.home_pose[:3] + rng.uniform(-2 * spread, 2 * spread, (n, 3))
        return m.ik(positions, full_output=True, strokes="ignore").pose
    x = np.tile(m.home_pose, (n, 1))
    x += rng.uniform(-spread, spread, x.shape)
    return x


def _one(m, x, tol):
    """The compiled one-pose model of pose x (whatever its strokes), or None."""
    q = m.one_pose_inverse()(x)
    if q is None:
        return None
    xb, qb = np.array([x], dtype=float), np.array([q])
    evaluation = OnePoseFullVelocity(m.direct_kernel().geom, m.n_actuators,
                                     float(m.characteristic_length), xb[0], qb[0], tol,
                                     lambda: pytest.fail("the kernel refused the row"))
    return type(m.jacobian(m.home_pose))(evaluation)


@pytest.mark.parametrize("name", FULL_POSE)
def test_one_pose_is_the_batch_row(name):
    m = pkmkit.machine(name)
    m.jacobian(m.home_pose)  # a first single call may take the batch path (Numba's import)
    x = _poses(m, 60, seed=1)
    within = np.isfinite(x).all(axis=1)
    q = m.ik(x[within], full_output=True)
    beyond = np.zeros(len(q.q), dtype=bool) if q.out_of_stroke is None else q.out_of_stroke
    x = x[within][np.isfinite(q.q).all(axis=1) & ~beyond]
    assert len(x) >= 20
    # the batch rows from one batch call each (docs/testing.md, "Sixth round (session 34,
    # suite3a)": a batch's rows are those of batches of one, to the tolerance compared here)
    batch, batch_02 = m.jacobian(x), m.jacobian(x, tol=0.2)
    for k, pose in enumerate(x):
        fast = m.jacobian(pose)
        assert type(fast).__name__.startswith("OnePose")  # the compiled path answered
        _assert_same(fast, _row(batch, k), f"{name} pose {k}")
        _assert_same(m.jacobian(pose.tolist(), tol=0.2), _row(batch_02, k))


@pytest.mark.parametrize("name", FULL_POSE)
@pytest.mark.parametrize("tol", [1e-6, 0.02, 0.3])
def test_far_poses_near_singularities_and_the_flags(name, tol):
    """Poses far from home (out of stroke too) up to the edge of reach, where measures fall
    towards the singularities, with tolerances that flag some of them."""
    m = pkmkit.machine(name)
    flagged = compared = 0
    for spread in (0.05, 0.2, 0.5):
        poses = _poses(m, 40, seed=2, spread=spread)
        ones = [(k, pose, _one(m, pose.tolist(), tol)) for k, pose in enumerate(poses)
                if np.isfinite(pose).all()]
        ones = [(k, pose, fast) for k, pose, fast in ones if fast is not None]
        batch = m.jacobian(np.array([pose for _, pose, _ in ones]),  # one call: the rows
                           q=np.array([np.asarray(fast.q) for _, _, fast in ones]), tol=tol)
        for j, (k, _, fast) in enumerate(ones):
            unit = np.asarray(fast.A) / np.linalg.norm(np.asarray(fast.A)[:, :3], axis=1)[:,
                                                                                          None]
            _assert_same(fast, _row(batch, j), f"{name} pose {k} spread {spread}",
                         kappa=float(np.linalg.cond(unit)))
            flagged += int(fast.singularity) != 0
            compared += 1
    assert compared >= 40
    if tol == 0.3:
        assert flagged > 0


def test_refusals_are_those_of_the_batch_path():
    verne = pkmkit.machine("verne")
    verne.jacobian(verne.home_pose)
    with pytest.raises(UnreachablePoseError):  # rods of fixed length: out of reach
        verne.jacobian(verne.home_pose + np.array([2.0, 0, 0, 0, 0, 0]))
    m = pkmkit.machine("gough-stewart")
    m.jacobian(m.home_pose)
    for bad in ([np.nan, 0, 0, 0, 0, 0], [0.0] * 5, [1e300, 0, 0, 0, 0, 0]):
        with pytest.raises(InputError):
            m.jacobian(bad)
    for tol in (-1.0, float("nan"), "0.1"):
        with pytest.raises(InputError, match="tol"):
            m.jacobian(m.home_pose, tol=tol)
    x = m.home_pose + np.array([0, 0, 0.4, 0, 0, 0])  # reachable, beyond the struts' strokes
    with pytest.warns(StrokeWarning):
        jac = m.jacobian(x)
    assert not type(jac).__name__.startswith("OnePose")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert type(m.jacobian(m.home_pose)).__name__.startswith("OnePose")


def test_a_row_the_kernel_refuses_goes_to_the_batch_path(monkeypatch):
    monkeypatch.setenv("PKMKIT_NATIVE", "0")  # the Numba kernel (its C twin: tests/native)
    m = pkmkit.machine("dietmaier-hexapod")
    m.jacobian(m.home_pose)
    x = m.home_pose + 0.01
    monkeypatch.setattr(kernel, "velocity_one", lambda *args: 1)
    fast = m.jacobian(x)
    assert type(fast).__name__.startswith("OnePose")
    _assert_same(fast, _row(m.jacobian(x[None])))


def test_without_compiled_kernels_the_batch_path_answers(monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    m = pkmkit.machine("verne")
    for _ in range(2):
        assert not type(m.jacobian(m.home_pose)).__name__.startswith("OnePose")


def test_replace_and_repr():
    m = pkmkit.machine("gough-stewart")
    m.jacobian(m.home_pose)
    jac = m.jacobian(m.home_pose + 0.01)
    changed = dataclasses.replace(jac, condition=np.float64(3.0))
    assert changed.condition == 3.0
    np.testing.assert_array_equal(changed.J, jac.J)
    assert "1 pose" in repr(jac)


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod"])
def test_at_and_beside_parallel_singularities(name):
    """Rotations of the platform swept from home about each axis; where det A changes sign,
    bisection onto the parallel singularity, and poses 1e-9 … 1e-3 rad beside it."""
    m = pkmkit.machine(name)
    m.jacobian(m.home_pose)
    starts, ends, signs = [], [], []
    for axis in range(3, 6):
        x = np.tile(m.home_pose, (61, 1))
        x[:, axis] += np.linspace(0.0, 3.0, 61)
        det = m.jacobian(x, q=m.ik(x, strokes="ignore")).det_A
        for k in np.flatnonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0)[:2]:
            starts.append(x[k])
            ends.append(x[k + 1])
            signs.append(np.sign(det[k]))
    # every crossing bisected at once: one batch ik and Jacobian a step (the rows of a batch
    # are independent, so each row takes the steps it took alone)
    lo, hi, signs = np.array(starts), np.array(ends), np.array(signs)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        q = m.ik(mid, strokes="ignore")
        inside = (np.sign(m.jacobian(mid, q=q).det_A) == signs)[:, None]
        lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
    near = [lo[j] + shift * (hi[j] - starts[j]) / np.linalg.norm(hi[j] - starts[j])
            for j in range(len(lo)) for shift in (0.0, -1e-9, -1e-6, -1e-3)]
    assert len(near) >= 8
    parallel = 0
    for tol in (1e-6, 1e-3):
        ones = [_one(m, pose.tolist(), tol) for pose in near]
        batch = m.jacobian(np.array(near), q=np.array([np.asarray(f.q) for f in ones]),
                           tol=tol)
        for j, (pose, fast) in enumerate(zip(near, ones, strict=True)):
            unit = np.asarray(fast.A) / np.linalg.norm(np.asarray(fast.A)[:, :3], axis=1)[
                :, None]
            _assert_same(fast, _row(batch, j), f"{name} {pose}",
                         kappa=float(np.linalg.cond(unit)))
            parallel += bool(fast.singularity & 2)
    assert parallel > 0


def test_pickles_as_the_plain_record():
    """A single-pose model crosses process boundaries (Dask, multiprocessing) as the plain
    record with every field (its evaluation holds a closure over the machine)."""
    m = pkmkit.machine("verne")
    m.jacobian(m.home_pose)
    jac = m.jacobian(m.home_pose)
    back = pickle.loads(pickle.dumps(jac))
    assert type(back) is FullPoseJacobians
    _assert_same(back, {name: getattr(jac, name) for name in FIELDS})


def _bits(got, want, where):
    assert type(got) is type(want), where
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape and np.array_equal(got, want, equal_nan=True), where


@pytest.mark.parametrize("name", FULL_POSE)
def test_a_field_read_alone_runs_only_the_matrices_kernel_with_the_same_bits(name, monkeypatch):
    """J, A, B, J⁻¹, the determinants and the flags of a fresh record come from
    ``velocity_matrices`` (no singular values computed), bit for bit what the full kernel
    gives; the singular values, condition and parallel measure run the full kernel (the
    OnePoseFullVelocity path; with the C extension m.jacobian takes PoseOne:
    tests/native/test_pose_one.py)."""
    monkeypatch.setattr(full_pose, "native_one", lambda machine: None)
    m = pkmkit.machine(name)
    for k, p in enumerate(_poses(m, 12, seed=21)):
        full = m.jacobian(p)
        assert np.isfinite(full.condition)  # the full kernel
        assert full._evaluation._full
        for field in FIELDS:
            jac = m.jacobian(p)
            got = getattr(jac, field)
            _bits(got, getattr(full, field), f"{name} pose {k} {field}")
            ev = jac._evaluation
            assert (ev._out is None) or bool(ev._full) == (field in (
                "singular_values", "translation_singular_values", "rotation_singular_values",
                "condition", "parallel_measure")), field


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod"])
def test_flags_with_the_tolerance_at_the_parallel_measure(name, monkeypatch):
    """A tolerance 1e-6 (relative) below a pose's parallel measure does not flag it, 1e-6
    above does: the matrices kernel decides by the measure itself where its bound cannot
    (both one-pose paths: OnePoseFullVelocity's, then PoseOne's). A tolerance equal to the
    measure, or the next float up, is within the band handed to the batch path (its measure
    rounds otherwise by an ulp or a few): the flags and J are the batch's."""
    for native_one in (lambda machine: None, full_pose.native_one):
        monkeypatch.setattr(full_pose, "native_one", native_one)
        _flags_at_the_measure(name)


def _flags_at_the_measure(name):
    m = pkmkit.machine(name)
    for p in _poses(m, 8, seed=22):
        measure = float(m.jacobian(p).parallel_measure)
        for tol in (measure, float(np.nextafter(measure, np.inf))):
            jac = m.jacobian(p, tol=tol)
            batch = m.jacobian(np.asarray(p, dtype=float)[None], tol=tol)
            assert int(jac.singularity) == int(batch.singularity[0])
            assert np.array_equal(np.isnan(jac.J), np.isnan(batch.J[0]))
        for tol in (measure * (1 - 1e-6), measure * (1 + 1e-6)):
            jac = m.jacobian(p, tol=tol)
            assert bool(jac.singularity & 2) == (tol > measure)
            ev = jac._evaluation  # the exact-measure level not run (the flags decided it)
            assert not (ev._full if hasattr(ev, "_full") else ev.level & 4)
            assert np.isnan(jac.J).all() == (tol > measure)


def test_the_six_by_six_parallel_bound_holds():
    """σ_min/σ_max ≥ |det U| / (‖U‖²_F / 3)³ (the bound ``velocity_matrices`` uses)."""
    rng = np.random.default_rng(23)
    u = rng.normal(size=(20000, 6, 6)) * rng.uniform(1e-2, 1, (20000, 6, 1)) ** 3
    u[1::2, 0] = u[1::2, 1] + 1e-5 * u[1::2, 0]  # nearly singular ones too
    sv = np.linalg.svd(u, compute_uv=False)
    bound = np.abs(np.linalg.det(u)) / ((u * u).sum(axis=(1, 2)) / 3) ** 3
    assert (sv[:, -1] / sv[:, 0] >= bound * (1 - 1e-9) - 1e-15).all()
