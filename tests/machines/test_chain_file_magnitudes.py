"""The magnitude guard of joint-chain machine files (a unit mistake whose squares would overflow
in the closure) judges the value in SI units, whatever the file's unit: a stroke written in mm
as ±2·10⁶ mm (2 km either way, a way of writing "unlimited") is 2,000 m and loads, the same
as ±2000 in a file in metres; ±2·10⁹ mm (2·10⁶ m) is beyond the 10⁶ m guard and is refused."""

import re

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import MachineFileError
from pkmkit.machines.chain_file import machine_file_text


def _with_q1_stroke(units: str, half_width: float) -> str:
    text = machine_file_text(pkmkit.machine("tripteor-x7"), units=units)
    # the first stroke in the file is the actuator Q1's (a prismatic joint: file units)
    return re.sub(r"stroke = \[[^\]]*\]", f"stroke = [{-half_width!r}, {half_width!r}]",
                  text, count=1)


@pytest.mark.parametrize(("units", "half_width"), [("mm", 2e6), ("m", 2e3)])
def test_a_wide_stroke_is_judged_in_metres(tmp_path, units, half_width):
    path = tmp_path / f"wide-{units}.toml"
    path.write_text(_with_q1_stroke(units, half_width))
    machine = pkmkit.load(path)
    q1 = next(e for e in machine.model.elements if e.name == "Q1")
    np.testing.assert_allclose(q1.stroke, [-2000.0, 2000.0], rtol=1e-12)


def test_a_stroke_beyond_the_guard_in_metres_is_refused_from_a_mm_file(tmp_path):
    path = tmp_path / "huge-mm.toml"
    path.write_text(_with_q1_stroke("mm", 2e9))
    with pytest.raises(MachineFileError, match="magnitude beyond"):
        pkmkit.load(path)
