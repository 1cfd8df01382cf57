"""Property tests (Hypothesis) of the joint-chain machines (Tripteor X7, TriMule 600), against
a chain walk written out here (4×4 products of the model's element frames and the joint
motions: a revolute joint turns about its frame's z, a prismatic one slides along it), not
against the engine's own residual:

- at every configuration the direct model solves, every leg, walked from the base with the
  actuator values given and the passive values found, ends exactly on the platform frame it
  reports (the loops close), and the head, walked from the platform, ends on the tool frame;
- the inverse model of that tool pose reaches the same pose (fk ∘ ik ∘ fk), and gives the
  actuator values back when started near them.
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.model.chains import PRISMATIC, REVOLUTE
from pkmkit.status import Status

CHAINS = {name: pkmkit.machine(name) for name in ("tripteor-x7", "trimule-600")}


def joint_motion(kind, value):
    t = np.eye(4)
    if kind == REVOLUTE:
        c, s = np.cos(value), np.sin(value)
        t[:2, :2] = [[c, -s], [s, c]]
    elif kind == PRISMATIC:
        t[2, 3] = value
    return t


def walk(model, chain, values, start=None):
    """End frame of ``chain`` (element indices) for the joint values ``values`` (n_var,)."""
    t = np.eye(4) if start is None else start.copy()
    for e in chain:
        t = t @ model.frames[e]
        kind = model.elements[e].type
        if kind in (REVOLUTE, PRISMATIC):
            t = t @ joint_motion(kind, values[model.element_variable[e]])
    return t


def frame_of(row):
    t = np.eye(4)
    t[:3, :3] = Rotation.from_rotvec(np.array(row[3:])).as_matrix()  # records: read-only
    t[:3, 3] = row[:3]
    return t


@given(st.sampled_from(sorted(CHAINS)), st.integers(0, 2**32 - 1))
def test_legs_close_on_the_platform_and_the_head_reaches_the_tool(name, seed):
    m = CHAINS[name]
    model = m.model
    rng = np.random.default_rng(seed)
    lo, hi = model.q_min[model.actuated], model.q_max[model.actuated]
    span = np.where(np.isfinite(hi - lo), hi - lo, 0.2)
    q = m.home_q + 0.15 * span * rng.uniform(-1, 1, m.n_actuators)
    res = m.fk(q[None], full_output=True, strokes="ignore")
    if res.status[0] != Status.OK:
        pytest.skip("no assembly")  # pragma: no cover - the box is inside the workspace
    values = np.zeros(model.n_variables)
    values[model.actuated] = q
    values[~model.actuated] = res.passive[0]
    assert tuple(np.array(model.variables)[~model.actuated]) == res.passive_names
    platform = frame_of(res.platform[0])
    for leg, leg_name in zip(model.legs, model.leg_names, strict=True):
        end = walk(model, leg, values)
        np.testing.assert_allclose(end[:3, 3], platform[:3, 3], atol=1e-11, err_msg=leg_name)
        np.testing.assert_allclose(end[:3, :3], platform[:3, :3], atol=1e-11, err_msg=leg_name)
    tool = walk(model, model.head, values, start=platform)
    np.testing.assert_allclose(tool, frame_of(res.tool_frame[0]), atol=1e-11)
    # the tool point is on the tool axis (z of the tool frame) at the tool length
    axis = tool[:3, 2]
    offset = res.pose[0, :3] - tool[:3, 3]
    np.testing.assert_allclose(np.cross(offset, axis), 0.0, atol=1e-12)
    # ik ∘ fk: the inverse model reaches the same tool point and axis (in the working mode
    # it chooses), and from a start near q it finds q itself
    back = np.atleast_2d(m.ik(res.pose, strokes="ignore"))
    np.testing.assert_allclose(m.fk(back, strokes="ignore"), res.pose, atol=1e-9)
    near = np.atleast_2d(m.ik(res.pose, q0=q + 1e-3, strokes="ignore"))
    np.testing.assert_allclose(near[0], q, atol=1e-8)
