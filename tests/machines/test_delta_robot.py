"""The Clavel Delta robot (crank legs) against formulations written independently here:
the inverse model by the tangent-half-angle quadratic of each arm, the direct model by
trilateration of the three elbow spheres, J by finite differences of the direct model, J̇ by
finite differences of J, and the symmetric-pose closed form."""

import math

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import UnreachablePoseError
from pkmkit.machines.delta_robot import symmetric_height

RNG = np.random.default_rng(42)


@pytest.fixture(scope="module")
def delta():
    return pkmkit.machine("delta")


def _dims(m):
    p = m.params
    return p["R"], p["r"], p["arm"], p["forearm"], np.asarray(p["angles"])


def _arm_angles_half_tangent(m, pose):
    """Both arm angles of each leg from the quadratic in t = tan(q/2) (independent of the
    library's atan2/acos form). Returns (3, 2) sorted roots."""
    big_r, small_r, arm, forearm, theta = _dims(m)
    out = []
    for th in theta:
        c, s = math.cos(th), math.sin(th)
        # effector joint in the leg frame (x' radial, y' tangent, z up)
        ex = c * pose[0] + s * pose[1] + small_r - big_r
        ey = -s * pose[0] + c * pose[1]
        ez = pose[2]
        k = ex * ex + ey * ey + ez * ez + arm * arm - forearm * forearm
        # (ex − arm cos q)² + ey² + (ez + arm sin q)² = forearm²
        # → K − 2 ex arm cos q + 2 ez arm sin q = 0, then cos/sin in t
        a2, a1, a0 = k + 2 * ex * arm, 4 * ez * arm, k - 2 * ex * arm
        roots = np.roots([a2, a1, a0])
        out.append(np.sort(2.0 * np.arctan(roots.real)))
    return np.array(out)


def _trilaterate(m, q):
    """Both effector positions for arm angles q, by trilateration of the elbow spheres shifted
    by the effector joint offsets."""
    big_r, small_r, arm, forearm, theta = _dims(m)
    centres = np.array([[(big_r + arm * math.cos(qi) - small_r) * math.cos(th),
                         (big_r + arm * math.cos(qi) - small_r) * math.sin(th),
                         -arm * math.sin(qi)] for qi, th in zip(q, theta, strict=True)])
    p1, p2, p3 = centres
    ex = (p2 - p1) / np.linalg.norm(p2 - p1)
    i = ex @ (p3 - p1)
    ey = p3 - p1 - i * ex
    ey /= np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    d = np.linalg.norm(p2 - p1)
    j = ey @ (p3 - p1)
    x = d / 2.0  # equal radii
    y = (i * i + j * j) / (2 * j) - i * x / j
    z = math.sqrt(forearm**2 - x * x - y * y)
    base = p1 + x * ex + y * ey
    return base - z * ez, base + z * ez, ez


def test_inverse_model_matches_the_half_tangent_quadratic(delta):
    poses = delta.home_pose + RNG.uniform(-0.25, 0.25, size=(40, 3))
    working = delta.ik(poses, full_output=True)
    other = delta.ik(poses, branches=-delta.model.leg_branch, full_output=True)
    checked = 0
    for k, pose in enumerate(poses):
        if working.status[k] != 0:
            continue
        expected = _arm_angles_half_tangent(delta, pose)
        got = np.sort(np.stack([working.q[k], other.q[k]], axis=1), axis=1)
        np.testing.assert_allclose(got, expected, atol=1e-10)
        checked += 1
    assert checked >= 30


def test_direct_model_matches_trilateration_and_labels_follow_the_geometry(delta):
    poses = delta.home_pose + RNG.uniform(-0.2, 0.2, size=(30, 3))
    q = delta.ik(poses)
    modes = delta.fk_all(q)
    for k in range(len(q)):
        below, above, normal = _trilaterate(delta, q[k])
        # the trilateration normal points so that "below" has a smaller z component
        if normal[2] < 0:
            below, above = above, below
        np.testing.assert_allclose(modes.poses[k, 0], below, atol=1e-10)
        np.testing.assert_allclose(modes.poses[k, 1], above, atol=1e-10)
        assert modes.labels == ("effector-below", "effector-above")
        np.testing.assert_allclose(modes.poses[k, 0], poses[k], atol=1e-10)


def test_symmetric_pose_closed_form(delta):
    for degrees in (-20.0, 0.0, 15.0, 30.0, 60.0, 85.0):
        angle = math.radians(degrees)
        x = delta.fk([angle] * 3)
        expected_z = symmetric_height(delta.params, angle)
        np.testing.assert_allclose(x, [0.0, 0.0, expected_z], atol=1e-12)
    assert delta.home_pose[2] == pytest.approx(
        symmetric_height(delta.params, delta.params["home_angle"]), abs=1e-15)
    np.testing.assert_allclose(delta.home_q, [delta.params["home_angle"]] * 3, atol=1e-12)


def test_jacobian_and_its_rate_against_finite_differences(delta):
    poses = delta.home_pose + RNG.uniform(-0.15, 0.15, size=(10, 3))
    jac = delta.jacobian(poses)
    h = 1e-6
    for k in range(len(poses)):
        for col in range(3):
            dq = np.zeros(3)
            dq[col] = h
            fd = (delta.fk(jac.q[k] + dq) - delta.fk(jac.q[k] - dq)) / (2 * h)
            np.testing.assert_allclose(jac.J[k][:, col], fd, rtol=1e-6, atol=1e-7)
    xd = RNG.normal(size=(10, 3)) * 0.3
    rates = delta.jacobian_dot(poses, xd)
    fd = (delta.jacobian(poses + h * xd).J - delta.jacobian(poses - h * xd).J) / (2 * h)
    np.testing.assert_allclose(rates.J_dot, fd, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(rates.qd, np.linalg.solve(jac.J, xd[:, :, None])[:, :, 0],
                               atol=1e-12)


def test_engine_agrees_with_the_closed_forms(delta):
    poses = delta.home_pose + RNG.uniform(-0.15, 0.15, size=(50, 3))
    q = delta.ik(poses)
    np.testing.assert_allclose(delta.ik(poses, method="numeric"), q, atol=1e-10)
    np.testing.assert_allclose(delta.fk(q, method="numeric"), poses, atol=1e-10)
    mob = delta.mobility()
    assert mob["grubler"].mobility == 3
    assert mob["grubler"].joints_by_type == {"R": 3, "S": 12}
    assert mob["instantaneous"].mobility == 3


def test_out_of_reach_names_the_leg_and_the_side(delta):
    big_r, small_r, arm, forearm, theta = _dims(delta)
    # far below: every forearm is too short
    with pytest.raises(UnreachablePoseError, match="too short") as info:
        delta.ik([0.0, 0.0, -(arm + forearm + 0.1)])
    assert info.value.shortfall == pytest.approx(
        math.hypot(big_r - small_r, arm + forearm + 0.1) - (arm + forearm), rel=1e-9)
    # effector joint 1 on the motor pivot: its farthest elbow is one arm away, forearm too long
    pivot_pose = (big_r - small_r) * np.array([math.cos(theta[0]), math.sin(theta[0]), 0.0])
    with pytest.raises(UnreachablePoseError, match=r"leg 1 .* too long") as info:
        delta.ik(pivot_pose)
    assert info.value.shortfall == pytest.approx(forearm - arm, rel=1e-12)
    assert info.value.too_long


def test_crank_legs_from_a_rod_legs_file(tmp_path, delta):
    """The same robot described leg by leg in a machine file gives the same kinematics."""
    model = delta.model
    lines = ['[machine]', 'kind = "rod-legs"', 'units = "m"',
             f'home = {model.home_pose.tolist()}']
    for i in range(3):
        lines += ['[[legs]]', 'type = "crank"', f'pivot = {model.leg_pivot[i].tolist()}',
                  f'axis = {model.leg_axis[i].tolist()}', f'base = {model.leg_base[i].tolist()}',
                  f'platform = {model.leg_platform[i].tolist()}',
                  f'length = {model.leg_length[i]}', f'branch = {model.leg_branch[i]}',
                  'stroke = [-40, 95]']
    path = tmp_path / "delta.toml"
    path.write_text("\n".join(lines))
    m = pkmkit.load(path)
    poses = delta.home_pose + RNG.uniform(-0.1, 0.1, size=(20, 3))
    np.testing.assert_allclose(m.ik(poses), delta.ik(poses), atol=1e-13)
    np.testing.assert_allclose(m.model.q_max, [math.radians(95.0)] * 3)
