"""Defect sets, exact application and the analytic tool sensitivity of every machine family,
against central finite differences of the exact model with the defects applied."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.exceptions import InputError, ParameterError
from pkmkit.geometric_errors.model import defect_set, tool_sensitivity, with_defects

MACHINES = ["linear-delta", "orthoglide", "five-bar", "delta", "gough-stewart", "verne",
            "tripteor-x7", "crank-slider"]


def _configuration(m, rng):
    q = np.asarray(m.home_q, dtype=float).copy()
    if type(m).__name__ == "JointChainMachine":
        return np.asarray(m.reference_poses().get("wrist", q), dtype=float)
    return q + rng.uniform(-0.01, 0.01, q.shape)


@pytest.mark.parametrize("name", MACHINES)
def test_tool_sensitivity_against_finite_differences(name):
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    m = pkmkit.machine(name)
    ds = defect_set(m)
    q = _configuration(m, rng)
    sens = tool_sensitivity(m, q)
    chain = type(m).__name__ == "JointChainMachine"
    # every defect of the small machines, a random sample of the larger ones
    picks = range(len(ds)) if len(ds) <= 30 else rng.choice(len(ds), 30, replace=False)
    h = 1e-5 if chain else 1e-6
    for i in picks:
        plus, minus = with_defects(m, {ds.names[i]: h}), with_defects(m, {ds.names[i]: -h})
        xp, xm = np.atleast_1d(plus.fk(q)), np.atleast_1d(minus.fk(q))
        k = min(m.dims, 3)
        fd = (xp[:k] - xm[:k]) / (2 * h)
        # incompatible chain defects are closed in least squares: the solve's precision
        tol = 1e-8 if chain and np.abs(sens.closure_defect[0, :, i]).max() > 1e-12 else 2e-9
        np.testing.assert_allclose(sens.point[0, :k, i], fd, atol=tol, err_msg=ds.names[i])
        if type(m).__name__ == "FullPoseMachine":
            rfd = (Rotation.from_rotvec(xp[3:]) * Rotation.from_rotvec(xm[3:]).inv()
                   ).as_rotvec() / (2 * h)
            np.testing.assert_allclose(sens.rotation[0, :, i], rfd, atol=5e-9,
                                       err_msg=ds.names[i])
        if chain:  # the tool axis turns with the tool frame
            afd = (xp[3:] - xm[3:]) / (2 * h)
            np.testing.assert_allclose(np.cross(sens.rotation[0, :, i], sens.pose[0, 3:]), afd,
                                       atol=tol, err_msg=ds.names[i])


def test_defect_names_follow_the_seeds():
    hexapod = defect_set(pkmkit.machine("gough-stewart"))
    # 7 per rod (A_i, B_i, length) as seed 003's 42-parameter six-rod model, then offsets
    per_rod = [n for n in hexapod.names if n[1] in "ABL"]
    assert len(per_rod) == 42
    assert hexapod.names[:7] == ("dA1x", "dA1y", "dA1z", "dB1x", "dB1y", "dB1z", "dL1")
    assert sum(n.startswith("dq") for n in hexapod.names) == 6
    verne = defect_set(pkmkit.machine("verne"))
    assert len([n for n in verne.names if n[1] in "ABL"]) == 42
    # vertical slides: the axis defects are the x and y components
    assert {"du1x", "du1y"} <= set(verne.names)
    tripteor = defect_set(pkmkit.machine("tripteor-x7"))
    # Table 4.3's minimal invariants: pivot 21 axis (1, 0, 0) → dJ21, dK21, db21, dc21
    assert {"dJ21", "dK21", "db21", "dc21"} <= set(tripteor.names)
    assert "dI21" not in tripteor.names and "da21" not in tripteor.names
    # prismatic joint 41: two orientation defects only
    assert [n for n in tripteor.names if n.endswith("41")] == ["dJ41", "dK41"]
    assert len(defect_set(pkmkit.machine("five-bar"))) == 14  # planar: no z components


def test_applying_defects_is_exact_and_checked():
    m = pkmkit.machine("gough-stewart")
    moved = with_defects(m, {"dL3": 0.002, "dA1z": -0.001})
    np.testing.assert_allclose(moved.model.rod_length[2], m.model.rod_length[2] + 0.002)
    np.testing.assert_allclose(moved.model.rod_base[0, 2], m.model.rod_base[0, 2] - 0.001)
    assert m.model.rod_length[2] == pytest.approx(0.0)  # the original is unchanged
    delta = pkmkit.machine("linear-delta")
    tilted = with_defects(delta, {"du2x": 0.01, "dq1": 0.003})
    np.testing.assert_allclose(np.linalg.norm(tilted.model.leg_axis[1]), 1.0)
    np.testing.assert_allclose(tilted.model.leg_axis[1, 0], 0.01)
    # an offset moves the carriage: the same q puts the carriage 3 mm higher
    np.testing.assert_allclose(tilted.model.leg_base[0, 2] - delta.model.leg_base[0, 2], 0.003)
    with pytest.raises(ParameterError, match="unknown defect 'dZ9'"):
        with_defects(m, {"dZ9": 1.0})
    with pytest.raises(InputError, match="48 finite values"):
        with_defects(m, np.zeros(3))
    with pytest.raises(InputError, match="components per row"):
        tool_sensitivity(m, np.zeros(4))


@pytest.mark.parametrize("name", ["linear-delta", "verne", "gough-stewart"])
def test_measurement_jacobians_against_finite_differences(name):
    from pkmkit.geometric_errors.measurements import measure, measurement_jacobian

    rng = np.random.default_rng(5)
    m = pkmkit.machine(name)
    ds = defect_set(m)
    q = np.atleast_2d(m.home_q) + rng.uniform(-0.005, 0.005, (2, m.n_actuators))
    points = measure(m, "point", q)
    part = measure(m, "pose", q) if m.n_actuators == 6 else points
    setups = {"point": {}, "height": {}, "ballbar": {"pivot": points[0] + [0.1, -0.2, -0.3]},
              "part": {"points": part}}
    if m.dims == 6:
        setups["pose"] = {}
    h = 1e-6
    for kind, setup in setups.items():
        jac = measurement_jacobian(m, kind, q, setup)
        for i in rng.choice(len(ds), 8, replace=False):
            plus = measure(with_defects(m, {ds.names[i]: h}), kind, q, setup)
            minus = measure(with_defects(m, {ds.names[i]: -h}), kind, q, setup)
            fd = (plus - minus) / (2 * h)
            if kind == "pose":  # rotation rows: rotation vectors differ to first order only
                fd[:, 3:] = [(Rotation.from_rotvec(a) * Rotation.from_rotvec(b).inv()
                              ).as_rotvec() / (2 * h) for a, b in zip(plus[:, 3:], minus[:, 3:],
                                                                       strict=True)]
            np.testing.assert_allclose(jac[:, :, i], fd, atol=5e-9,
                                       err_msg=f"{kind} {ds.names[i]}")
