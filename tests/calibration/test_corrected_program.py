"""Corrected G-code programs: the original's moves, in order, with their motion types; rapids
corrected at their end points only; feed moves subdivided only where the correction needs it;
blocks whose correction exceeds the bound refused with their line."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.calibration.controller import corrected_targets, executed
from pkmkit.calibration.corrected_program import CorrectionRefused, correct_path
from pkmkit.exceptions import InputError
from pkmkit.io.compensation_files import corrected_gcode
from pkmkit.model.defects_table import apply_defect_vector
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.paths import Arc

#: A pocket contour at the linear Delta's home height (docs/examples/pocket.nc).
POCKET = """(pocket)
G21 G90 G17
G0 X-50 Y-40 Z5
G1 Z0 F600
G1 X40 F1200
G3 X50 Y-30 R10
G1 Y30
G3 X40 Y40 I-10 J0
G1 X-40
G3 X-50 Y30 R10
G1 Y-30
G3 X-40 Y-40 I10 J0
G0 Z5
"""
ORIGIN = (0.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def machines():
    m = pkmkit.machine("linear-delta")
    true = apply_defect_vector(m, random_defects(m, np.random.default_rng(0)))
    return m, true


def _distance_to(seg, points: np.ndarray) -> np.ndarray:
    """Exact distance of ``points (k, 3)`` to a programmed segment (line or plane arc)."""
    if isinstance(seg, Arc):
        rel = points - seg.center
        axial = rel @ seg.normal
        radial = np.linalg.norm(rel - np.outer(axial, seg.normal), axis=1)
        return np.hypot(radial - seg.radius, axial)
    d = seg.end - seg.start
    u = np.clip((points - seg.start) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(points - seg.start - np.outer(u, d), axis=1)


def test_program_keeps_the_original_moves_and_types(machines):
    """The original (11 blocks: G0, G1…, G3…, G0) — the old corrected program began with ~65
    rapids from the work origin and cut every rapid into 1 mm pieces."""
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=3e-5)
    kinds = ["G0", "G1", "G1", "G3", "G1", "G3", "G1", "G3", "G1", "G3", "G0"]
    assert fixed.kind.tolist() == kinds  # no subdivision needed at 30 µm (11 µm at most)
    assert fixed.subdivided == 0 and fixed.correction.max() > 1e-3
    assert fixed.source.tolist() == list(path.source)
    assert fixed.text[3] == "G3 X50 Y-30 R10"
    first = corrected_targets(nominal, true, [[-0.05, -0.04, 0.005]])[0]
    np.testing.assert_allclose(fixed.corrected[0], first, atol=1e-12)
    np.testing.assert_allclose(fixed.targets[0], [-0.05, -0.04, 0.005], atol=1e-15)
    text = corrected_gcode(fixed, origin=ORIGIN)
    back = read_gcode(text, origin=ORIGIN)
    assert len(back.segments) == len(path.segments)
    assert [s.rapid for s in back.segments] == [s.rapid for s in path.segments]
    assert [isinstance(s, Arc) for s in back.segments] == [isinstance(s, Arc)
                                                           for s in path.segments]
    assert [np.sign(getattr(s, "sweep", 0.0)) for s in back.segments] == \
        [np.sign(getattr(s, "sweep", 0.0)) for s in path.segments]


@pytest.mark.parametrize("tolerance", [1e-5, 1e-6])
def test_the_calibrated_machine_follows_the_programmed_path(machines, tolerance):
    """Oracle: the calibrated (true) machine driven by the nominal controller along the
    corrected feed moves stays within the tolerance (+ the output rounding of 0.1 µm) of the
    programmed segments; the uncorrected program misses them by far more."""
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=tolerance, step=5e-4)
    assert fixed.deviation <= tolerance
    back = read_gcode(corrected_gcode(fixed, origin=ORIGIN), origin=ORIGIN)
    assert len(back.segments) == len(fixed.kind)
    worst = 0.0
    for k, seg in enumerate(back.segments):
        if seg.rapid:
            continue
        original = path.segments[path.source.index(int(fixed.source[k]))]
        commanded = seg.evaluate(np.linspace(0.0, seg.length, 200))[0]
        reached = executed(true, nominal, commanded)[:, :3]
        worst = max(worst, _distance_to(original, reached).max())
    assert worst < tolerance + 2e-7
    plain = executed(true, nominal, path.segments[2].evaluate(np.linspace(0, 0.09, 50))[0])
    assert _distance_to(path.segments[2], plain[:, :3]).min() > 1e-4  # 0.15 mm and more


def test_only_feed_moves_that_need_it_are_subdivided(machines):
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=1e-7, step=5e-4)
    assert len(fixed.kind) > len(path.segments)
    for k in np.flatnonzero(fixed.rapid):  # a rapid is one move, whatever the tolerance
        assert np.sum(fixed.source == fixed.source[k]) == 1
    # every move of a subdivided block has the block's type
    for line in np.unique(fixed.source):
        assert len(set(fixed.kind[fixed.source == line])) == 1


def test_a_correction_beyond_the_bound_refuses_its_blocks(machines):
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    sizes = np.linalg.norm(correct_path(nominal, true, path).correction)
    assert sizes > 0
    bound = float(np.median(correct_path(nominal, true, path).correction))
    with pytest.raises(CorrectionRefused) as info:
        correct_path(nominal, true, path, max_correction=bound)
    refused = info.value.blocks
    assert 0 < len(refused) < len(path.segments)
    lines = [line for line, _, _ in refused]
    assert set(lines) <= set(path.source)
    assert all(c > bound for _, _, c in refused)
    assert "line " in str(info.value)


@pytest.mark.parametrize("bad", [0.0, -1e-3, np.nan, np.inf])
def test_step_tolerance_and_bound_must_be_positive(machines, bad):
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    for name in ("step", "tolerance", "max_correction"):
        with pytest.raises(InputError, match="must be a finite number > 0"):
            correct_path(nominal, true, path, **{name: bad})


def test_a_step_needing_too_many_points_is_refused_up_front(machines):
    nominal, true = machines
    with pytest.raises(InputError, match="increase the step"):
        correct_path(nominal, true, read_gcode(POCKET, origin=ORIGIN), step=1e-9)


def test_arcs_in_every_plane_and_helices_read_back(machines):
    """G2 and G3 in G17, G18 and G19, a helix: the corrected program reads back as the same
    motion types, in order, ending at the corrected points."""
    nominal, true = machines
    program = ("G21 G90\nG0 X0 Y0 Z5\nG1 Z0 F600\nG1 X20\nG2 X0 Y-20 Z-5 I-20 J0\n"
               "G18 G3 X-20 Z-5 I-10 K0\nG19 G2 Y0 Z-5 J10 K0\nG17 G3 X-20 Y0 I0 J10\n")
    path = read_gcode(program, origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=1e-7, step=5e-4)
    back = read_gcode(corrected_gcode(fixed, origin=ORIGIN, decimals=6), origin=ORIGIN)
    np.testing.assert_allclose([s.end for s in back.segments], fixed.corrected, atol=1e-9)
    kinds = [("G0" if s.rapid else "G1") if not isinstance(s, Arc)
             else ("G2" if s.sweep < 0 else "G3") for s in back.segments]
    assert kinds == fixed.kind.tolist()
    assert [k for i, k in enumerate(kinds) if i == 0 or k != kinds[i - 1]] == \
        ["G0", "G1", "G2", "G3", "G2", "G3"]
    normals = [np.abs(s.normal).argmax() for s in back.segments if isinstance(s, Arc)]
    assert set(normals) == {0, 1, 2}


def test_a_program_starting_with_an_arc_is_refused(machines):
    nominal, true = machines
    with pytest.raises(InputError, match=r"line 2 .*starts with an arc"):
        correct_path(nominal, true, read_gcode("G21 G90 F600\nG2 X10 Y10 I10 J0\n",
                                               origin=ORIGIN))


def test_blocks_commanding_an_actuator_beyond_its_stroke_are_refused(machines):
    """900 mm lower the slides would have to run ~0.45 m below their 0.7 m stroke end."""
    nominal, true = machines
    with pytest.raises(CorrectionRefused) as info:
        correct_path(nominal, true, read_gcode(POCKET, origin=(0.0, 0.0, -0.9)))
    strokes = info.value.strokes
    assert len(strokes) == len(info.value.blocks) == 11
    line, text, actuator, by, angular = strokes[0]
    assert (line, text) == (3, "G0 X-50 Y-40 Z5") and actuator in nominal.actuator_names
    assert not angular
    q = true.ik(np.array([-0.05, -0.04, -0.895]))
    assert by == pytest.approx(0.7 - q.min(), abs=2e-3)


def test_a_first_feed_move_is_corrected_at_its_end_only(machines):
    """Its start is wherever the machine is, not the work origin the reader assumes: no point
    on a line from the origin is ever sent."""
    nominal, true = machines
    path = read_gcode("G21 G90\nG1 X40 Y30 Z5 F600\nG1 X-40\n", origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=1e-8, step=5e-4)
    assert fixed.source.tolist().count(2) == 1 and fixed.source.tolist().count(3) > 1
    np.testing.assert_allclose(fixed.corrected[0],
                               corrected_targets(nominal, true, [[0.04, 0.03, 0.005]])[0],
                               atol=1e-12)
