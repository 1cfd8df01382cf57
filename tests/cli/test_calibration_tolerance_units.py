"""``calibrate --tolerance NAME=VALUE`` reads lengths in ``--units`` and angles in degrees (its
help): the values handed to the verdict are the SI ones, worked out by hand."""

import math

import pytest

import pkmkit
from pkmkit.cli.calibration_cmds import _tolerances
from pkmkit.geometric_errors.model import defect_set


@pytest.mark.parametrize(("unit", "metres"), [("mm", 1e-3), ("m", 1.0)])
def test_tolerances_in_the_command_units_and_degrees(unit, metres):
    m = pkmkit.machine("tripteor-x7")
    dset = defect_set(m)
    angle = next(n for n, u in zip(dset.names, dset.units, strict=True) if u == "rad")
    length = next(n for n, u in zip(dset.names, dset.units, strict=True) if u == "m")
    out = _tolerances([f"{angle}=0.5", f"{length}=0.02"], m, unit)
    assert out[angle] == pytest.approx(0.5 * math.pi / 180, rel=1e-15)
    assert out[length] == pytest.approx(0.02 * metres, rel=1e-15)
