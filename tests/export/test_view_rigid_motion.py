"""The tool errors of a calibration's 3-D view judged (issue 18 §5): a machined-part
calibration of the Verne module showed "largest tool error 8.5 mm" (2.35 mm in an earlier
run) where the part measured at most 1.1 mm of error, without a word. The part's placement
absorbs any rigid motion of the whole machine, so the identified machine is only defined up to
one: the view now removes the vectors' best rigid motion when the set-up absorbs one, states
the size of that motion, and the report flags an error beyond the verdict's bound or far beyond
what was measured."""

from __future__ import annotations

import pytest

import pkmkit
from pkmkit.export.view import view_figure


def test_a_pure_translation_is_removed_as_the_set_up_removes_it():
    """Equal slide offsets of a linear Delta move the tool by the same 1 mm everywhere: a
    rigid motion. Without the removal the view shows 1 mm, with it nothing."""
    m = pkmkit.machine("linear-delta")
    shifted = m.with_defects({"dA1z": 1e-3, "dA2z": 1e-3, "dA3z": 1e-3})
    _, raw = view_figure(m, calibrated=shifted, steps=2, resolution=10)
    assert raw.error_max == pytest.approx(1e-3, rel=1e-6)
    assert raw.error_max_with_rigid is None
    _, removed = view_figure(m, calibrated=shifted, steps=2, resolution=10, rigid_free=True)
    assert removed.error_max < 1e-9
    assert removed.error_max_with_rigid == pytest.approx(1e-3, rel=1e-6)


def test_a_shape_error_survives_the_removal():
    """A rod 1 mm longer does not move the tool rigidly: its error stays after the removal
    (smaller: the mean shift and tilt go), never larger."""
    m = pkmkit.machine("linear-delta")
    longer = m.with_defects({"dL1": 1e-3})
    _, raw = view_figure(m, calibrated=longer, steps=2, resolution=10)
    _, removed = view_figure(m, calibrated=longer, steps=2, resolution=10, rigid_free=True)
    assert 1e-5 < removed.error_max < raw.error_max
    assert removed.error_max_with_rigid == pytest.approx(raw.error_max)


def test_the_report_note_judges_the_largest_error():
    from types import SimpleNamespace

    from pkmkit.export.view import ViewContent
    from pkmkit.plot.calibration_report import _view_note

    m = pkmkit.machine("verne")  # 0.69 m: the verdict's bound is 34.6 mm
    result = SimpleNamespace(nominal=m, before=SimpleNamespace(max=1.1e-3))
    ok = ViewContent(machine="verne", error_vectors=10, error_max=7e-4,
                     error_max_with_rigid=8.5e-3)
    note = _view_note(result, ok, "mm")
    assert "0.7 mm (the best rigid motion of the vectors removed" in note
    assert "with it 8.5 mm" in note and "Beyond" not in note and "3×" not in note
    far = ViewContent(machine="verne", error_vectors=10, error_max=5e-3)
    assert "More than 3× the largest error measured</b> (1.1 mm)" in _view_note(result, far, "mm")
    absurd = ViewContent(machine="verne", error_vectors=10, error_max=0.2)
    assert "Beyond a plausible error" in _view_note(result, absurd, "mm")
