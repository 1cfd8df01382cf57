"""TriMule 600 (seed 002 §3.4): structure and hyperstatism, the solver against the closed forms
of the measured leg, the thesis's own equations (3.26)–(3.36) evaluated at the solver's joints,
and the complete machine's inverse model and Jacobian."""

import math

import numpy as np
import pytest
from numpy import cos as C
from numpy import sin as S
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.machines import trimule_forms as forms
from pkmkit.spatial.rotation import rotvec_to_matrix
from pkmkit.status import Status

N_RANDOM = 500


@pytest.fixture(scope="module")
def machine():
    return pkmkit.machine("trimule-600")


@pytest.fixture(scope="module")
def sample(machine):
    """500 random configurations of the measured leg and the head, their actuator values by
    the closed form, and the engine's direct model of them."""
    rng = np.random.default_rng(2021)
    n = N_RANDOM
    leg = {"L4": rng.uniform(0.85, 1.15, n), "psi1": np.radians(rng.uniform(-12.5, 12.5, n)),
           "theta4": np.radians(rng.uniform(-12.5, 12.5, n))}
    head = np.column_stack([rng.uniform(-math.pi, math.pi, n),
                            np.radians(rng.uniform(-45, 45, n))])
    q = np.column_stack([forms.actuators(machine.params, leg["L4"], leg["psi1"],
                                         leg["theta4"]), head])
    direct = machine.fk(q, full_output=True)
    joints = {name: direct.passive[:, i] for i, name in enumerate(machine.passive_names)}
    joints.update(Q1=q[:, 0], Q2=q[:, 1], Q3=q[:, 2], Q4=q[:, 3], Q5=q[:, 4])
    return {"leg": leg, "q": q, "direct": direct, "joints": joints}


def test_structure_and_hyperstatism(machine):
    count = machine.hyperstatism()
    # 19 one-DOF joints (ψ1 once, although legs 1, 3 and 4 name it), 16 passive
    assert count.joints == 19 and count.joints_by_type == {"R": 15, "P": 4}
    assert len(machine.passive_names) == 16
    assert machine.actuator_names == ("Q1", "Q2", "Q3", "Q4", "Q5")
    # bodies: base, platform, ring (after ψ1) and one per non-final joint of each leg
    assert count.bodies == 17 and count.loops == 3
    # Fayet/Grübler: h = 6ν − Σf + m = 6·3 − 19 + 3 (eq. 3.2 printed the Tripteor's 6·2 − 13)
    assert count.mobility == 3 and count.hyperstatism == 6 * 3 - 19 + 3 == 2
    assert count.grubler_mobility == 1  # the count blind to the geometry: 3 − h
    # rank: 24 closure equations, 2 of them redundant
    assert count.rank_hyperstatism == 2
    legs = [[machine.model.elements[e].name for e in leg] for leg in machine.model.legs]
    assert [leg[0] for leg in legs] == ["psi1", "psi2", "psi1", "psi1"]


def test_home_closes_exactly_at_the_symmetric_configuration(machine):
    assert machine.home_closure_residual < 1e-14
    params = machine.params
    # at θ4 = 0 both legs 1 and 3 have the length sqrt(((L − l)/2)² + L4²) (notes C5)
    expected = math.hypot((params["L"] - params["l"]) / 2, params["L4_home"])
    assert machine.home_q[0] == pytest.approx(expected, abs=1e-15)
    assert machine.home_q[2] == pytest.approx(expected, abs=1e-15)
    assert machine.home_q[1] == pytest.approx(math.hypot(params["H"] - params["h"],
                                                         params["L4_home"]), abs=1e-15)


def test_direct_model_closes_on_every_random_configuration(sample):
    direct = sample["direct"]
    assert (direct.status == Status.OK).all()
    assert direct.closure_residual.max() < 1e-12
    assert not direct.out_of_stroke.any()


def test_structural_invariants_c3(sample):
    j = sample["joints"]
    for name in ("eta1", "eta3", "kappa1", "kappa3"):
        assert np.abs(j[name]).max() < 1e-12, name
    # φ1 and θ1 turn about parallel axes, φ3 about the axis opposite to θ3 (our frames, which
    # are the thesis's: eq. 3.28)
    assert np.abs(j["phi1"] + j["theta1"] - j["theta4"]).max() < 1e-12
    assert np.abs(j["theta3"] - j["phi3"] - j["theta4"]).max() < 1e-12
    # the measured leg is what the solver found
    for name in ("L4", "psi1", "theta4"):
        assert np.abs(j[name] - sample["leg"][name]).max() < 1e-12, name


def test_platform_pose_from_the_measured_leg_eq_3_31(machine, sample):
    j = sample["joints"]
    rot, p = forms.platform_pose(j["L4"], j["psi1"], j["theta4"])
    platform = sample["direct"].platform
    assert np.abs(platform[:, :3] - p).max() < 1e-12
    assert np.abs(rotvec_to_matrix(platform[:, 3:]) - rot).max() < 1e-12
    # (3.31) as printed: X = −L4 sin θ4, Y = L4 cos θ4 sin ψ1, Z = L4 cos θ4 cos ψ1, and the
    # thesis's Cardan x–z–y angles (β_P = π, γ_P = θ4) with α_P = −ψ1 (erratum: printed +ψ1)
    length, psi, theta = j["L4"], j["psi1"], j["theta4"]
    printed = np.column_stack([-length * S(theta), length * C(theta) * S(psi),
                               length * C(theta) * C(psi)])
    assert np.abs(platform[:, :3] - printed).max() < 1e-12
    cardan = Rotation.from_euler("XZY", np.column_stack([-psi, np.full_like(psi, np.pi),
                                                         theta])).as_matrix()
    assert np.abs(rotvec_to_matrix(platform[:, 3:]) - cardan).max() < 1e-12
    literal = Rotation.from_euler("XZY", np.column_stack([psi, np.full_like(psi, np.pi),
                                                          theta])).as_matrix()
    assert np.abs(rotvec_to_matrix(platform[:, 3:]) - literal).max() > 0.1


def test_closed_form_actuators_q1_q3_and_passive_joints(machine, sample):
    j = sample["joints"]
    params = machine.params
    big, small = params["L"], params["l"]
    length, theta = j["L4"], j["theta4"]
    # notes §2.4 [derived], from the solver's (not the sampled) measured leg
    q1 = 0.5 * np.sqrt((big - small * C(theta) + 2 * length * S(theta)) ** 2
                       + (small * S(theta) + 2 * length * C(theta)) ** 2)
    q3 = 0.5 * np.sqrt((-big + small * C(theta) + 2 * length * S(theta)) ** 2
                       + (-small * S(theta) + 2 * length * C(theta)) ** 2)
    assert np.abs(q1 - sample["q"][:, 0]).max() < 1e-12
    assert np.abs(q3 - sample["q"][:, 2]).max() < 1e-12
    closed = forms.passive_joints(params, j["L4"], j["psi1"], j["theta4"])
    for name in machine.passive_names:
        assert np.abs(closed[name] - j[name]).max() < 1e-11, name


def test_closed_form_direct_model_matches_the_engine(machine, sample):
    leg = forms.measured_leg(machine.params, sample["q"][:, :3])
    expected = np.column_stack([sample["leg"][k] for k in ("L4", "psi1", "theta4")])
    assert np.abs(leg - expected).max() < 1e-12
    pose = forms.direct(machine.params, sample["q"], machine.tool_length)
    assert np.abs(pose - sample["direct"].pose).max() < 1e-12


def test_closed_form_direct_model_flags_lengths_without_assembly(machine):
    q = np.array([[1.0, 1.0, 1.0], [0.1, 1.0, 1.0], [1.0, 5.0, 1.0], [np.nan, 1.0, 1.0]])
    leg = forms.measured_leg(machine.params, q)
    assert np.isfinite(leg[0]).all() and np.isnan(leg[1:]).all()


def test_thesis_projected_closures_3_26_hold_in_our_frames(machine, sample):
    """(3.26) printed term by term (line 9 with its OCR-lost factors l restored): our frames
    are the thesis's."""
    j, p = sample["joints"], machine.params
    big, small, hb, hs, length = p["L"], p["l"], p["H"], p["h"], j["L4"]
    q1, q2, q3 = j["Q1"], j["Q2"], j["Q3"]
    ps1, t4 = j["psi1"], j["theta4"]
    t1, e1, k1, p1 = j["theta1"], j["eta1"], j["kappa1"], j["phi1"]
    ps2, t2, e2, k2, f2 = j["psi2"], j["theta2"], j["eta2"], j["kappa2"], j["phi2"]
    t3, e3, k3, p3 = j["theta3"], j["eta3"], j["kappa3"], j["phi3"]
    lines = [
        big - small * C(e1) * C(t1) * C(p1) - 2 * q1 * S(t1) + 2 * length * S(t4)
        + small * (C(k1) * S(t1) + C(t1) * S(e1) * S(k1)) * S(p1),
        q1 * C(t1) * S(ps1) - length * C(t4) * S(ps1) - 0.5 * small * (
            C(p1) * (C(ps1) * S(e1) + C(e1) * S(t1) * S(ps1)) + S(p1) * (
                C(e1) * C(ps1) * S(k1) + (C(t1) * C(k1) - S(e1) * S(t1) * S(k1)) * S(ps1))),
        -q1 * C(t1) * C(ps1) + length * C(t4) * C(ps1) + 0.5 * (
            small * C(ps1) * (C(e1) * C(p1) * S(t1) + (C(t1) * C(k1) - S(e1) * S(t1) * S(k1))
                              * S(p1))
            - small * (C(p1) * S(e1) + C(e1) * S(k1) * S(p1)) * S(ps1)),
        length * S(t4) - S(t2) * (q2 + hs * C(k2) * S(f2))
        - hs * C(t2) * (C(f2) * S(e2) + C(e2) * S(k2) * S(f2)),
        -hb - length * C(t4) * S(ps1) + q2 * C(t2) * S(ps2)
        + hs * C(t2) * C(k2) * S(f2) * S(ps2)
        - hs * S(k2) * S(f2) * (C(ps2) * S(e2) + C(e2) * S(t2) * S(ps2))
        + hs * C(f2) * (C(e2) * C(ps2) - S(e2) * S(t2) * S(ps2)),
        length * C(t4) * C(ps1) - C(t2) * C(ps2) * (q2 + hs * C(k2) * S(f2))
        + hs * C(ps2) * S(t2) * (C(f2) * S(e2) + C(e2) * S(k2) * S(f2))
        + hs * (C(e2) * C(f2) - S(e2) * S(k2) * S(f2)) * S(ps2),
        0.5 * (-big + small * C(e3) * C(t3) * C(p3) - 2 * q3 * S(t3) + 2 * length * S(t4)
               + small * (C(k3) * S(t3) + C(t3) * S(e3) * S(k3)) * S(p3)),
        q3 * C(t3) * S(ps1) - length * C(t4) * S(ps1) + 0.5 * small * (
            C(p3) * (C(ps1) * S(e3) + C(e3) * S(t3) * S(ps1)) - S(p3) * (
                C(e3) * C(ps1) * S(k3) + (C(t3) * C(k3) - S(e3) * S(t3) * S(k3)) * S(ps1))),
        -q3 * C(t3) * C(ps1) + length * C(t4) * C(ps1) + 0.5 * small * (
            C(ps1) * (C(t3) * C(k3) - S(e3) * S(t3) * S(k3)) * S(p3) + C(p3) * S(e3) * S(ps1)
            - C(e3) * (C(p3) * C(ps1) * S(t3) + S(k3) * S(p3) * S(ps1))),
    ]
    for i, line in enumerate(lines):
        assert np.abs(line).max() < 1e-12, f"(3.26) line {i + 1}"


def test_thesis_angular_closures_3_27_of_leg_2(sample):
    """The six leg-2 lines of (3.27): the only ones where every angle is non-zero."""
    j = sample["joints"]
    ps1, t4 = j["psi1"], j["theta4"]
    ps2, t2, e2, k2, f2 = j["psi2"], j["theta2"], j["eta2"], j["kappa2"], j["phi2"]
    lines = [
        C(e2) * C(t2) * C(k2) - S(t2) * S(k2) - C(t4),
        -C(k2) * S(t2) * S(f2) - C(t2) * (C(f2) * S(e2) + C(e2) * S(k2) * S(f2)),
        C(k2) * C(f2) * S(t2) - S(t4) + C(t2) * (C(e2) * C(f2) * S(k2) - S(e2) * S(f2)),
        C(t2) * S(k2) * S(ps2) + C(k2) * (C(ps2) * S(e2) + C(e2) * S(t2) * S(ps2))
        - S(t4) * S(ps1),
        (C(t2) * C(k2) * S(f2) - C(f2) * S(e2) * S(t2)) * S(ps2)
        - C(ps2) * S(e2) * S(k2) * S(f2)
        + C(e2) * (C(f2) * C(ps2) - S(t2) * S(k2) * S(f2) * S(ps2)) - C(ps1),
        C(f2) * (C(ps2) * S(e2) * S(k2) + (C(e2) * S(t2) * S(k2) - C(t2) * C(k2)) * S(ps2))
        + S(f2) * (C(e2) * C(ps2) - S(e2) * S(t2) * S(ps2)) + C(t4) * S(ps1),
    ]
    for i, line in enumerate(lines):
        assert np.abs(line).max() < 1e-12, f"(3.27) leg-2 line {i + 1}"


def test_thesis_result_3_28(machine, sample):
    j, p = sample["joints"], machine.params
    big, small, length = p["L"], p["l"], j["L4"]
    t1, t2, t3, t4 = j["theta1"], j["theta2"], j["theta3"], j["theta4"]
    e2, k2, f2 = j["eta2"], j["kappa2"], j["phi2"]
    checks = {
        "S(θ1)": S(t1) - (big - small * C(t4) + 2 * length * S(t4)) / (2 * j["Q1"]),
        "C(θ1)": C(t1) - (small * S(t4) + 2 * length * C(t4)) / (2 * j["Q1"]),
        "S(θ3)": S(t3) - (-big + small * C(t4) + 2 * length * S(t4)) / (2 * j["Q3"]),
        "C(θ3)": C(t3) - (-small * S(t4) + 2 * length * C(t4)) / (2 * j["Q3"]),
        "C(η2)": C(e2) - (C(t4) + S(t2) * S(k2)) / (C(t2) * C(k2)),
        "S(η2)": S(e2) + (S(t2) + C(t4) * S(k2)) * S(f2) / (C(t2) * C(f2) * C(k2)),
        "S(θ2)": S(t2) - length * S(t4) / j["Q2"],
    }
    for name, value in checks.items():
        assert np.abs(value).max() < 1e-12, name
    # η2, κ2, φ2 vary over the sample: the leg-2 formulas are really exercised
    assert min(np.ptp(e2), np.ptp(k2), np.ptp(f2)) > 0.02


def test_al_kashi_3_29_in_triangle_a4_a2_b2(machine, sample):
    j, p = sample["joints"], machine.params
    points = forms.platform_points(p, j["L4"], j["psi1"], j["theta4"])
    lam = np.linalg.norm(points["B2"] - points["A4"], axis=1)
    cos_alpha = (p["H"] ** 2 + j["Q2"] ** 2 - lam ** 2) / (2 * p["H"] * j["Q2"])
    # the angle at A2 between A2A4 and the leg: + sin ψ2 cos θ2 with the ψ2 of (3.26); the
    # printed −sin ψ2 cos θ2 uses the opposite sense of ψ2 (Fig. 3.13's frames are lost)
    assert np.abs(cos_alpha - S(j["psi2"]) * C(j["theta2"])).max() < 1e-12


def _tool_cardan(direct):
    """The tool frame's Cardan angles in the thesis's x–z–y convention of (3.35)."""
    return Rotation.from_rotvec(np.array(direct.tool_frame[:, 3:])).as_euler("XZY").T


def test_head_orientation_3_35_and_3_36(machine, sample):
    j = sample["joints"]
    q4, q5 = j["Q4"], j["Q5"]
    a_p, b_p, g_p = -j["psi1"], np.full_like(q4, np.pi), j["theta4"]
    a_t, b_t, g_t = _tool_cardan(sample["direct"])
    eq_3_35 = [
        C(q4) * C(q5) * C(b_p) * C(g_p) - (S(q4) * C(q5) * S(b_p) + S(q5) * C(b_p) * S(g_p)
                                           + C(b_t) * C(g_t)),
        S(q4) * C(b_p) * C(g_p) + C(q4) * S(b_p) - S(b_t),
        S(q4) * S(q5) * S(b_p) + C(b_t) * S(g_t)
        - C(b_p) * (C(q4) * S(q5) * C(g_p) + C(q5) * S(g_p)),
        C(q4) * C(a_p) * C(b_p) - (S(q4) * (C(a_p) * S(b_p) * C(g_p) + S(a_p) * S(g_p))
                                   + C(a_t) * C(b_t)),
        S(a_p) * (C(q4) * C(b_p) - S(q4) * S(b_p) * C(g_p)) + S(q4) * C(a_p) * S(g_p)
        - S(a_t) * C(b_t),
    ]
    for i, line in enumerate(eq_3_35):
        assert np.abs(line).max() < 1e-12, f"(3.35) line {i + 1}"
    # (3.36) γ_T (tan γ = N/D, checked as N cos γ − D sin γ = 0)
    num = (-C(q4) * S(q5) * C(b_p) * C(g_p) + S(q4) * S(q5) * S(b_p) - C(q5) * C(b_p) * S(g_p))
    den = (-C(q4) * C(q5) * C(b_p) * C(g_p) + S(q4) * C(q5) * S(b_p) + S(q5) * C(b_p) * S(g_p))
    assert np.abs(num * C(g_t) - den * S(g_t)).max() < 1e-12
    # (3.36) β_T: sin β_T = S(Q4) C(βP) C(γP) + C(Q4) S(βP)
    assert np.abs(S(b_t) - (S(q4) * C(b_p) * C(g_p) + C(q4) * S(b_p))).max() < 1e-12
    # (3.36) α_T as printed lacks S(Q4) in two terms (erratum); with it, it is (3.35)'s
    def alpha_residual(sq4_on_last_terms):
        f = S(q4) if sq4_on_last_terms else 1.0
        num = S(q4) * S(a_p) * S(b_p) * C(g_p) - f * C(a_p) * S(g_p) - C(q4) * S(a_p) * C(b_p)
        den = S(q4) * C(a_p) * S(b_p) * C(g_p) + f * S(a_p) * S(g_p) - C(q4) * C(a_p) * C(b_p)
        return np.abs(num * C(a_t) - den * S(a_t)).max()

    assert alpha_residual(True) < 1e-12
    assert alpha_residual(False) > 1e-2


def test_tool_point_3_36(machine, sample):
    """(3.36)'s tool point with (α_P, β_P, γ_P) = (−ψ1, π, θ4) and c1, c2, L_outil of opposite
    signs (its head points along −z_P) is our tool point; L_outil = spindle + tool length."""
    j, p = sample["joints"], machine.params
    q4, q5 = j["Q4"], j["Q5"]
    a, b, g = -j["psi1"], np.full_like(q4, np.pi), j["theta4"]
    c1, c2, lo = -p["c1"], -p["c2"], -(p["spindle"] + machine.tool_length)
    x_p, y_p, z_p = sample["direct"].platform[:, :3].T
    x_t = (c1 * (-C(b)) * S(g) - c2 * C(q4) * C(b) * C(g) + c2 * S(q4) * S(b)
           - lo * C(q4) * S(q5) * C(b) * C(g) + lo * S(q4) * S(q5) * S(b)
           - lo * C(q5) * C(b) * S(g) + x_p)
    y_t = (-c1 * C(a) * S(b) * S(g) + c1 * S(a) * C(g) - c2 * C(q4) * C(a) * S(b) * C(g)
           - c2 * S(q4) * C(a) * C(b) - c2 * C(q4) * S(a) * S(g)
           - lo * C(q4) * S(q5) * C(a) * S(b) * C(g) - lo * S(q4) * S(q5) * C(a) * C(b)
           - lo * C(q4) * S(q5) * S(a) * S(g) - lo * C(q5) * C(a) * S(b) * S(g)
           + lo * C(q5) * S(a) * C(g) + y_p)
    z_t = (-c1 * S(a) * S(b) * S(g) + c1 * (-C(a)) * C(g) - c2 * C(q4) * S(a) * S(b) * C(g)
           - c2 * S(q4) * S(a) * C(b) + c2 * C(q4) * C(a) * S(g)
           - lo * C(q4) * S(q5) * S(a) * S(b) * C(g) - lo * S(q4) * S(q5) * S(a) * C(b)
           + lo * C(q4) * S(q5) * C(a) * S(g) - lo * C(q5) * S(a) * S(b) * S(g)
           - lo * C(q5) * C(a) * C(g) + z_p)
    pose = sample["direct"].pose
    assert np.abs(np.column_stack([x_t, y_t, z_t]) - pose[:, :3]).max() < 1e-12
    # and the library's form of it
    rot, p_x = forms.platform_pose(j["L4"], j["psi1"], j["theta4"])
    assert np.abs(forms.tool_pose(p, rot, p_x, q4, q5, machine.tool_length) - pose).max() < 1e-12


def test_tool_points_away_from_the_base(machine, sample):
    pose = sample["direct"].pose
    leg_direction = sample["direct"].platform[:, :3]  # read-only: the shared sample's record
    leg_direction = leg_direction / np.linalg.norm(leg_direction, axis=1)[:, None]
    along = np.einsum("ij,ij->i", pose[:, 3:], leg_direction)
    assert (along >= np.cos(np.radians(45.0)) - 1e-12).all()  # |Q5| ≤ 45°
    assert machine.home_pose[2] == pytest.approx(1.0 + 0.2 + 0.12 + 0.1)


def test_inverse_model_round_trip(machine, sample):
    q = sample["q"][:40]
    pose = sample["direct"].pose[:40]
    back = machine.ik(pose, q0=q + 0.02)
    assert np.abs(back - q).max() < 1e-10
    # the inverse model from the closed forms' poses: any branch it finds maps back to the pose
    found = machine.ik(pose[:5])
    assert np.abs(forms.direct(machine.params, found, machine.tool_length) - pose[:5]).max() < 1e-10


def test_jacobian_matches_finite_differences(machine, sample):
    q = sample["q"][:8]
    jac = machine.jacobian(q)
    assert (jac.status == Status.OK).all() and (jac.closure_rank == jac.expected_rank).all()
    step = 1e-6
    for k in range(5):
        dq = np.zeros(5)
        dq[k] = step
        plus = forms.direct(machine.params, q + dq, machine.tool_length)
        minus = forms.direct(machine.params, q - dq, machine.tool_length)
        velocity = (plus[:, :3] - minus[:, :3]) / (2 * step)
        assert np.abs(jac.J[:, :3, k] - velocity).max() < 1e-8, k
        axis_rate = (plus[:, 3:] - minus[:, 3:]) / (2 * step)
        omega = jac.J[:, 3:, k]
        assert np.abs(np.cross(omega, plus[:, 3:] / 2 + minus[:, 3:] / 2) - axis_rate).max() < 1e-8


def test_reference_configurations_are_in_stroke(machine):
    poses = np.array(list(machine.reference_poses().values()))
    direct = machine.fk(poses, full_output=True)
    assert (direct.status == Status.OK).all() and not direct.out_of_stroke.any()


def test_workspace_covers_a_600_mm_cylinder_within_the_strokes(machine):
    """The assumed dimensions make a "600" machine: with the head at Q4 = Q5 = 0 every point of
    a Ø 600 mm × 300 mm cylinder about the home tool axis is reached with the actuators and
    the measured leg within their strokes (the measured leg found by scipy's root finder)."""
    from scipy.optimize import root

    params, model = machine.params, machine.model

    def tool_point(leg):
        rot, p = forms.platform_pose(*leg)
        return forms.tool_pose(params, rot, p, 0.0, 0.0, machine.tool_length)[0, :3]

    centre = machine.home_pose[:2]
    angles = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    targets = [np.r_[centre + r * np.array([np.cos(a), np.sin(a)]), z]
               for z in (1.24, 1.39, 1.54) for r in (0.3, 0.15) for a in angles]
    for target in targets:
        sol = root(lambda leg, t=target: tool_point(leg) - t, [1.0, 0.0, 0.0], tol=1e-13)
        assert sol.success and np.abs(tool_point(sol.x) - target).max() < 1e-9
        q = np.r_[forms.actuators(params, *sol.x)[0], 0.0, 0.0]
        values = dict(zip(("L4", "psi1", "theta4"), sol.x, strict=True))
        values.update(zip(machine.actuator_names, q, strict=True))
        for name, value in values.items():
            i = model.variables.index(name)
            assert model.q_min[i] <= value <= model.q_max[i], (target, name, value)
