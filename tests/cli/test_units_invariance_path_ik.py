"""The same request in m and in mm gives the same physical answer: a helix for ``path``
(centre, radius and pitch all lengths) and a tool length for the inverse model of a five-axis
machine."""

import math

import numpy as np
import pytest

import pkmkit


def test_path_helix_in_mm_is_the_helix_in_m(run, as_json):
    common = ["--feed", "0.05", "--accel", "1", "--json"]
    m = as_json(run("path", "linear-delta", "--helix", "0,0,0.3,0.05,0.01,2", *common))
    mm = as_json(run("path", "linear-delta", "--helix", "0,0,300,50,10,2", "--units", "mm",
                     "--feed", "50", "--accel", "1000", "--json"))
    # by hand: two turns of radius 50 mm rising 10 mm each
    assert m["length"] == pytest.approx(2 * math.hypot(2 * math.pi * 0.05, 0.01), rel=1e-12)
    assert mm["length"] == pytest.approx(1000 * m["length"], rel=1e-9)
    assert mm["duration"] == pytest.approx(m["duration"], rel=1e-9)
    np.testing.assert_allclose(mm["stroke"], 1000 * np.asarray(m["stroke"]), rtol=1e-9)


def test_ik_tool_length_in_mm_is_the_tool_length_in_m(run, as_json):
    machine = pkmkit.machine("tripteor-x7")
    home = machine.fk(machine.home_q)
    pose_m = ",".join(repr(float(v)) for v in (*home[:3], *home[3:]))
    pose_mm = ",".join(repr(float(v)) for v in (*(1000 * home[:3]), *home[3:]))
    tool = machine.tool_length + 0.002
    m = as_json(run("ik", "tripteor-x7", "--pose", pose_m, "--tool-length", repr(tool),
                    "--json"))
    mm = as_json(run("ik", "tripteor-x7", "--pose", pose_mm, "--tool-length",
                     repr(1000 * tool), "--units", "mm", "--json"))
    scale = np.array([1000.0 if u == "m" else 1.0 for u in m["actuator_units"]])
    np.testing.assert_allclose(mm["q"], scale * np.asarray(m["q"]), rtol=1e-9, atol=1e-9)
    # the same actuators as the library with that tool length
    q = machine.ik(home, tool_length=tool)
    deg = [u == "deg" for u in m["actuator_units"]]
    np.testing.assert_allclose(np.where(deg, np.radians(m["q"]), m["q"]), q, atol=1e-9)
