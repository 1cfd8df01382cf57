"""The identification's compiled closures (issue 22 §7): the same answer as the NumPy path
(``PKMKIT_COMPILED=0``: the engine's closures, as before the kernels) to far below the printed
digits, on the benchmark's two problems (smaller), the kernels actually used, and the analytic
Jacobian of the exposed problem against finite differences of its residual."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import calibrate, identification_problem, random_defects, simulate
from pkmkit.calibration.simulate import default_configurations
from pkmkit.solve import chain_rows
from pkmkit.solve.chains import compiled_closure_available

TRIPTEOR = {"frame": "identify", "prior": True}


@pytest.fixture(scope="module")
def tripteor_data():
    m = pkmkit.machine("tripteor-x7")
    rng = np.random.default_rng(7)
    true = m.with_defects(random_defects(m, rng))
    q = default_configurations(m, 60, rng)
    return m, simulate(true, m, "point", len(q), rng, q=q, noise="tracker")


@pytest.fixture(scope="module")
def hexapod_data():
    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(3)
    return m, simulate(m.with_defects(random_defects(m, rng)), m, "pose", 30, rng)


def _same(new, old):
    assert new.names == old.names and new.setup_names == old.setup_names
    assert new.iterations == old.iterations
    ours = np.concatenate([new.values, new.setup_values])
    theirs = np.concatenate([old.values, old.setup_values])
    std = np.concatenate([old.std, old.setup_std])
    # the compiled chain inverse (issue 22 §3) agrees with the NumPy engine to ~1e-12 m; the
    # identification's conditioning carries that to a few 1e-6 of the smallest σ (measured
    # 3.3e-6 on the Tripteor): differences far below what the data determine
    assert np.abs(ours - theirs).max() < 1e-5 * std.min()
    np.testing.assert_allclose(np.concatenate([new.std, new.setup_std]), std, rtol=1e-6)
    for a, b in ((new.before, old.before), (new.after, old.after)):
        assert a.rms == pytest.approx(b.rms, rel=1e-9)
        assert a.max == pytest.approx(b.max, rel=1e-9)
    assert new.sigma_posterior == pytest.approx(old.sigma_posterior, rel=1e-9)
    np.testing.assert_allclose(new.tool_uncertainty, old.tool_uncertainty, rtol=1e-6)


@pytest.mark.slow  # 15-40 s: .ci/run runs it (-m "slow or ci")
@pytest.mark.skipif(not compiled_closure_available(), reason="needs Numba")
def test_tripteor_identification_is_the_numpy_paths(tripteor_data, monkeypatch):
    m, data = tripteor_data
    calls = []
    solve = chain_rows.solve  # the engine's entry point (the C twin or the Numba kernel)
    monkeypatch.setattr(chain_rows, "solve", lambda *a, **k: calls.append(1) or solve(*a, **k))
    new = calibrate(m, data, **TRIPTEOR)
    assert len(calls) >= new.iterations  # every residual's closure ran compiled
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    calls.clear()
    old = calibrate(m, data, **TRIPTEOR)
    assert not calls
    _same(new, old)


def test_hexapod_identification_is_the_one_before_the_kernels(monkeypatch):
    """bench/calibration.py's hexapod problem (50 full poses), against the figures of the code
    before issue 22 §7 (commit e97186d; its JᵀJ, SVDs and Jacobian evaluations were changed).
    A rod length and its actuator offset tie (the same column): the selection takes the one
    named first, ``dL``, for every leg and along both paths (``PKMKIT_COMPILED=0`` also switches
    the hexapod's direct model; before ``numerics.pivoted_qr``, LAPACK's pivoting took ``dq5``
    on one path and ``dL5`` on the other, by the last bits of the norms)."""
    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(3)
    data = simulate(m.with_defects(random_defects(m, rng)), m, "pose", 50, rng)
    res = calibrate(m, data, prune=False)
    assert len(res.names) == 42 and res.iterations == 4
    assert [n for n in res.names if n[:2] in ("dL", "dq")] == [f"dL{k}" for k in range(1, 7)]
    assert res.before.rms == pytest.approx(1.1772867330442493e-04, rel=1e-9)
    assert res.after.rms == pytest.approx(2.146875688694596e-05, rel=1e-9)
    assert res.sigma_posterior == pytest.approx(1.143797558403951e-05, rel=1e-9)
    for name, value, std in (("dA1x", 2.23181e-04, 1.183e-04), ("dA2x", 1.35292e-04, 1.263e-04),
                             ("dL3", -8.67129e-05, 2.133e-04), ("dL5", 1.45524e-04, 2.554e-04)):
        i = res.names.index(name)
        assert res.values[i] == pytest.approx(value, rel=1e-5)
        assert res.std[i] == pytest.approx(std, rel=1e-3)
    monkeypatch.setenv("PKMKIT_COMPILED", "0")
    numpy_path = calibrate(m, data, prune=False)
    assert numpy_path.names == res.names
    np.testing.assert_allclose(numpy_path.values, res.values, rtol=1e-7, atol=1e-12)


@pytest.mark.parametrize("case", ["tripteor", "hexapod"])
def test_analytic_jacobian_matches_finite_differences(case, tripteor_data, hexapod_data):
    """Through the compiled closures (warm-started from the previous evaluation), at a point
    away from the start: central differences of the whitened residual, column by column."""
    m, data = tripteor_data if case == "tripteor" else hexapod_data
    options = TRIPTEOR if case == "tripteor" else {"prune": False}
    problem = identification_problem(m, data, **options)
    rng = np.random.default_rng(1)
    u = problem.u0 + rng.normal(0.0, 0.3, problem.u0.size)
    jac = problem.jacobian(u)
    h = 1e-4
    scale = np.abs(jac).max()
    for k in range(0, len(u), 4):
        e = np.zeros(len(u))
        e[k] = h
        fd = (problem.residual(u + e) - problem.residual(u - e)) / (2 * h)
        np.testing.assert_allclose(jac[:, k], fd, rtol=0, atol=2e-6 * scale)
