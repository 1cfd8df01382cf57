"""One defect rule (issue 19 §2): defects are absolute deviations from the nominal geometry,
applied by one function on every family — applying the same defects twice is applying them once,
through every door (the machine's method, ``geometric_errors.model.with_defects``, the deprecated
``apply_defect_vector``); ``add_defects`` adds on top, and a machine file written with the
source's defects plus the new ones reloads to exactly that machine."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ParameterError
from pkmkit.geometric_errors.model import defect_set, with_defects
from pkmkit.io.machine_defects import machine_text_with_defects
from pkmkit.machines.registry import preset_path
from pkmkit.model.defect_rule import add_defects
from pkmkit.model.defects_table import apply_defect_vector

# one defect per family whose repetition shows: a rod length, a hexapod rod end, a joint axis
CASES = {"linear-delta": "dL2", "delta": "dq1", "five-bar": "dA1x", "gough-stewart": "dA3z",
         "verne": "dL4", "tripteor-x7": "dK21", "crank-slider": "da2"}


def _geometry(m) -> np.ndarray:
    """The tool pose at the nominal machine's home actuators: what a defect changes."""
    q = pkmkit.machine(m.id).home_q if m.id in pkmkit.machines() else m.home_q
    return np.asarray(m.fk(q, strokes="ignore") if m.family != "chain" else
                      m.fk(q[None], full_output=True, strokes="ignore").pose[0])


def _legacy(m, delta):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return apply_defect_vector(m, delta)


@pytest.mark.parametrize(("name", "defect"), CASES.items())
def test_the_same_defect_twice_is_the_defect_once_on_every_family(name, defect):
    m = pkmkit.machine(name)
    delta = defect_set(m).vector({defect: 1e-3})
    once = with_defects(m, delta)
    np.testing.assert_array_equal(once.defects(), delta)
    for twice in (with_defects(once, delta), once.with_defects({defect: 1e-3}),
                  _legacy(once, delta), _legacy(_legacy(m, delta), delta)):
        np.testing.assert_array_equal(twice.defects(), delta)
        np.testing.assert_allclose(_geometry(twice), _geometry(once), rtol=0, atol=1e-12)
    # and the geometry moved: the test can tell one application from none
    assert np.abs(_geometry(once) - _geometry(m)).max() > 1e-5
    # zero defects give the nominal geometry back
    np.testing.assert_allclose(_geometry(once.with_defects(np.zeros(len(delta)))), _geometry(m),
                               rtol=0, atol=1e-12)


def test_apply_defect_vector_is_deprecated():
    m = pkmkit.machine("linear-delta")
    with pytest.warns(DeprecationWarning, match="with_defects"):
        apply_defect_vector(m, np.zeros(len(defect_set(m))))


def test_add_defects_adds_to_the_machines_own():
    m = pkmkit.machine("gough-stewart")
    ds = defect_set(m)
    a, b = ds.vector({"dL1": 1e-3, "dq2": 2e-4}), ds.vector({"dL1": 5e-4, "dB2x": -1e-4})
    np.testing.assert_array_equal(add_defects(with_defects(m, a), b).defects(), a + b)
    with pytest.raises(ParameterError, match="unknown defect"):
        m.with_defects({"dZ9": 1.0})


@pytest.mark.parametrize("name", ["linear-delta", "delta", "tripteor-x7"])
def test_a_written_calibrated_file_reloads_to_the_fitted_machine(name, tmp_path):
    """Identification fits ``add_defects(source, δ)`` and writes the source's defects plus δ:
    loading that file must give the fitted machine. With defects that couple (an actuator
    offset and a tilt of the same slide), adding δ to the current geometry of a rod machine
    (the old accumulation) differs from the file at second order."""
    nominal = pkmkit.machine(name)
    ds = defect_set(nominal)
    axis = next(n for n in ds.names if n.startswith(("du1", "dw1", "dI", "dJ")))
    offset = next(n for n in ds.names if n.startswith(("dq1", "da", "dc")))
    source_delta = ds.vector({offset: 5e-3})
    source_text = machine_text_with_defects(preset_path(name), nominal, source_delta)
    source = tmp_path / f"source{Path(preset_path(name)).suffix}"
    source.write_text(source_text)
    start = pkmkit.load(str(source))
    # (angles go through the file in degrees to 10 digits)
    np.testing.assert_allclose(start.defects(), source_delta, rtol=0, atol=1e-12)
    step = ds.vector({axis: 0.02})
    fitted = add_defects(start, step)
    written = tmp_path / f"calibrated{source.suffix}"
    written.write_text(machine_text_with_defects(source, start, step))
    reloaded = pkmkit.load(str(written))
    np.testing.assert_allclose(reloaded.defects(), start.defects() + step, rtol=0, atol=1e-12)
    np.testing.assert_allclose(_geometry(reloaded), _geometry(fitted), rtol=0, atol=1e-10)


@pytest.mark.parametrize("name", ["delta", "linear-delta"])
def test_actuator_offset_is_a_shift_of_the_actuator_coordinate(name):
    """An actuator offset dq_k (a crank's angle, a slide's travel) moves the actuator's zero:
    the machine with it reaches x at q − dq_k e_k when the nominal one needs q."""
    m = pkmkit.machine(name)
    offset = 0.01 if name == "delta" else 2e-3
    k = 1
    shifted = with_defects(m, {"dq2": offset})
    x = np.atleast_2d(m.fk(m.home_q, strokes="ignore"))[0]
    expected = np.asarray(m.ik(x, strokes="ignore"), dtype=float).copy()
    expected[k] -= offset
    np.testing.assert_allclose(shifted.ik(x, strokes="ignore"), expected, atol=1e-12)
