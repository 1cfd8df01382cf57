"""Each field of the one-pose velocity model (:mod:`pkmkit.machines.velocity_one`), read alone
on a fresh record, is **bit for bit** the batch path's row — of a batch of many poses and of a
batch of one (issue 22 §1) — at random poses, near the Orthoglide's isotropic home and the
linear Delta's axis (nearly equal singular values: LAPACK in both paths), and with tolerances
placed exactly at a pose's parallel measure; and a field computes only the pieces it needs."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import velocity_one
from pkmkit.machines.velocity_one import OnePoseJacobians, OnePoseVelocity

TRANSLATIONAL = [name for name in pkmkit.machines()
                 if pkmkit.machine(name).family == "translational"]
FIELDS = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
          "parallel_measure", "serial_measure", "singularity", "tolerance", "q", "mode")


def _one(m, x, tol=1e-6):
    q = m._closed.inverse_one(list(x), m._default_branches)
    if q is None:
        return None
    return OnePoseJacobians(OnePoseVelocity(m._closed, [float(v) for v in x], q, tol), True)


def _same_bits(got, want, where):
    assert type(got) is type(want), where
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape and got.dtype == want.dtype, where
    assert np.array_equal(got, want, equal_nan=True), (where, got, want)


def _poses(m, n, seed, spread=1.0):
    """n reachable poses of the default box (``spread``: the fraction of it, about its centre)."""
    lo, hi = m.default_box()
    centre, half = (lo + hi) / 2, (hi - lo) / 2
    x = centre + spread * half * (2 * np.random.default_rng(seed).random((n, m.dims)) - 1)
    return x[np.isfinite(m.ik(x, strokes="ignore")).all(axis=1)]


def _check(m, x, tol=1e-6, name=""):
    """Every field of a fresh one-pose record against the batch rows (many and one)."""
    q = np.array([_one(m, p).q for p in x])
    batch = m.jacobian(x, q=q, tol=tol)
    for k, p in enumerate(x):
        alone = m.jacobian(x[k:k + 1], q=q[k:k + 1], tol=tol)
        for field in FIELDS:
            got = getattr(_one(m, p, tol), field)  # a fresh record: this field alone
            want = getattr(batch, field)
            want = want[k] if np.ndim(want) else want
            _same_bits(got, want, f"{name} pose {k} {field}")
            one_row = getattr(alone, field)
            _same_bits(got, one_row[0] if np.ndim(one_row) else one_row,
                       f"{name} pose {k} {field} (batch of one)")


@pytest.mark.parametrize("name", TRANSLATIONAL)
def test_each_field_is_the_batch_row_bit_for_bit(name):
    m = pkmkit.machine(name)
    x = _poses(m, 60, seed=11)
    assert len(x) >= 20
    _check(m, x, name=name)
    _check(m, x[:15], tol=0.3, name=name)  # some flagged


@pytest.mark.parametrize(("name", "spread"), [("orthoglide", 1e-4), ("linear-delta", 0.02)])
def test_nearly_equal_singular_values_go_to_lapack_in_both_paths(name, spread, monkeypatch):
    """Near the Orthoglide's isotropic home and the linear Delta's axis the closed forms hand
    the matrices to LAPACK: the one-pose path does so too, with the same bits (in Python
    ``numpy.linalg.svd``; with the C extension NumPy's ``svd`` gufunc loop from C,
    tests/native/test_rod_one.py)."""
    m = pkmkit.machine(name)
    x = _poses(m, 40, seed=12, spread=spread)
    calls = []
    svd = np.linalg.svd

    def counted(*args, **kwargs):
        calls.append(1)
        return svd(*args, **kwargs)

    monkeypatch.setattr(np.linalg, "svd", counted)
    monkeypatch.setenv("PKMKIT_NATIVE", "0")  # the Python pieces
    for p in x:  # the one-pose path alone
        assert np.isfinite(_one(m, p).condition)
        assert np.isfinite(_one(m, p).parallel_measure)
    assert len(calls) >= 10
    _check(m, x, name=name)
    monkeypatch.delenv("PKMKIT_NATIVE")
    _check(m, x, name=name)  # the C path where the extension is built


@pytest.mark.parametrize("name", ["orthoglide", "delta", "five-bar"])
def test_flags_with_the_tolerance_at_the_parallel_measure(name):
    """A tolerance 1e-6 (relative) below a pose's parallel measure does not flag it, 1e-6
    above does: the one-pose flags decide by the measure itself wherever its cheap bound
    cannot. A tolerance equal to the measure, or the next float up, is within the band
    handed to the general path (its q and measure round otherwise by an ulp): its flags and
    J are the general path's."""
    m = pkmkit.machine(name)
    x = _poses(m, 12, seed=13)
    q = np.array([_one(m, p).q for p in x])  # (the Delta's cranks: an ulp from m.ik's)
    measures = m.jacobian(x, q=q).parallel_measure
    for p, measure in zip(x, measures, strict=True):
        for tol in (float(measure), float(np.nextafter(measure, np.inf))):
            got, general = _one(m, p, tol), m.jacobian(p[None], tol=tol)
            _same_bits(got.singularity, general.singularity[0], f"{name} {tol}")
            _same_bits(got.J, general.J[0], name)
        for tol in (float(measure) * (1 - 1e-6), float(measure) * (1 + 1e-6)):
            got = _one(m, p, tol)
            _same_bits(got.singularity, m.jacobian(p[None], q=np.array([got.q]),
                                                   tol=tol).singularity[0], f"{name} {tol}")
            assert bool(got.singularity & 2) == (tol > measure)
            _same_bits(got.J, m.jacobian(p[None], q=np.array([got.q]), tol=tol).J[0], name)


def test_the_parallel_bound_holds():
    """σ_min/σ_max ≥ |det U| / 2 for matrices with unit rows (the bound the flags use)."""
    rng = np.random.default_rng(14)
    for n in (2, 3):
        u = rng.normal(size=(20000, n, n)) * rng.uniform(1e-3, 1, (20000, n, 1)) ** 4
        u[:, 0] = u[:, 1] + 1e-6 * u[:, 0]  # nearly singular ones too
        u[::2] = rng.normal(size=(10000, n, n))
        u /= np.linalg.norm(u, axis=2, keepdims=True)
        sv = np.linalg.svd(u, compute_uv=False)
        # (1e-14: the rounding of LAPACK's values, far inside the flags' margin)
        assert (sv[:, -1] / sv[:, 0] >= np.abs(np.linalg.det(u)) / 2 - 1e-14).all()
        assert (sv[:, -1] / sv[:, 0] < np.abs(np.linalg.det(u)) / 2 * 1.5).any()  # near tight


def test_a_field_computes_only_its_pieces(monkeypatch):
    monkeypatch.setenv("PKMKIT_NATIVE", "0")  # the Python pieces (the C kernel: tests/native)
    m = pkmkit.machine("linear-delta")
    x = m.home_pose + np.array([0.02, -0.01, 0.03])
    jac = m.jacobian(x)
    assert isinstance(jac, OnePoseJacobians)
    ev = jac._evaluation
    assert jac.A.shape == (3, 3)
    assert ev._adj is None and ev._lengths is None  # rows only
    assert np.isfinite(jac.J).all()
    assert ev._parallel is None and ev._sv is None  # no singular values for J
    assert jac.condition >= 1.0
    assert ev._parallel is None and ev._sv is not None  # those of J only
    assert 0.0 < jac.parallel_measure <= 1.0
    assert ev._parallel is not None


def test_machine_constants_are_built_once():
    m = pkmkit.machine("delta")
    first = velocity_one._legs(m._closed)
    assert np.isfinite(m.jacobian(m.home_pose).J).all()
    assert velocity_one._legs(m._closed) is first
