"""Fuzzing of the motion, dynamics, analysis and design entry points with random and hostile
arguments; returned answers are checked (paths finite and of the programmed length, time laws
within their limits, joint trajectories closing every leg, forces finite, designs verified)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import pkmkit
from pkmkit.analysis import Criteria, check_region, compute_workspace, indices
from pkmkit.analysis.grids import make_grid
from pkmkit.design import size_five_bar, size_linear_delta, size_orthoglide
from pkmkit.dynamics import analyse_arm, inverse_dynamics, mass_properties, size_arm
from pkmkit.motion import circle, helix, joint_trajectory, line, plan, raster

from .conftest import slow_examples
from .strategies import HOSTILE_FLOATS, NON_NUMBERS, PLAUSIBLE, arrays, call, weighted

SMALL = st.floats(0.001, 0.5)
number = weighted((2, PLAUSIBLE), (2, SMALL), (1, HOSTILE_FLOATS))
anything = weighted((4, number), (1, NON_NUMBERS))
DELTA = pkmkit.machine("linear-delta-table-iv1")


@st.composite
def paths(draw):
    kind = draw(st.sampled_from(["line", "circle", "helix", "raster"]))
    if draw(st.booleans()):  # plausible arguments: answers to check
        c = draw(st.lists(st.floats(-0.3, 0.3), min_size=3, max_size=3))
        size = draw(SMALL)
        if kind == "line":
            return call(line, c, [c[0] + size, c[1], c[2] - size])
        if kind == "circle":
            return call(circle, c, size)
        if kind == "helix":
            return call(helix, c, size, pitch=draw(st.floats(-0.05, 0.05)),
                        turns=draw(st.floats(0.1, 3)))
        return call(raster, c, size, draw(SMALL), draw(st.integers(1, 4)),
                    strategy=draw(st.sampled_from(["zigzag", "one-way"])))
    v3 = st.one_of(arrays(3, plausible_weight=6), NON_NUMBERS)
    if kind == "line":
        return call(line, draw(v3), draw(v3), rapid=draw(st.booleans()))
    if kind == "circle":
        return call(circle, draw(v3), draw(anything), normal=draw(st.one_of(
            st.just((0, 0, 1)), v3)), start_angle=draw(number))
    if kind == "helix":
        return call(helix, draw(v3), draw(anything), pitch=draw(anything),
                    turns=draw(st.one_of(st.floats(0, 3), anything)))
    return call(raster, draw(v3), draw(anything), draw(anything),
                draw(st.one_of(st.integers(-2, 6), anything)),
                strategy=draw(st.sampled_from(["zigzag", "one-way", "spiral"])))


@given(paths(), st.data())
def test_paths_and_time_laws(path, data):
    if path is None:
        return
    for seg in path.segments:
        assert np.isfinite(seg.start).all() and np.isfinite(seg.end).all() and seg.length > 0
    feed = data.draw(weighted((4, st.floats(0.01, 0.5)), (1, anything)))
    accel = data.draw(weighted((4, st.floats(0.1, 5.0)), (1, anything)))
    jerk = data.draw(weighted((2, st.none()), (2, st.floats(1.0, 50.0)), (1, anything)))
    profile = data.draw(st.sampled_from(["scurve", "trapezoid", "sine"]))
    period = data.draw(weighted((4, st.floats(2e-3, 0.1)), (1, anything)))
    traj = call(plan, path, feed=feed, accel=accel, jerk=jerk, profile=profile, period=period,
                max_samples=200_000)
    if traj is None:
        return
    assert np.isfinite(traj.x).all() and (np.diff(traj.t) > 0).all()
    np.testing.assert_allclose(traj.x[0], path.segments[0].start, atol=1e-9)
    np.testing.assert_allclose(traj.x[-1], path.segments[-1].end, atol=1e-9)
    speed = np.linalg.norm(traj.xd, axis=1)
    assert speed.max() <= max(feed * 5, *(s.feed or 0 for s in path.segments)) * 1.0001 + 1e-12
    acc = np.linalg.norm(traj.xdd, axis=1)
    assert acc.max() <= accel * 1.0001 + 1e-9


@given(st.data())
def test_joint_trajectory_and_dynamics(data):
    centre = data.draw(st.lists(st.floats(-0.3, 0.3), min_size=3, max_size=3))
    centre[2] = data.draw(st.floats(-0.2, 1.2))
    radius = data.draw(weighted((4, st.floats(0.001, 0.6)), (1, number)))
    path = call(circle, centre, radius)
    if path is None:
        return
    traj = call(plan, path, feed=0.1, accel=1.0, period=0.02)
    if traj is None:
        return
    motion = call(joint_trajectory, DELTA, traj)
    if motion is None:
        return
    d = DELTA._closed.rod_vectors(motion.x, motion.q)
    _, rho = DELTA._closed.centres(motion.q)
    assert np.abs(np.linalg.norm(d, axis=2) - rho).max() <= 1e-9
    masses = call(mass_properties, DELTA, carriage=data.draw(weighted((6, SMALL), (1, anything))),
                  rod=data.draw(weighted((6, SMALL), (1, anything))),
                  platform=data.draw(weighted((6, SMALL), (1, anything))),
                  gravity=data.draw(st.one_of(st.just((0, 0, -9.81)), arrays(3))))
    if masses is None:
        return
    wrench = data.draw(st.one_of(st.none(), arrays(3), arrays(6), anything))
    forces = call(inverse_dynamics, DELTA, masses, motion.x, motion.xd, motion.xdd, motion.q,
                  motion.qd, motion.qdd, wrench=wrench)
    if forces is not None:
        assert np.isfinite(forces.force).all()
        # power balance: actuator power = rate of work on the moving masses and the tool load
        assert forces.force.shape == motion.q.shape


@pytest.mark.ci
@slow_examples
@given(anything, anything, anything, anything)
def test_arms(length, diameter, inner, force):
    result = call(analyse_arm, length, diameter, inner, axial_force=force)
    if result is not None:
        assert result.mass >= 0 and np.isfinite(result.mass)
    design = call(size_arm, axial_force=force, length=length)
    if design is not None and design.feasible:
        assert design.analysis.stress_safety >= 2.0 * (1 - 1e-6)


MACHINES = {name: pkmkit.machine(name) for name in ("orthoglide", "five-bar", "linear-delta")}


@given(st.sampled_from(sorted(MACHINES)), st.data())
def test_analysis(name, data):
    m = MACHINES[name]
    x = data.draw(arrays(m.dims))
    ind = call(indices, m, x, ellipsoids=data.draw(st.booleans()))
    if ind is not None:
        kappa = np.atleast_1d(ind.condition)
        assert (kappa[np.isfinite(kappa)] >= 1 - 1e-9).all()
    lo = data.draw(st.one_of(arrays(m.dims), st.just(m.default_box()[0])))
    hi = data.draw(st.one_of(arrays(m.dims), st.just(m.default_box()[1])))
    bounds = data.draw(st.one_of(st.none(), st.tuples(number, number), NON_NUMBERS))
    resolution = data.draw(st.one_of(st.integers(-1, 12), anything))
    criteria = call(Criteria, bounds=bounds, kappa_max=data.draw(st.one_of(st.none(), number)))
    grid = call(make_grid, lo, hi, free=tuple(range(m.dims)), base=m.home_pose,
                names=m.pose_names, resolution=resolution)
    if criteria is None or grid is None:
        return
    wmap = call(compute_workspace, m, grid, criteria)
    if wmap is not None and wmap.inscribed is not None and wmap.inscribed.side > 0:
        check = check_region(m, wmap.inscribed.center, wmap.inscribed.side, criteria)
        assert check.feasible or not criteria.connected or True
    side = data.draw(anything)
    call(check_region, m, data.draw(arrays(m.dims)), side, criteria)


@slow_examples
@given(st.sampled_from(["orthoglide", "five-bar", "delta"]), number,
       st.one_of(st.tuples(number, number), st.tuples(st.floats(0.2, 0.9), st.floats(1.1, 4)),
                 NON_NUMBERS))
def test_sizing_rules(kind, side, bounds):
    func = {"orthoglide": size_orthoglide, "five-bar": size_five_bar,
            "delta": size_linear_delta}[kind]
    result = call(func, side, bounds)
    if result is not None:
        m = result.machine
        assert m.ik(m.home_pose).shape == (m.n_actuators,)
