"""``workspace``, ``map``, ``analyze`` and ``path`` on full-pose and joint-chain machines."""

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.exceptions import InputError
from pkmkit.spatial.rotation import rotvec_to_matrix


def _hexapod_feasible(m, points):
    """Independent oracle: a hexapod pose is in its workspace when every strut length
    |p + R b_i − a_i| lies within the strokes."""
    rot = rotvec_to_matrix(points[:, 3:])
    tips = points[:, None, :3] + np.einsum("nij,kj->nki", rot, m.model.rod_platform)
    lengths = np.linalg.norm(tips - m.model.rod_base[None], axis=2)
    lo, hi = m.model.q_min[m.model.rod_actuator], m.model.q_max[m.model.rod_actuator]
    return ((lengths >= lo) & (lengths <= hi)).all(axis=1)


@pytest.mark.ci
def test_hexapod_workspace_at_a_held_orientation_matches_the_strut_lengths(run, as_json):
    m = pkmkit.machine("gough-stewart")
    data = as_json(run("workspace", "gough-stewart", "--box", "-800,800,-800,800,300,1300",
                       "--slice", "z=800", "--orientation", "10,0,0", "--resolution", "41",
                       "--units", "mm", "--json"))
    assert data["orientation"]["angles_deg"] == pytest.approx([10, 0, 0], abs=1e-12)
    rotvec = np.radians([10.0, 0.0, 0.0])
    assert data["orientation"]["rotation_vector"] == pytest.approx(rotvec, abs=1e-15)
    g = data["grid"]
    assert g["free"] == ["x", "y"] and g["fixed"] == {"z": pytest.approx(800.0)}
    grid = make_grid(np.array(g["lower"]) / 1000, np.array(g["upper"]) / 1000,
                     free=(0, 1), base=np.concatenate([[0.0, 0.0, 0.8], rotvec]),
                     names=m.pose_names, resolution=41)
    counts = data["points_per_criterion"]
    assert counts["strokes"] == int(_hexapod_feasible(m, grid.points).sum())
    assert 0 < data["feasible_points"] <= counts["strokes"]
    assert data["faces_reached"] == []
    assert data["inscribed"]["center"][2] == pytest.approx(800.0)


def test_default_box_is_widened_until_the_workspace_fits(run, as_json):
    data = as_json(run("workspace", "gough-stewart", "--resolution", "9", "--json"))
    assert data["grid"]["default_box_widened"] >= 1
    assert data["faces_reached"] == []
    lo, hi = pkmkit.machine("gough-stewart").default_box()
    assert (np.array(data["grid"]["lower"]) <= lo + 1e-12).all()
    assert (np.array(data["grid"]["upper"]) >= hi - 1e-12).all()


@pytest.mark.ci
def test_verne_workspace_over_positions(run, as_json):
    data = as_json(run("workspace", "verne", "--box", "-300,300,-300,300", "--slice", "z=-300",
                       "--units", "mm", "--resolution", "9", "--json"))
    assert data["grid"]["free"] == ["x", "y"] and "orientation" not in data
    m = pkmkit.machine("verne")
    axis = np.linspace(-0.3, 0.3, 9)
    gx, gy = np.meshgrid(axis, axis, indexing="ij")
    points = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, -0.3)])
    q = m.ik(points)
    counts = data["points_per_criterion"]
    assert counts["reachable"] == 9 ** 2  # the module reaches this whole square...
    inside = ((q >= m.model.q_min) & (q <= m.model.q_max)).all(axis=1)
    assert counts["strokes"] == int(inside.sum()) < 9 ** 2  # ...not all within its strokes
    result = run("workspace", "verne", "--orientation", "1,0,0")
    assert result.exit_code != 0 and "takes no orientation" in result.output


def test_joint_chain_workspace_counts_passive_joint_ranges(run, as_json):
    m = pkmkit.machine("tripteor-x7")
    # every point's criteria (by default a flood fill from home evaluates the part kept)
    data = as_json(run("workspace", "tripteor-x7", "--resolution", "7", "--whole-grid",
                       "--json"))
    counts = data["points_per_criterion"]
    assert 0 < counts["strokes"] < counts["reachable"]
    assert data["inscribed"] is None or data["inscribed"]["rtol"] is None
    assert data["orientation"]["tool_axis"] == pytest.approx(m.home_pose[3:], abs=1e-12)
    # the stroke mask against the joints of the direct model at the solutions
    g = data["grid"]
    grid = make_grid(np.array(g["lower"]), np.array(g["upper"]), free=(0, 1, 2), base=m.home_pose,
                     names=m.pose_names, resolution=7)
    q = m.ik(grid.points)
    ok = np.isfinite(q).all(axis=1)
    assert counts["reachable"] == int(ok.sum())
    res = m.fk(q[ok], full_output=True, strokes="ignore")
    model = m.model
    act = np.flatnonzero(model.actuated)
    passive = [model.variables.index(n) for n in res.passive_names]
    inside = ((q[ok] >= model.q_min[act]) & (q[ok] <= model.q_max[act])).all(axis=1)
    inside &= ((res.passive >= model.q_min[passive])
               & (res.passive <= model.q_max[passive])).all(axis=1)
    assert counts["strokes"] == int(inside.sum())


@pytest.mark.ci
def test_joint_chain_map_and_its_indices(run, tmp_path, as_json):
    bad = run("map", "tripteor-x7", "--index", "serial_distance", "--slice", "z=1.84",
              "--out", tmp_path / "s.png")
    assert bad.exit_code != 0 and "not defined for a joint-chain machine" in bad.output
    data = as_json(run("map", "tripteor-x7", "--index", "condition", "--slice", "z=1.84",
                       "--range", "-0.12,-0.09,-0.54,-0.51", "--resolution", "11",
                       "--out", tmp_path / "c.png", "--json"))
    m = pkmkit.machine("tripteor-x7")
    at = np.concatenate([np.array(data["at_min"])[:3], m.home_pose[3:]])
    kappa = m.jacobian(m.ik(at, strokes="ignore")).condition
    assert data["min"] == pytest.approx(float(np.ravel(kappa)[0]), rel=1e-9)


def test_slices_name_positions_only(run, tmp_path):
    result = run("map", "gough-stewart", "--index", "condition", "--slice", "rx=0",
                 "--out", tmp_path / "m.png")
    assert result.exit_code != 0 and "NAME in x, y, z" in result.output


def test_analyze_full_pose_and_chain(run, as_json):
    data = as_json(run("analyze", "gough-stewart", "--pose", "100,0,800,5,0,0", "--units", "mm",
                       "--json"))
    assert data["pose"] == pytest.approx([100, 0, 800, 5, 0, 0], abs=1e-9)
    m = pkmkit.machine("gough-stewart")
    from pkmkit.spatial.poses import pose_from_angles

    x = pose_from_angles([0.1, 0.0, 0.8], [5.0, 0.0, 0.0], "xyz", degrees=True)
    assert data["q"] == pytest.approx(m.ik(x) * 1000, rel=1e-12)
    verne = as_json(run("analyze", "verne", "--pose", "100,0,0", "--units", "mm", "--json"))
    assert len(verne["velocity_factors"]) == 3
    result = run("analyze", "tripteor-x7")
    assert result.exit_code != 0 and "pkmkit jacobian tripteor-x7" in result.output


def test_path_refuses_machines_without_a_trajectory_model(run):
    result = run("path", "verne", "--circle", "0,0,0,0.05", "--feed", "0.05", "--accel", "1")
    assert result.exit_code != 0 and "full-pose machine" in result.output


def test_pose_frame_validates_orientations():
    from pkmkit.analysis.grids import pose_frame

    chain = pkmkit.machine("tripteor-x7")
    frame = pose_frame(chain, [0.0, 0.0, 2.0])
    np.testing.assert_allclose(frame.base[3:], [0, 0, 1])
    with pytest.raises(InputError, match="tool axis must not be zero"):
        pose_frame(chain, [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="it only translates"):
        pose_frame(pkmkit.machine("orthoglide"), [0.0, 0.0, 0.0])
    with pytest.raises(InputError, match="needs 3 finite values"):
        pose_frame(pkmkit.machine("gough-stewart"), [0.0, np.nan, 0.0])
