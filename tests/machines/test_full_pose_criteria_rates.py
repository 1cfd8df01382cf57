"""Analytic derivatives of the workspace criteria's quantities along position axes
(:mod:`pkmkit.machines.full_pose_criteria_rates`) against central differences of the machine's
own ``ik`` and ``jacobian``: actuator coordinates, rod shortfalls, the parallel measure and the
transmission factors, on the hexapod (struts, orientation held), the Verne module (slides, the
orientation its rods impose follows the position) and the Delta robot's rods on a full-pose
platform (cranks). A wrong sign, a missing term (the orientation's motion, the normalisation of
A's rows, Ȧ's moment part) or a wrong singular vector moves them far beyond the tolerance:
central differences with h = 1e-6 m are exact to ~1e-9 of the quantity's scale here (truncation
h² ≈ 1e-12, rounding 1e-16/h plus the position inverse's own convergence, 1e-14, over h)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.criteria import solved_poses
from tests.machines.test_full_pose import _full_pose_delta

H = 1e-6


def _machine(name):
    return _full_pose_delta() if name == "delta6" else pkmkit.machine(name)


def _points(m, count, seed, spread):
    rng = np.random.default_rng(seed)
    width = 3 if m.position_controlled else 6
    points = np.tile(m.home_pose[:width], (count, 1))
    points[:, :3] += rng.uniform(-spread, spread, (count, 3))
    return points


def _models(m, points):
    inv = m.ik(points, full_output=True, strokes="ignore")
    return inv, m.jacobian(solved_poses(points, inv), q=inv.q)


@pytest.mark.parametrize("compiled", ["0", "1"])
@pytest.mark.parametrize("name,spread", [("gough-stewart", 0.25), ("verne", 0.3),
                                         ("delta6", 0.1)])
def test_rates_match_central_differences(name, spread, compiled, monkeypatch):
    """Both paths: LAPACK's SVD with vectors and the compiled Jacobi kernel with rates
    (:mod:`pkmkit.numerics.svd_rates_kernel`, large batches; forced here)."""
    monkeypatch.setenv("PKMKIT_COMPILED", compiled)
    m = _machine(name)
    points = _points(m, 120, 3, spread)
    inv, jac = _models(m, points)
    rates = m.criteria_rates(points, inv, jac, (0, 1, 2), factors=True)
    lean = m.criteria_rates(points, inv, jac, (0, 2))  # a subset of axes, no factors
    assert lean.singular_values is None
    ok = inv.status == 0
    assert ok.sum() > 60
    for i, axis in enumerate((0, 1, 2)):
        step = np.zeros(points.shape[1])
        step[axis] = H
        (up, jac_up), (down, jac_down) = _models(m, points + step), _models(m, points - step)
        keep = ok & (up.status == 0) & (down.status == 0)
        pairs = {
            "q": (rates.q[:, :, i], (up.q - down.q) / (2 * H)),
            "parallel": (rates.parallel_measure[:, i],
                         (jac_up.parallel_measure - jac_down.parallel_measure) / (2 * H)),
            "factors": (rates.singular_values[:, :, i],
                        (jac_up.singular_values - jac_down.singular_values) / (2 * H)),
        }
        short_up, short_down = up.shortfall, down.shortfall
        finite = np.isfinite(short_up) & np.isfinite(short_down)
        with np.errstate(invalid="ignore"):  # struts: −inf, always reached
            differences = np.where(finite, (short_up - short_down) / (2 * H), 0.0)
        pairs["shortfall"] = (np.where(finite, rates.shortfall[:, :, i], 0.0), differences)
        if axis in (0, 2):
            j = (0, 2).index(axis)
            np.testing.assert_allclose(lean.parallel_measure[keep, j],
                                       rates.parallel_measure[keep, i], rtol=1e-12, atol=1e-14)
        for label, (got, want) in pairs.items():
            got, want = got[keep], want[keep]
            scale = max(1.0, float(np.abs(want).max()))
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-7 * scale,
                                       err_msg=f"{name} {label} along axis {axis}")


def test_rates_refused_for_an_orientation_axis():
    """A rotation-vector component is not a position axis: no analytic rates (the caller
    differences)."""
    m = pkmkit.machine("gough-stewart")
    points = _points(m, 4, 0, 0.05)
    inv, jac = _models(m, points)
    assert m.criteria_rates(points, inv, jac, (0, 4)) is None
    assert pkmkit.machine("orthoglide").criteria_rates(points[:, :3], None, None, (0,)) is None


def _hexapod_rods_reversed():
    """The Gough–Stewart platform with its six rods listed last to first: rod j drives
    actuator 5 − j, so B (one entry a row, in the column of the rod's actuator) is a
    permuted diagonal, not a diagonal — B⁺ ≠ B⁺ᵀ. The same machine: the same ik."""
    from pkmkit.machines.full_pose import FullPoseMachine
    from pkmkit.model.rods import build_rod_model, leg_specs

    hexapod = pkmkit.machine("gough-stewart")
    model = build_rod_model(list(reversed(leg_specs(hexapod.model))), dims=6,
                            actuator_names=tuple(hexapod.model.actuator_names),
                            home_pose=tuple(hexapod.home_pose))
    return FullPoseMachine(id="hexapod-reversed", name="hexapod-reversed", kind=None,
                           params={}, model=model)


def test_actuator_rates_of_rods_listed_in_another_order():
    """q̇ = B⁺A ṗ against central differences of ik, on a hexapod whose rods are not in the
    order of their actuators (a transposed B⁺ is right only for a diagonal B)."""
    m = _hexapod_rods_reversed()
    assert list(m.model.rod_actuator) == [5, 4, 3, 2, 1, 0]
    points = _points(m, 12, 5, 0.1)
    inv, jac = _models(m, points)
    np.testing.assert_array_equal(inv.q, pkmkit.machine("gough-stewart").ik(points))
    rates = m.criteria_rates(points, inv, jac, (0, 1, 2))
    ok = inv.status == 0
    assert ok.sum() >= 8
    for i in range(3):
        step = np.zeros(6)
        step[i] = H
        want = (m.ik(points + step) - m.ik(points - step)) / (2 * H)
        np.testing.assert_allclose(rates.q[ok, :, i], want[ok], rtol=0, atol=1e-7)
