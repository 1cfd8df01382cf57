"""The TriMule's two-branch head in the generated LinuxCNC module and in pkmkit: (Q4, Q5) and
(Q4 ± π, −Q5) give the same tool axis; at and near the tool axis along the Q4 axis (Q5 = 0, the
vertical axis at home, where Q4 leaves the axis unchanged) both take the branch whose Q4 is
nearest the start's (:mod:`pkmkit.machines.head_branches`)."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.head_branches import wrapped
from pkmkit.status import Status

from .test_linuxcnc_chains import TOL, ChainModule, calibrated


@pytest.fixture(scope="module", params=[False, True], ids=["nominal", "calibrated"])
def module(request, tmp_path_factory):
    m = pkmkit.machine("trimule-600")
    if request.param:
        m = calibrated(m, seed=3)
    return ChainModule(m, tmp_path_factory.mktemp("trimule"))


def _tilted(point: np.ndarray, tilt: float, azimuths: np.ndarray) -> np.ndarray:
    """Targets at ``point`` whose tool axis leans ``tilt`` rad from +z at each azimuth."""
    axis = np.stack([np.sin(tilt) * np.cos(azimuths), np.sin(tilt) * np.sin(azimuths),
                     np.full(len(azimuths), np.cos(tilt))], axis=1)
    return np.hstack([np.tile(point, (len(azimuths), 1)), axis])


def _targets(m) -> np.ndarray:
    """The vertical tool axis at tool points about home, and axes leaning 1e-9 to 0.02 rad from
    it at azimuths every 25° (no tie at ±90°), and the tool axis along the platform's z axis
    (Q5 = 0) at tilted platforms with Q4 all round."""
    home = m.home_pose[:3]
    rng = np.random.default_rng(4)
    points = home + rng.uniform(-0.05, 0.05, (12, 3))
    rows = [_tilted(p, 0.0, np.zeros(1)) for p in points]
    azimuths = np.radians(np.arange(5.0, 360.0, 25.0))
    rows += [_tilted(p, tilt, azimuths) for p in points[:3] for tilt in (1e-9, 1e-6, 1e-3, 2e-2)]
    q = np.tile(m.home_q, (16, 1))
    q[:, :3] += rng.uniform(-0.03, 0.03, (16, 3))
    q[:, 3], q[:, 4] = rng.uniform(-np.pi, np.pi, 16), 0.0
    rows.append(m.fk(q))
    return np.vstack(rows)


@pytest.mark.ci
def test_from_home_both_take_the_branch_nearest_home(module):
    """From home (Q4 = 0): the module's joints are pkmkit's (1e-9 m, rad), every target
    reached, and |Q4| ≤ π/2 (the branch nearest home's Q4)."""
    m = module.machine
    x = _targets(m)
    ref = m.ik(x, full_output=True, strokes="ignore")
    assert (np.asarray(ref.status) == Status.OK).all()
    q, status = module.inverse(x)
    assert (status == 0).all()
    assert np.abs(q - ref.q).max() <= TOL
    assert np.abs(q[:, 3]).max() <= np.pi / 2
    assert np.abs(m.fk(q) - x).max() <= TOL


@pytest.mark.parametrize("turn", [1.0, -1.2])
def test_from_a_start_both_take_the_branch_nearest_its_q4(module, turn):
    """From a configuration with Q4 = ``turn`` and Q5 = 0 (the module's last one, pkmkit's
    q0): the same joints, on the branch whose Q4 is nearest ``turn`` (within Q4's ±180°
    stroke from these starts)."""
    m = module.machine
    start = m.home_q.copy()
    start[3] = turn
    x = _targets(m)
    ref = m.ik(x, q0=start, full_output=True, strokes="refuse")
    assert (np.asarray(ref.status) == Status.OK).all()
    q = np.full((len(x), m.n_actuators), np.nan)
    status = np.zeros(len(x), dtype=int)
    for i, row in enumerate(x):  # each from the start: the forward model leaves it as last
        assert module.forward(start[None])[1][0] == 0
        q[i], status[i] = (v[0] for v in module.inverse(row[None], from_home=False))
    assert (status == 0).all()
    assert np.abs(q - ref.q).max() <= TOL
    assert np.abs(wrapped(q[:, 3] - turn)).max() <= np.pi / 2


def test_pkmkit_keeps_the_branch_it_is_started_on():
    """Along a path through Q5 = 0 started on either branch, pkmkit's inverse model follows the
    branch whose Q4 is nearest the previous one: the path's own joints."""
    m = pkmkit.machine("trimule-600")
    q = np.tile(m.home_q, (41, 1))
    q[:, 3] = 0.7
    q[:, 4] = np.linspace(-0.2, 0.2, 41)  # the tilt through 0
    x = m.fk(q)
    for path in (q, np.column_stack([q[:, :3], q[:, 3] - np.pi, -q[:, 4]])):
        reached = m.ik(x[0], q0=path[0])
        previous = reached
        out = [reached]
        for row in x[1:]:
            previous = m.ik(row, q0=previous)
            out.append(previous)
        out = np.array(out)
        assert np.abs(m.fk(out) - x).max() <= TOL
        assert np.abs(wrapped(out[:, 3] - path[:, 3])).max() < 0.1
