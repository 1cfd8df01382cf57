"""Tilt-and-torsion angles, the hexapod's orientation workspace and the Verne module's coupled
orientation."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.analysis.orientation import (
    coupled_orientation,
    orientation_workspace,
    tilt_torsion_angles,
    tilt_torsion_rotation,
)
from pkmkit.exceptions import InputError


def test_tilt_and_torsion_round_trip_and_meaning():
    rng = np.random.default_rng(3)
    az, ti, to = rng.uniform(-3, 3, 50), rng.uniform(0.01, 1.5, 50), rng.uniform(-3, 3, 50)
    rot = tilt_torsion_rotation(az, ti, to)
    a, t, s = tilt_torsion_angles(rot)
    np.testing.assert_allclose(t, ti, atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (a - az))), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.angle(np.exp(1j * (s - to))), 0.0, atol=1e-10)
    # the tilt is the angle between the platform z axis and the base z axis
    z = rot.apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(np.arccos(z[:, 2]), ti, atol=1e-12)
    # pure torsion: a rotation about z by σ
    np.testing.assert_allclose(tilt_torsion_rotation(0.0, 0.0, 0.4).as_rotvec(), [[0, 0, 0.4]],
                               atol=1e-15)


@pytest.mark.slow  # 15-40 s: .ci/run runs it (-m "slow or ci")
def test_hexapod_orientation_workspace_has_its_symmetry_and_a_true_boundary():
    m = pkmkit.machine("gough-stewart")
    ws = orientation_workspace(m, m.home_pose[:3], max_tilt=np.radians(85), azimuths=36,
                               tilts=171)
    assert (ws.max_tilt < np.radians(80)).all()  # the strokes bound the tilt
    assert ws.feasible[:, 0].all()  # untilted at home is feasible
    # three-fold symmetry of the layout: 120° apart, the same largest tilt
    np.testing.assert_allclose(ws.max_tilt, np.roll(ws.max_tilt, 12), atol=1e-12)
    # just beyond the largest tilt a stroke fails or the assembly mode changes (a parallel
    # singularity was crossed), checked directly; just before it neither
    for k in range(0, 36, 5):
        for theta, inside in ((ws.max_tilt[k], True), (ws.max_tilt[k] + ws.resolution, False)):
            pose = np.r_[m.home_pose[:3],
                         tilt_torsion_rotation(ws.azimuth[k], theta).as_rotvec()[0]]
            q = m.ik(pose)
            in_stroke = ((q >= m.model.q_min) & (q <= m.model.q_max)).all()
            jac = m.jacobian(pose)
            same_mode = np.sign(jac.det_A) == m.working_mode and jac.status == "regular"
            assert (in_stroke and same_mode) == inside, (k, theta)


def test_verne_coupled_orientation_zero_on_the_symmetry_plane():
    m = pkmkit.machine("verne")
    xs = np.linspace(-0.15, 0.15, 7)
    pts = np.column_stack([xs, np.full(7, 0.05), np.full(7, -0.05)])
    c = coupled_orientation(m, pts)
    assert c.tilt[3] < 1e-12 and c.angle[3] < 1e-12
    assert (c.angle[[0, 1, 2, 4, 5, 6]] > 1e-4).all()
    np.testing.assert_allclose(c.angle, c.angle[::-1], atol=1e-12)  # mirror symmetry
    np.testing.assert_allclose(np.linalg.norm(Rotation.from_rotvec(c.rotation).as_rotvec(),
                                              axis=1), c.angle)


def test_refusals():
    with pytest.raises(InputError, match="six actuators"):
        orientation_workspace(pkmkit.machine("verne"), [0, 0, 0])
    with pytest.raises(InputError, match="fewer than six"):
        coupled_orientation(pkmkit.machine("gough-stewart"), [[0, 0, 0.8]])
