"""The Tripteor X7 (seed 002, Guyon 2021) as joint chains, checked by oracles independent of
the solver that computes it:

- structural invariants of the closure (notes §2.7 and C3) on 600 random configurations within
  and beyond the thesis's measured ranges (Table 5.3), from points computed through the chains
  at the solver's passive joints;
- the thesis's closed forms (3.7), (3.10), (3.12)/(3.13), each with its domain of validity
  (errata in docs/seed-errata.md, seed 002);
- the complete 5-axis model: round trips, velocity model by finite differences, the platform
  orientation (3.16)–(3.18) and the head orientation (3.23) in a named Cardan convention, and
  the inverse model's two head branches;
- a plausibility check of the reconstructed geometry against the five measurements the thesis
  prints (Table 5.2), registered with :func:`pkmkit.spatial.registration.rigid_registration`.

Conventions: the thesis's passive joints have the names of :attr:`passive_names`; where its
Chapter 3 angles are measured from other zeros than the Chapter 4 chains (its figures are
lost), the mapping is stated in the test. Lengths in metres unless said otherwise.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import pkmkit
from pkmkit.exceptions import ParameterError
from pkmkit.machines.joint_chain import JointChainMachine
from pkmkit.model.chains import build_chain_model
from pkmkit.solve.chains import chain_pose
from pkmkit.spatial.registration import rigid_registration
from pkmkit.status import Status

L, D, SMALL_L, SMALL_D = 1.0006254, 0.7998675, 0.38986, 0.29024
C, S = np.cos, np.sin

# Table 5.2 (L1846-1853): Q1, Q2, Q3 (mm), Q4 = Q5 = 0, and the tracker's X, Y, Z (LTS, mm)
TABLE_5_2_Q = np.array([[983.186, 1064.076, 988.005], [982.802, 1063.747, 989.454],
                        [979.856, 1055.661, 977.383], [983.451, 1069.396, 988.545],
                        [984.694, 1060.561, 979.943]]) / 1000.0
TABLE_5_2_LTS = np.array([[-340.391, 2564.142, 383.470], [-344.146, 2564.760, 381.491],
                          [-327.230, 2574.734, 384.640], [-339.670, 2554.941, 393.010],
                          [-322.048, 2569.917, 384.831]])
# Table 5.4: the tracker → CNC frame transfer (points and the spindle vectors of points 1, 3,
# measured at Q4 = Q5 = 0, see tests/spatial/test_registration.py)
TABLE_5_4_LTS = np.array([[-331.205, 2567.607, 389.687], [-809.819, 2774.647, 423.530],
                          [-330.062, 2558.758, 383.845], [-808.695, 2765.857, 417.398]])
TABLE_5_4_BCS = np.array([[794.963, 415.758, -59.545], [1242.534, 450.304, 207.671],
                          [794.958, 409.808, -68.367], [1242.53, 444.061, 198.884]])
SPINDLE_LTS = np.array([[-5.357, 42.349, 41.987], [-5.382, 42.412, 41.934]])
LONG_TOOL = 0.169889
#: Chanal et al. 2012 (Fig. 2.4): the ICS origin in the CNC frame, mm
CHANAL_O_ICS_IN_BCS = np.array([1295.0, 1696.179, 1313.664])


@pytest.fixture(scope="module")
def tripteor():
    return pkmkit.machine("tripteor-x7")


@pytest.fixture(scope="module")
def wide(tripteor):
    """The same machine with unlimited joint strokes, for configurations beyond Table 5.3."""
    model = tripteor.model
    elements = [replace(e, stroke=(-np.inf, np.inf)) for e in model.elements]
    names = model.element_names()
    rebuilt = build_chain_model(
        elements, legs=[[names[e] for e in leg] for leg in model.legs],
        leg_names=model.leg_names, head=[names[e] for e in model.head],
        characteristic_length=model.characteristic_length)
    return JointChainMachine(id="tripteor-x7-wide", name="unlimited strokes", kind=None,
                             params=tripteor.params, model=rebuilt,
                             tool_length=tripteor.tool_length)


def random_q(rng, n, beyond=0.0):
    """Actuator vectors in the Table 5.3 ranges, widened by ``beyond`` × (20 mm, 10°)."""
    lo = np.array([0.975, 1.055, 0.975, np.radians(-15.0), np.radians(0.0)])
    hi = np.array([0.995, 1.075, 0.995, np.radians(15.0), np.radians(55.0)])
    pad = beyond * np.array([0.02, 0.02, 0.02, np.radians(10.0), np.radians(10.0)])
    return lo - pad + (hi - lo + 2 * pad) * rng.random((n, 5))


def passive_dict(result):
    return {name: result.passive[..., i] for i, name in enumerate(result.passive_names)}


def joint_points(machine, q, result):
    """A_i (base joints) and B_i (platform joints) from the solver's passive joints, through
    the legs' chains: the origin of the first joint's frame and of the last joint's frame."""
    model = machine.model
    values = machine.full_values(np.atleast_2d(q))
    values[:, machine._passive] = np.atleast_2d(result.passive)
    names = model.element_names()
    out = {}
    for i, (first, last) in enumerate((("psi1", "phi1"), ("psi2", "phi2"), ("psi3", "phi3"))):
        chain = model.legs[i]
        for label, name in (("A", first), ("B", last)):
            upto = [names[e] for e in chain].index(name)
            out[f"{label}{i + 1}"] = chain_pose(model, chain[:upto + 1], values.T).p.T
    return out


def distance_to_line(p, a, b):
    u = (b - a) / np.linalg.norm(b - a, axis=1)[:, None]
    w = p - a
    return np.linalg.norm(w - np.einsum("ij,ij->i", w, u)[:, None] * u, axis=1)


def norm(v):
    return np.linalg.norm(v, axis=1)


@pytest.fixture(scope="module")
def sample(tripteor, wide):
    """600 configurations: 400 in the Table 5.3 ranges, 200 up to 20 mm / 10° beyond."""
    rng = np.random.default_rng(2026)
    q = np.vstack([random_q(rng, 400), random_q(rng, 200, beyond=1.0)])
    res = wide.fk(q, full_output=True)
    assert (res.status == Status.OK).all() and res.closure_residual.max() < 1e-12
    inside = tripteor.fk(q[:400], full_output=True)
    np.testing.assert_allclose(inside.passive, res.passive[:400], atol=1e-13)
    return q, res, joint_points(wide, q, res)


def median_plane(machine, q, symmetric=False):
    """Move Q2 (Newton on the velocity model) until ψ1 = 0; with ``symmetric`` also Q3 = Q1."""
    q = np.array(q, dtype=float)
    if symmetric:
        q[:, 2] = q[:, 0]
    for _ in range(12):
        res = machine.fk(q, full_output=True)
        rate = machine.jacobian(q=q).passive_rates[:, 0, 1]  # dψ1/dQ2
        q[:, 1] -= res.passive[:, 0] / rate
    res = machine.fk(q, full_output=True)
    assert np.abs(res.passive[:, 0]).max() < 1e-14
    return q, res


# --------------------------------------------------------------------------- structure


def test_counts_and_hyperstatism(tripteor):
    """13 one-DOF joints (10 R + 3 P), 10 passive; h = 2 by the count and by the rank."""
    count = tripteor.hyperstatism()
    assert count.joints == 13 and count.joints_by_type == {"R": 10, "P": 3}
    assert count.loops == 2 and count.mobility == 3
    assert count.hyperstatism == 2 and count.rank_hyperstatism == 2
    assert tripteor.passive_names == ("psi1", "theta1", "phi1", "psi2", "theta2", "eta2",
                                      "phi2", "psi3", "theta3", "phi3")
    assert tripteor.actuator_names == ("Q1", "Q2", "Q3", "Q4", "Q5")


def test_structural_invariants(sample):
    """Notes §2.7 / C3 on 600 configurations: ψ1 = ψ3; θ1 + φ1 = θ3 + φ3; A1B1B3A3 planar;
    |B1B3| = l; dist(B2, B1B3) = d; dist(A2, A1A3) = D; |A1A3| = L; |A_iB_i| = Q_i."""
    q, res, pts = sample
    p = passive_dict(res)
    assert np.abs(p["psi1"] - p["psi3"]).max() < 1e-12
    assert np.abs(p["theta1"] + p["phi1"] - p["theta3"] - p["phi3"]).max() < 1e-12
    normal = np.cross(pts["A3"] - pts["A1"], pts["B1"] - pts["A1"])
    normal /= norm(normal)[:, None]
    assert np.abs(np.einsum("ij,ij->i", pts["B3"] - pts["A1"], normal)).max() < 1e-12
    assert np.abs(norm(pts["B3"] - pts["B1"]) - SMALL_L).max() < 1e-12
    assert np.abs(distance_to_line(pts["B2"], pts["B1"], pts["B3"]) - SMALL_D).max() < 1e-12
    assert np.abs(distance_to_line(pts["A2"], pts["A1"], pts["A3"]) - D).max() < 1e-15
    assert np.abs(norm(pts["A3"] - pts["A1"]) - L).max() < 1e-15
    for i in range(3):
        assert np.abs(norm(pts[f"B{i + 1}"] - pts[f"A{i + 1}"]) - q[:, i]).max() < 1e-12
    # the configurations are genuinely spread (the invariants are not trivially at rest)
    assert np.ptp(p["psi1"]) > np.radians(3.0) and np.ptp(p["eta2"]) > 1e-5


def test_al_kashi_with_denominator_2_q3_capital_l(sample):
    """(3.12)/(3.13): in triangle A1A3B3, cos(Â3) = (L² + Q3² − |A1B3|²)/(2·Q3·L) with
    |A1B3|² = Q1² + l² − 2·Q1·l·cos(B̂1) (triangle A1B1B3). The thesis's θ3 and φ1 there are
    these interior angles: Â3 = π/2 + θ3 and B̂1 = π/2 − φ1 in the chain's joint angles.
    The printed denominator 2·Q3·l is wrong (erratum): it does not even give a cosine."""
    q, res, pts = sample
    p = passive_dict(res)
    q1, q3 = q[:, 0], q[:, 2]
    b1 = np.pi / 2 - p["phi1"]
    a3 = np.pi / 2 + p["theta3"]
    # the interior angles, from the points
    u, v = pts["A1"] - pts["B1"], pts["B3"] - pts["B1"]
    assert np.abs(np.arccos(np.einsum("ij,ij->i", u, v) / norm(u) / norm(v)) - b1).max() < 1e-12
    u, v = pts["A1"] - pts["A3"], pts["B3"] - pts["A3"]
    assert np.abs(np.arccos(np.einsum("ij,ij->i", u, v) / norm(u) / norm(v)) - a3).max() < 1e-12
    numerator = -q1**2 - SMALL_L**2 + 2 * q1 * SMALL_L * C(b1) + L**2 + q3**2
    assert np.abs(np.arccos(numerator / (2 * q3 * L)) - a3).max() < 1e-12
    printed = numerator / (2 * q3 * SMALL_L)
    assert (np.abs(printed) > 0.6).all() and (np.abs(printed - C(a3)) > 0.4).all()


def test_notes_example_configuration(tripteor):
    """Notes §2.7's reconstructed configuration at Q = (982.802, 1063.747, 989.454) mm (the
    machine's home): its passive joints (degrees, 4 decimals) and the Al-Kashi cosines."""
    res = tripteor.fk([0.982802, 1.063747, 0.989454, 0.0, 0.0], full_output=True)
    got = dict(zip(res.passive_names, np.degrees(res.passive), strict=True))
    notes = {"psi1": 0.2813, "theta1": 17.7023, "phi1": -18.1040, "psi2": -0.4005,
             "theta2": 28.3439, "eta2": -0.0022, "phi2": 28.6252, "psi3": 0.2813,
             "theta3": -18.3763, "phi3": 17.9747}
    for name, value in notes.items():
        assert got[name] == pytest.approx(value, abs=6e-5), name
    q1, q3 = 0.982802, 0.989454
    numerator = -q1**2 - SMALL_L**2 + 2 * q1 * SMALL_L * C(np.pi / 2 - res.passive[2]) \
        + L**2 + q3**2
    assert numerator / (2 * q3 * L) == pytest.approx(0.31526, abs=5e-6)
    assert numerator / (2 * q3 * SMALL_L) == pytest.approx(0.80915, abs=5e-6)


def test_eta2_vanishes_when_q1_equals_q3_and_in_the_median_plane(wide):
    """Thesis L890 / notes C3 say η2 = 0 iff Q1 = Q3. The closure gives η2 = 0 iff Q1 = Q3
    **or ψ1 = 0** — as the thesis's own (3.7), line 5, S(Φ)S(ψ1) = C(θ2)S(η2), says (Φ = 0 iff
    Q1 = Q3). Erratum: the 'only if' is wrong in the median plane."""
    rng = np.random.default_rng(11)
    q = random_q(rng, 40, beyond=0.5)
    equal = q.copy()
    equal[:, 2] = equal[:, 0]
    res = wide.fk(equal, full_output=True)
    assert np.abs(passive_dict(res)["eta2"]).max() < 1e-13
    assert np.abs(passive_dict(res)["psi1"]).min() > 1e-4  # not in the median plane
    far = q[np.abs(q[:, 0] - q[:, 2]) > 0.005][:20]
    _, med = median_plane(wide, far)
    assert np.abs(passive_dict(med)["eta2"]).max() < 1e-14
    res = wide.fk(q, full_output=True)
    p = passive_dict(res)
    off = (np.abs(q[:, 0] - q[:, 2]) > 0.002) & (np.abs(p["psi1"]) > np.radians(0.5))
    assert off.sum() > 10
    assert np.abs(p["eta2"][off]).min() > 1e-6
    phi = p["theta1"] + p["phi1"]
    np.testing.assert_allclose(S(phi) * S(p["psi1"]), C(p["theta2"]) * S(p["eta2"]),
                               atol=1e-14)


# --------------------------------------------------------------------------- closed forms


def thesis_angles(res):
    """The solver's joints in the convention of the thesis's (3.7): θ2 changes sign (its axis
    is reversed in the Chapter 4 chains); ψ1, Φ = θ1 + φ1, ψ2, η2, φ2 are the same."""
    p = passive_dict(res)
    return (p["psi1"], p["theta1"] + p["phi1"], p["eta2"], -p["theta2"], p["phi2"], p["psi2"])


def test_angular_closure_3_7(sample):
    """(3.7), L878, lines 2–6 hold exactly. Line 1 as printed, C(φ2)S(η2) = S(Φ)S(ψ1), does not:
    it should read C(θ2)S(η2) (a copy of line 5; lines 1–3 are the components of one unit
    vector, and only C(θ2)S(η2) makes their squares sum to 1)."""
    _, res, _ = sample
    psi1, phi, eta2, th2, ph2, psi2 = thesis_angles(res)
    lines = [C(eta2) * C(th2) * C(ph2) - S(th2) * S(ph2) - C(psi1),
             C(ph2) * S(th2) + C(eta2) * C(th2) * S(ph2) - C(phi) * S(psi1),
             C(phi) - (C(eta2) * C(psi2) + S(eta2) * S(th2) * S(psi2)),
             S(phi) * S(psi1) - C(th2) * S(eta2),
             C(psi1) * S(phi) - (C(eta2) * S(psi2) - C(psi2) * S(eta2) * S(th2))]
    assert max(np.abs(x).max() for x in lines) < 1e-13
    printed = C(ph2) * S(eta2) - S(phi) * S(psi1)
    corrected = C(th2) * S(eta2) - S(phi) * S(psi1)
    assert np.abs(printed).max() > 5e-5 and np.abs(corrected).max() < 1e-13
    unit = (C(th2) * S(eta2)) ** 2 + (C(eta2) * C(th2) * C(ph2) - S(th2) * S(ph2)) ** 2 + (
        C(ph2) * S(th2) + C(eta2) * C(th2) * S(ph2)) ** 2
    assert np.abs(unit - 1).max() < 1e-14


def test_explicit_forms_3_10_and_3_13(sample):
    """(3.10)/(3.11) and (3.13) against the solver, everywhere: ψ3 = ψ1 and the C(ψ1), C(Φ),
    S(Φ), tan ψ1, tan Φ forms are exact; (3.10)'s S(ψ1) has a sign error (− S(θ2)C(φ2) must be
    + S(θ2)C(φ2), as in (3.7) line 3 and in (3.13)'s ψ1)."""
    _, res, _ = sample
    p = passive_dict(res)
    psi1, phi, eta2, th2, ph2, psi2 = thesis_angles(res)
    c_psi1 = C(eta2) * C(th2) * C(ph2) - S(th2) * S(ph2)
    c_phi = C(eta2) * C(psi2) + S(eta2) * S(th2) * S(psi2)
    assert np.abs(p["psi3"] - psi1).max() < 1e-12
    assert np.abs(C(psi1) - c_psi1).max() < 1e-13
    assert np.abs(C(phi) - c_phi).max() < 1e-13
    s_phi = (C(eta2) * S(psi2) - S(eta2) * S(th2) * C(psi2)) / c_psi1
    assert np.abs(S(phi) - s_phi).max() < 1e-13
    printed = (C(eta2) * C(th2) * S(ph2) - S(th2) * C(ph2)) / C(phi)
    fixed = (C(eta2) * C(th2) * S(ph2) + S(th2) * C(ph2)) / C(phi)
    assert np.abs(S(psi1) - fixed).max() < 1e-13
    assert np.abs(S(psi1) - printed).max() > 0.5 * np.abs(S(psi1)).max()
    # (3.13): ψ1 and Φ as arctangents
    tan_psi1 = (C(eta2) * C(th2) * S(ph2) + S(th2) * C(ph2)) / (c_phi * c_psi1)
    tan_phi = (C(eta2) * S(psi2) - S(eta2) * S(th2) * C(psi2)) / (c_psi1 * c_phi)
    assert np.abs(np.arctan(tan_psi1) - psi1).max() < 1e-13
    assert np.abs(np.arctan(tan_phi) - phi).max() < 1e-13


def leg2_elevation(pts):
    """Angle between leg 2 (A2B2) and the plane of legs 1 and 3 (A1, A3, B1)."""
    normal = np.cross(pts["A3"] - pts["A1"], pts["B1"] - pts["A1"])
    normal /= norm(normal)[:, None]
    leg = pts["B2"] - pts["A2"]
    return np.arcsin(np.abs(np.einsum("ij,ij->i", leg, normal)) / norm(leg))


def test_theta2_closed_form_holds_only_in_the_median_plane(wide, sample):
    """(3.10): θ2 = asin((D − d)/Q2) and θ2 + φ2 = 0. Exact for ψ1 = 0 (then |θ2| is leg 2's
    elevation over the plane of legs 1/3), wrong elsewhere: the exact relation is
    Q2·sin(elevation) = D·cos ψ1 − d (the thesis's own (3.4) line 2 reduces to D − d only at
    ψ1 = 0). Within the measured ranges the printed form is off by up to ~0.5°, beyond them by
    up to ~1°."""
    q, res, pts = sample
    p = passive_dict(res)
    elevation = leg2_elevation(pts)
    np.testing.assert_allclose(q[:, 1] * S(elevation), D * C(p["psi1"]) - SMALL_D, atol=1e-12)
    error = np.abs(np.abs(p["theta2"]) - np.arcsin((D - SMALL_D) / q[:, 1]))
    assert np.degrees(error[:400].max()) > 0.3 and np.degrees(error.max()) > 0.7
    assert np.abs(p["phi2"] - p["theta2"]).max() > np.radians(1.0)  # θ2 + φ2 = 0 in (3.7)'s
    rng = np.random.default_rng(12)
    q_med, med = median_plane(wide, random_q(rng, 30, beyond=0.5))
    pm = passive_dict(med)
    np.testing.assert_allclose(np.abs(pm["theta2"]), np.arcsin((D - SMALL_D) / q_med[:, 1]),
                               atol=1e-13)
    np.testing.assert_allclose(-pm["theta2"] + pm["phi2"], 0.0, atol=1e-13)  # (3.7) signs
    np.testing.assert_allclose(leg2_elevation(joint_points(wide, q_med, med)),
                               np.abs(pm["theta2"]), atol=1e-12)


def test_psi2_and_theta1_closed_forms(wide):
    """(3.10): ψ2 = acos(A_T) + atan(B_T) and θ1 = atan(…) with A_T, B_T, C_T of Q1, Q2 only.
    ψ2's form gives the solver's ψ2 + 90° only in the symmetric configuration (Q1 = Q3,
    ψ1 = 0, where ψ2 = 0); with ψ1 = 0 and Q1 ≠ Q3 it is off by degrees. θ1's form holds
    nowhere, not even there, where the closure and elementary geometry give
    sin θ1 = (L − l) / (2 Q1) (erratum: not reproduced)."""

    def closed(q):
        q1, q2 = q[:, 0], q[:, 1]
        a_t = (4 * (D - SMALL_D) ** 2 - (SMALL_L**2 + L**2) + 4 * (q1**2 - q2**2)) / (
            2 * L * np.sqrt(SMALL_L**2 + 4 * (q2**2 - (D - SMALL_D) ** 2)))
        b_t = -SMALL_L / (2 * np.sqrt(q2**2 - (D - SMALL_D) ** 2))
        c_t = np.sqrt(1 - (D - SMALL_D) ** 2 / q2**2)
        psi2 = np.arccos(a_t) + np.arctan(b_t)
        theta1 = np.arctan((SMALL_L * S(psi2) + 2 * q2 * C(psi2) * c_t)
                           / (L - SMALL_L * C(psi2) + 2 * q2 * S(psi2) * c_t))
        return psi2, theta1

    rng = np.random.default_rng(13)
    q_sym, sym = median_plane(wide, random_q(rng, 20, beyond=0.5), symmetric=True)
    ps = passive_dict(sym)
    psi2, theta1 = closed(q_sym)
    np.testing.assert_allclose(psi2, ps["psi2"] + np.pi / 2, atol=1e-12)
    np.testing.assert_allclose(S(ps["theta1"]), (L - SMALL_L) / (2 * q_sym[:, 0]), atol=1e-13)
    assert np.degrees(np.abs(theta1 - ps["theta1"]).min()) > 5.0
    q = random_q(rng, 30, beyond=0.5)
    q = q[np.abs(q[:, 0] - q[:, 2]) > 0.01]
    q_med, med = median_plane(wide, q)
    psi2, _ = closed(q_med)
    assert np.degrees(np.abs(psi2 - passive_dict(med)["psi2"] - np.pi / 2).max()) > 2.0


# --------------------------------------------------------------------------- complete model


def test_direct_then_inverse_round_trip(tripteor):
    rng = np.random.default_rng(21)
    q = random_q(rng, 200)
    pose = tripteor.fk(q)
    back = tripteor.ik(pose)
    assert np.abs(back - q).max() < 1e-9
    assert np.abs(np.linalg.norm(pose[:, 3:], axis=1) - 1).max() < 1e-14


def test_inverse_then_direct_from_tool_point_and_axis(tripteor):
    """Targets that are not outputs of the direct model: reachable poses moved by up to 2 mm
    and tilted by up to 2°, with an axis of any length (normalised)."""
    rng = np.random.default_rng(22)
    pose = tripteor.fk(random_q(rng, 100))
    target = pose.copy()
    target[:, :3] += rng.uniform(-0.002, 0.002, (100, 3))
    tilt = Rotation.from_rotvec(rng.uniform(-1, 1, (100, 3)) * np.radians(2.0) / np.sqrt(3))
    target[:, 3:] = tilt.apply(pose[:, 3:]) * rng.uniform(0.5, 3.0, (100, 1))
    res = tripteor.ik(target, full_output=True)
    q, direct = res.q, res.direct
    assert np.isfinite(q).all()
    assert np.abs(direct.pose[:, :3] - target[:, :3]).max() < 1e-10
    unit = target[:, 3:] / np.linalg.norm(target[:, 3:], axis=1)[:, None]
    assert np.abs(direct.pose[:, 3:] - unit).max() < 1e-10
    assert direct.closure_residual.max() < 1e-12
    # a longer tool: the same axis, the point moves along it
    q_short = tripteor.ik(target, tool_length=0.110006)
    short = tripteor.fk(q_short, tool_length=0.110006)
    assert np.abs(short[:, :3] - target[:, :3]).max() < 1e-10


def tool_rotations(machine, q):
    res = machine.fk(q, full_output=True)
    rot = Rotation.from_rotvec(np.array(res.tool_frame[:, 3:]))  # scipy: writeable only
    return res.pose[:, :3], rot.as_matrix(), res


def test_velocity_model_against_finite_differences(tripteor):
    """J (tool point velocity and tool angular velocity per actuator rate) and the passive
    joint rates, against central differences of the direct model."""
    rng = np.random.default_rng(23)
    q = random_q(rng, 8)
    jac = tripteor.jacobian(q=q)
    h = 1e-6
    for j in range(5):
        step = np.zeros(5)
        step[j] = h
        p_plus, r_plus, res_plus = tool_rotations(tripteor, q + step)
        p_minus, r_minus, res_minus = tool_rotations(tripteor, q - step)
        velocity = (p_plus - p_minus) / (2 * h)
        spin = np.einsum("nij,nkj->nik", r_plus - r_minus, (r_plus + r_minus) / 2) / (2 * h)
        omega = np.stack([spin[:, 2, 1], spin[:, 0, 2], spin[:, 1, 0]], axis=1)
        assert np.abs(jac.J[:, :3, j] - velocity).max() < 1e-7
        assert np.abs(jac.J[:, 3:, j] - omega).max() < 1e-7
        rates = (res_plus.passive - res_minus.passive) / (2 * h)
        assert np.abs(jac.passive_rates[:, :, j] - rates).max() < 1e-6
    assert (jac.closure_rank == jac.expected_rank).all() and jac.expected_rank == 16
    assert np.isfinite(jac.condition).all()


def platform_and_head_frames(machine, q):
    """R_P, R_T in the thesis's frames (see the test below) and the solver's passive joints."""
    model = machine.model
    res = machine.fk(q, full_output=True)
    values = machine.full_values(q)
    values[:, machine._passive] = res.passive
    index = {n: i for i, n in enumerate(model.element_names())}
    to_mps = (*model.legs[0], index["R51_MPS"])
    to_q5 = (*to_mps, index["Q4"], index["Q5"])
    r_mps = chain_pose(model, to_mps, values.T).R
    r_7 = chain_pose(model, to_q5, values.T).R
    zero = values.T.copy()
    zero[model.variables.index("psi1")] = 0.0
    zero[model.variables.index("phi1")] = -zero[model.variables.index("theta1")]
    t0 = chain_pose(model, to_mps, zero).R  # MPS at ψ1 = Φ = 0
    d7 = model.frames[index["Q5"]][:3, :3]  # takes z to y: R_7 = R_MPS Rz(Q4) Ry(Q5) D7
    r_p = np.einsum("bak,bck->kac", t0, r_mps)
    r_t = np.einsum("bak,bck,dc->kad", t0, r_7, d7)
    return r_p, r_t, res


def test_platform_orientation_3_16_to_3_18(wide):
    """The platform's orientation depends on ψ1 and Φ = θ1 + φ1 only: in the frame of MPS at
    ψ1 = Φ = 0 (x along B1B3, the ψ axis; y along the θ/φ axes; z the platform normal) its
    Cardan angles — intrinsic X-Z-Y, R = Rx(α)·Rz(β)·Ry(γ) — are α_P = ψ1, β_P = 0,
    γ_P = −Φ ((3.18): α_P = ψ1, β_P = 0, ±γ_P = θ1 + φ1)."""
    rng = np.random.default_rng(24)
    q = random_q(rng, 200, beyond=1.0)
    r_p, _, res = platform_and_head_frames(wide, q)
    p = passive_dict(res)
    alpha, beta, gamma = Rotation.from_matrix(r_p).as_euler("XZY").T
    assert np.abs(alpha - p["psi1"]).max() < 1e-13
    assert np.abs(beta).max() < 1e-13
    assert np.abs(gamma + p["theta1"] + p["phi1"]).max() < 1e-13


def head_3_23(alpha_p, beta_p, gamma_p, q4, q5, *, corrected):
    """(3.23), L1016, as printed or corrected (tan α_T's denominator: − S(Q4)S(α_P)S(γ_P)
    instead of + S(α_P)S(γ_P); tan γ_T's C(Q5)S(γ_P) term: times C(β_P))."""
    a, b, g = alpha_p, beta_p, gamma_p
    num_a = S(q4) * C(a) * S(g) + S(a) * (C(q4) * C(b) - S(q4) * S(b) * C(g))
    last = -S(q4) * S(a) * S(g) if corrected else S(a) * S(g)
    tan_a = num_a / (C(q4) * C(a) * C(b) - S(q4) * C(a) * S(b) * C(g) + last)
    sin_b = C(q4) * S(b) + S(q4) * C(b) * C(g)
    mid = C(q5) * S(g) * (C(b) if corrected else 1.0)
    tan_g = (C(b) * C(q4) * S(q5) * C(g) + mid - S(q4) * S(q5) * S(b)) / (
        C(q4) * C(q5) * C(b) * C(g) - S(q4) * C(q5) * S(b) - S(q5) * C(b) * S(g))
    return tan_a, sin_b, tan_g


def test_head_orientation_3_23(wide):
    """The head turns the tool frame by Q4 about the platform normal z, then by Q5 about the
    new y: R_T = R_P·Rz(Q4)·Ry(Q5). In the X-Z-Y Cardan convention of the test above, (3.23)'s
    S(β_T) and tan γ_T hold as printed (β_P = 0 on this machine), tan α_T only corrected."""
    rng = np.random.default_rng(25)
    q = random_q(rng, 200, beyond=1.0)
    q[:, 3:] = rng.uniform(-1.2, 1.2, (200, 2))  # the wrist far beyond its strokes
    r_p, r_t, _ = platform_and_head_frames(wide, q)
    ap, bp, gp = Rotation.from_matrix(r_p).as_euler("XZY").T
    at, bt, gt = Rotation.from_matrix(r_t).as_euler("XZY").T
    np.testing.assert_allclose(r_t, r_p @ Rotation.from_euler("ZY", q[:, 3:]).as_matrix(),
                               atol=1e-14)
    tan_a, sin_b, tan_g = head_3_23(ap, bp, gp, q[:, 3], q[:, 4], corrected=False)
    assert np.abs(S(bt) - sin_b).max() < 1e-13
    assert np.abs(np.tan(gt) - tan_g).max() < 1e-10
    assert np.abs(np.tan(at) - tan_a).max() > 1e-5
    tan_a, _, _ = head_3_23(ap, bp, gp, q[:, 3], q[:, 4], corrected=True)
    assert np.abs(np.tan(at) - tan_a).max() < 1e-12


def test_head_orientation_algebra_3_23():
    """The same relations for any platform orientation (β_P ≠ 0, large angles): the corrected
    forms are exact, the printed tan α_T and tan γ_T are not. Why the printed tan α_T must be
    wrong: at Q4 = 0 the head only turns about the last Cardan axis, so α_T = α_P — the printed
    denominator C(α_P)C(β_P) + S(α_P)S(γ_P) breaks that."""
    rng = np.random.default_rng(26)
    angles = rng.uniform(-1.2, 1.2, (500, 5))
    r_p = Rotation.from_euler("XZY", angles[:, :3])
    r_t = r_p * Rotation.from_euler("ZY", angles[:, 3:])
    at, bt, gt = r_t.as_euler("XZY").T
    a, b, g, q4, q5 = angles.T
    tan_a, sin_b, tan_g = head_3_23(a, b, g, q4, q5, corrected=True)
    assert np.abs(np.tan(at) - tan_a).max() < 1e-9
    assert np.abs(S(bt) - sin_b).max() < 1e-13
    assert np.abs(np.tan(gt) - tan_g).max() < 1e-9
    printed_a, _, printed_g = head_3_23(a, b, g, q4, q5, corrected=False)
    assert np.median(np.abs(np.arctan(printed_a) - at)) > 0.05
    assert np.median(np.abs(np.arctan(printed_g) - gt)) > 0.01
    at_zero, _, _ = head_3_23(a, b, g, 0 * q4, q5, corrected=False)
    assert np.abs(np.arctan(at_zero) - a).max() > 0.1


def test_inverse_model_has_two_head_branches(tripteor, wide):
    """For one tool point and axis the head reaches the axis with (Q4, Q5) or about
    (Q4 + π, −Q5); the Q5 axis's offset c1 then changes where the platform must be, so Q1–Q3
    differ too. Both branches are found from different starts (the default start, home, finds
    the first) and both satisfy the direct model."""
    rng = np.random.default_rng(27)
    q = random_q(rng, 20)
    q[:, 4] = rng.uniform(np.radians(10.0), np.radians(55.0), 20)
    pose = tripteor.fk(q)
    first = wide.ik(pose)
    start = first.copy()
    start[:, 3] += np.pi
    start[:, 4] *= -1
    second = wide.ik(pose, q0=start)
    np.testing.assert_allclose(first, q, atol=1e-9)
    # the platform tilts by Φ ≈ 2.7° between the branches (Q1 +22 mm, Q3 −23 mm, beyond
    # the measured strokes): Q4 + π, and −Q5 − 2.7°
    np.testing.assert_allclose(second[:, 3] - first[:, 3], np.pi, atol=np.radians(0.1))
    np.testing.assert_allclose(second[:, 4] + first[:, 4], np.radians(-2.74),
                               atol=np.radians(0.1))
    assert (second[:, 0] - first[:, 0] > 0.02).all() and (first[:, 2] - second[:, 2] > 0.02).all()
    for branch in (first, second):
        np.testing.assert_allclose(wide.fk(branch), pose, atol=1e-10)


# --------------------------------------------------------------------------- Table 5.2


@pytest.fixture(scope="module")
def table_5_2(tripteor):
    q = np.c_[TABLE_5_2_Q, np.zeros((5, 2))]
    res = tripteor.fk(q, tool_length=LONG_TOOL, full_output=True)
    assert (res.status == Status.OK).all()
    return res.pose[:, :3] * 1000.0, res.pose[:, 3:]


def test_table_5_2_distances_without_registration(table_5_2):
    """The ten distances between the five measured tool points against the model's, with no
    frame to fit: within 0.45 mm (the points span 25 mm)."""
    model_mm, _ = table_5_2
    i, j = np.triu_indices(5, 1)
    measured = norm(TABLE_5_2_LTS[i] - TABLE_5_2_LTS[j])
    predicted = norm(model_mm[i] - model_mm[j])
    assert measured.max() > 24.0
    assert np.abs(predicted - measured).max() < 0.45


def test_table_5_2_registered_residuals(table_5_2):
    """Rigid registration of the model's tool points (long tool) onto the tracker's: residuals
    0.15–0.26 mm (rms 0.21 mm) — the order of the thesis's nominal-model errors ("at least ten
    times" its identified 21.6 µm). The registered tool axis points opposite to the spindle
    vectors of Table 5.4 (the CNC's tool-orientation convention, from the tip into the
    spindle) within 5.3°. Composed with Table 5.4's tracker → CNC registration, the ICS origin
    — 2 m from the 25 mm cloud of points — lands within 7 / 14 / 28 mm of Chanal et al.'s
    O_BCS O_ICS = (1295, 1696.179, 1313.664) mm, with the ICS y axis along the CNC's x
    (1.6°) and the ICS z axis at 50° in its y–z plane, near the 45° that the 1/√2 factors of
    (3.19)–(3.20) and the spindle of Table 5.4 suggest."""
    model_mm, axis = table_5_2
    reg = rigid_registration(model_mm, TABLE_5_2_LTS)
    assert 0.14 < reg.point_errors.min() and reg.point_errors.max() < 0.27
    assert reg.rms == pytest.approx(0.214, abs=0.002)
    spindle = SPINDLE_LTS.mean(axis=0)
    spindle /= np.linalg.norm(spindle)
    angles = np.degrees(np.arccos(reg.apply_directions(axis) @ -spindle))
    assert angles.max() < 5.5
    tracker = rigid_registration(TABLE_5_4_LTS, TABLE_5_4_BCS)
    ics_in_bcs = tracker.rotation @ reg.rotation
    origin = tracker.rotation @ reg.translation + tracker.translation
    assert np.abs(origin - CHANAL_O_ICS_IN_BCS).max() < 30.0
    assert np.degrees(np.arccos(ics_in_bcs[0, 1])) < 2.0  # y_ICS ≈ x_BCS
    z_ics = ics_in_bcs[:, 2]
    assert np.degrees(np.arctan2(-z_ics[2], -z_ics[1])) == pytest.approx(45.0, abs=6.0)


def test_table_5_2_fixes_the_tool_lever(table_5_2):
    """One more parameter — the tool point's distance along the spindle (the head's unknown
    offsets, h + spindle + tool length, in one number) — fitted with the registration: the best
    is 22 mm beyond the assumed one (rms 0.175 mm), and ±200 mm makes the fit 5–7 times worse:
    the measurements do constrain the reconstructed lever arm, to a few centimetres. With it,
    the ICS origin in the CNC frame comes within 2 / 2 / 15 mm of Chanal et al.'s."""
    model_mm, axis = table_5_2
    offsets = np.linspace(-200.0, 200.0, 401)
    shifted = model_mm[None] + offsets[:, None, None] * axis[None]
    rms = rigid_registration(shifted, np.broadcast_to(TABLE_5_2_LTS, shifted.shape)).rms
    best = offsets[np.argmin(rms)]
    assert 10.0 < best < 35.0 and rms.min() == pytest.approx(0.175, abs=0.003)
    assert rms[0] > 5 * rms.min() and rms[-1] > 5 * rms.min()
    reg = rigid_registration(model_mm + best * axis, TABLE_5_2_LTS)
    tracker = rigid_registration(TABLE_5_4_LTS, TABLE_5_4_BCS)
    origin = tracker.rotation @ reg.translation + tracker.translation
    assert np.abs(origin - CHANAL_O_ICS_IN_BCS)[:2].max() < 2.5
    assert np.abs(origin - CHANAL_O_ICS_IN_BCS)[2] < 16.0


def test_printed_4_31_joint_53_axis_does_not_close(tripteor, wide):
    """(4.31) prints D_R43^L53 with its z column along x (I53 = 1): with φ3's axis there the two
    loops do not close (least-squares residual of decimetres at the home actuator values, and
    the machine refuses to be built), while Table 4.2's J53 = 1 (pkmkit's model) closes to
    round-off (erratum, seed 002)."""
    model = wide.model
    names = model.element_names()
    legs = [[names[e] for e in leg] for leg in model.legs]
    head = [names[e] for e in model.head]

    def machine_with(axis):
        elements = [replace(e, axis=axis) if e.name == "phi3" else e for e in model.elements]
        rebuilt = build_chain_model(elements, legs=legs, leg_names=model.leg_names, head=head,
                                    characteristic_length=model.characteristic_length)
        return JointChainMachine(id="tripteor-4-31", name="(4.31)", kind=None,
                                 params=tripteor.params, model=rebuilt,
                                 tool_length=tripteor.tool_length)

    q = random_q(np.random.default_rng(431), 20)
    assert machine_with((0.0, 1.0, 0.0)).fk(q, full_output=True).closure_residual.max() < 1e-12
    with pytest.raises(ParameterError, match=r"do not close .*residual 0\.[1-9]"):
        machine_with((1.0, 0.0, 0.0))


def test_annex_b_single_defects(tripteor):
    """Seed 002 Annex B (docs/tripteor-x7.md §5): a 1 % rotation (0.01) of J21, J41, J23 or J43
    moves exactly one passive angle (ψ1, θ1, ψ3, θ3) by asin 0.01 = 0.5730° and leaves the
    platform where it was, at the median (home) position and at an offset one; K21, K41, I51,
    K51 (CATIA's "Erreur" columns) close only in least squares and move the platform."""
    names = list(tripteor.passive_names)
    one = {"dJ21": "psi1", "dJ41": "theta1", "dJ23": "psi3", "dJ43": "theta3"}
    for q in (tripteor.home_q, tripteor.home_q + np.array([0.02, -0.02, 0.02, 0.0, 0.0])):
        nominal = tripteor.fk(q[None], full_output=True)
        for name, joint in one.items():
            r = tripteor.with_defects({name: 0.01}).fk(q[None], full_output=True)
            d = r.passive[0] - nominal.passive[0]
            k = names.index(joint)
            assert abs(d[k]) == pytest.approx(np.arcsin(0.01), abs=1e-9)
            assert np.abs(np.delete(d, k)).max() < 1e-9
            np.testing.assert_allclose(r.platform, nominal.platform, atol=1e-10)
            assert r.status[0] == 0
        for name in ("dK21", "dK41", "dI51", "dK51"):
            r = tripteor.with_defects({name: 0.01}).fk(q[None], full_output=True)
            assert r.status[0] != 0 and r.closure_residual[0] > 1e-4
            assert np.abs(r.platform[0, :3] - nominal.platform[0, :3]).max() > 1e-4
