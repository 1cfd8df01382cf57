"""Linear Delta against seed 000 (Bourebbou 2019), with the seed's errata handled."""

import math

import numpy as np
import pytest

import pkmkit

R, r, L = 0.7, 0.15, 1.3

# Table III.2 (L1422-1434): the 11 entries that agree with the corrected IGM, as (pose, leg, q).
# They are printed with 4-5 decimals; two (1.0780 and 1.5780, exact 1.07789 and 1.57789) are off
# by one unit in the last digit, hence the 1.5e-4 m tolerance.
TABLE_III2_CONSISTENT = [
    ((0.25, 0.25, 0.0), 0, 1.240),
    ((0.25, 0.25, 0.0), 1, 1.1675),
    ((0.25, 0.25, 0.0), 2, 0.94173),
    ((0.25, -0.25, 0.0), 0, 1.24),
    ((0.25, -0.25, 0.0), 2, 1.1675),
    ((-0.25, 0.25, 0.0), 1, 1.2799),
    ((-0.25, 0.25, 0.5), 1, 1.7799),
    ((-0.25, -0.25, 0.0), 1, 1.0780),
    ((-0.25, -0.25, 0.0), 2, 1.2799),
    ((-0.25, -0.25, 0.5), 1, 1.5780),
    ((-0.25, -0.25, 0.5), 2, 1.7799),
]

# The 13 inconsistent entries (seed value, and where it comes from; see docs/seed-errata.md).
TABLE_III2_INCONSISTENT = [
    ((0.25, 0.25, 0.5), 0, 1.49), ((0.25, 0.25, 0.5), 1, 1.1917), ((0.25, 0.25, 0.5), 2, 1.1917),
    ((0.25, -0.25, 0.0), 1, 1.1675),
    ((0.25, -0.25, 0.5), 0, 1.49), ((0.25, -0.25, 0.5), 1, 1.4175),
    ((0.25, -0.25, 0.5), 2, 1.4175),
    ((-0.25, 0.25, 0.0), 0, 1.5058), ((-0.25, 0.25, 0.0), 2, 1.4889),
    ((-0.25, 0.25, 0.5), 0, 2.0058), ((-0.25, 0.25, 0.5), 2, 1.9889),
    ((-0.25, -0.25, 0.0), 0, 1.5058), ((-0.25, -0.25, 0.5), 0, 2.0058),
]


def seed_igm(x, y, z):
    """Corrected (III.5): q_i = z + sqrt(L² − (x − d cos θ_i)² − (y − d sin θ_i)²), d = R − r."""
    d = R - r
    out = []
    for theta in (0.0, 2 * math.pi / 3, 4 * math.pi / 3):
        out.append(z + math.sqrt(L**2 - (x - d * math.cos(theta)) ** 2
                                 - (y - d * math.sin(theta)) ** 2))
    return out


@pytest.fixture(scope="module")
def delta():
    return pkmkit.machine("linear-delta")


def test_reference_entry(delta):
    np.testing.assert_allclose(delta.ik([0.25, 0.25, 0.0]), [1.240, 1.1675, 0.94173], atol=5e-5)


@pytest.mark.parametrize("pose, leg, value", TABLE_III2_CONSISTENT)
def test_table_iii2_consistent_entries(delta, pose, leg, value):
    assert delta.ik(pose)[leg] == pytest.approx(value, abs=1.5e-4)


def test_table_iii2_inconsistent_entries_follow_the_corrected_model(delta):
    """At the 13 misprinted entries the library gives the corrected (III.5) exactly — and so
    not the printed number (each is ≥ 1 cm away; see docs/seed-errata.md)."""
    for pose, leg, printed in TABLE_III2_INCONSISTENT:
        value = delta.ik(pose)[leg]
        assert value == pytest.approx(seed_igm(*pose)[leg], abs=1e-14)
        assert abs(value - printed) > 1e-2


def test_matches_independent_formula_on_random_poses(delta):
    rng = np.random.default_rng(0)
    poses = rng.uniform([-0.25, -0.25, 0.0], [0.25, 0.25, 0.5], (200, 3))
    expected = np.array([seed_igm(*p) for p in poses])
    np.testing.assert_allclose(delta.ik(poses), expected, atol=1e-13)


@pytest.mark.parametrize("ident, dims, value", [
    ("linear-delta", (0.7, 0.15, 1.3), 1.1779218989),
    ("linear-delta-table-iv1", (0.7, 0.15, 1.04), 0.8826664149),
])
def test_centre_of_both_dimension_sets(ident, dims, value):
    """At the centre every carriage is sqrt(L² − (R − r)²) above the nacelle; the presets carry
    the seed's dimensions (written here independently of the preset files)."""
    m = pkmkit.machine(ident)
    big_r, small_r, length = dims
    assert (m.params["R"], m.params["r"], m.params["L"]) == pytest.approx(dims, rel=1e-15)
    expected = math.sqrt(length**2 - (big_r - small_r) ** 2)
    assert expected == pytest.approx(value, abs=1e-10)
    np.testing.assert_allclose(m.ik([0, 0, 0]), [expected] * 3, rtol=0, atol=1e-15)


def test_plane_map_extremes(delta):
    """Figs 3.9-3.11 (z = 0, |x|, |y| <= 0.25 m): extremes of the corrected IGM."""
    g = np.linspace(-0.25, 0.25, 201)
    xx, yy = np.meshgrid(g, g)
    q = delta.ik(np.column_stack([xx.ravel(), yy.ravel(), np.zeros(xx.size)]))
    np.testing.assert_allclose(q.min(axis=0), [0.9937, 0.9417, 0.9417], atol=1e-4)
    np.testing.assert_allclose(q.max(axis=0), [1.2649, 1.2799, 1.2799], atol=1e-4)


def test_seed_jacobians_iv5_iv6(delta):
    """J_x and J_q of (IV.5)-(IV.6) equal A and B."""
    x, y, z = 0.1, -0.2, 0.3
    q1, q2, q3 = delta.ik([x, y, z])
    s3 = math.sqrt(3) / 2
    jx = np.array([
        [r - R + x, y, z - q1],
        [(R - r) / 2 + x, s3 * (r - R) + y, z - q2],
        [(R - r) / 2 + x, s3 * (R - r) + y, z - q3],
    ])
    jq = np.diag([z - q1, z - q2, z - q3])
    jac = delta.jacobian([x, y, z])
    np.testing.assert_allclose(jac.A, jx, atol=1e-14)
    np.testing.assert_allclose(jac.B, jq, atol=1e-14)


def test_vertical_motion_moves_all_carriages_equally(delta):
    jac = delta.jacobian([0.05, 0.1, 0.2])
    np.testing.assert_allclose(jac.J_inv @ [0, 0, 1.0], [1.0, 1.0, 1.0], atol=1e-14)


def test_acceleration_mapping_ii35(delta):
    """q̈ = J⁻¹ẍ + J_q⁻¹(J̇_x − J̇_q J⁻¹)ẋ, with (IV.12)-(IV.13), against finite differences."""
    t = np.linspace(0.0, 1.0, 5)
    h = 1e-4

    def path(s):
        return np.column_stack([0.1 * np.cos(s), 0.1 * np.sin(s), 0.2 + 0.05 * s])

    x, xd = path(t), np.column_stack([-0.1 * np.sin(t), 0.1 * np.cos(t), 0.05 * np.ones_like(t)])
    xdd = np.column_stack([-0.1 * np.cos(t), -0.1 * np.sin(t), np.zeros_like(t)])
    jac = delta.jacobian(x)
    rates = delta.jacobian_dot(x, xd)
    qd = rates.qd
    jx_dot = np.stack([np.column_stack([xd[:, :2], xd[:, 2] - qd[:, i]]) for i in range(3)], 1)
    jq_dot = np.stack([np.diag(xd[k, 2] - qd[k]) for k in range(len(t))])
    np.testing.assert_allclose(rates.A_dot, jx_dot, atol=1e-14)
    np.testing.assert_allclose(rates.B_dot, jq_dot, atol=1e-14)
    qdd = np.einsum("kij,kj->ki", jac.J_inv, xdd) + np.einsum(
        "kij,kj->ki", np.linalg.inv(jac.B),
        np.einsum("kij,kj->ki", rates.A_dot - jq_dot @ jac.J_inv, xd))
    fd = (delta.ik(path(t + h)) - 2 * delta.ik(path(t)) + delta.ik(path(t - h))) / h**2
    np.testing.assert_allclose(qdd, fd, atol=1e-5)


def test_modes_are_nacelle_below_and_above(delta):
    q = delta.ik([0.0, 0.0, 0.0])
    modes = delta.fk_all(q)
    assert modes.labels == ("nacelle-below", "nacelle-above")
    assert modes.poses[0, 2] < q.min() < modes.poses[1, 2]
    # reversed slide order flips the orientation, not the names' meaning
    flipped = delta.with_params(angles=tuple(np.radians([0.0, 240.0, 120.0])))
    assert flipped.working_mode == -delta.working_mode
    assert flipped.mode_labels[0] == "nacelle-below"


@pytest.mark.parametrize("outside", [1e-7, 1e-9])
def test_a_pose_just_out_of_reach_is_unreachable(delta, outside):
    """Leg 1's rod is too short by ``outside`` metres: no clamping tolerance may hide it, while
    the same pose moved inside by as much is reachable with the rod horizontal (q1 = z)."""
    d = R - r
    z = 0.1
    out = np.array([d - (L + outside), 0.0, z])
    inside = np.array([d - (L - outside), 0.0, z])
    res = delta.ik(np.array([out, inside]), full_output=True)
    assert res.status.tolist() == [pkmkit.Status.UNREACHABLE, pkmkit.Status.OK]
    assert np.isnan(res.q[0]).all()
    assert res.q[1, 0] == pytest.approx(z + math.sqrt(L**2 - (L - outside) ** 2), abs=1e-12)
    with pytest.raises(pkmkit.UnreachablePoseError, match="leg 1"):
        delta.ik(out)


def test_vertical_static_load_is_shared_in_thirds(delta):
    """F_mot = Jᵀ F_nac: at a symmetric pose a vertical load splits equally."""
    jac = delta.jacobian([0.0, 0.0, 0.2])
    np.testing.assert_allclose(jac.J.T @ [0, 0, -300.0], [-100.0] * 3, atol=1e-10)


def test_default_box_is_the_documented_one(delta):
    """|x|, |y| ≤ 0.4 L and −0.4 L ≤ z ≤ 0.65 L (the maps' and workspaces' default region)."""
    lower, upper = delta.default_box()
    np.testing.assert_allclose(lower, [-0.52, -0.52, -0.52], rtol=1e-15)
    np.testing.assert_allclose(upper, [0.52, 0.52, 0.845], rtol=1e-15)


def test_invalid_dimensions():
    with pytest.raises(pkmkit.ParameterError, match="smaller than L"):
        pkmkit.machine("linear-delta", L=0.5)
    with pytest.raises(pkmkit.ParameterError, match="distinct"):
        pkmkit.machine("linear-delta", angles=(0.0, 0.0, 1.0))
    with pytest.raises(pkmkit.ParameterError, match=">= 0"):
        pkmkit.machine("linear-delta", r=-0.01)


def test_firmware_effective_radius_is_the_same_machine():
    """Delta firmware gives R_eff = R − r and r = 0: every model agrees with (R, r)."""
    seed = pkmkit.machine("linear-delta")
    firmware = pkmkit.machine("linear-delta", R=R - r, r=0.0)
    x = np.random.default_rng(5).uniform(-0.3, 0.3, (500, 3))
    q = seed.ik(x)
    np.testing.assert_allclose(firmware.ik(x), q, atol=1e-14)
    np.testing.assert_allclose(firmware.fk(q), x, atol=1e-12)
    np.testing.assert_allclose(firmware.jacobian(x).J, seed.jacobian(x).J, atol=1e-12)
    numeric = firmware.fk(q[:50], method="numeric", dof="full", full_output=True)
    assert (numeric.status == 0).all()
    np.testing.assert_allclose(numeric.pose, x[:50], atol=1e-9)
    assert firmware.mobility()["instantaneous"].mobility == 3


def test_tower_angles_in_any_order():
    """Klipper's default towers (210°, 330°, 90°) and a permuted, clockwise order: the same
    carriages, relabelled; modes keep their physical names."""
    x = np.random.default_rng(6).uniform(-0.25, 0.25, (300, 3))
    ccw = pkmkit.machine("linear-delta", angles=np.radians([210.0, 330.0, 90.0]))
    cw = pkmkit.machine("linear-delta", angles=np.radians([90.0, 330.0, 210.0]))
    np.testing.assert_allclose(cw.ik(x), ccw.ik(x)[:, ::-1], atol=1e-14)
    assert cw.mode_labels[0] == ccw.mode_labels[0] == "nacelle-below"
    np.testing.assert_allclose(cw.fk(cw.ik(x)), x, atol=1e-12)
    # angles beyond 180° and negative ones are the same towers
    wrapped = pkmkit.machine("linear-delta", angles=np.radians([-150.0, -30.0, 90.0]))
    np.testing.assert_allclose(wrapped.ik(x), ccw.ik(x), atol=1e-12)
