"""Rigid registration: seed 002's Table 5.4 (pkmkit's fit: rms ≈ 0.085 mm; the thesis prints no
residual), exact recovery of known
transforms, directions, degenerate data, files."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.calibration.registration import (
    Registration,
    load_registration,
    register_points,
    save_registration,
)
from pkmkit.exceptions import InputError

# seed 002, Table 5.4 (mm): tracker (LTS) and controller (BCS) coordinates of 4 points; LTS
# "directions" are long-tool minus short-tool tips (norm 59.883 = 169.889 − 110.006)
LTS = np.array([[-331.205, 2567.607, 389.687], [-809.819, 2774.647, 423.530],
                [-330.062, 2558.758, 383.845], [-808.695, 2765.857, 417.398]])
BCS = np.array([[794.963, 415.758, -59.545], [1242.534, 450.304, 207.671],
                [794.958, 409.808, -68.367], [1242.53, 444.061, 198.884]])
LTS_DIR = np.array([[-5.357, 42.349, 41.987], [59.375, 7.779, -0.283],
                    [-5.382, 42.412, 41.934], [59.378, 7.778, -0.286]])
BCS_DIR = np.array([[-0.001, 0.709, 0.705], [-0.999, -0.0, -0.0],
                    [-0.001, 0.708, 0.706], [-0.999, -0.0, -0.0]])


def test_table_5_4_rms():
    reg = register_points(LTS, BCS)
    assert reg.rms == pytest.approx(0.0850, abs=5e-4)
    np.testing.assert_allclose(np.linalg.norm(reg.point_residuals, axis=1),
                               [0.0744, 0.0837, 0.0954, 0.0853], atol=5e-4)
    np.testing.assert_allclose(reg.translation, [799.111, -7.298, -2643.210], atol=2e-3)
    # the spindle directions agree within 0.16° after rotation (notes §4.2)
    d = reg.apply_directions(LTS_DIR / np.linalg.norm(LTS_DIR, axis=1)[:, None])
    cos = np.einsum("ij,ij->i", d, BCS_DIR / np.linalg.norm(BCS_DIR, axis=1)[:, None])
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 0.16
    np.testing.assert_allclose(np.linalg.norm(LTS_DIR, axis=1), 169.889 - 110.006, atol=0.01)


def test_directions_fix_the_rotation_of_nearly_degenerate_points():
    """Table 5.4's points are two pairs 10.7 mm apart: the directions tighten the rotation."""
    with_dirs = register_points(LTS, BCS, measured_directions=LTS_DIR,
                                nominal_directions=BCS_DIR)
    assert np.degrees(with_dirs.direction_residuals).max() < 0.07
    assert with_dirs.rms < 0.12


def test_exact_transform_is_recovered():
    rng = np.random.default_rng(3)
    rot = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    t = rng.normal(size=3)
    pts = rng.normal(size=(6, 3))
    reg = register_points(pts, pts @ rot.T + t)
    np.testing.assert_allclose(reg.rotation, rot, atol=1e-12)
    np.testing.assert_allclose(reg.translation, t, atol=1e-12)
    assert reg.rms < 1e-12
    # directions alone with one point (collinear data otherwise)
    dirs = rng.normal(size=(2, 3))
    reg = register_points(pts[:1], pts[:1] @ rot.T + t, measured_directions=dirs,
                          nominal_directions=dirs @ rot.T)
    np.testing.assert_allclose(reg.rotation, rot, atol=1e-12)
    # inverse and composition
    back = reg.inverse().compose(reg)
    np.testing.assert_allclose(back.rotation, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(back.translation, 0.0, atol=1e-12)


def test_registration_refuses_degenerate_and_bad_input():
    line = np.outer(np.arange(4.0), [1.0, 2.0, 3.0])
    with pytest.raises(InputError, match="do not fix the rotation"):
        register_points(line, line + 1.0)
    with pytest.raises(InputError, match="at least 3 points"):
        register_points(LTS[:2], BCS[:2])
    with pytest.raises(InputError, match="differ in number"):
        register_points(LTS, BCS[:3])
    bad = LTS.copy()
    bad[2, 1] = np.nan
    with pytest.raises(InputError, match="row 2 is not finite"):
        register_points(bad, BCS)
    with pytest.raises(InputError, match="both frames"):
        register_points(LTS, BCS, measured_directions=LTS_DIR)


def test_registration_file_round_trip(tmp_path):
    reg = register_points(LTS / 1e3, BCS / 1e3)
    path = tmp_path / "frame.json"
    save_registration(path, reg, units="mm")
    data = json.loads(path.read_text())
    assert data["units"] == "mm"
    assert data["rms"] == pytest.approx(0.085, abs=5e-4)
    back = load_registration(path)
    np.testing.assert_allclose(back.apply(LTS / 1e3), reg.apply(LTS / 1e3), atol=1e-12)
    path.write_text('{"rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 2]], "translation": [0, 0, 0]}')
    with pytest.raises(InputError, match="not a rotation"):
        load_registration(path)
    # an entry of 1e308: R^T R overflowed with a RuntimeWarning (issue 18 §7 fuzz)
    path.write_text('{"rotation": [[0, -1, 0], [1, 0, 0], [0, -1e308, 1]], '
                    '"translation": [0, 0, 0]}')
    with pytest.raises(InputError, match="not a rotation"):
        load_registration(path)
    path.write_text("{")
    with pytest.raises(InputError, match="not JSON"):
        load_registration(path)
    assert Registration.identity().rms == 0.0


def test_registration_file_that_is_not_text_or_too_deep(tmp_path):
    """Binary garbage, deeply nested JSON and a 5000-digit number as --frame (issue 18 §7 fuzz:
    UnicodeDecodeError, RecursionError, ValueError)."""
    path = tmp_path / "frame.json"
    path.write_bytes(b"\xff\xfe{\x00")
    with pytest.raises(InputError, match=r"frame\.json: not a UTF-8 text file \(byte 0\)"):
        load_registration(path)
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(InputError, match="nested too deeply"):
        load_registration(path)
    path.write_text('{"units": "m", "translation": [' + "7" * 5000 + ', 0, 0]}')
    with pytest.raises(InputError, match="not a registration JSON: Exceeds the limit"):
        load_registration(path)


def test_a_direction_lever_arm_beyond_1000_km_is_a_unit_mistake():
    """--direction-weight 1e300 (issue 18 §7 fuzz: OverflowError squaring it)."""
    for lever in (1e300, 2e6):
        with pytest.raises(InputError, match=r"direction_weight = .* beyond 1e\+06 m"):
            register_points(LTS / 1e3, BCS / 1e3, measured_directions=LTS_DIR,
                            nominal_directions=BCS_DIR, direction_weight=lever)
    reg = register_points(LTS / 1e3, BCS / 1e3, measured_directions=LTS_DIR,
                          nominal_directions=BCS_DIR, direction_weight=1e6)
    assert np.isfinite(reg.rotation).all()
