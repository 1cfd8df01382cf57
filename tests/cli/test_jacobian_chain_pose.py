"""``jacobian`` of a joint-chain machine at a tool point and axis (``--pose``) is its Jacobian
at the actuator values of that pose: the pose is made in the test by the library's direct
model at actuator values within the strokes, and ``--pose`` must give those values and the
same matrix as ``--q`` (in mm and degrees). No ordinary test ran the ``--pose`` path of a joint
chain (a plausible bug there, the second row of a one-row array, passed the ordinary run)."""

from __future__ import annotations

import numpy as np

import pkmkit

Q_SI = np.array([0.985, 1.065, 0.985, np.radians(5.0), np.radians(20.0)])
Q_CLI = np.array([985.0, 1065.0, 985.0, 5.0, 20.0])  # mm, mm, mm, deg, deg


def test_jacobian_at_a_pose_is_the_jacobian_at_its_actuator_values(run, as_json):
    pose = np.ravel(pkmkit.machine("tripteor-x7").fk(Q_SI))
    pose_text = ",".join(f"{v:.15g}" for v in np.concatenate([pose[:3] * 1e3, pose[3:]]))
    by_pose = as_json(run("jacobian", "tripteor-x7", "--pose", pose_text, "--units", "mm",
                          "--json"))
    by_q = as_json(run("jacobian", "tripteor-x7", "--q", ",".join(map(str, Q_CLI)),
                       "--units", "mm", "--json"))
    np.testing.assert_allclose(by_pose["q"], Q_CLI, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(by_pose["J"], by_q["J"], rtol=1e-7, atol=1e-10)
