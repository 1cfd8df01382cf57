"""Derivatives with respect to every parameter of the one vector (issue 19 §2): nominal
parameters (a hexapod's ``base_radius``, a rod length, a chain element's invariant) as well as
defects, of the tool pose at held actuators and of the actuators at a held tool pose — checked
against central differences of the direct and inverse models of the machine rebuilt by
``with_parameters``, on every built-in machine and a machine file of each family."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import PkmError
from pkmkit.geometric_errors.parameter_sensitivity import parameter_sensitivity
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
FILES = ("my-machine.toml", "hexapod-6-6.toml", "planar-3rpr.toml", "strut-tripod.toml")
H = 1e-6


def _machines():
    for name in pkmkit.machines():
        yield pytest.param(lambda name=name: pkmkit.machine(name), id=name)
    for file in FILES:
        yield pytest.param(lambda file=file: pkmkit.load(str(EXAMPLES / file)), id=file)


def _tool(m, q):
    """Tool point (3,) and rotation matrix (3, 3) at actuators q."""
    if m.family == "chain":
        r = m.fk(q[None], full_output=True, strokes="ignore")
        return r.pose[0, :3], rotvec_to_matrix(r.tool_frame[:, 3:])[0]
    x = np.asarray(m.fk(q, strokes="ignore"), dtype=float)
    point = np.zeros(3)
    point[:min(3, m.dims)] = x[:3]
    rot = rotvec_to_matrix(x[None, 3:6])[0] if m.family == "full-pose" else np.eye(3)
    return point, rot


def _pose(m, q):
    if m.family == "chain":
        return m.fk(q[None], full_output=True, strokes="ignore").pose[0]
    return np.asarray(m.fk(q, strokes="ignore"), dtype=float)


@pytest.fixture(params=list(_machines()))
def machine(request):
    return request.param()


def test_parameter_derivatives_match_central_differences(machine):
    m = machine
    q = m.home_q
    s = parameter_sensitivity(m, q)
    v = m.parameters()
    assert s.point.shape == (1, 3, len(v)) and s.actuator.shape == (1, m.n_actuators, len(v))
    assert s.index.names == v.names
    pose = _pose(m, q)
    nominal = set(v.index.select("nominal").tolist())
    checked = {"nominal": 0, "defect": 0, "actuator": 0}
    for j, name in enumerate(v.names):
        if j not in nominal and j % 5:  # every nominal parameter, every fifth defect
            continue
        h = H * max(1.0, abs(v[name]))
        try:
            sides = [m.with_parameters(v.replace({name: v[name] + s_ * h})) for s_ in (1, -1)]
        except PkmError:  # a hyperstatic chain whose legs no longer close: no machine to test
            continue
        (p1, r1), (p2, r2) = (_tool(side, q) for side in sides)
        np.testing.assert_allclose(s.point[0, :, j], (p1 - p2) / (2 * h), rtol=0, atol=1e-7,
                                   err_msg=name)
        omega = matrix_to_rotvec((r1 @ r2.T)[None])[0] / (2 * h)
        np.testing.assert_allclose(s.rotation[0, :, j], omega, rtol=0, atol=1e-7, err_msg=name)
        checked[v.index.roles[j]] += 1
        try:
            q1, q2 = (side.ik(pose, strokes="ignore") for side in sides)
        except PkmError:  # the held pose is out of reach of a machine with fewer freedoms
            continue
        np.testing.assert_allclose(s.actuator[0, :, j], (q1 - q2) / (2 * h), rtol=0, atol=1e-6,
                                   err_msg=name)
        checked["actuator"] += 1
    assert checked["nominal"] >= 4 and checked["defect"] >= 2 and checked["actuator"] >= 4


def test_methods_are_labelled():
    gough = pkmkit.machine("gough-stewart")
    hexapod = parameter_sensitivity(gough, gough.home_q, names=("base_radius", "dL3"))
    assert hexapod.method == ("composition", "analytic")
    assert hexapod.index.roles == ("nominal", "defect")
    tripteor = pkmkit.machine("tripteor-x7")
    s = parameter_sensitivity(tripteor, tripteor.home_q, names=("L", "dK21"))
    assert s.method == ("central-difference", "analytic")
    planar = pkmkit.load(str(EXAMPLES / "planar-3rpr.toml"))
    assert parameter_sensitivity(planar, planar.home_q, names=("Aa1",)).method == (
        "composition",)
    biglide = pkmkit.machine("five-bar-biglide")  # parallel slides: alpha1 ± h is refused
    s = parameter_sensitivity(biglide, biglide.home_q, names=("alpha1",))
    assert s.method == ("undefined",) and np.isnan(s.point).all()
