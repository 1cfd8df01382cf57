"""Closed forms against the generic least-squares engine on >= 1000 random poses per machine.

The closed forms use one equivalent rod per leg; the engine closes every rod (two per
parallelogram, so the translational closure is over-constrained). Two formulations of the same
model must agree to 1e-9 m.
"""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ConvergenceError
from pkmkit.status import Status
from tests.conftest import random_poses

N = 1200
TOL = 1e-9


def test_direct_closed_form_matches_engine(preset):
    x = random_poses(preset, N, seed=11)
    q = preset.ik(x)
    assert np.isfinite(q).all()
    closed = preset.fk(q)
    numeric = preset.fk(q, method="numeric", full_output=True)
    assert (numeric.status == Status.OK).all()
    assert np.abs(closed - x).max() <= TOL
    assert np.abs(numeric.pose - closed).max() <= TOL


def test_direct_full_pose_engine_recovers_no_rotation(preset):
    x = random_poses(preset, N, seed=12)
    q = preset.ik(x)
    res = preset.fk(q, method="numeric", dof="full", full_output=True)
    assert (res.status == Status.OK).all()
    assert np.abs(res.pose - x).max() <= TOL
    assert np.abs(res.rotation).max() <= 1e-9


@pytest.mark.parametrize("name, q", [("linear-delta-ch3", [0.0, 1.0, 2.0]),
                                     ("delta", [0.0, 2.0, -2.0])])
def test_direct_full_pose_engine_flags_a_turned_platform(name, q):
    """From a poor start the six-unknown solve may close the rods with the platform turned:
    another assembly of the rods, not a mode of the translating platform. Flagged (NaN),
    never an OK translation that the legs do not close without that rotation (fuzzing)."""
    m = pkmkit.machine(name)
    res = m.fk(np.vstack([m.home_q, q]), method="numeric", dof="full", full_output=True)
    assert res.status.tolist() == [Status.OK, Status.WRONG_MODE]
    assert np.abs(res.rotation[0]).max() <= 1e-9
    assert np.isnan(res.pose[1]).all() and np.isnan(res.rotation[1]).all()
    with pytest.raises(ConvergenceError, match="platform turned by"):
        m.fk(q, method="numeric", dof="full")


def test_inverse_closed_form_matches_engine(preset):
    x = random_poses(preset, N, seed=13)
    res = preset.ik(x, method="numeric", full_output=True)
    assert (res.status == Status.OK).all()
    assert np.abs(res.q - preset.ik(x)).max() <= TOL


def test_closed_form_matches_engine_over_the_whole_working_workspace(preset):
    """Not only near home: every reachable working-mode pose of the default box (not too close
    to a parallel singularity, where the two assembly modes are closer than the warm start's
    offset)."""
    lo, hi = preset.default_box()
    x = np.random.default_rng(15).uniform(lo, hi, (4000, preset.dims))
    inv = preset.ik(x, full_output=True)
    jac = preset.jacobian(x, q=inv.q)
    keep = ((inv.status == 0) & (inv.mode == preset.working_mode)
            & (jac.parallel_measure > 2e-2) & (jac.serial_measure > 1e-3))
    assert keep.sum() > 500
    x, q = x[keep], inv.q[keep]
    np.testing.assert_allclose(preset.fk(q), x, atol=TOL)
    numeric = preset.fk(q, method="numeric", x0=x + 1e-4, full_output=True)
    assert (numeric.status == Status.OK).all()
    np.testing.assert_allclose(numeric.pose, x, atol=TOL)


def test_engine_reports_other_mode_and_unreachable_rows():
    m = pkmkit.machine("linear-delta")
    q = m.ik(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.2]]))
    q = np.vstack([q, [[10.0, 0.0, 0.0]]])  # no assembly: carriages too far apart
    other = m.fk_all(q[:2]).poses[:, 1]
    res = m.fk(q, method="numeric", x0=np.vstack([other, [[0.0, 0.0, 0.0]]]), full_output=True)
    assert res.status.tolist() == [Status.WRONG_MODE, Status.WRONG_MODE, Status.NO_ASSEMBLY]
    assert np.isnan(res.pose).all()
    same = m.fk(q[:2], method="numeric", mode="other", x0=other, full_output=True)
    assert (same.status == Status.OK).all()
    np.testing.assert_allclose(same.pose, other, atol=1e-12)


def test_user_strut_machine_from_file(tmp_path):
    """A user rod-leg machine with struts: closed forms and engine on the same model."""
    path = tmp_path / "tripod.toml"
    path.write_text(
        """
[machine]
kind = "rod-legs"
name = "strut tripod"
units = "mm"
dims = 3
home = [0, 0, -800]

[[legs]]
type = "strut"
base = [500, 0, 0]
platform = [100, 0, 0]
length = 700

[[legs]]
type = "strut"
base = [-250, 433, 0]
platform = [-50, 86.6, 0]
length = 700

[[legs]]
type = "slide"
base = [-250, -433, 0]
axis = [0, 0, 1]
platform = [-50, -86.6, 0]
length = 900
parallelogram = { width = 80, direction = [1, 0, 0] }
"""
    )
    m = pkmkit.load(path)
    x = random_poses(m, N, seed=14)
    q = m.ik(x)
    np.testing.assert_allclose(m.fk(q), x, atol=TOL)
    np.testing.assert_allclose(m.fk(q, method="numeric"), x, atol=TOL)
    np.testing.assert_allclose(m.ik(x, method="numeric"), q, atol=TOL)
    # a strut's actuator coordinate is its length beyond the nominal one
    d = x + m.model.leg_platform[0] - m.model.leg_base[0]
    np.testing.assert_allclose(q[:, 0], np.linalg.norm(d, axis=1) - 0.7, atol=1e-12)
