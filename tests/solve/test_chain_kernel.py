"""The compiled joint-chain closure (:mod:`pkmkit.solve.chain_kernel`) against the NumPy engine
it mirrors: the same solutions, statuses and iteration counts (Tripteor, TriMule with its joint
shared by two legs, nominal and with incompatible defects, cold and warm starts, bad rows), and
the compiled linearisation (C_U, C_δ, the tool's defect twists) against
:func:`pkmkit.solve.chains.closure` / :func:`~pkmkit.solve.chains.tool_frame` away from closure."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity
from pkmkit.model.defect_rule import add_defects
from pkmkit.solve import chain_kernel
from pkmkit.solve.chains import (
    closure,
    compiled_closure_available,
    rotvec_matrices,
    solve_closure,
    tool_frame,
    with_column_twists,
)
from pkmkit.status import Status

pytestmark = pytest.mark.skipif(not compiled_closure_available(), reason="needs Numba")


@pytest.fixture(scope="module", params=["tripteor-x7", "trimule-600"])
def machines(request):
    """The nominal machine and one with random (incompatible) defects."""
    m = pkmkit.machine(request.param)
    rng = np.random.default_rng(4)
    return m, add_defects(m, rng.normal(0.0, 1.0, len(defect_set(m)))
                          * np.where(np.array(defect_set(m).units) == "m", 1e-4, 1e-3))


def _problem(machine, rng, n=40):
    """Known values (actuators drawn in the default region) and the engine's default start."""
    q = machine.measurement_configurations(n, rng)
    values = machine.full_values(q)
    return q, values, machine._default_start(q, values)


def _both(machine, values, u0, **options):
    kw = {"unknown_variables": machine.passive_variables, "compute_rank": False,
          "damping": 1e-8, **options}
    return (solve_closure(machine.model, values, u0, **kw),
            solve_closure(machine.model, values, u0, compiled=True, **kw))


@pytest.mark.parametrize("which", [0, 1], ids=["nominal", "defects"])
def test_compiled_closure_is_the_engines(machines, which):
    machine = machines[which]
    _, values, u0 = _problem(machine, np.random.default_rng(1))
    ref, out = _both(machine, values, u0)
    assert out.rank.tolist() == [-1] * len(u0)  # the kernel ran (the engine gives no -1 here)
    np.testing.assert_array_equal(out.status, ref.status)
    # least-squares closures of incompatible legs crawl (linear convergence) and stop on the
    # stall test: where it falls, at the rounding level, is not the same iteration in both
    if which == 0:
        np.testing.assert_array_equal(out.iterations, ref.iterations)
    np.testing.assert_allclose(out.u, ref.u, rtol=0, atol=1e-12 if which == 0 else 1e-10)
    np.testing.assert_allclose(out.residual, ref.residual, rtol=1e-6, atol=1e-15)
    expected = Status.OK if which == 0 else Status.INCONSISTENT
    assert (out.status == expected).all()


def test_warm_starts_options_and_bad_rows(machines):
    machine = machines[1]
    rng = np.random.default_rng(2)
    _, values, u0 = _problem(machine, rng, 12)
    solved = solve_closure(machine.model, values, u0, unknown_variables=machine.passive_variables,
                           compute_rank=False, damping=1e-8).u
    warm = solved + rng.normal(0.0, 1e-5, solved.shape)
    warm[3, 2] = np.nan                      # a non-finite start: INVALID_INPUT, untouched
    far = values.copy()
    far[5, machine._actuated[0]] += 5.0      # an actuator value no assembly has
    for options in ({}, {"xtol": 1e-6, "max_iter": 7}):
        ref, out = _both(machine, far, warm, **options)
        np.testing.assert_array_equal(out.status, ref.status)
        np.testing.assert_array_equal(out.iterations, ref.iterations)
        finite = np.isfinite(ref.u).all(axis=1)
        np.testing.assert_allclose(out.u[finite], ref.u[finite], rtol=0, atol=1e-9)
        assert out.status[3] == Status.INVALID_INPUT and np.isnan(out.u[3, 2])
        assert out.status[5] != Status.OK


def test_unsupported_options_fall_back_to_the_engine(machines):
    machine = machines[0]
    _, values, u0 = _problem(machine, np.random.default_rng(3), 5)
    out = solve_closure(machine.model, values, u0, unknown_variables=machine.passive_variables,
                        compiled=True)  # compute_rank defaults to True: the engine's ranks
    assert (out.rank > 0).all()


@pytest.mark.parametrize("columns", [False, True], ids=["defects", "column twists"])
def test_compiled_linearisation_matches_the_numpy_closure(machines, columns):
    """Away from closure (random states), every row of C_U, C_δ and the tool's defect twists."""
    machine = machines[1]
    model = machine.model
    rng = np.random.default_rng(5)
    k = 7
    if columns:
        elements = rng.integers(0, len(model.elements), 9)
        model = with_column_twists(model, elements, rng.normal(size=(9, 6)))
    values = machine.home_values[None] + rng.normal(0.0, 0.05, (k, model.n_variables))
    platform = machine.home_platform[None] + rng.normal(0.0, [0.02] * 3 + [0.3] * 3, (k, 6))
    passive = machine.passive_variables
    cu, cd, tool_r, tool_p, tool_tw = chain_kernel.linearise(model, values, platform, passive)
    rot = rotvec_matrices(platform[:, 3:].T)
    c = closure(model, rot, platform[:, :3].T, values.T, defects=True)
    ref_cu = np.concatenate([c.platform, c.variables[:, passive]], axis=1).transpose(2, 0, 1)
    scale = np.abs(ref_cu).max()
    np.testing.assert_allclose(cu, ref_cu, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(cd, c.defects.transpose(2, 0, 1), rtol=0,
                               atol=1e-12 * np.abs(c.defects).max())
    tool = tool_frame(model, rot, platform[:, :3].T, values.T, defects=True)
    np.testing.assert_allclose(tool_r, tool.R.transpose(2, 0, 1), rtol=0, atol=1e-14)
    np.testing.assert_allclose(tool_p, tool.p.T, rtol=0, atol=1e-14)
    np.testing.assert_allclose(tool_tw, tool.defect_twists.transpose(2, 0, 1), rtol=0,
                               atol=1e-13)


def test_compiled_warm_started_sensitivity_is_the_numpy_one():
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(6)
    machine = add_defects(m, random_defects(m, rng))
    q = machine.measurement_configurations(30, rng)
    tl = np.where(np.arange(30) % 2 == 0, 0.169889, 0.110006)
    ref = tool_sensitivity(machine, q, tool_length=tl)
    start = machine.tool_frames(q, tl, compiled=True).start
    out = tool_sensitivity(machine, q, tool_length=tl, start=start, compiled=True)
    for name in ("point", "rotation", "pose", "closure_defect"):
        a, b = getattr(ref, name), getattr(out, name)
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * max(1.0, np.abs(a).max()))


def test_absorb_is_the_pseudo_inverse_and_flags_rank_deficient_rows():
    rng = np.random.default_rng(8)
    cu, cd = rng.normal(size=(5, 18, 16)), rng.normal(size=(5, 18, 30))
    cu[2, :, 7] = cu[2, :, 3] * 2.0  # a row whose C_U lost a rank
    du, rest, ok = chain_kernel.absorb(cu, cd)
    assert ok.tolist() == [True, True, False, True, True]
    assert np.isnan(du[2]).all() and np.isnan(rest[2]).all()
    good = np.flatnonzero(ok)
    ref = -np.linalg.pinv(cu[good]) @ cd[good]
    np.testing.assert_allclose(du[good], ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    np.testing.assert_allclose(rest[good], cd[good] + cu[good] @ ref, rtol=0, atol=1e-12)


def test_rank_deficient_closure_rows_take_the_pseudo_inverse(monkeypatch):
    """Rows the compiled normal equations refuse get the pseudo-inverse (as without kernels)."""
    m = pkmkit.machine("tripteor-x7")
    q = m.measurement_configurations(6, np.random.default_rng(9))
    ref = tool_sensitivity(m, q)
    from pkmkit.solve import chain_rows  # the entry point the identification calls

    absorb = chain_rows.absorb
    calls = []

    def refusing(cu, cd):
        du, rest, ok = absorb(cu, cd)
        ok[::2] = False
        calls.append(len(ok))
        return du, rest, ok

    monkeypatch.setattr(chain_rows, "absorb", refusing)
    out = tool_sensitivity(m, q, compiled=True)
    assert calls  # the refusing kernel ran
    assert np.isfinite(out.point).all()
    np.testing.assert_allclose(out.point, ref.point, rtol=0, atol=1e-12)
    np.testing.assert_allclose(out.closure_defect, ref.closure_defect, rtol=0, atol=1e-12)


def test_a_rod_machine_refuses_a_closure_start():
    from pkmkit.exceptions import UnsupportedOperationError

    m = pkmkit.machine("gough-stewart")
    with pytest.raises(UnsupportedOperationError):
        tool_sensitivity(m, m.home_q, start=np.zeros(6))
