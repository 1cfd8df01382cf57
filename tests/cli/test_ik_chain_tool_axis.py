"""``pkmkit ik`` of a five-axis joint-chain machine reports the tool axis it was given, and the
actuator values it prints put the tool on that point and axis (the library's direct model)."""

import math
import re

import numpy as np

import pkmkit


def test_ik_reports_the_tool_axis_that_its_actuators_reach(run, as_json):
    m = pkmkit.machine("tripteor-x7")
    home = m.fk(m.home_q)  # within the strokes: a tool point and a unit tool axis
    point, given = home[:3], home[3:] * 2.0  # the axis need not be a unit vector
    text = ",".join(repr(float(v)) for v in (*point, *given))
    out = as_json(run("ik", "tripteor-x7", "--pose", text, "--json"))
    axis = np.asarray(out["tool_axis"], dtype=float)
    np.testing.assert_allclose(axis / np.linalg.norm(axis), given / np.linalg.norm(given),
                               atol=1e-12)
    q = np.array([v if u == "m" else math.radians(v)
                  for v, u in zip(out["q"], out["actuator_units"], strict=True)])
    pose = m.fk(q)
    np.testing.assert_allclose(pose[:3], point, atol=1e-9)
    np.testing.assert_allclose(pose[3:] / np.linalg.norm(pose[3:]),
                               given / np.linalg.norm(given), atol=1e-9)


def test_ik_text_names_the_tool_point_and_axis_given(run):
    m = pkmkit.machine("tripteor-x7")
    home = m.fk(m.home_q)
    point, given = home[:3], home[3:] * 2.0
    text = run("ik", "tripteor-x7", "--pose",
               ",".join(repr(float(v)) for v in (*point, *given))).output
    found = re.search(r"tool point \[([^\]]*)\] m, tool axis \[([^\]]*)\]", text)
    assert found, text
    shown_point = np.array([float(v) for v in found.group(1).split(",")])
    shown_axis = np.array([float(v) for v in found.group(2).split(",")])
    np.testing.assert_allclose(shown_point, point, rtol=1e-8)
    np.testing.assert_allclose(shown_axis / np.linalg.norm(shown_axis),
                               given / np.linalg.norm(given), atol=1e-8)
