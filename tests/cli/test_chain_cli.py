"""``pkmkit fk`` on joint-chain machines (docs/joint-chains.md): the JSON fields against the
Python API, the frames' angles against their rotation vectors, and the documented example file
``docs/examples/planar-3rpr.toml`` against an independent planar computation."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit

EXAMPLE = Path(__file__).parents[2] / "docs" / "examples" / "planar-3rpr.toml"


@pytest.mark.parametrize("convention", ["xyz", "ZYX"])
def test_fk_json_frames_give_angles_in_the_convention(run, as_json, convention):
    data = as_json(run("fk", "tripteor-x7", "--units", "mm", "--q",
                       "982.802,1063.747,989.454,10,30", "--angles", convention, "--json"))
    m = pkmkit.machine("tripteor-x7")
    q = np.array([0.982802, 1.063747, 0.989454, np.radians(10), np.radians(30)])
    r = m.fk(q, full_output=True)
    np.testing.assert_allclose(data["pose"], r.pose[:3] * 1000, atol=1e-9)
    np.testing.assert_allclose(data["tool_axis"], r.pose[3:], atol=1e-12)
    np.testing.assert_allclose(list(data["passive"].values()), np.degrees(r.passive),
                               atol=1e-9)
    for key, frame in (("tool_frame", r.tool_frame), ("platform", r.platform)):
        got = data[key]
        assert got["convention"] == convention
        np.testing.assert_allclose(got["position"], frame[:3] * 1000, atol=1e-9)
        np.testing.assert_allclose(got["rotation_vector"], frame[3:], atol=1e-12)
        from_angles = Rotation.from_euler(convention, got["angles"], degrees=True).as_matrix()
        turn = Rotation.from_rotvec(np.array(frame[3:]))  # scipy: writeable buffers only
        np.testing.assert_allclose(from_angles, turn.as_matrix(), atol=1e-12)


def test_planar_example_closes_its_legs_on_the_platform(run, as_json):
    """The example's direct model against the planar geometry: |A_i B_i| = q_i, with B_i the
    platform points turned by the platform angle read from the tool axis."""
    base = np.array([[0.0, 0.0], [600.0, 0.0], [300.0, 520.0]])
    platform = 100.0 * np.array([[np.cos(b), np.sin(b)] for b in np.radians([-90, 30, 150])])
    q = np.array([300.0, 280.0, 320.0])
    data = as_json(run("fk", EXAMPLE, "--units", "mm", "--q", ",".join(map(str, q)),
                       "--json"))
    axis = np.array(data["tool_axis"])
    assert abs(axis[2]) < 1e-12
    angle = np.arctan2(axis[1], axis[0])
    centre = np.array(data["pose"][:2]) - 50.0 * axis[:2]  # tool length 50 mm along the axis
    turn = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    ends = centre + platform @ turn.T
    np.testing.assert_allclose(np.linalg.norm(ends - base, axis=1), q, atol=1e-9)
    assert data["closure_residual"] < 1e-9
    m = pkmkit.load(EXAMPLE)
    assert m.hyperstatism().hyperstatism == 6 and m.hyperstatism().mobility == 3
