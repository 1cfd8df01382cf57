"""Identifiability: the Tripteor's structural gauges (notes §4.5, Annex B), the linear Delta's
rod length / radius trap from height probing, gauges checked against the exact model, the
observability indices against their definitions, and bad input."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import IdentifiabilityError, MeasurementError, ParameterError
from pkmkit.geometric_errors.compatibility import compatibility_configurations
from pkmkit.geometric_errors.identifiability import (
    identifiability,
    identification_jacobian,
    observability,
)
from pkmkit.geometric_errors.measurements import measure
from pkmkit.geometric_errors.model import with_defects

NOTES_UNSEEN = ("dJ21", "dJ41", "da51", "dJ12", "dK12", "dJ22", "dK22", "dJ32", "dK32", "dI42",
                "dJ42", "dI52", "da52", "dJ23", "dJ43", "da53")


@pytest.fixture(scope="module")
def tripteor():
    return pkmkit.machine("tripteor-x7")


@pytest.fixture(scope="module")
def tripteor_q(tripteor):
    q = compatibility_configurations(tripteor, 40, seed=3)
    q[:, 3:] = np.random.default_rng(1).uniform([-0.26, 0.0], [0.26, 0.96], (40, 2))
    return q


def test_tripteor_rank_19_of_36_compatible_parallel_part(tripteor, tripteor_q):
    r = identifiability(tripteor, "point", tripteor_q, compatible=True, scope="loops",
                        exclude=["*11", "dS*", "da62", "dc63"])
    assert (r.rank, r.rank_qr, r.n_parameters) == (19, 19, 36)
    assert r.unidentifiable == NOTES_UNSEEN  # J21, J41, J23, J43, leg-2 base pivots, ...
    assert r.together == (("dJ62", "db62"),)
    assert 1e4 < r.condition < 1e7
    # full pose measurements see no more of the parallel part
    pose = identifiability(tripteor, "pose", tripteor_q, compatible=True, scope="loops",
                           exclude=["*11", "dS*", "da62", "dc63"])
    assert pose.rank == 19 and pose.unidentifiable == NOTES_UNSEEN


def test_unseen_defects_do_not_move_the_tool_exactly(tripteor, tripteor_q):
    """Annex B's CATIA outcome: J21, J41, J23, J43 (0.01 each) change only passive angles."""
    q = tripteor_q[:6]
    nominal = tripteor.fk(q, full_output=True)
    for name in ("dJ21", "dJ41", "dJ23", "dJ43", "dK22"):
        moved = with_defects(tripteor, {name: 0.01}).fk(q, full_output=True)
        np.testing.assert_allclose(moved.pose, nominal.pose, atol=1e-11, err_msg=name)
        assert np.abs(moved.passive - nominal.passive).max() > 1e-3, name


def test_linear_delta_rod_length_radius_trap_from_height_probing():
    m = pkmkit.machine("linear-delta")
    rng = np.random.default_rng(0)
    r = rng.uniform(0, 1, 300) ** 0.5 * 0.1
    t = rng.uniform(0, 2 * np.pi, 300)
    q = m.ik(np.stack([r * np.cos(t), r * np.sin(t), np.zeros(300)], axis=1))
    angles = np.asarray(m.params["angles"])
    delta_printer = {"L": {f"dL{j + 1}": 1.0 for j in range(3)},
                     "R": {**{f"dA{j + 1}x": float(np.cos(a)) for j, a in enumerate(angles)},
                           **{f"dA{j + 1}y": float(np.sin(a)) for j, a in enumerate(angles)}},
                     **{f"q{j + 1}": {f"dq{j + 1}": 1.0} for j in range(3)}}
    height = identifiability(m, "height", q, parameters=delta_printer)
    point = identifiability(m, "point", q, parameters=delta_printer)
    assert height.rank == point.rank == 5  # identifiable in principle...
    assert height.condition > 30 * point.condition  # ...but ill-conditioned from heights
    j = identification_jacobian(m, "height", q, parameters=delta_printer).matrix
    cos = j[:, 0] @ j[:, 1] / np.linalg.norm(j[:, 0]) / np.linalg.norm(j[:, 1])
    assert abs(cos) > 0.9999  # rod length and radius act almost alike on heights
    # per-rod defects: the platform and base offsets of an equivalent leg are one gauge
    full = identifiability(m, "point", q)
    assert ("dA1x", "dB1x") in full.together


def test_gauges_are_invisible_on_the_exact_model():
    m = pkmkit.machine("linear-delta")
    q = m.ik(m.home_pose + np.random.default_rng(2).uniform(-0.2, 0.2, (30, 3)))
    r = identifiability(m, "point", q)
    assert r.rank == 18 and r.n_parameters == 30 and r.gauges.shape == (30, 12)
    base = measure(m, "point", q)
    for g in r.gauges.T:
        step = 1e-4 * g / np.abs(g).max()
        moved = measure(with_defects(m, step), "point", q)
        assert np.abs(moved - base).max() < 1e-11  # exact gauges of the equivalent legs
    # and the combinations are what the measurements see: J_nb = J_b β
    jac = r.jacobian.raw
    names = list(r.names)
    for c in r.combinations:
        for other, coef in list(c.terms.items())[1:]:
            col_b, col_o = jac[:, names.index(c.base)], jac[:, names.index(other)]
            assert np.linalg.norm(col_o) <= np.linalg.norm(col_b) * abs(coef) * 1.0001 + 1e-12


def test_observability_indices_match_their_definitions():
    rng = np.random.default_rng(4)
    j = rng.normal(size=(40, 6))
    s = np.linalg.svd(j, compute_uv=False)
    out = observability(j)
    assert out["O1"] == pytest.approx(np.prod(s) ** (1 / 6) / np.sqrt(40))
    assert out["O2"] == pytest.approx(s[-1] / s[0])
    assert out["O3"] == pytest.approx(s[-1])
    assert out["O4"] == pytest.approx(s[-1] ** 2 / s[0])
    assert out["O5"] == pytest.approx(1 / np.sum(1 / s))
    assert out["condition"] == pytest.approx(s[0] / s[-1])
    j[:, 2] = 0.0
    assert observability(j)["O3"] == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(Exception, match="rows"):
        observability(j[:3])


def test_bad_input_is_typed():
    m = pkmkit.machine("linear-delta")
    q = m.ik(m.home_pose + np.random.default_rng(5).uniform(-0.1, 0.1, (3, 3)))
    with pytest.raises(IdentifiabilityError, match=r"3 poses × 1 height readings = 3 scalar "
                       r"measurements for 30 parameters.*rank 3") as info:
        identifiability(m, "height", q)
    assert info.value.rank == 3 and info.value.n_parameters == 30
    with pytest.raises(MeasurementError, match="only translates"):
        identifiability(m, "pose", q)
    with pytest.raises(MeasurementError, match="unknown measurement type"):
        identifiability(m, "laser", q)
    with pytest.raises(MeasurementError, match="rod machines"):
        identifiability(pkmkit.machine("tripteor-x7"), "part", np.atleast_2d(
            pkmkit.machine("tripteor-x7").home_q))
    with pytest.raises(ParameterError, match="unknown defect or owner 'dL9'"):
        identifiability(m, "point", q, parameters="dL9")
    many = m.ik(m.home_pose + np.random.default_rng(6).uniform(-0.1, 0.1, (30, 3)))
    with pytest.raises(IdentifiabilityError, match="rank 18 of 30"):
        identifiability(m, "point", many, require_full_rank=True)


def test_part_setup_measures_full_poses_of_a_six_actuator_machine():
    """Documented default: the machined points of a ``"part"`` measurement are the nominal tool
    poses for a six-actuator machine (position and orientation), tool points otherwise."""
    from pkmkit.geometric_errors.identifiability import default_setup

    hexapod = pkmkit.machine("gough-stewart")
    q = hexapod.home_q + 0.01 * np.random.default_rng(3).standard_normal((4, 6))
    points = default_setup(hexapod, "part", q)["points"]
    fk = np.atleast_2d(hexapod.fk(q))
    assert points.shape == (4, 6)
    np.testing.assert_allclose(points, fk[:, :6], atol=1e-12)
    verne = pkmkit.machine("verne")  # five actuators: position-controlled, points only
    assert default_setup(verne, "part", np.atleast_2d(verne.home_q))["points"].shape == (1, 3)


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_unidentifiable_columns_are_relative_to_the_jacobian(scale):
    """A column is "no effect" when its norm is below rtol × σ_max, whatever the units of the
    Jacobian: multiplying J by any factor changes neither the rank nor which columns are dead.
    Hand-built J: column 3 is 1e-13 of the others (dead), column 2 is 1e-3 (alive)."""
    from pkmkit.geometric_errors.identifiability import analyse_jacobian

    rng = np.random.default_rng(5)
    base = rng.standard_normal((12, 2))
    j = np.column_stack([base[:, 0], 1e-3 * base[:, 1], 1e-13 * rng.standard_normal(12)])
    out = analyse_jacobian(scale * j, ("a", "b", "c"), np.ones(3))
    assert out["unidentifiable"] == ("c",)
    assert set(out["base"]) == {"a", "b"}


def test_rank_threshold_is_relative_to_the_largest_singular_value():
    """Singular values 1, 1e-4 and 1e-11 (rtol 1e-9): the rank is 2 and the third column is
    dead (1e-11 < 1e-9 × 1); a threshold taken from the second singular value (1e-13) would
    keep it. A rank-one Jacobian (one singular value, the others exactly 0) has rank 1."""
    from pkmkit.geometric_errors.identifiability import analyse_jacobian

    one = analyse_jacobian(np.outer([1.0, 2.0, 2.0], [0.0, 3.0, 0.0]), ("a", "b", "c"),
                           np.ones(3))
    assert one["rank"] == 1 and one["base"] == ("b",) and one["unidentifiable"] == ("a", "c")

    j = np.zeros((5, 3))
    j[0, 0], j[1, 1], j[2, 2] = 1.0, 1e-4, 1e-11
    out = analyse_jacobian(j, ("a", "b", "c"), np.ones(3), rtol=1e-9)
    assert out["rank"] == 2
    assert out["unidentifiable"] == ("c",)
    np.testing.assert_allclose(out["singular_values"], [1.0, 1e-4, 1e-11])


def _combination_null_directions(result):
    """For every parameter o outside the base with a coefficient: the SI defect direction
    e_o − Σ_b c_b,o e_b, which changes none of the reported combinations δ_b + Σ c_b,o δ_o."""
    names = list(result.names)
    out = {}
    for c in result.combinations:
        for other, coef in list(c.terms.items())[1:]:
            d = out.setdefault(other, np.eye(len(names))[names.index(other)])
            d[names.index(c.base)] -= coef
    return out


def test_tripteor_combinations_are_invisible_on_the_exact_model(tripteor, tripteor_q):
    """A combination mixing a direction defect and a length defect (``daT + 0.16989·dIT``:
    the coefficient is the tool length, m) is what the tool points see: moving the defects
    along the combination's null direction leaves the exact tool points still (second order,
    < 1e-11 m for 1e-6 steps). The old coefficients were scaled by 1/L² (0.67956·dIT), which
    moved the tool by 5e-7 m."""
    q = tripteor_q[:8]
    r = identifiability(tripteor, "point", tripteor_q)
    terms = next(c.terms for c in r.combinations if c.base == "daT")
    assert terms["dIT"] == pytest.approx(0.169889, rel=1e-4)  # the tool length
    base = measure(tripteor, "point", q)
    directions = _combination_null_directions(r)
    assert len(directions) >= 10
    for name, d in directions.items():
        step = 1e-6 * d / np.abs(d).max()
        moved = measure(with_defects(tripteor, dict(zip(r.names, step, strict=True))), "point", q)
        assert np.abs(moved - base).max() < 1e-11, name


def _cancellation(raw, d):
    """|J d| relative to Σ |J_i| |d_i|: 0 when d is a null direction, whatever the units."""
    return np.abs(raw @ d).max() / (np.abs(raw) @ np.abs(d)).max()


@pytest.mark.parametrize("scaling", ["length", "norm", "none"])
def test_combinations_are_null_directions_whatever_the_scaling(tripteor, tripteor_q, scaling):
    """The combinations are reported in SI: whatever the column scaling, each one's null
    direction cancels in the SI Jacobian (a units-free test: |J d| against Σ|J_i||d_i|)."""
    r = identifiability(tripteor, "point", tripteor_q, scaling=scaling)
    # the rank and the unseen defects do not depend on the scaling either ("norm" used to
    # blow the round-off columns of unseen defects up to unit columns: rank 63 instead of 46)
    assert (r.rank, r.rank_qr) == (46, 46)
    assert r.unidentifiable == identifiability(tripteor, "point", tripteor_q).unidentifiable
    directions = _combination_null_directions(r)
    assert len(directions) >= 10
    for name, d in directions.items():
        assert _cancellation(r.jacobian.raw, d) < 1e-8, name


def test_length_scaling_is_the_documented_one(tripteor, tripteor_q):
    """``"length"`` scaling: angle-like columns (direction components, rad) divided by L (the
    defect counted as L·δ metres), length columns unchanged, L the characteristic length
    (0.5 m for the Tripteor); pose readings: rotation rows × L."""
    for kind in ("point", "pose"):
        ij = identification_jacobian(tripteor, kind, tripteor_q[:5])
        assert ij.length == 0.5
        angle = np.array([u in ("1", "rad") for u in ij.units])
        assert angle.any() and (~angle).any()
        rows = np.tile(np.r_[np.ones(3), np.full(ij.rows - 3, 0.5)], 5)
        expected = ij.raw * rows[:, None] / np.where(angle, 0.5, 1.0)
        np.testing.assert_allclose(ij.matrix, expected, rtol=1e-15, atol=0)
