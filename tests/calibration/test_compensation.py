"""Compensation: corrected targets make the real machine reach the targets; corrected G-code
and correction tables."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.calibration.compensation import (
    check_compensation,
    correct_targets,
    grid_targets,
)
from pkmkit.calibration.controller import corrected_targets, executed
from pkmkit.calibration.corrected_program import correct_path
from pkmkit.exceptions import InputError
from pkmkit.io.compensation_files import corrected_gcode, correction_table
from pkmkit.model.defects_table import apply_defect_vector
from pkmkit.motion.gcode import read_gcode


@pytest.mark.parametrize("name", ["linear-delta", "verne", "gough-stewart", "tripteor-x7"])
def test_perfect_identification_compensates_exactly(name):
    m = pkmkit.machine(name)
    true = apply_defect_vector(m, random_defects(m, np.random.default_rng(4)))
    lo, hi = m.default_box() if hasattr(m, "default_box") else (None, None)
    if name == "tripteor-x7":
        q = np.atleast_2d(m.home_q) + np.array([[0.003, -0.002, 0.002, 0.1, 0.3],
                                                [-0.004, 0.004, 0.001, -0.1, 0.5]])
        targets = m.fk(q)
        tool = 0.15
    else:
        targets = np.asarray(lo)[:3] + (np.asarray(hi)[:3] - np.asarray(lo)[:3]) * np.array(
            [[0.3, 0.4, 0.5], [0.6, 0.5, 0.4], [0.5, 0.5, 0.5]])
        tool = 0.05 if name in ("verne", "gough-stewart") else None
    check = check_compensation(true, m, true, targets, tool_length=tool)
    assert check.before.max() > 1e-5
    assert check.after.max() < 1e-8
    corrected = corrected_targets(m, true, targets, tool)
    reached = executed(true, m, corrected, tool)
    np.testing.assert_allclose(reached[:, :3], np.atleast_2d(targets)[:, :3], atol=1e-8)


def test_corrected_gcode_reads_back(tmp_path):
    m = pkmkit.machine("linear-delta")
    true = apply_defect_vector(m, random_defects(m, np.random.default_rng(5)))
    program = "G21 G90\nG0 X0 Y0 Z50\nG1 X40 Y0 Z50 F600\nG2 X40 Y40 Z50 I0 J20\nG1 X0 Y40\n"
    path = read_gcode(program, origin=(0.0, 0.0, 0.0))
    fixed = correct_path(m, true, path, step=2e-3)
    assert len(fixed.targets) >= 4
    assert fixed.rapid[0] and not fixed.rapid[1:].any()
    text = corrected_gcode(fixed, header="test")
    back = read_gcode(text)
    ends = np.array([seg.end for seg in back.segments])
    np.testing.assert_allclose(ends, fixed.corrected, atol=1e-7)
    assert "F600" in text
    assert (fixed.correction > 1e-6).all()
    table = correction_table(fixed.targets, fixed.corrected, units="mm")
    rows = [r for r in table.splitlines() if not r.startswith("#")]
    assert rows[0] == "x,y,z,cx,cy,cz,dx,dy,dz"
    assert len(rows) == len(fixed.targets) + 1


def test_grid_and_unreachable_targets():
    g = grid_targets([0, 0, 0], [1, 2, 3], [2, 3, 1])
    assert g.shape == (6, 3)
    np.testing.assert_allclose(np.unique(g[:, 1]), [0, 1, 2])
    np.testing.assert_allclose(np.unique(g[:, 2]), [1.5])
    with pytest.raises(InputError):
        grid_targets([0, 0], [1, 1, 1], [1, 1, 1])
    m = pkmkit.machine("linear-delta")
    with pytest.raises(InputError, match=r"out of reach of the calibrated machine \(rows 2\)"):
        correct_targets(m, m, [[0, 0, 0.2], [9.0, 0, 0]])


def test_large_batches_show_a_compensating_progress_bar(capsys):
    """More than one batch (CHUNK targets) with progress on: the bar is labelled, and the
    correction through an identified model equal to the nominal one is the identity."""
    from pkmkit.calibration.compensation import CHUNK

    m = pkmkit.machine("linear-delta")
    home = np.atleast_2d(m.fk(m.home_q))[0, :3]
    x = home + 0.01 * np.random.default_rng(2).uniform(-1, 1, (CHUNK + 1, 3))
    out = correct_targets(m, m, x, progress=True)
    np.testing.assert_allclose(out, x, atol=1e-12)
    assert "compensating" in capsys.readouterr().err


def test_point_targets_of_a_tool_axis_machine_get_the_home_tool_axis():
    """Targets given as points (N, 3) for a joint-chain machine (tool point + unit tool axis)
    get the tool axis of the home configuration: a unit vector, the direct model's at home."""
    from pkmkit.calibration.controller import as_targets

    m = pkmkit.machine("tripteor-x7")
    points = m.home_pose[:3] + np.array([[0.0, 0.0, 0.0], [0.01, -0.02, 0.03]])
    targets = as_targets(m, points)
    assert targets.shape == (2, 6)
    np.testing.assert_array_equal(targets[:, :3], points)
    axis = np.atleast_2d(m.fk(m.home_q))[0, 3:]
    np.testing.assert_allclose(np.linalg.norm(axis), 1.0, atol=1e-12)
    np.testing.assert_allclose(targets[:, 3:], np.tile(axis, (2, 1)), atol=1e-12)


def test_home_offset_is_the_tool_displacement_at_home():
    """The tool-point distance at the home actuators between a machine with small defects
    and the nominal one: zero for the nominal itself, the first-order displacement J δ
    otherwise (the sensitivity is an independent formula), on a rod machine and a
    full-pose one."""
    from pkmkit.calibration.compensation import home_offset
    from pkmkit.geometric_errors.model import tool_sensitivity

    for name in ("linear-delta", "gough-stewart"):
        m = pkmkit.machine(name)
        assert home_offset(m, m) == 0.0
        delta = 1e-3 * random_defects(m, np.random.default_rng(2), magnitude={
            "m": 1e-4, "1": 1e-3, "rad": 1e-3})
        moved = apply_defect_vector(m, delta)
        sens = tool_sensitivity(m, np.atleast_2d(m.home_q))
        first_order = float(np.linalg.norm(np.asarray(sens.point)[0] @ delta))
        assert first_order > 1e-9
        assert home_offset(m, moved) == pytest.approx(first_order, rel=1e-3)


def test_refusal_reason_in_the_output_unit():
    from pkmkit.calibration.corrected_program import refusal_reason

    assert refusal_reason(2e-3, 1e-3, 1e-3, "mm") == "correction 2 mm > 1 mm"
    assert refusal_reason(float("nan"), 1e-3) == "out of reach of the calibrated machine"
    assert refusal_reason(float("inf"), 1e-3) == "an actuator out of stroke"
