"""Files of a compensation (corrected G-code, correction tables): the numbers written against
values worked out by hand (mm and mm/min from metres and m/s; the work offset subtracted; arc
centres relative to the previous end; degrees for rotation vectors)."""

from types import SimpleNamespace

import numpy as np

from pkmkit.io.compensation_files import corrected_gcode, correction_table

NAN3 = [np.nan] * 3


def _path():
    """A rapid, a line at 10 mm/s, an XY arc (G2) and an XZ arc (G3), in metres."""
    return SimpleNamespace(
        corrected=np.array([[0.011, 0.022, 0.033], [0.041, 0.022, 0.033],
                            [0.041, 0.062, 0.033], [0.061, 0.062, 0.013]]),
        kind=np.array(["G0", "G1", "G2", "G3"]),
        center=np.array([NAN3, NAN3, [0.041, 0.042, 0.033], [0.041, 0.062, 0.013]]),
        normal=np.array([NAN3, NAN3, [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),
        rapid=np.array([True, False, False, False]),
        feed=np.array([np.nan, 0.01, 0.01, 0.005]),
    )


def test_corrected_gcode_writes_millimetres_from_the_work_origin():
    lines = corrected_gcode(_path(), origin=(0.001, 0.002, 0.003)).splitlines()
    assert lines[2:] == [
        "G0 X10.0000 Y20.0000 Z30.0000",
        "G1 X40.0000 Y20.0000 Z30.0000 F600",
        "G2 X40.0000 Y60.0000 Z30.0000 I0.0000 J20.0000",
        # the XZ plane: G18, centre by I and K from the previous end (40, 60, 30) mm
        "G18 G3 X60.0000 Y60.0000 Z10.0000 I0.0000 K-20.0000 F300",
        "%",
    ]


def _rows(text):
    rows = [r.split(",") for r in text.splitlines() if not r.startswith("#")]
    numbers = [[float(c) if c else np.nan for c in r if c != "ok"] for r in rows[1:]]
    return rows[0], np.array(numbers)


def test_correction_table_in_mm_and_m_gives_the_same_lengths():
    targets = np.array([[0.1, 0.2, 0.3], [0.4, -0.5, 0.6]])
    corrected = targets + np.array([[1e-5, -2e-5, 3e-5], [0.0, 4e-5, -5e-5]])
    head, mm = _rows(correction_table(targets, corrected, units="mm"))
    assert head == ["x", "y", "z", "cx", "cy", "cz", "dx", "dy", "dz"]
    np.testing.assert_allclose(mm[:, :3], targets * 1e3, rtol=1e-12)
    np.testing.assert_allclose(mm[:, 3:6], corrected * 1e3, rtol=1e-12)
    np.testing.assert_allclose(mm[:, 6:9], [[0.01, -0.02, 0.03], [0.0, 0.04, -0.05]],
                               atol=1e-9)
    _, m = _rows(correction_table(targets, corrected, units="m"))
    np.testing.assert_allclose(m, mm / 1e3, rtol=1e-9, atol=1e-15)


def test_correction_table_orientation_columns():
    targets = np.array([[0.1, 0.2, 0.3, 0.0, 0.6, 0.8]])
    corrected = np.array([[0.1, 0.2, 0.3, 0.0, 0.8, 0.6]])
    head, axis = _rows(correction_table(targets, corrected, units="mm"))
    assert head[9:] == ["i", "j", "k", "ci", "cj", "ck"]
    np.testing.assert_allclose(axis[0, 9:], [0.0, 0.6, 0.8, 0.0, 0.8, 0.6])
    head, rv = _rows(correction_table(targets, corrected, units="mm", orientation="rotvec",
                                      status=["ok"]))
    assert head[9:] == ["rx", "ry", "rz", "crx", "cry", "crz", "status"]
    np.testing.assert_allclose(rv[0, 9:15], np.array([0.0, 0.6, 0.8, 0.0, 0.8, 0.6])
                               * 180.0 / np.pi, rtol=1e-9)

