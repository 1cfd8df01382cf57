import re

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import InputError
from pkmkit.motion import Limits, check_limits, circle, helix, joint_trajectory, line, plan


@pytest.fixture(scope="module")
def delta_b():
    return pkmkit.machine("linear-delta-table-iv1")


def test_joint_rates_match_finite_differences(delta_b):
    tr = plan(helix([0.02, -0.01, 0.2], 0.1, pitch=0.02, turns=1.5), feed=0.15, accel=1.0,
              jerk=10.0, period=5e-4)
    jt = joint_trajectory(delta_b, tr)
    dt = np.diff(jt.t)
    assert np.allclose(dt[:-1], dt[0])
    qd_fd = np.gradient(jt.q, jt.t, axis=0)
    qdd_fd = np.gradient(jt.qd, jt.t, axis=0)
    np.testing.assert_allclose(jt.qd[2:-2], qd_fd[2:-2], atol=2e-6)
    np.testing.assert_allclose(jt.qdd[2:-2], qdd_fd[2:-2], atol=2e-3)


def test_seed_000_circle_and_helix(delta_b):
    """Table IV.1 machine, Ø300 mm at 120 mm/s: stroke ≈ 190 mm (thesis), 190.84 mm computed;
    motor speeds within ±76.3 mm/s (thesis: 69–82); helix of pitch 20 mm over 10 turns:
    stroke 381 mm (thesis ≈ 390)."""
    jt = joint_trajectory(delta_b, plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0,
                                        jerk=10.0, period=0.002))
    np.testing.assert_allclose(jt.stroke, 0.19084, atol=2e-5)
    assert np.abs(jt.qd).max() == pytest.approx(0.07634, abs=2e-5)
    hx = joint_trajectory(delta_b, plan(helix([0, 0, 0.0], 0.15, pitch=0.02, turns=10),
                                        feed=0.12, accel=1.0, jerk=10.0, period=0.01))
    assert hx.stroke.max() == pytest.approx(0.381, abs=0.001)
    assert hx.qd.min() == pytest.approx(-0.0738, abs=2e-4)
    assert hx.qd.max() == pytest.approx(0.0789, abs=2e-4)


def test_seed_000_helix_speeds_with_the_chapter_iii_dimensions():
    """Seed 000's helix motor speeds "entre 55 mm/s et 73 mm/s" (L1800; erratum 14): with the
    Chapter III dimensions (Table III.2's set A, L = 1.3 m) a Ø300 mm, 20 mm pitch helix at
    120 mm/s gives −54.0 … +59.1 mm/s (the 55 is that machine's negative peak), with Table
    IV.1's machine (set B, L = 1.04 m, the other Chapter IV figures) −73.8 … +78.9 mm/s (the
    73 is that one's): no single machine gives both printed bounds."""
    path = plan(helix([0, 0, 0.0], 0.15, pitch=0.02, turns=10), feed=0.12, accel=1.0,
                jerk=10.0, period=0.01)
    a = joint_trajectory(pkmkit.machine("linear-delta-ch3"), path)
    assert a.qd.min() == pytest.approx(-0.0540, abs=2e-4)
    assert a.qd.max() == pytest.approx(0.0591, abs=2e-4)
    b = joint_trajectory(pkmkit.machine("linear-delta-table-iv1"), path)
    assert b.qd.min() == pytest.approx(-0.0738, abs=2e-4)
    assert b.qd.max() == pytest.approx(0.0789, abs=2e-4)
    # 55 and 73 are the two machines' negative peaks (to 1 mm/s); neither machine has both:
    # set A never reaches 73 mm/s, both of set B's peaks are far above 55 mm/s
    assert abs(a.qd.min() + 0.055) < 1.1e-3 and abs(b.qd.min() + 0.073) < 1.1e-3
    assert np.abs(a.qd).max() < 0.073 - 0.01
    assert min(-b.qd.min(), b.qd.max()) > 0.055 + 0.015


def _reported_time(error: InputError) -> float:
    return float(re.search(r"first at t = ([0-9.e+-]+) s", str(error)).group(1))


def test_leaving_the_workspace_names_the_first_sample(delta_b):
    """The first sample where a leg cannot reach (radicand L² − horizontal distance² < 0,
    computed here from the seed's geometry), and the stroke exceeded before it."""
    tr = plan(line([0, 0, 0.2], [1.5, 0, 0.2]), feed=0.5, accel=2.0, jerk=20.0, period=0.01)
    with pytest.raises(InputError, match=r"leaves the workspace \(leg 3 too short by .*\): "
                       r"first at t = .*; the stroke of q\d is already exceeded") as info:
        joint_trajectory(delta_b, tr)
    angles = np.radians([0, 120, 240])
    centres = (0.7 - 0.15) * np.column_stack([np.cos(angles), np.sin(angles)])
    radicand = 1.04**2 - ((tr.x[:, None, :2] - centres[None]) ** 2).sum(axis=2)
    first = np.flatnonzero((radicand < 0).any(axis=1))[0]
    assert _reported_time(info.value) == pytest.approx(tr.t[first])


def test_crossing_into_the_other_mode_names_the_first_sample():
    """Orthoglide along the diagonal: the first sample past det A = 0 (A's rows P − C_i with
    the carriages at ρ_i e_i, ρ_i = p_i + √(L² − |p|² + p_i²))."""
    ortho = pkmkit.machine("orthoglide")
    tr = plan(line([0, 0, 0], [0.5, 0.5, 0.5]), feed=0.1, accel=1.0, jerk=10.0, period=0.01)
    with pytest.raises(InputError, match=r"crosses a parallel singularity") as info:
        joint_trajectory(ortho, tr)
    p = tr.x
    with np.errstate(invalid="ignore"):  # beyond the reach at the end of the line
        rho = p + np.sqrt(0.31**2 - (p**2).sum(axis=1, keepdims=True) + p**2)
    reach = np.isfinite(rho).all(axis=1)
    rows = p[reach, None, :] - rho[reach, :, None] * np.eye(3)[None]
    det = np.linalg.det(rows)
    first = np.flatnonzero(np.sign(det) != np.sign(det[0]))[0]
    assert _reported_time(info.value) == pytest.approx(tr.t[first])


def test_limit_report(delta_b):
    jt = joint_trajectory(delta_b, plan(circle([0, 0, 0.2], 0.15), feed=0.12, accel=1.0,
                                        jerk=10.0, period=0.002))
    report = check_limits(delta_b, jt, Limits(speed=0.05, accel=1.0, force=1e4),
                          forces=np.full_like(jt.q, 5.0))
    assert report["position"]["exceeded"] is False
    assert report["speed"]["exceeded"] and report["speed"]["first"]["excess"] > 0
    first = report["speed"]["first"]
    k = int(np.argmin(np.abs(jt.t - first["t"])))
    assert np.abs(jt.qd[k]).max() > 0.05 and (np.abs(jt.qd[:k]) <= 0.05).all()
    assert not report["accel"]["exceeded"] and not report["force"]["exceeded"]
    with pytest.raises(InputError, match="> 0"):
        check_limits(delta_b, jt, Limits(speed=-1.0))


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600", "crank-slider"])
def test_joint_chains_are_refused_with_a_typed_error(name):
    """Issue 19: joint trajectories need J̇, which joint chains do not have: an
    UnsupportedOperationError (an InputError) naming why (it was an AttributeError on a private
    field)."""
    import pkmkit
    from pkmkit.exceptions import UnsupportedOperationError
    from pkmkit.motion import circle, joint_trajectory, plan

    traj = plan(circle([0, 0, 0.9], 0.05), feed=0.05, accel=1.0, jerk=10.0, period=0.01)
    with pytest.raises(UnsupportedOperationError, match="time derivative") as info:
        joint_trajectory(pkmkit.machine(name), traj)
    assert info.value.family == "chain" and isinstance(info.value, InputError)


def _local_quadratic_oracle(m, x, xd, xdd, rotation):
    """q̇ and q̈ from the inverse model along x(s) = x + ẋ s + ẍ s²/2 by central differences
    (step 1e-4 s): an oracle independent of the velocity model."""
    h = 1e-4

    def q_at(s):
        p = x + xd * s + 0.5 * xdd * s * s
        if rotation is not None:
            p = np.hstack([p, np.broadcast_to(rotation, p.shape)])
        return m.ik(p)

    qp, q0, qm = q_at(h), q_at(0.0), q_at(-h)
    return q0, (qp - qm) / (2 * h), (qp - 2 * q0 + qm) / h ** 2


@pytest.mark.parametrize(("name", "held"), [("gough-stewart", None),
                                            ("gough-stewart", [0.02, -0.01, 0.03]),
                                            ("verne", None)])
def test_full_pose_machines_follow_a_path_at_a_held_orientation(name, held):
    """Issue 19: a full-pose machine follows a tool path at a held orientation (the home one by
    default; a Verne-type module at the orientation its rods impose); q̇, q̈ from the analytic
    velocity model agree with differences of the inverse model along the local motion."""
    import pkmkit
    from pkmkit.motion import circle, joint_trajectory, plan

    m = pkmkit.machine(name)
    traj = plan(circle(m.home_pose[:3], 0.02), feed=0.05, accel=1.0, jerk=10.0, period=0.01)
    jt = joint_trajectory(m, traj, orientation=held)
    assert jt.q.shape == jt.qd.shape == jt.qdd.shape == (traj.t.size, m.n_actuators)
    rotation = None if m.position_controlled else (m.home_pose[3:] if held is None else held)
    rows = np.linspace(0, traj.t.size - 1, 9).astype(int)
    q, qd, qdd = _local_quadratic_oracle(m, jt.x[rows], jt.xd[rows], jt.xdd[rows], rotation)
    np.testing.assert_allclose(jt.q[rows], q, atol=1e-12)
    np.testing.assert_allclose(jt.qd[rows], qd, atol=1e-8)
    np.testing.assert_allclose(jt.qdd[rows], qdd, atol=1e-6)
    assert np.abs(jt.qdd[rows]).max() > 1e-2  # the oracle compares something


def test_full_pose_path_out_of_reach_names_the_sample():
    import pkmkit
    from pkmkit.motion import joint_trajectory, line, plan

    m = pkmkit.machine("verne")
    start = m.home_pose[:3]
    traj = plan(line(start, np.add(start, [5.0, 0.0, 0.0])), feed=1.0, accel=10.0, jerk=100.0,
                period=0.01)
    with pytest.raises(InputError, match=r"the path leaves the workspace .*first at t = "):
        joint_trajectory(m, traj)
    with pytest.raises(InputError, match="cannot be held"):
        joint_trajectory(m, traj, orientation=[0, 0, 0])


def _every_builtin():
    import pkmkit

    return pkmkit.machines()


@pytest.mark.parametrize("name", _every_builtin())
def test_every_builtin_follows_a_small_circle_or_refuses_with_a_typed_error(name):
    """Issue 19: joint_trajectory works on every built-in machine whose velocity model has a
    time derivative (rod legs, translating or full-pose) and refuses the others with an
    UnsupportedOperationError — never an AttributeError. The circle is centred at home."""
    import pkmkit
    from pkmkit.exceptions import UnsupportedOperationError
    from pkmkit.motion import circle, joint_trajectory, plan

    m = pkmkit.machine(name)
    centre = np.zeros(3)
    centre[:min(3, m.dims)] = m.home_pose[:min(3, m.dims)]
    traj = plan(circle(centre, 0.002), feed=0.01, accel=0.5, jerk=5.0, period=0.01)
    if m.family == "chain":
        with pytest.raises(UnsupportedOperationError, match="not implemented"):
            joint_trajectory(m, traj)
        return
    jt = joint_trajectory(m, traj)
    assert jt.q.shape == (traj.t.size, m.n_actuators)
    assert np.isfinite(jt.q).all() and np.isfinite(jt.qdd).all()
    held = None if m.position_controlled or m.dims < 6 else m.home_pose[3:]
    x = jt.x if held is None else np.hstack([jt.x, np.broadcast_to(held, jt.x.shape)])
    np.testing.assert_allclose(jt.q, m.ik(x), atol=1e-12)
