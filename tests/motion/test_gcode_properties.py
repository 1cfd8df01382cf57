"""G-code arcs given by their centre (I/J/K) and by their radius (R) are the same arc — on
random arcs in the three planes, both directions, short and long."""

import math

import numpy as np
from hypothesis import assume, given
from hypothesis import strategies as st

from pkmkit.motion.gcode import read_gcode

#: plane → (G word, in-plane axis letters, centre-offset letters, normal the arc is seen from)
PLANES = {17: ("XY", "IJ", (0, 0, 1)), 18: ("ZX", "KI", (0, 1, 0)), 19: ("YZ", "JK", (1, 0, 0))}


@given(plane=st.sampled_from([17, 18, 19]), clockwise=st.booleans(),
       start=st.tuples(*[st.floats(-50, 50)] * 3), radius=st.floats(0.5, 40.0),
       phase=st.floats(-math.pi, math.pi), sweep=st.floats(0.05, 2 * math.pi - 0.05))
def test_centre_and_radius_arcs_agree(plane, clockwise, start, radius, phase, sweep):
    axes, offsets, normal = PLANES[plane]
    u = {"X": 0, "Y": 1, "Z": 2}
    first, second = u[axes[0]], u[axes[1]]  # the plane's axes, seen from +normal (right-handed)
    start = np.array(start)
    center = start.copy()
    center[first] -= radius * math.cos(phase)
    center[second] -= radius * math.sin(phase)
    angle = phase + (-sweep if clockwise else sweep)  # CCW is positive seen from +normal
    end = center.copy()
    end[first] += radius * math.cos(angle)
    end[second] += radius * math.sin(angle)
    assume(np.linalg.norm(end - start) > 1e-3)
    assume(abs(sweep - math.pi) > 1e-3)  # a half turn by R is ambiguous
    def num(v):  # G-code numbers: fixed point, no exponent
        return f"{float(v):.10f}"

    head = f"G21 G90 G{plane}\nG0 X{num(start[0])} Y{num(start[1])} Z{num(start[2])}\n"
    move = f"G{2 if clockwise else 3} X{num(end[0])} Y{num(end[1])} Z{num(end[2])}"
    offset = dict(zip("IJK", (center - start).tolist(), strict=True))
    by_centre = read_gcode(head + move + "".join(
        f" {k}{num(offset[k])}" for k in offsets) + " F600\n").segments[-1]
    signed = radius if sweep < math.pi else -radius
    by_radius = read_gcode(head + move + f" R{num(signed)} F600\n").segments[-1]
    for arc in (by_centre, by_radius):
        # (the program's numbers carry 10 decimals of a millimetre; an R arc near a half turn
        # amplifies that rounding in its centre)
        np.testing.assert_allclose(arc.center, center / 1000, atol=1e-11)
        assert abs(arc.radius - radius / 1000) < 1e-12
        assert abs(abs(arc.sweep) - sweep) < 1e-7
        np.testing.assert_allclose(arc.normal * np.sign(arc.sweep),
                                   np.array(normal) * (-1 if clockwise else 1), atol=1e-12)
        np.testing.assert_allclose(arc.end, end / 1000, atol=1e-12)
    s = np.linspace(0.0, by_centre.length, 7)
    np.testing.assert_allclose(by_radius.evaluate(s)[0], by_centre.evaluate(s)[0], atol=1e-11)
