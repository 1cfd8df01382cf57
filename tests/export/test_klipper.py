"""The Klipper delta section against Klipper's own delta formulas, implemented here from Klipper's
documented model (klippy/kinematics/delta.py): towers at delta_radius (cos angle, sin angle),
carriage height z + sqrt(arm² − (x − tx)² − (y − ty)²), endstop height position_endstop +
sqrt(arm² − delta_radius²)."""

from __future__ import annotations

import configparser

import numpy as np
import pytest

import pkmkit
from pkmkit.export.base import UnsupportedExportError
from pkmkit.export.klipper import klipper_config
from pkmkit.model.defects_table import apply_defect_vector, defect_index

MM = 1e-3


def _klipper_displacements(text: str, x: np.ndarray) -> np.ndarray:
    """Carriage travel from the endstop (mm, (N, 3)) that Klipper commands for points x (mm)."""
    cfg = configparser.ConfigParser()
    cfg.read_string(text)
    assert cfg.get("printer", "kinematics") == "delta"
    radius = cfg.getfloat("printer", "delta_radius")
    out = np.empty((len(x), 3))
    for k, name in enumerate(("stepper_a", "stepper_b", "stepper_c")):
        angle = np.radians(cfg.getfloat(name, "angle"))
        arm = cfg.getfloat(name, "arm_length")
        tx, ty = radius * np.cos(angle), radius * np.sin(angle)
        height = x[:, 2] + np.sqrt(arm**2 - (x[:, 0] - tx) ** 2 - (x[:, 1] - ty) ** 2)
        endstop = cfg.getfloat(name, "position_endstop") + np.sqrt(arm**2 - radius**2)
        out[:, k] = height - endstop
    return out


def _defects(machine, **values) -> np.ndarray:
    index = defect_index(machine)
    delta = np.zeros(len(index.names))
    for name, value in values.items():
        delta[index.names.index(name)] = value
    return delta


def _calibrated_delta():
    """A linear Delta as a delta calibration leaves it: towers turned, arms and endstops apart."""
    m = pkmkit.machine("linear-delta-table-iv1").with_params(angles=np.radians([0.3, 120.0,
                                                                                 239.2]))
    return apply_defect_vector(m, _defects(m, dL1=4e-4, dL3=-2.5e-4, dq1=1.2e-3, dq2=-7e-4))


@pytest.mark.parametrize("make", [lambda: pkmkit.machine("linear-delta-ch3"),
                                  lambda: pkmkit.machine("linear-delta-table-iv1"),
                                  _calibrated_delta],
                         ids=["ch3", "table-iv1", "calibrated"])
def test_klipper_moves_the_carriages_as_pkmkit(make):
    m = make()
    rng = np.random.default_rng(0)
    lo, hi = m.default_box()
    x = rng.uniform(lo, hi, (20_000, 3))
    q = m.ik(x)
    ok = np.isfinite(q).all(axis=1)
    assert ok.mean() > 0.5
    text = klipper_config(m)
    travel = _klipper_displacements(text, x[ok] / MM) * MM
    assert np.abs(travel - (q[ok] - m.model.q_max)).max() <= 1e-9


def test_endstops_given_elsewhere_shift_position_endstop():
    m = pkmkit.machine("linear-delta-ch3")
    endstops = np.array([1.9, 1.95, 1.8])
    x = m.home_pose[None] + np.array([[0.05, -0.02, 0.1]])
    travel = _klipper_displacements(klipper_config(m, endstops=endstops), x / MM) * MM
    assert np.abs(travel - (m.ik(x) - endstops)).max() <= 1e-9


@pytest.mark.parametrize("defects, words", [
    ({"dA1x": 5e-4}, "one delta_radius"),
    ({"du2x": 1e-3}, "not vertical"),
])
def test_what_klipper_cannot_hold_is_refused(defects, words):
    m = pkmkit.machine("linear-delta-ch3")
    m = apply_defect_vector(m, _defects(m, **defects))
    with pytest.raises(UnsupportedExportError, match=words):
        klipper_config(m)


@pytest.mark.parametrize("name", ["orthoglide", "gough-stewart", "tripteor-x7", "delta"])
def test_other_machines_are_refused(name):
    with pytest.raises(UnsupportedExportError, match="klipper"):
        klipper_config(pkmkit.machine(name))


@pytest.mark.parametrize("endstops, words", [
    ([1e300, 1e300, 1e300], r"endstop of q1 at 1e\+303 mm lies outside its stroke \[700, 2000\]"),
    ([1.9, 0.005, 1.8], r"endstop of q2 at 5 mm lies outside its stroke \[700, 2000\] mm"),
    ([1.9, 1.9, 2.5], "endstop of q3 at 2500 mm lies outside"),
    ([1.9, -0.0, np.nan], "3 finite actuator coordinates"),
])
def test_endstops_outside_the_strokes_are_refused(endstops, words):
    """An endstop no carriage can reach (1e300, a value in mm read as m) was written as
    position_endstop: 1e+303 with a passing check."""
    from pkmkit.exceptions import InputError

    with pytest.raises(InputError, match=words):
        klipper_config(pkmkit.machine("linear-delta-ch3"), endstops=np.array(endstops))


def test_strokes_or_rods_of_a_stadium_are_refused():
    """Stroke tops of 200 km (the default endstops) or 150 m arms are unit slips: refused with
    the value, instead of a configuration (or a failed self-check blaming rounding)."""
    m = pkmkit.machine("linear-delta-ch3")
    with pytest.raises(UnsupportedExportError, match="endstop 200000 m is beyond 100 m"):
        klipper_config(m.with_params(q_max=np.full(3, 2e5)), units="m")
    with pytest.raises(UnsupportedExportError, match="arm_length 150000 mm is beyond"):
        klipper_config(m.with_params(L=150.0, R=100.0, q_min=np.full(3, 100.0),
                                     q_max=np.full(3, 120.0)))
