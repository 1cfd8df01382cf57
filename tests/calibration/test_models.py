"""Residual models: analytic Jacobians (defects and set-up parameters) against central finite
differences of the exact residuals, for every measurement type."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.calibration.models import make_model
from pkmkit.calibration.registration import Registration
from pkmkit.calibration.simulate import random_defects, simulate
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.model import defect_set
from pkmkit.model.defects_table import apply_defect_vector

CASES = [("linear-delta", "point"), ("linear-delta", "height"), ("verne", "ballbar"),
         ("verne", "part"), ("verne", "point"), ("gough-stewart", "pose"),
         ("tripteor-x7", "point"), ("tripteor-x7", "pose")]


def _case(name, kind, frame):
    m = pkmkit.machine(name)
    rng = np.random.default_rng(8)
    true = apply_defect_vector(m, random_defects(m, rng, magnitude={"m": 2e-5, "1": 2e-4,
                                                                    "rad": 2e-4}))
    n = 24 if kind == "part" else 6
    data = simulate(true, m, kind, n, rng, noise="none")
    if kind == "ballbar":
        data = data.subset(np.arange(6))
    sigma = np.ones(1)
    model = make_model(m, data, sigma, identify_frame=frame and kind in ("point", "pose"))
    return m, model


@pytest.mark.parametrize(("name", "kind"), CASES)
def test_residual_jacobians_match_finite_differences(name, kind):
    m, model = _case(name, kind, frame=True)
    ds = defect_set(m)
    setup = model.setup.initial.copy()
    if len(setup):
        setup = setup + 3e-3 * np.arange(1, len(setup) + 1) / len(setup)
    r, jd, js = model.residuals(m, setup, jacobian=True)
    assert np.isfinite(r).all()
    rng = np.random.default_rng(1)
    h = 1e-7
    count = 5 if name == "tripteor-x7" else 10  # joint chains: each evaluation closes the legs
    for i in rng.choice(len(ds), count, replace=False):
        e = np.zeros(len(ds))
        e[i] = h
        plus = model.residuals(apply_defect_vector(m, e), setup, jacobian=False)[0]
        minus = model.residuals(apply_defect_vector(m, -e), setup, jacobian=False)[0]
        np.testing.assert_allclose(jd[:, :, i], (plus - minus) / (2 * h), atol=2e-6,
                                   rtol=1e-5, err_msg=f"{name} {kind} {ds.names[i]}")
    for k in range(len(setup)):
        e = np.zeros(len(setup))
        e[k] = h
        plus = model.residuals(m, setup + e, jacobian=False)[0]
        minus = model.residuals(m, setup - e, jacobian=False)[0]
        np.testing.assert_allclose(js[:, :, k], (plus - minus) / (2 * h), atol=2e-6,
                                   rtol=1e-5, err_msg=f"{name} {kind} {model.setup.names[k]}")


def test_exact_readings_have_zero_residual_on_the_true_machine():
    m = pkmkit.machine("verne")
    rng = np.random.default_rng(4)
    true = apply_defect_vector(m, random_defects(m, rng))
    for kind in ("point", "ballbar", "height"):
        data = simulate(true, m, kind, 10, rng, noise="none")
        model = make_model(m, data, np.ones(1))
        setup = model.setup.initial
        if kind == "ballbar":  # the true pivots are not the nominal ones: refit
            from pkmkit.calibration.identify import fit_setup

            setup = fit_setup(true, model)
        if kind == "height":
            from pkmkit.calibration.identify import fit_setup

            setup = fit_setup(true, model)
        r, _, _ = model.residuals(true, setup, jacobian=False)
        assert np.abs(r).max() < 1e-9, kind
        r_nominal, _, _ = model.residuals(m, setup, jacobian=False)
        assert np.abs(r_nominal).max() > 1e-6, kind


def test_frames_and_kinds_are_checked():
    m = pkmkit.machine("linear-delta")
    data = simulate(m, m, "height", 5, np.random.default_rng(0), noise="none")
    with pytest.raises(InputError, match="frame applies to point and pose"):
        make_model(m, data, np.ones(1), registration=Registration.identity())
    point = simulate(m, m, "point", 5, np.random.default_rng(0), noise="none")
    from dataclasses import replace

    pose = replace(point, kind="pose", values=np.concatenate([point.values,
                                                              np.zeros((5, 3))], axis=1))
    with pytest.raises(InputError, match="only translates"):
        make_model(m, pose, np.ones(6))
    chain = pkmkit.machine("tripteor-x7")
    part = simulate(pkmkit.machine("verne"), pkmkit.machine("verne"), "part", 12,
                    np.random.default_rng(0), noise="none")
    with pytest.raises(InputError, match="machined-part identification"):
        make_model(chain, part, np.ones(5))


def test_pose_rows_the_machine_does_not_assemble_give_nan_residuals():
    """A pose reading the machine cannot assemble (here actuator values of 1 mm) made the
    rotation residual of a zero matrix: SciPy's 'non-positive determinant' ended the whole
    calibration (issue 18 §7 fuzz: a pose file with a reading of -1e9 mm, the identification
    stepping where no row assembles)."""
    from dataclasses import replace

    m = pkmkit.machine("gough-stewart")
    data = simulate(m, m, "pose", 4, np.random.default_rng(2), noise="none")
    q = data.q.copy()
    q[1] = 1e-3
    model = make_model(m, replace(data, q=q), np.ones(6))
    r, _, _ = model.residuals(m, model.setup.initial, jacobian=False)
    assert np.isnan(r[1]).all()
    np.testing.assert_allclose(r[[0, 2, 3]], 0.0, atol=1e-9)
