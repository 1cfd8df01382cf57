"""A G-code program corrected for the calibrated machine's gravity sag as well
(``correct_path(..., aim=LoadedAim(...))``, ``pkmkit compensate --gcode --gravity``): the
original's moves with their types, and the *loaded* tool point of the calibrated machine on the
programmed path."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration import random_defects
from pkmkit.calibration.controller import commanded_q, reached
from pkmkit.calibration.corrected_program import CorrectionRefused, correct_path
from pkmkit.calibration.gravity import LoadedAim, gravity_deflection
from pkmkit.io.compensation_files import corrected_gcode
from pkmkit.motion.gcode import read_gcode

from .test_corrected_program import ORIGIN, POCKET, _distance_to


@pytest.fixture(scope="module")
def machines():
    m = pkmkit.machine("linear-delta")
    return m, m.with_defects(random_defects(m, np.random.default_rng(0)))


def _loaded(true, nominal, commanded):
    """Where the calibrated machine's loaded tool point is when the nominal controller is sent
    ``commanded (k, 3)``: its unloaded tool point plus its sag, both at the commanded q."""
    q = commanded_q(nominal, commanded)
    return reached(true, q)[:, :3] + gravity_deflection(true, q).deflection[:, :3]


def _worst_miss(fixed, path, true, nominal):
    """Largest distance of the loaded tool point from the programmed feed segments along the
    corrected program read back (6 decimals in mm: 1 nm of rounding)."""
    back = read_gcode(corrected_gcode(fixed, origin=ORIGIN, decimals=6), origin=ORIGIN)
    assert len(back.segments) == len(fixed.kind)
    worst = 0.0
    for k, seg in enumerate(back.segments):
        if seg.rapid or k == 0:
            continue
        original = path.segments[path.source.index(int(fixed.source[k]))]
        commanded = seg.evaluate(np.linspace(0.0, seg.length, 60))[0]
        worst = max(worst, _distance_to(original, _loaded(true, nominal, commanded)).max())
    return worst


@pytest.mark.ci
def test_the_loaded_tool_point_follows_the_program(machines):
    """The sag (0.9 µm here) is corrected like the calibration: with --gravity the loaded tool
    point stays within the tolerance of the programmed path; without it misses by the sag."""
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    tolerance = 1e-7
    aim = LoadedAim(true)
    fixed = correct_path(nominal, true, path, tolerance=tolerance, step=5e-4, aim=aim)
    plain = correct_path(nominal, true, path, tolerance=tolerance, step=5e-4)
    sag = aim.summary()
    assert 5e-7 < sag["deflection_max"] < 2e-6 and "illustrative" in sag["masses"]
    assert _worst_miss(fixed, path, true, nominal) < tolerance + 1e-8
    assert _worst_miss(plain, path, true, nominal) > 0.5 * sag["deflection_max"]
    # the rapids' end points too: the loaded tool point lands on the programmed point
    for k in np.flatnonzero(fixed.rapid):
        landed = _loaded(true, nominal, fixed.corrected[k][None])[0]
        np.testing.assert_allclose(landed, fixed.targets[k], atol=1e-9)


def test_the_program_keeps_its_moves_and_types(machines):
    """Every block of the original, in order, one G0 per rapid, the feed blocks' moves of their
    own type; subdivided only where the tolerance needs it (none at 30 µm)."""
    nominal, true = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    fixed = correct_path(nominal, true, path, tolerance=3e-5, aim=LoadedAim(true))
    kinds = ["G0", "G1", "G1", "G3", "G1", "G3", "G1", "G3", "G1", "G3", "G0"]
    assert fixed.kind.tolist() == kinds and fixed.subdivided == 0
    assert fixed.source.tolist() == list(path.source)
    plain = correct_path(nominal, true, path, tolerance=3e-5)
    moved = np.linalg.norm(fixed.corrected - plain.corrected, axis=1)
    assert (moved > 5e-7).all() and (moved < 2e-6).all()  # by the sag, at every move


def test_a_bound_below_the_sag_refuses_the_blocks_with_their_lines(machines):
    """A bound the calibration alone meets but calibration plus sag does not: refused per
    block by line (a nominal machine 'calibrated' as itself needs only the sag)."""
    nominal, _ = machines
    path = read_gcode(POCKET, origin=ORIGIN)
    correct_path(nominal, nominal, path, max_correction=1e-7)  # no correction without sag
    with pytest.raises(CorrectionRefused) as info:
        correct_path(nominal, nominal, path, max_correction=1e-7, aim=LoadedAim(nominal))
    assert [b[0] for b in info.value.blocks] == list(path.source)
    assert all(5e-7 < b[2] < 2e-6 for b in info.value.blocks)


def test_a_point_without_a_sag_is_refused_not_left_uncorrected(machines, monkeypatch):
    """A reachable point whose deflection is undefined (singular stiffness) makes its block
    refused (NaN), never silently corrected for the calibration alone."""
    import pkmkit.calibration.gravity as gravity

    nominal, true = machines
    real = gravity.gravity_deflection

    def holed(machine, q, **kw):
        out = real(machine, q, **kw)
        d = out.deflection.copy()
        d[np.asarray(q)[:, 2] > np.median(np.asarray(q)[:, 2])] = np.nan
        return gravity.GravityDeflection(d, out.note)

    monkeypatch.setattr(gravity, "gravity_deflection", holed)
    path = read_gcode(POCKET, origin=ORIGIN)
    with pytest.raises(CorrectionRefused) as info:
        correct_path(nominal, true, path, aim=LoadedAim(true))
    assert info.value.blocks and all(np.isnan(b[2]) for b in info.value.blocks)


def test_a_turning_platform_program_lands_its_loaded_tool_on_the_end_points():
    """The Verne module (a platform that turns as it moves, struts of slides and rods): the
    sag of its tool tip 0.1 m below the platform, rotation included, is aimed away."""
    nominal = pkmkit.machine("verne")
    true = nominal.with_defects(0.2 * random_defects(nominal, np.random.default_rng(1)))
    path = read_gcode("G21 G90\nG0 X0 Y0 Z5\nG1 X20 Y0 Z5 F300\nG1 X20 Y20 Z0\n",
                      origin=(0.0, 0.0, -0.1))
    tl = 0.1
    aim = LoadedAim(true, tl)
    fixed = correct_path(nominal, true, path, aim=aim, tool_length=tl, max_correction=0.02)
    assert fixed.kind.tolist()[:1] == ["G0"] and set(fixed.kind[1:]) == {"G1"}
    assert aim.summary()["deflection_max"] > 1e-7
    q = commanded_q(nominal, fixed.corrected, tl)
    landed = reached(true, q, tl)[:, :3] + gravity_deflection(true, q,
                                                              tool_length=tl).deflection[:, :3]
    np.testing.assert_allclose(landed, fixed.targets, atol=1e-10)
