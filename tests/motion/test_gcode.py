import math

import numpy as np
import pytest

from pkmkit.exceptions import InputError
from pkmkit.motion.gcode import read_gcode

PROGRAM = """%
(facing test)
N10 G21 G90 G17
N20 G0 X10 Y0 Z5
N30 G1 Z0 F600
N40 G2 X0 Y10 I-10 J0
N50 G3 X-10 Y0 R10 ; short arc
N60 G1 X-10 Y-10
N70 G2 X-10 Y-10 I10 Z-2 (helical full turn)
%
"""


def test_program_segments():
    path = read_gcode(PROGRAM)
    kinds = [type(s).__name__ for s in path.segments]
    assert kinds == ["Line", "Line", "Arc", "Arc", "Line", "Arc"]
    assert path.source == (4, 5, 6, 7, 8, 9)
    assert path.segments[0].rapid and path.segments[1].feed == pytest.approx(0.01)
    assert path.segments[2].sweep == pytest.approx(-1.5 * math.pi)
    assert path.segments[3].sweep == pytest.approx(math.pi / 2)
    helix = path.segments[5]
    assert helix.sweep == pytest.approx(-2 * math.pi) and helix.rise == pytest.approx(-0.002)
    np.testing.assert_allclose(helix.end, [-0.01, -0.01, -0.002], atol=1e-12)


def test_units_incremental_and_origin():
    inch = read_gcode("G20 G91\nG1 X1 Y2 F60\nX1\n", origin=(0.1, 0, 0))
    np.testing.assert_allclose(inch.segments[0].end, [0.1 + 0.0254, 0.0508, 0], atol=1e-12)
    np.testing.assert_allclose(inch.segments[1].end, [0.1 + 0.0508, 0.0508, 0], atol=1e-12)
    assert inch.segments[0].feed == pytest.approx(0.0254)


@pytest.mark.parametrize("plane, ijk, end, normal", [
    ("G17", "I-5 J0", "X0 Y5 Z0", (0, 0, 1)),
    ("G18", "I-5 K0", "X0 Y0 Z5", (0, 1, 0)),
    ("G19", "J-5 K0", "X0 Y0 Z5", (1, 0, 0)),
])
@pytest.mark.parametrize("motion", ["G2", "G3"])
def test_centre_and_radius_forms_agree_in_every_plane(plane, ijk, end, normal, motion):
    start = {"G17": "X5 Y0 Z0", "G18": "X5 Y0 Z0", "G19": "X0 Y5 Z0"}[plane]
    head = f"G21 G90 {plane}\nG0 {start}\n"
    by_centre = read_gcode(head + f"{motion} {end} {ijk} F100\n").segments[1]
    # the same arc by its radius: R > 0 for the short way round, R < 0 for the long way
    radius = 5 if abs(by_centre.sweep) <= math.pi else -5
    by_radius = read_gcode(head + f"{motion} {end} R{radius} F100\n").segments[1]
    assert abs(by_centre.sweep) in (pytest.approx(math.pi / 2), pytest.approx(1.5 * math.pi))
    np.testing.assert_allclose(by_centre.center, by_radius.center, atol=1e-12)
    assert by_centre.sweep == pytest.approx(by_radius.sweep)
    np.testing.assert_allclose(np.cross(by_centre.e1, by_centre.e2), normal, atol=1e-12)


@pytest.mark.parametrize(
    "text, line, message",
    [
        ("G1 X1 F100\nG43 H1\n", 2, "unsupported G code G43"),
        ("G1 X1 F100\nG41 D1\n", 2, "unsupported G code G41"),
        ("G1 X1 F100\nP2\n", 2, "unsupported word P2"),
        ("G1 X1 F100\nG4 P1\n", 2, "unsupported G code G4"),
        ("G1 X1\n", 1, "feed rate"),
        ("X1 Y1\n", 1, "motion mode"),
        ("G1 X1 F100\nG2 X2 Y1 I0 J0.6\n", 2, "inconsistent arc"),
        ("G0 X0 Y0\nG2 X10 Y0 R2 F100\n", 2, "smaller than half the chord"),
        ("G0 X1 Y0\nG2 X1 Y0 R1 F100\n", 2, "full circle"),
        ("G1 X1 F-5\n", 1, "feed must be > 0"),
        ("G1 X1 X2 F5\n", 1, "appears twice"),
        ("G1 X1 F5 #3\n", 1, "cannot read"),
        ("(only a comment)\n", None, "no motion"),
    ],
)
def test_errors_name_the_line(text, line, message):
    with pytest.raises(InputError, match=message) as info:
        read_gcode(text, name="prog.nc")
    if line is not None:
        assert f"prog.nc:{line}:" in str(info.value)


@pytest.mark.parametrize("program, midpoint", [
    # viewed from +Z (X right, Y up): clockwise from +X to −Y is the short quarter
    ("G17 G0 X10 Y0 Z0\nG2 X0 Y-10 I-10 J0 F100\n", [7.0711, -7.0711, 0]),
    # G18 is viewed from +Y (Z right, X up): clockwise from X10 (up) to Z10 (right) is short
    ("G18 G0 X10 Y0 Z0\nG2 X0 Z10 I-10 K0 F100\n", [7.0711, 0, 7.0711]),
    ("G18 G0 X10 Y0 Z0\nG3 X0 Z10 I-10 K0 F100\n", [-7.0711, 0, -7.0711]),
    # G19 is viewed from +X (Y right, Z up): clockwise from Z10 (up) to Y10 (right) is short
    ("G19 G0 X0 Y0 Z10\nG2 Y10 Z0 J0 K-10 F100\n", [0, 7.0711, 7.0711]),
])
def test_arc_direction_conventions(program, midpoint):
    """G2/G3 directions per plane, from the RS274/NGC convention (each plane viewed from its
    positive normal axis), checked at the arc's midpoint."""
    arc = read_gcode("G21 G90\n" + program).segments[-1]
    mid = arc.evaluate(np.array([arc.length / 2]))[0][0]
    np.testing.assert_allclose(mid * 1e3, midpoint, atol=1e-3)


def test_rounded_cam_arcs_are_accepted_and_end_on_the_programmed_point():
    # 30° arc about the origin written with 3 decimals (radius error 2.5e-4 mm) and one 0.05 % off
    for end in ("X8.660 Y5.000", "X8.6645 Y5.0025"):
        path = read_gcode(f"G21 G90\nG0 X10 Y0\nG3 {end} I-10 J0 F600\n")
        arc = path.segments[-1]
        expected = np.array([float(w[1:]) for w in end.split()] + [0.0]) * 1e-3
        np.testing.assert_allclose(arc.end, expected, atol=1e-12)
    with pytest.raises(InputError, match=r"radius 10 mm at the start but 10.02"):
        read_gcode("G21 G90\nG0 X10 Y0\nG3 X0 Y10.02 I-10 J0 F600\n")


@pytest.mark.parametrize("text, message", [
    ("G1 X1 G0 Y1 F100\n", "two motion codes on one line: G1 G0"),
    ("G17 G18 G1 X1 F100\n", "two plane codes"),
    ("G20 G21 G1 X1 F100\n", "two unit codes"),
    ("G90 G91 G1 X1 F100\n", "two distance codes"),
    ("G17 G2 X0 Y2 I0 J1 K3 F100\n", "K is not an offset of an arc in the G17 plane"),
    ("G19 G2 Y0 Z2 I1 K1 F100\n", "I is not an offset"),
])
def test_modal_conflicts_and_off_plane_offsets(text, message):
    with pytest.raises(InputError, match=message):
        read_gcode(text, name="p.nc")


def test_cam_preamble_and_program_end_are_read():
    """Words every post-processor writes (O, S, T, M, G40/G49/G80/G94/G54) leave the path as
    it is; M30 ends the program."""
    body = "G0 X0 Y0 Z5\nG1 Z-1 F300\nG1 X20 F600\nG2 X30 Y10 I0 J10\nG0 Z5\n"
    plain = read_gcode("G21 G90 G17\n" + body)
    decorated = read_gcode("%\nO1000 (pocket)\nN10 G21 G90 G94 G17 G40 G49 G80 G54\n"
                           "N20 T1 M6\nN30 S12000 M3 M8\n" + body
                           + "M5 M9\nM30\nG1 X500 Y500 F100\n%\n")
    assert len(decorated.segments) == len(plain.segments)
    for a, b in zip(decorated.segments, plain.segments, strict=True):
        np.testing.assert_array_equal(a.start, b.start)
        np.testing.assert_array_equal(a.end, b.end)
        assert a.feed == b.feed
