"""The compiled elastostatics (:mod:`pkmkit.stiffness.kernels`) against the NumPy paths they
replace on large batches: the same status codes and compliances to 1e-12 (relative, in the
Frobenius norm of each matrix), on reachable, unreachable and singular poses."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.full_pose_forms import FullPoseForms
from pkmkit.spatial import pose_from_angles
from pkmkit.status import Status
from pkmkit.stiffness import default_data, rod_leg_stiffness, with_settings
from pkmkit.stiffness.compiled import chain_reduced_compliance, rod_kernel, rod_stiffness
from pkmkit.stiffness.indices import _smallest, stiffness_figures
from pkmkit.stiffness.joint_chains import (
    RANK_TOL,
    assemble,
    chain_compliance,
    null_space_compliance,
    system_compliance,
)
from pkmkit.stiffness.rod_legs import rod_leg_compliance

RTOL = 1e-12


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(b).all(axis=(1, 2))
    assert np.array_equal(ok, np.isfinite(a).all(axis=(1, 2)))
    gap = np.linalg.norm(a[ok] - b[ok], axis=(1, 2)) / np.linalg.norm(b[ok], axis=(1, 2))
    return float(gap.max(initial=0.0))


def _poses(m, rng, n=400):
    if m.dims == 6:
        x = pose_from_angles(m.home_pose[:3] + rng.uniform(-0.1, 0.1, (n, 3)),
                             rng.uniform(-8, 8, (n, 3)), "xyz", degrees=True)
    else:
        x = m.home_pose + rng.uniform(-0.2, 0.2, (n, m.dims))
    x[0] = m.home_pose
    x[1] = 50.0  # unreachable
    x[2, 0] = np.nan  # invalid input
    return x


def _numpy(monkeypatch, fun, *args):
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    try:
        return fun(*args)
    finally:
        monkeypatch.setenv("PKMKIT_COMPILED", "1")


@pytest.mark.parametrize("name", ["orthoglide", "linear-delta", "five-bar-isotropic",
                                  "gough-stewart", "dietmaier-hexapod"])
@pytest.mark.parametrize("rods", [None, "circle:0.02"])
def test_rod_kernels_match_the_numpy_path(monkeypatch, name, rods):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine(name)
    assert rod_kernel(m) is not None
    data = default_data(m)
    if rods is not None:
        data = with_settings(data, {"rod_section": rods}, m.n_actuators)
    x = _poses(m, np.random.default_rng(3))
    fast = rod_stiffness(m, x, data)
    assert fast is not None
    c0, s0, _, _ = _numpy(monkeypatch, rod_leg_compliance, m, x, data)
    assert np.array_equal(fast.status, s0)
    assert s0[2] == Status.INVALID_INPUT
    assert s0[1] == (Status.UNREACHABLE if m.dims < 6 else Status.OK)  # struts reach it
    assert (s0 == Status.OK).sum() > 300
    assert _relative(fast.compliance, c0) <= RTOL
    if m.dims < 6:
        ok = s0 == Status.OK
        reference = _smallest(c0, m.dims)
        assert np.isnan(fast.smallest[~ok]).all()
        assert np.allclose(fast.smallest[ok], reference[ok], rtol=RTOL, atol=0)
        figures = stiffness_figures(m, x, data=data, wrench=np.ones(m.dims))
        assert np.allclose(figures.smallest, reference, rtol=RTOL, atol=0, equal_nan=True)
    else:
        # K = A_uᵀ D⁻¹ A_u from the NumPy velocity model (inverting C would lose cond(C) ε)
        ok = s0 == Status.OK
        a, b = FullPoseForms(m.model).jacobians(x[ok], m.ik(x[ok]))
        ell = np.linalg.norm(a[:, :, :3], axis=2)
        b_u = b[:, np.arange(6), m.model.rod_actuator] / ell
        c_r = 0.0 if data.rod_section is None else ell / (data.rod_material.E
                                                          * data.rod_section.area)
        d = b_u**2 / data.actuator_stiffness[m.model.rod_actuator] + c_r
        expected = np.full_like(c0, np.nan)
        expected[ok] = np.einsum("nji,nj,njk->nik", a / ell[:, :, None], 1.0 / d,
                                 a / ell[:, :, None])
        assert _relative(fast.stiffness, expected) <= RTOL


def test_singular_poses_are_flagged_as_the_numpy_path_does(monkeypatch):
    """A linear Delta on its parallel singularity (rods parallel to the slides: the platform
    raised by the rod length above the home height is not, so scan a column of heights)."""
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine("five-bar-isotropic")
    x = m.home_pose + np.linspace(-3.0, 3.0, 4001)[:, None] * np.array([1.0, 0.0])
    data = default_data(m)
    fast = rod_stiffness(m, x, data)
    c0, s0, _, _ = _numpy(monkeypatch, rod_leg_compliance, m, x, data)
    assert np.array_equal(fast.status, s0)
    assert _relative(fast.compliance, c0) <= RTOL


def test_rod_leg_stiffness_is_the_inverse_of_the_compliance(monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine("gough-stewart")
    x = _poses(m, np.random.default_rng(4), 50)
    k, c, status = rod_leg_stiffness(m, x)
    ok = status == Status.OK
    eye = np.einsum("nij,njk->nik", k[ok], c[ok])
    gap = np.abs(eye - np.eye(6)).max(axis=(1, 2))
    assert (gap <= 1e-14 * np.linalg.cond(c[ok])).all()  # rounding grows with cond(C)
    assert np.isnan(k[~ok]).all()


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_chain_kernel_matches_the_svd_path(monkeypatch, name):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine(name)
    rng = np.random.default_rng(5)
    q = m.home_q + rng.uniform(-0.05, 0.05, (120, m.n_actuators))
    q[1] = np.nan  # not a configuration
    data = default_data(m)
    c, status, system = chain_compliance(m, q, data)
    c0, s0 = null_space_compliance(system.G, system.H, system.T, system.status)
    assert np.array_equal(status, s0)
    assert s0[1] != Status.OK and (s0 == Status.OK).sum() > 100
    assert _relative(c, c0) <= RTOL


def test_chain_kernel_leaves_link_springs_to_the_svd_path(monkeypatch):
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine("tripteor-x7")
    data = with_settings(default_data(m), {"link_section": "tube:0.12,0.1"}, m.n_actuators)
    q = m.home_q + np.random.default_rng(6).uniform(-0.03, 0.03, (20, m.n_actuators))
    c, status, system = chain_compliance(m, q, data)
    c0, s0 = null_space_compliance(system.G, system.H, system.T, system.status)
    assert np.array_equal(status, s0)
    assert _relative(c, c0) == 0.0


def test_a_rank_that_is_not_the_batchs_is_singular_in_both_paths(monkeypatch):
    """Most configurations of the batch lose closure rank (three rows of G zeroed): the
    kernel's full-rank rows are then the odd ones out, singular as the SVD path says."""
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine("tripteor-x7")
    q = m.home_q + np.random.default_rng(7).uniform(-0.03, 0.03, (30, m.n_actuators))
    data = default_data(m)
    s = assemble(m, q, data)
    g = s.G.copy()
    g[:20, :3, :] = 0.0
    c_s = 1.0 / data.actuator_stiffness
    _, done = chain_reduced_compliance(g, s.T, s.columns, c_s, s.status, RANK_TOL)
    assert done[20:].all() and not done[:20].any()
    c, status = system_compliance(g, s.H, s.T, s.status, s.columns, c_s)
    c0, s0 = null_space_compliance(g, s.H, s.T, s.status)
    assert np.array_equal(status, s0) and (s0[20:] == Status.SINGULAR).all()
    assert _relative(c, c0) <= RTOL  # NaN on the same rows
