"""Tolerance analysis: the batched exact model against the machine's own direct model with the
defects applied, first order against Monte Carlo, the file format and its errors."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ParameterError, ToleranceFileError
from pkmkit.geometric_errors.configurations import sample_configurations
from pkmkit.geometric_errors.model import with_defects
from pkmkit.geometric_errors.tolerance import (
    accuracy_map,
    exact_rod_points,
    first_order_error,
    monte_carlo,
    read_tolerances,
    tolerances,
)

ROD_MACHINES = ["gough-stewart", "verne", "linear-delta", "orthoglide", "five-bar", "delta"]


@pytest.mark.parametrize("name", ROD_MACHINES)
def test_batched_exact_model_equals_the_defected_machines(name):
    m = pkmkit.machine(name)
    kinds = {k: 2e-4 for k in set(pkmkit.geometric_errors.model.defect_set(m).kinds)}
    tol = tolerances(m, classes=kinds)
    q = sample_configurations(m, 4, seed=2).q
    samples = tol.sample(3, np.random.default_rng(1))
    got = exact_rod_points(m, q, samples)
    for s, delta in enumerate(samples):
        ref = np.atleast_2d(with_defects(m, delta).fk(q))[:, :min(m.dims, 3)]
        np.testing.assert_allclose(got[:, s, :ref.shape[1]], ref, atol=1e-12)


def test_monte_carlo_against_first_order():
    m = pkmkit.machine("gough-stewart")
    tol = tolerances(m, classes={"base": 1e-5, "platform": 1e-5, "length": 1e-5})
    q = sample_configurations(m, 3, seed=0).q
    mc = monte_carlo(m, q, tol, 20000, seed=1)
    fo = first_order_error(m, q, tol)
    rms = np.sqrt(np.nanmean(mc.norm ** 2, axis=1))
    np.testing.assert_allclose(rms, fo.rms, rtol=0.02)  # sampling error ~1 %
    assert mc.nonlinearity < 1e-3 * fo.rms.max()
    assert np.all(mc.norm.max(axis=1) <= fo.worst_norm * (1 + 1e-9))
    assert mc.failed == 0


def test_tolerance_file(tmp_path):
    m = pkmkit.machine("linear-delta")
    path = tmp_path / "tol.toml"
    path.write_text('units = "mm"\nangle_units = "mrad"\ndistribution = "normal"\n'
                    '[classes]\nlength = 0.01\naxis = 0.5\n[parameters]\n"dA*z" = 0.02\n')
    tol = read_tolerances(str(path), m)
    width = dict(zip(tol.names, tol.half_width, strict=True))
    assert width["dL2"] == pytest.approx(1e-5) and width["du1x"] == pytest.approx(5e-4)
    assert width["dA3z"] == pytest.approx(2e-5) and width["dB1x"] == 0.0
    assert tol.distribution == "normal"
    amap = accuracy_map(m, tol, n_samples=50, resolution=5, fixed={2: 0.1})
    assert np.isfinite(amap.exact).all()
    np.testing.assert_allclose(amap.exact, amap.first_order, rtol=1e-3)
    for text, message, line in [
        ('[classes]\nlength = -0.01\n', "must be ≥ 0", 2),
        ('[parameters]\ndZ1 = 0.01\n', "unknown defect 'dZ1'", 2),
        ('units = "mm"\n[classes]\nwobble = 0.1\n', "unknown defect class 'wobble'", 3),
        ('units = "furlong"\n', "unknown length unit", 1),
        ('[classes]\nlength = "tight"\n', "must be a number", 2),
        # 400 digits: np.isfinite raised TypeError on the Python int (issue 18 §7 fuzz)
        ('\n[classes]\nlength = ' + "7" * 400 + '\n', "must be ≥ 0", 3),
    ]:
        path.write_text(text)
        with pytest.raises(ToleranceFileError, match=message) as info:
            read_tolerances(str(path), m)
        assert info.value.line == line
    with pytest.raises(ParameterError, match="≥ 0"):
        tolerances(m, classes={"length": -1.0})


@pytest.mark.parametrize(("units", "angle_units", "length", "axis"), [
    ("m", "rad", 2e-5, 3e-4), ("mm", "mrad", 0.02, 0.3), ("um", "urad", 20.0, 300.0),
    ("µm", "deg", 20.0, float(np.degrees(3e-4)))])
def test_tolerance_file_units_give_the_same_physical_half_widths(tmp_path, units, angle_units,
                                                                length, axis):
    """The same tolerances (20 µm, 0.3 mrad) written in every length and angle unit."""
    m = pkmkit.machine("linear-delta")
    path = tmp_path / "tol.toml"
    path.write_text(f'units = "{units}"\nangle_units = "{angle_units}"\n'
                    f'[classes]\nlength = {length!r}\naxis = {axis!r}\n')
    tol = read_tolerances(str(path), m)
    width = dict(zip(tol.names, tol.half_width, strict=True))
    assert width["dL2"] == pytest.approx(2e-5, rel=1e-12)
    assert width["du1x"] == pytest.approx(3e-4, rel=1e-12)
