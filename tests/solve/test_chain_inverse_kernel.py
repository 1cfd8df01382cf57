"""The compiled inverse model of joint-chain machines (:func:`pkmkit.solve.chain_kernel.
solve_inverse`) and the compiled closure rates (:func:`~pkmkit.solve.chain_kernel.
closure_rates`) against the NumPy engine and LAPACK's pseudo-inverse they replace in the
workspace studies (issue 22 §3): the same solutions, statuses and iterations on a grid of the
default box (reachable and unreachable points), the same velocity model."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.criteria import Criteria, evaluate_grid
from pkmkit.analysis.grids import make_grid
from pkmkit.machines.chain_jacobians import RANK_RCOND, _pinv_and_singular_values
from pkmkit.solve import chain_kernel
from pkmkit.solve.chains import closure, compiled_closure_available, solve_machine_inverse
from pkmkit.spatial.rotation import rotvec_to_matrix

pytestmark = pytest.mark.skipif(not compiled_closure_available(), reason="needs Numba")


@pytest.fixture(scope="module", params=["tripteor-x7", "trimule-600"])
def grid(request):
    """A 10-point-per-edge grid of the machine's default box at home's tool axis (the
    Tripteor's is mostly beyond its head's reach: unreachable rows too)."""
    m = pkmkit.machine(request.param)
    lo, hi = m.default_box()
    return m, make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                        resolution=10)


def test_compiled_inverse_is_the_engines(grid):
    m, g = grid
    n = g.size
    u0 = np.concatenate([np.tile(m.home_platform, (n, 1)), np.tile(m.home_values, (n, 1))],
                        axis=1)
    u0[3] = np.nan  # a bad row
    lengths = np.full(n, m.tool_length)
    ref = solve_machine_inverse(m.model, g.points, u0, tool_length=lengths, compute_rank=False)
    out = solve_machine_inverse(m.model, g.points, u0, tool_length=lengths, compute_rank=False,
                                compiled=True)
    assert out.rank.tolist() == [-1] * n  # the kernel ran
    np.testing.assert_array_equal(out.status, ref.status)
    assert 0 < (ref.status == 0).sum()
    ok = ref.status == 0
    np.testing.assert_allclose(out.u[ok], ref.u[ok], rtol=0, atol=1e-10)
    # the same iterates to rounding: the same count but where a last step sits at the
    # tolerance
    assert (out.iterations[ok] != ref.iterations[ok]).mean() < 0.01


def test_compiled_closure_rates_are_the_pseudo_inverse(grid):
    """dU = −C_U⁺ C_q, the rank and σ_expected/σ_max at solved configurations (the QR path)
    and at rank-deficient ones (a column repeated: the Jacobi path), against LAPACK."""
    m, g = grid
    inv = m.ik(g.points[:200], full_output=True)
    ok = inv.status == 0
    sol = inv.solution[ok]
    rot = rotvec_to_matrix(sol[:, 3:6]).transpose(1, 2, 0)
    c = closure(m.model, rot, sol[:, :3].T, sol[:, 6:].T)
    passive = m.passive_variables
    cu = np.concatenate([c.platform, c.variables[:, passive]], axis=1).transpose(2, 0, 1)
    loop_act = [i for i in np.flatnonzero(m.model.actuated) if m.model.loop_variables[i]]
    cq = c.variables[:, loop_act].transpose(2, 0, 1)
    deficient = cu.copy()
    deficient[:, :, -1] = deficient[:, :, -2]
    expected = m.expected_rank()
    for mats, rank in ((cu, expected), (deficient, expected - 1)):
        pinv, sv = _pinv_and_singular_values(mats, RANK_RCOND)
        du, ranks, ratio = chain_kernel.closure_rates(mats, cq, RANK_RCOND, 1e-6, expected)
        np.testing.assert_allclose(du, -pinv @ cq, rtol=0, atol=1e-9 * np.abs(pinv @ cq).max())
        assert ranks.tolist() == [rank] * len(mats)
        exact = sv[:, expected - 1] / sv[:, 0]
        if rank == expected:  # a lower bound (within a factor √c) clearing the tolerance
            assert (ratio <= exact * (1 + 1e-12)).all() and (ratio > 1e-6).all()
        else:
            np.testing.assert_allclose(ratio, exact, rtol=1e-6, atol=1e-15)


def test_workspace_criteria_compiled_and_numpy_agree(grid, monkeypatch):
    """The criteria of a grid with the compiled kernels and through the NumPy
    engine and LAPACK (``PKMKIT_COMPILED=0``): the same masks, q to 1e-10, factors to 1e-10.
    On a 6-point-per-edge grid of the same box (the TriMule's NumPy engine costs 1.6 s of CPU
    there, 3.0 s on the 10-point ``grid``), which still has rows within and beyond the strokes
    on both machines, and on the TriMule's rows out of the bounds and one out of reach
    (docs/testing.md, "Fifth round": the planted bugs it still catches)."""
    m, g = grid
    lo, hi = m.default_box()
    g = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names, resolution=6)
    fast = evaluate_grid(m, g, Criteria(bounds=(0.2, 5.0)))
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    slow = evaluate_grid(m, g, Criteria(bounds=(0.2, 5.0)))
    for name in fast.masks:
        np.testing.assert_array_equal(fast.masks[name], slow.masks[name], err_msg=name)
    assert fast.masks["reachable"].any()
    assert 0 < fast.masks["strokes"].sum() < fast.masks["strokes"].size  # both kinds of rows
    np.testing.assert_allclose(fast.q, slow.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.factors, slow.factors, rtol=1e-10, atol=0)
