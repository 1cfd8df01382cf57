"""``fk`` of a six-actuator machine prints its pose as position (in --units), angles (in the
convention, degrees) and rotation vector (rad); each half in its place (issue 18 §9,
plausible bugs: the angles printed as the position, or the position as the rotation vector,
passed every test). The pose is made in the test: actuators from the library's inverse model
of a tilted pose; the rotation vector from scipy."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit

POSITION_MM = np.array([20.0, -10.0, 800.0])
ANGLES_DEG = np.array([3.0, -2.0, 5.0])


def _vector(line: str, after: str) -> np.ndarray:
    m = re.search(re.escape(after) + r"\s*\[([^\]]*)\]", line)
    assert m, (after, line)
    return np.array([float(v) for v in m.group(1).split(",")])


@pytest.mark.parametrize("units, scale", [("mm", 1e-3), ("m", 1.0)])
def test_fk_text_pose_halves(run, units, scale):
    rotvec = Rotation.from_euler("xyz", ANGLES_DEG, degrees=True).as_rotvec()
    m = pkmkit.machine("gough-stewart")
    q = m.ik(np.concatenate([POSITION_MM * 1e-3, rotvec]))
    q_text = ",".join(f"{v / scale:.12g}" for v in q)
    res = run("fk", "gough-stewart", "--q", q_text, "--units", units, "--angles", "xyz")
    assert res.exit_code == 0, res.output
    line = next(x for x in res.output.splitlines() if x.strip().startswith("pose "))
    np.testing.assert_allclose(_vector(line, "position"), POSITION_MM * 1e-3 / scale,
                               rtol=1e-7, atol=1e-9 / scale)
    np.testing.assert_allclose(_vector(line, "(xyz)"), ANGLES_DEG, atol=1e-7)
    np.testing.assert_allclose(_vector(line, "rotation vector"), rotvec, atol=1e-8)
    assert f"{units}, angles (xyz)" in line and "deg, rotation vector" in line


@pytest.mark.parametrize("units, scale", [("mm", 1e-3), ("m", 1.0)])
def test_fk_json_pose_halves(run, as_json, units, scale):
    """The same pose through ``--json``: ``pose.position`` in --units, ``pose.angles`` in
    degrees, ``pose.rotation_vector`` in rad, each half in its place."""
    rotvec = Rotation.from_euler("xyz", ANGLES_DEG, degrees=True).as_rotvec()
    m = pkmkit.machine("gough-stewart")
    q = m.ik(np.concatenate([POSITION_MM * 1e-3, rotvec]))
    q_text = ",".join(f"{v / scale:.12g}" for v in q)
    pose = as_json(run("fk", "gough-stewart", "--q", q_text, "--units", units, "--angles",
                       "xyz", "--json"))["pose"]
    np.testing.assert_allclose(pose["position"], POSITION_MM * 1e-3 / scale, rtol=1e-7,
                               atol=1e-9 / scale)
    np.testing.assert_allclose(pose["angles"], ANGLES_DEG, atol=1e-7)
    np.testing.assert_allclose(pose["rotation_vector"], rotvec, atol=1e-8)
    assert pose["convention"] == "xyz"
