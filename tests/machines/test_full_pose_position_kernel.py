"""The compiled position inverse of a machine whose rods set its orientation
(:mod:`pkmkit.machines.full_pose_position_kernel`) against the batched NumPy engine
(:func:`pkmkit.solve.rod_closure.solve_position_inverse`), and the early stop of the rows nowhere
near a solution (``POSITION_CRAWL``, the engine's ``crawl``): it loses no reachable position."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import full_pose_position as position
from pkmkit.machines import full_pose_position_kernel as kernel
from pkmkit.solve.rod_closure import solve_position_inverse
from pkmkit.status import Status
from tests.machines.test_full_pose import _full_pose_delta

pytest.importorskip("numba")


def _positions(m, count, seed, spread):
    rng = np.random.default_rng(seed)
    out = m.home_pose[:3] + rng.uniform(-spread, spread, (count, 3))
    out[5] = np.nan
    return out


def _starts(m, positions):
    """The engine's default start (first order from home), NaN for the hopeless rows."""
    dq = np.linalg.lstsq(m._home_jacobian[:3], np.nan_to_num(positions - m.home_pose[:3]).T,
                         rcond=None)[0].T
    guess_q = m.home_q + dq
    u0 = np.concatenate([guess_q, m.first_order_pose(guess_q)[:, 3:]], axis=1)
    u0[m._surely_unreachable(positions) | ~np.isfinite(positions).all(axis=1)] = np.nan
    return u0


@pytest.mark.parametrize("name,spread", [("verne", 0.9), ("delta6", 0.4)])
@pytest.mark.parametrize("crawl", [None, (12, 2e-6)])
def test_kernel_follows_the_engine(name, spread, crawl):
    """The same statuses, iteration counts within one (rounding-level acceptance decisions)
    and solutions to 1e-12 where OK, from the same starts, with and without the crawl limit."""
    m = _full_pose_delta() if name == "delta6" else pkmkit.machine(name)
    positions = _positions(m, 4000, 1, spread)
    u0 = _starts(m, positions)
    options = {"max_iter": 30, "compute_rank": False}
    if crawl is not None:
        options["crawl"] = crawl
    ref = solve_position_inverse(m.model, positions, u0, **options)
    data = m.direct_kernel()
    limit = crawl or (0, np.inf)
    opts = np.concatenate([data.options(options), limit])
    u, status, iterations, residual = kernel.solve(data.geom, positions, u0, opts)
    np.testing.assert_array_equal(status, ref.status)
    assert len(set(status.tolist())) >= 3  # OK, INVALID_INPUT and some failures
    assert np.abs(iterations - ref.iterations).max() <= 1
    ok = status == Status.OK
    np.testing.assert_allclose(u[ok], ref.u[ok], atol=1e-12)
    np.testing.assert_allclose(residual[ok], ref.residual[ok], atol=1e-13)


def test_the_compiled_path_of_ik_is_the_numpy_one(monkeypatch):
    """``ik`` of a batch of positions compiled (start computed in the kernel) and through the
    NumPy engine (``PKMKIT_COMPILED=0``): the same statuses (working mode checked), q to
    1e-12."""
    m = pkmkit.machine("verne")
    positions = _positions(m, 5000, 2, 0.8)
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    compiled = m.ik(positions, full_output=True, strokes="ignore")
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    numpy_path = m.ik(positions, full_output=True, strokes="ignore")
    np.testing.assert_array_equal(compiled.status, numpy_path.status)
    ok = compiled.status == Status.OK
    assert ok.sum() > 1000 and (compiled.status == Status.WRONG_MODE).any()
    np.testing.assert_allclose(compiled.q[ok], numpy_path.q[ok], atol=1e-12)
    np.testing.assert_allclose(compiled.pose[ok], numpy_path.pose[ok], atol=1e-12)


@pytest.mark.ci
def test_the_early_stop_loses_no_reachable_position(monkeypatch):
    """Every position the inverse reaches in the working mode without the crawl limit it
    reaches with it, to the same q (a dense grid over the Verne module's study box, where most
    rows are beyond reach, and random positions); only rows that were not OK stop earlier."""
    m = pkmkit.machine("verne")
    axis = np.linspace(-0.8, 0.85, 24)
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    positions = np.concatenate([grid, _positions(m, 6000, 3, 1.0)])
    limited = m.ik(positions, full_output=True, strokes="ignore")
    explicit = m.ik(positions, full_output=True, strokes="ignore", max_iter=30)  # a caller's
    monkeypatch.setattr(position, "POSITION_CRAWL", (0, np.inf))  # limit: no early stop
    free = m.ik(positions, full_output=True, strokes="ignore")
    ok = free.status == Status.OK
    assert ok.sum() > 5000 and (~ok).sum() > 5000
    np.testing.assert_array_equal(limited.status == Status.OK, ok)
    np.testing.assert_array_equal(limited.q[ok], free.q[ok])
    assert limited.iterations.sum() < 0.8 * free.iterations.sum()
    np.testing.assert_array_equal(explicit.iterations, free.iterations)
