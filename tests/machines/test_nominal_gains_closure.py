"""The chord iteration of sampled defects (Monte Carlo tolerance analysis) uses the
pseudo-inverse of the rod closure's Jacobian at the nominal pose; checked here against central
differences of the strut lengths (the inverse model) over the platform pose, position and a
small spatial rotation exp(δθ) R (issue 18 §9, plausible bugs: the rotation columns with their
cross product reversed passed every test: the chord iteration still converged, only slower).
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.machines.defect_samples import nominal_gains


def _moved(pose: np.ndarray, k: int, eps: float) -> np.ndarray:
    out = pose.copy()
    if k < 3:
        out[k] += eps
    else:
        turn = np.zeros(3)
        turn[k - 3] = eps
        out[3:] = (Rotation.from_rotvec(turn) * Rotation.from_rotvec(pose[3:])).as_rotvec()
    return out


@pytest.mark.parametrize("name", ["gough-stewart", "dietmaier-hexapod"])
def test_gain_inverts_the_closure_jacobian_of_a_tilted_pose(name):
    m = pkmkit.machine(name)
    pose = m.home_pose + np.array([0.02, -0.01, 0.015, 0.08, -0.05, 0.12])
    q = m.ik(pose[None], strokes="ignore")
    assert np.isfinite(q).all()
    position, rot, gain = nominal_gains(m, q)
    np.testing.assert_allclose(position[0], pose[:3], atol=1e-9)
    np.testing.assert_allclose(rot[0], Rotation.from_rotvec(pose[3:]).as_matrix(), atol=1e-9)
    eps = 1e-6
    fd = np.column_stack([(m.ik(_moved(pose, k, eps)[None], strokes="ignore")[0]
                           - m.ik(_moved(pose, k, -eps)[None], strokes="ignore")[0]) / (2 * eps)
                          for k in range(6)])  # (m, 6): d(strut)/d(position, δθ)
    np.testing.assert_allclose(gain[0] @ fd, np.eye(6), atol=1e-6)
