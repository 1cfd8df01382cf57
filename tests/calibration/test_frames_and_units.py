"""Values and invariants of the calibration's geometry (no comparison of the code with itself):
registrations with non-commuting rotations against scipy's ``Rotation``, the identified frame of
the point and pose models against readings made through a known frame, set-up Jacobians at a
large frame rotation against finite differences, the identification in m and mm, and the robust
loss's invariance to the stated noise."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.calibration import random_defects, simulate
from pkmkit.calibration.identify import _huber_weights, _outliers, calibrate
from pkmkit.calibration.models import make_model
from pkmkit.calibration.registration import Registration, register_points
from pkmkit.io.measurements import read_measurements, write_measurements
from pkmkit.model.defects_table import apply_defect_vector

# 90° about x, then 90° about z: they do not commute
RA = Rotation.from_rotvec([np.pi / 2, 0.0, 0.0])
RB = Rotation.from_rotvec([0.0, 0.0, np.pi / 2])
TA, TB = np.array([0.3, -0.2, 1.1]), np.array([-0.5, 0.4, 0.05])


def _reg(rot: Rotation, t: np.ndarray) -> Registration:
    return Registration(rot.as_matrix(), t, np.zeros((0, 3)), np.zeros(0))


def test_registration_maps_against_scipy_with_non_commuting_rotations():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(7, 3))
    a, b = _reg(RA, TA), _reg(RB, TB)
    np.testing.assert_allclose(a.apply(p), RA.apply(p) + TA, atol=1e-14)
    np.testing.assert_allclose(a.apply(p[0]), RA.apply(p[0]) + TA, atol=1e-14)
    np.testing.assert_allclose(a.apply_directions(p), RA.apply(p), atol=1e-14)
    rv = rng.normal(size=(4, 3))
    np.testing.assert_allclose(a.apply_rotations(rv),
                               (RA * Rotation.from_rotvec(rv)).as_rotvec(), atol=1e-12)
    # a ∘ b: b first, then a
    np.testing.assert_allclose(a.compose(b).apply(p), a.apply(b.apply(p)), atol=1e-14)
    np.testing.assert_allclose(a.compose(b).apply(p), (RA * RB).apply(p) + RA.apply(TB) + TA,
                               atol=1e-14)
    assert np.abs(a.compose(b).apply(p) - b.compose(a).apply(p)).max() > 0.5
    np.testing.assert_allclose(a.inverse().apply(a.apply(p)), p, atol=1e-14)
    np.testing.assert_allclose(a.inverse().apply(p), RA.inv().apply(p - TA), atol=1e-14)
    # registration of points moved by the composition recovers it, and not the other order
    reg = register_points(p, a.compose(b).apply(p))
    np.testing.assert_allclose(reg.rotation, (RA * RB).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(reg.translation, RA.apply(TB) + TA, atol=1e-12)
    # directions alone fix the rotation: two directions and one point
    d = rng.normal(size=(2, 3))
    reg = register_points(p[:1], a.apply(p[:1]), measured_directions=d,
                          nominal_directions=RA.apply(d))
    np.testing.assert_allclose(reg.rotation, RA.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(np.degrees(reg.direction_residuals), 0.0, atol=1e-6)


@pytest.mark.parametrize(("name", "kind"), [("linear-delta", "point"),
                                            ("gough-stewart", "pose")])
def test_identified_frame_brings_readings_through_a_known_frame_onto_the_machine(name, kind):
    """Readings of the nominal machine taken through a known frame F (turned about
    non-commuting axes): from a rough registration (0.7 rad about y), the set-up that makes
    F — a rotation ``F_R R0ᵀ`` about the readings' centre ``c`` (in the roughly registered
    frame) and the translation that follows — fits the readings exactly, and ``frame(setup)``
    is F."""
    m = pkmkit.machine(name)
    r0 = Rotation.from_rotvec([0.0, 0.7, 0.0])
    rough = _reg(r0, np.array([0.1, 0.2, -0.3]))
    f_rot = Rotation.from_rotvec([0.4, 0.0, 0.0]) * r0           # about x, after y
    frame = _reg(f_rot, np.array([0.15, 0.18, -0.27]))
    exact = simulate(m, m, kind, 8, np.random.default_rng(2), noise="none")
    values = frame.inverse().apply(exact.values[:, :3])
    if kind == "pose":
        values = np.concatenate([values, frame.inverse().apply_rotations(exact.values[:, 3:6])],
                                axis=1)
    through = replace(exact, values=values)
    model = make_model(m, through, np.ones(1), registration=rough, identify_frame=True)
    c = rough.apply(values[:, :3]).mean(axis=0)
    corr = f_rot * r0.inv()                                       # F ∘ rough⁻¹
    t_corr = frame.translation - corr.apply(rough.translation)
    setup = np.concatenate([corr.as_rotvec(), t_corr - c + corr.apply(c)])
    np.testing.assert_allclose(model.frame(setup).rotation, f_rot.as_matrix(), atol=1e-12)
    np.testing.assert_allclose(model.frame(setup).translation, frame.translation, atol=1e-12)
    r, _, _ = model.residuals(m, setup, jacobian=False)
    assert np.abs(r).max() < 1e-9
    np.testing.assert_allclose(model.frame(setup).apply(values[:, :3]), exact.values[:, :3],
                               atol=1e-12)
    turned = setup.copy()
    turned[:3] = [0.0, 0.4, 0.0]
    assert np.abs(model.residuals(m, turned, jacobian=False)[0]).max() > 1e-2


@pytest.mark.parametrize(("name", "kind"), [("linear-delta", "point"),
                                            ("gough-stewart", "pose")])
def test_setup_jacobians_at_a_large_frame_rotation(name, kind):
    """The frame's Jacobian is exact, not only near a zero rotation (the second-order terms of
    the SO(3) Jacobians matter at 0.5 rad)."""
    m = pkmkit.machine(name)
    rng = np.random.default_rng(4)
    true = apply_defect_vector(m, random_defects(m, rng))
    data = simulate(true, m, kind, 6, rng, noise="none")
    model = make_model(m, data, np.ones(1), identify_frame=True)
    setup = np.array([0.3, -0.25, 0.35, 0.01, 0.02, -0.01])
    _, _, js = model.residuals(m, setup, jacobian=True)
    h = 1e-6
    for k in range(6):
        e = np.zeros(6)
        e[k] = h
        fd = (model.residuals(m, setup + e, jacobian=False)[0]
              - model.residuals(m, setup - e, jacobian=False)[0]) / (2 * h)
        np.testing.assert_allclose(js[:, :, k], fd, atol=1e-7, rtol=1e-6,
                                   err_msg=f"{kind} {model.setup.names[k]}")


def test_identification_is_the_same_from_a_file_in_m_and_in_mm(tmp_path):
    """One set of readings written in m and in mm: the same identified machine, the same
    physical values in every output unit."""
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(12)
    true = apply_defect_vector(m, random_defects(m, rng))
    data = simulate(true, m, "point", 30, rng, noise=1e-5)
    results = {}
    for unit in ("m", "mm"):
        path = tmp_path / f"{unit}.csv"
        write_measurements(path, data, m, units=unit)
        results[unit] = calibrate(m, read_measurements(path, m, "point"))
    a, b = results["m"], results["mm"]
    assert a.names == b.names
    np.testing.assert_allclose(a.values, b.values, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(a.std, b.std, rtol=1e-6)
    np.testing.assert_allclose(a.tool_uncertainty, b.tool_uncertainty, rtol=1e-6)
    ja, jb = a.to_json("m"), b.to_json("mm")
    for key in ("rms_before", "rms_after", "mean_before", "max_after", "sigma",
                "sigma_posterior"):
        assert jb[key] == pytest.approx(1e3 * ja[key], rel=1e-6), key
    assert jb["tool_uncertainty_k2"]["max"] == pytest.approx(
        1e3 * ja["tool_uncertainty_k2"]["max"], rel=1e-6)
    for n, u in ja["parameter_units"].items():
        f = 1e3 if u == "m" else 1.0
        assert jb["parameters"][n] == pytest.approx(f * ja["parameters"][n], rel=1e-6,
                                                    abs=1e-12)


def test_robust_weights_do_not_depend_on_the_stated_noise():
    """Huber's weights and the outliers are judged against the residuals' robust scale:
    stating the noise 10× larger (or the readings in other units, residuals and σ scaled
    together) changes neither."""
    rng = np.random.default_rng(1)
    r = 1e-5 * rng.normal(size=(40, 3))
    r[[4, 11]] += [[2e-4, 0, 0], [0, -1.5e-4, 0]]
    labels = tuple(f"row {i + 1}" for i in range(40))

    def model(sigma):
        return SimpleNamespace(sigma=np.full((40, 3), sigma), width=3,
                               data=SimpleNamespace(labels=labels),
                               errors=lambda rr: np.linalg.norm(rr, axis=1))

    base = _huber_weights(model(1e-5), r)
    assert base[4] < 0.5 and base[11] < 0.5 and (np.delete(base, [4, 11]) > 0.5).all()
    np.testing.assert_allclose(_huber_weights(model(1e-4), r), base, rtol=1e-12)
    np.testing.assert_allclose(_huber_weights(model(1e-2), 1e3 * r), base, rtol=1e-12)
    flagged = [lab for lab, _, _ in _outliers(model(1e-5), r, base)]
    assert flagged == ["row 5", "row 12"]
    assert [lab for lab, _, _ in _outliers(model(1e-3), r, base)] == flagged
