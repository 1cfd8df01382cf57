"""The generated LinuxCNC module of the Verne-type module (three slides, six rods, the tilt
following the position), compiled against the stand-in headers and compared with pkmkit's
inverse model of positions and its direct model, nominal and with calibration-sized defects."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.status import Status

from .test_linuxcnc import MM, TOL, Module, _calibrated


@pytest.fixture(scope="module", params=[False, True], ids=["nominal", "calibrated"])
def verne(request, tmp_path_factory):
    machine = pkmkit.machine("verne")
    if request.param:
        machine = _calibrated(machine, seed=5)
    return Module(machine, tmp_path_factory.mktemp("verne"))


def _inverse(module, p: np.ndarray, from_home: bool) -> tuple[np.ndarray, np.ndarray]:
    world = np.zeros((len(p), 6))
    world[:, :3] = p / MM
    q = np.full((len(p), 3), np.nan)
    status = np.zeros(len(p), dtype=np.int32)
    f = module.lib.pkm_batch_inverse_from_home if from_home else module.lib.pkm_batch_inverse
    f.argtypes = module.lib.pkm_batch_inverse.argtypes
    f(len(p), 3, np.ascontiguousarray(world), q, status)
    return q * MM, status


def _forward(module, q: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    world_start = np.zeros((len(q), 6))
    world_start[:, :3] = start / MM
    world = np.zeros((len(q), 6))
    status = np.zeros(len(q), dtype=np.int32)
    module.lib.pkm_batch_forward(len(q), 3, np.ascontiguousarray(q / MM), world_start, world,
                                 status)
    return world, status


def test_inverse_matches_pkmkit_from_home(verne):
    """Positions across and beyond the default cube: the same joints (1e-9 m) where pkmkit's
    inverse model of positions finds them, refused (out of reach, not converged) where not."""
    m = verne.machine
    lo, hi = m.default_box()
    rng = np.random.default_rng(1)
    p = 0.5 * (lo + hi) + rng.uniform(-1, 1, (3000, 3)) * 1.6 * (hi - lo)
    ref = m.ik(p, full_output=True)
    ok = (np.asarray(ref.status) == Status.OK) & (np.asarray(ref.mode) == m.working_mode)
    assert 0.1 < ok.mean() < 0.9
    q, status = _inverse(verne, p, from_home=True)
    assert np.array_equal(status == 0, ok)
    assert set(np.unique(status[~ok])) <= {-1, -2, -3, -5}
    assert np.abs(q[ok] - ref.q[ok]).max() <= TOL


def test_inverse_along_a_path_from_the_previous_solution(verne):
    m = verne.machine
    rng = np.random.default_rng(2)
    p = np.cumsum(rng.normal(0, 2e-3, (500, 3)), axis=0)
    p = np.clip(p, *m.default_box())
    verne.lib.pkm_home(np.zeros(6), np.zeros(3))
    q, status = _inverse(verne, p, from_home=False)
    assert (status == 0).all()
    assert np.abs(q - m.ik(p)).max() <= TOL


def test_forward_matches_pkmkit_and_refuses_without_assembly(verne):
    """Actuator sets of reachable positions give the position back (1e-9 m; A B C = 0, the tilt
    follows); a carriage moved more than twice the rod length away from the others (no
    assembly can exist, and pkmkit finds none) is refused."""
    m = verne.machine
    lo, hi = m.default_box()
    rng = np.random.default_rng(3)
    p = 0.5 * (lo + hi) + rng.uniform(-1, 1, (2000, 3)) * 0.5 * (hi - lo)
    q = m.ik(p)
    length = m.model.rod_length.max()
    bad = m.home_q + rng.uniform(-0.1, 0.1, (1000, 3)) * length
    bad[np.arange(1000), rng.integers(0, 3, 1000)] += rng.choice([-1, 1], 1000) * rng.uniform(
        2.5, 4.0, 1000) * length
    none = np.asarray(m.fk(bad, full_output=True).status) != Status.OK
    assert none.all()
    q_all = np.concatenate([q, bad[none]])
    start = np.concatenate([p, np.zeros((none.sum(), 3))])
    start[:2000] += rng.normal(0, 1e-3, (2000, 3))  # the previous position, 1 mm off
    world, status = _forward(verne, q_all, start)
    assert (status[:2000] == 0).all() and (status[2000:] != 0).all()
    assert np.abs(world[:2000, :3] * MM - p).max() <= TOL
    assert (world[:, 3:] == 0).all()
    ref = m.fk(q, full_output=True)
    assert np.abs(ref.pose[:, :3] - p).max() <= TOL  # pkmkit's direct model agrees


def test_home_and_invalid_inputs(verne):
    m = verne.machine
    world, joints = np.zeros(6), np.zeros(3)
    assert verne.lib.pkm_home(world, joints) == 0
    assert np.abs(joints * MM - m.home_q).max() <= TOL
    assert np.abs(world[:3] * MM - m.home_pose[:3]).max() <= TOL
    p = np.zeros((2, 3))
    p[0, 0], p[1, 2] = np.nan, 1e12
    assert (_inverse(verne, p, from_home=True)[1] == -4).all()


def test_the_read_back_catches_a_rod_on_the_wrong_carriage():
    """The export's self-check reads which carriage drives each rod: a rod moved to another
    carriage in the text is caught."""
    from pkmkit.exceptions import ExportCheckError
    from pkmkit.export.linuxcnc import linuxcnc_source
    from pkmkit.export.linuxcnc_check import check_linuxcnc_source

    m = pkmkit.machine("verne")
    text = linuxcnc_source(m)
    assert check_linuxcnc_source(m, text) <= TOL
    line = "rod_joint[N_RODS] = {0, 0, 1, 1, 2, 2};"
    assert line in text
    with pytest.raises(ExportCheckError):
        check_linuxcnc_source(m, text.replace(line, "rod_joint[N_RODS] = {0, 1, 0, 1, 2, 2};"))
