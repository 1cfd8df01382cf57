"""Deflection along a move: the samples are the pose-by-pose model, the peak holds between
samples (a dense sampling is the oracle), the blocks are the program's lines."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.wrench import WrenchSeries
from pkmkit.machines.registry import machine
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.paths import line
from pkmkit.motion.timelaw import plan
from pkmkit.stiffness.along_path import path_deflection
from pkmkit.stiffness.loads import load_deflection

POCKET = Path(__file__).resolve().parents[2] / "docs" / "examples" / "pocket.nc"


@pytest.fixture(scope="module")
def pocket():
    m = machine("linear-delta-table-iv1")
    traj = plan(read_gcode(POCKET, origin=(0.0, 0.0, 0.2)), feed=0.02, accel=1.0, jerk=10.0,
                rapid_feed=0.1, period=0.25)  # coarse samples: the peak lies between them
    return m, traj, default_masses(m)


@pytest.mark.ci
def test_samples_are_the_pose_model_and_the_peak_holds_between_samples(pocket):
    m, traj, masses = pocket
    force = np.array([150.0, -60.0, -250.0])
    pd = path_deflection(m, traj, masses, force=force)
    ref = load_deflection(m, traj.x[:, :3], masses, force=force)
    np.testing.assert_allclose(pd.total, ref.total, rtol=1e-12)
    dense_t = np.linspace(0.0, traj.duration, 40001)
    dense = load_deflection(m, traj.at(dense_t).x[:, :3], masses, force=force)
    norms = np.linalg.norm(dense.total, axis=1)
    span = norms.max() - norms.min()
    assert pd.peak["value"] >= norms.max() - 1e-4 * span
    assert pd.peak["value"] <= norms.max() + 1e-3 * span  # no more than the model gives
    assert pd.peak["value"] > np.linalg.norm(pd.total, axis=1).max()  # between samples
    k = int(np.argmax(norms))
    assert abs(pd.peak["t"] - dense_t[k]) < 0.05 * traj.duration


def test_blocks_are_program_lines_with_their_sample_maxima(pocket):
    m, traj, masses = pocket
    pd = path_deflection(m, traj, masses, force=[0.0, 0.0, -300.0])
    lines = {b["line"] for b in pd.blocks}
    program = [n for n, text in enumerate(POCKET.read_text().splitlines(), 1)
               if text.startswith(("G0 ", "G1 ", "G3 "))]
    assert lines <= set(program) and len(lines) >= 8
    norms = np.linalg.norm(pd.total, axis=1)
    seg = np.asarray(traj.segment)
    for b in pd.blocks:
        assert b["max"] == pytest.approx(norms[seg == b["segment"]].max(), rel=1e-15)
        assert b["block"] == traj.path.blocks[b["segment"]]
    assert pd.peak["line"] in lines
    assert pd.gravity_peak > 0 and pd.force_peak > 0


def test_force_against_time_and_gravity_superpose():
    m = machine("orthoglide")
    traj = plan(line([-0.05, 0.0, 0.0], [0.05, 0.0, 0.0]), feed=0.05, accel=1.0, jerk=10.0,
                period=0.01)
    series = WrenchSeries(np.array([0.0, traj.duration]),
                          np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -800.0]]))
    masses = default_masses(m)
    both = path_deflection(m, traj, masses, force=series)
    weight = path_deflection(m, traj, masses)
    cut = path_deflection(m, traj, None, force=series)
    np.testing.assert_allclose(both.total, weight.total + cut.total, rtol=1e-12, atol=1e-18)
    # the force grows along the move: its deflection is zero at the start, largest at the end
    assert np.linalg.norm(cut.total[0]) == 0.0
    assert np.argmax(np.linalg.norm(cut.total, axis=1)) == len(traj.t) - 1
