"""Rigid registration against exact transforms, SciPy's independent ``align_vectors`` and the
laser-tracker registration of seed 002 (Guyon 2021, Table 5.4)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmkit.exceptions import InputError
from pkmkit.spatial.registration import rigid_registration

# Table 5.4 (L1884-1912): four points measured by the tracker (LTS) and read by the CNC (BCS),
# mm; the LTS "i, j, k" columns are the long-tool tip minus the short-tool tip (a spindle
# vector of 169.889 - 110.006 = 59.883 mm), the BCS ones the CNC's unit tool directions.
LTS = np.array([[-331.205, 2567.607, 389.687], [-809.819, 2774.647, 423.530],
                [-330.062, 2558.758, 383.845], [-808.695, 2765.857, 417.398]])
LTS_DIR = np.array([[-5.357, 42.349, 41.987], [59.375, 7.779, -0.283],
                    [-5.382, 42.412, 41.934], [59.378, 7.778, -0.286]])
BCS = np.array([[794.963, 415.758, -59.545], [1242.534, 450.304, 207.671],
                [794.958, 409.808, -68.367], [1242.53, 444.061, 198.884]])
BCS_DIR = np.array([[-0.001, 0.709, 0.705], [-0.999, 0.0, 0.0], [-0.001, 0.708, 0.706],
                    [-0.999, 0.0, 0.0]])


def random_transforms(rng, batch):
    rot = Rotation.random(batch, random_state=rng).as_matrix()
    return rot, rng.normal(0.0, 2.0, (batch, 3))


def test_recovers_exact_transforms_batched():
    rng = np.random.default_rng(1)
    rot, trans = random_transforms(rng, 50)
    a = rng.normal(0.0, 1.0, (50, 6, 3))
    b = np.einsum("bij,bnj->bni", rot, a) + trans[:, None, :]
    reg = rigid_registration(a, b)
    assert reg.rotation.shape == (50, 3, 3) and reg.rms.shape == (50,)
    assert np.abs(reg.rotation - rot).max() < 1e-12
    assert np.abs(reg.translation - trans).max() < 1e-12
    assert reg.rms.max() < 1e-12 and reg.well_posed.all()
    assert np.abs(reg.apply(a) - b).max() < 1e-12
    back = reg.inverse()
    assert np.abs(back.apply(b) - a).max() < 1e-12
    assert np.allclose(reg.matrix[:, :3, :3], rot) and np.allclose(reg.matrix[:, 3], [0, 0, 0, 1])


def test_weighted_solution_matches_scipy_align_vectors():
    """Independent oracle: SciPy's Wahba solver on the weighted-centred points plus the
    directions gives the same rotation; the translation is the weighted centroid relation."""
    rng = np.random.default_rng(2)
    for _ in range(20):
        a = rng.normal(0.0, 1.0, (7, 3))
        b = a @ Rotation.random(random_state=rng).as_matrix().T + rng.normal(0, 1, 3)
        b += rng.normal(0.0, 0.05, b.shape)  # noisy: the optimum is not exact
        w = rng.uniform(0.1, 2.0, 7)
        d = rng.normal(0.0, 1.0, (2, 3))
        e = d + rng.normal(0.0, 0.2, d.shape)
        v = np.array([0.7, 3.0])
        reg = rigid_registration(a, b, weights=w, source_directions=d, target_directions=e,
                                 direction_weights=v)
        ca, cb = w @ a / w.sum(), w @ b / w.sum()
        d_unit = d / np.linalg.norm(d, axis=1)[:, None]
        e_unit = e / np.linalg.norm(e, axis=1)[:, None]
        oracle, _ = Rotation.align_vectors(np.vstack([b - cb, e_unit]),
                                           np.vstack([a - ca, d_unit]),
                                           weights=np.concatenate([w, v]))
        assert np.abs(reg.rotation - oracle.as_matrix()).max() < 1e-10
        assert np.allclose(reg.translation, cb - reg.rotation @ ca, atol=1e-12)
        # optimality: no small rotation or translation lowers the cost
        cost = _cost(reg.rotation, reg.translation, a, b, w, d_unit, e_unit, v)
        for k in range(6):
            for h in (1e-4, -1e-4):
                step = np.zeros(6)
                step[k] = h
                rot = Rotation.from_rotvec(step[3:]).as_matrix() @ reg.rotation
                assert _cost(rot, reg.translation + step[:3], a, b, w, d_unit, e_unit,
                             v) >= cost - 1e-12


def _cost(rot, trans, a, b, w, d, e, v):
    return (w * ((a @ rot.T + trans - b) ** 2).sum(axis=1)).sum() + (
        v * ((d @ rot.T - e) ** 2).sum(axis=1)).sum()


def test_directions_weigh_in_the_rotation_only():
    rng = np.random.default_rng(3)
    a = rng.normal(0.0, 1.0, (5, 3))
    rot, trans = random_transforms(rng, 1)
    b = a @ rot[0].T + trans[0] + rng.normal(0.0, 0.01, a.shape)
    d = rng.normal(0.0, 1.0, (3, 3))
    e = d @ Rotation.from_rotvec([0.0, 0.0, 0.05]).as_matrix().T @ rot[0].T  # 0.05 rad off
    loose = rigid_registration(a, b, source_directions=d, target_directions=e,
                               direction_weights=1e-9)
    plain = rigid_registration(a, b)
    assert np.allclose(loose.rotation, plain.rotation, atol=1e-8)
    tight = rigid_registration(a, b, source_directions=d, target_directions=e,
                               direction_weights=1e9)
    assert tight.direction_angles.max() < loose.direction_angles.max()
    assert tight.rms > plain.rms  # the points pay for the directions
    # scaling a direction vector changes nothing (directions are normalised)
    scaled = rigid_registration(a, b, source_directions=7.0 * d, target_directions=e,
                                direction_weights=1e9)
    assert np.allclose(scaled.rotation, tight.rotation, atol=1e-13)


def test_never_returns_a_reflection():
    rng = np.random.default_rng(4)
    a = rng.normal(0.0, 1.0, (6, 3))
    mirrored = a * np.array([-1.0, 1.0, 1.0])
    reg = rigid_registration(a, mirrored)
    assert np.isclose(np.linalg.det(reg.rotation), 1.0)
    assert reg.rms > 0.1  # a mirror image cannot be registered exactly


def test_collinear_points_are_ill_posed_unless_a_direction_fixes_the_roll():
    line = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0]])
    moved = line + np.array([0.0, 1.0, 0.0])
    with pytest.raises(InputError, match="ill-posed"):
        rigid_registration(line, moved)
    reg = rigid_registration(line, moved, source_directions=[[0.0, 0.0, 1.0]],
                             target_directions=[[0.0, 0.0, 1.0]])
    assert np.allclose(reg.rotation, np.eye(3), atol=1e-12)
    # batched: the ill-posed row is flagged and NaN, the good one kept
    batch = rigid_registration(np.stack([line, np.eye(3)]), np.stack([moved, np.eye(3)]))
    assert batch.well_posed.tolist() == [False, True]
    assert np.isnan(batch.rotation[0]).all() and np.allclose(batch.rotation[1], np.eye(3))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"source": np.zeros((3, 2)), "target": np.zeros((3, 2))}, "shape"),
    ({"source": np.eye(3), "target": np.eye(4)[:, :3]}, "same shape"),
    ({"source": [[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], "target": np.eye(3)},
     r"non-finite entry at index \(1,\)"),
    ({"source": np.eye(3), "target": np.eye(3), "weights": [1, -1, 1]}, "≥ 0"),
    ({"source": np.eye(3), "target": np.eye(3), "weights": [0, 0, 0]}, "not all be zero"),
    ({"source": np.eye(3), "target": np.eye(3), "source_directions": [[1, 0, 0]]}, "or neither"),
    ({"source": np.eye(3), "target": np.eye(3), "source_directions": [[0, 0, 0]],
      "target_directions": [[1, 0, 0]]}, "zero length"),
])
def test_bad_input_is_named(kwargs, message):
    with pytest.raises(InputError, match=message):
        rigid_registration(**kwargs)


def test_table_5_4_tracker_registration():
    """The notes' Kabsch registration of Table 5.4 (LTS → BCS): residuals 0.074 / 0.084 / 0.095
    / 0.085 mm, rms 0.085 mm; the rotated spindle vectors agree with the CNC directions within
    0.08–0.15°, and the LTS vectors are 59.883 mm long (the two tools' length difference)."""
    reg = rigid_registration(LTS, BCS)
    assert np.allclose(reg.point_errors, [0.074, 0.084, 0.095, 0.085], atol=5e-4)
    assert abs(reg.rms - 0.085) < 5e-4
    assert np.allclose(reg.rotation, [[-0.99143, -0.13046, 0.00611],
                                      [0.00438, 0.01358, 0.99990],
                                      [-0.13053, 0.99136, -0.01289]], atol=5e-5)
    assert np.allclose(reg.translation, [799.111, -7.298, -2643.210], atol=5e-3)
    turned = reg.apply_directions(LTS_DIR)
    turned /= np.linalg.norm(turned, axis=1)[:, None]
    unit = BCS_DIR / np.linalg.norm(BCS_DIR, axis=1)[:, None]
    angles = np.degrees(np.arccos(np.clip((turned * unit).sum(axis=1), -1, 1)))
    assert angles.max() < 0.16 and angles.min() > 0.07
    assert np.allclose(np.linalg.norm(LTS_DIR, axis=1), 169.889 - 110.006, atol=0.01)
    # with the directions as well (weighted as the 59.883 mm tool vector): the four points are
    # two close pairs, nearly degenerate about their long axis, so the directions turn the
    # transform by 0.15° and bring every direction within 0.07° at no cost in the points
    # (0.076 / 0.084 / 0.097 / 0.087 mm, rms 0.086)
    both = rigid_registration(LTS, BCS, source_directions=LTS_DIR, target_directions=BCS_DIR,
                              direction_weights=59.883**2)
    angle = np.degrees(np.arccos((np.trace(both.rotation.T @ reg.rotation) - 1) / 2))
    assert 0.1 < angle < 0.2
    assert np.degrees(both.direction_angles).max() < 0.075
    assert both.rms < 0.087
