"""Hyperstatic compatibility: the crank–slider and Tripteor results of seed 002 (Guyon 2021,
§4.3–4.4; notes §3.9), an independent symbolic (SymPy) stationarity analysis of the
crank–slider, the exact nonlinear closure as evidence for the leg-2 disagreement, and
machines without hyperstatism."""

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import ParameterError
from pkmkit.geometric_errors.compatibility import compatibility, projected_defects
from pkmkit.geometric_errors.model import with_defects

CRANK_FORCED = ("dI2", "dJ2", "dI3", "dJ3", "dJ4")
TRIPTEOR_ORIENTATION_FORCED = ("dK21", "dK41", "dI51", "dK51", "dI13", "dK13", "dK23", "dK43",
                               "dI53", "dK53", "dI63", "dJ63")
TRIPTEOR_ORIENTATION_FREE = ("dJ21", "dJ41", "dJ12", "dK12", "dJ22", "dK22", "dJ32", "dK32",
                             "dI42", "dJ42", "dI52", "dK52", "dJ62", "dK62", "dJ23", "dJ43")
#: the notes' minimal set: our fixed frames 62/63 also carry a spin and the along-axis offset
NOTES_EXTRA = ["dS*", "da62", "dc63"]


@pytest.fixture(scope="module")
def crank():
    return pkmkit.machine("crank-slider")


@pytest.fixture(scope="module")
def tripteor():
    return pkmkit.machine("tripteor-x7")


def test_crank_slider_as_the_thesis_with_dk4_free(crank):
    # the thesis's set: pivots 2, 3 and the slider (D_R0^L1 nominal, junctions exact)
    r = compatibility(crank, reference_nominal=True, exclude="*F")
    assert r.forced_zero == CRANK_FORCED
    assert r.conditions == ()
    assert r.compatible_dimension == 5
    assert set(r.free) == {"da2", "db2", "da3", "db3", "dK4"}  # dK4: an in-plane slide tilt
    assert r.hyperstatism == 3 and r.clear_gap and r.gap_ratio > 1e10
    # no condition: every defect not forced to zero is independent, in the JSON summary too
    summary = r.summary()
    assert summary["independent"] == [n for n in r.names if n not in CRANK_FORCED]
    assert summary["forced_zero"] == list(CRANK_FORCED) and summary["free"] == list(r.free)
    # the basis is compatible: the projected columns annihilate it
    blocks, _, _, _ = projected_defects(crank, r.q, np.array([crank.model.defect_index.index(n)
                                                              for n in r.names]))
    np.testing.assert_allclose(np.concatenate(blocks) @ r.basis, 0.0, atol=1e-12)


def test_an_in_plane_slide_tilt_assembles_exactly(crank):
    """The thesis's dK4 = 0 (4.18) is not a compatibility condition: a slide inclined in the
    plane of motion closes exactly at every crank angle; an out-of-plane tilt does not."""
    q = np.linspace(-2.5, 2.5, 25)[:, None]
    assert with_defects(crank, {"dK4": 0.01}).fk(q, full_output=True).closure_residual.max() \
        < 1e-12
    for name in ("dJ4", "dI2", "dJ3"):
        res = with_defects(crank, {name: 0.01}).fk(q, full_output=True).closure_residual
        assert res.max() > 1e-4, name


def test_crank_slider_junctions_and_base_give_frame_relations(crank):
    r = compatibility(crank)
    texts = [c.text() for c in r.conditions]
    # tilting the crank axis out of the plane is compatible if the slider follows it
    assert "dI1 − dJ4 = 0" in texts
    assert "dS3F − dS4F = 0" in texts
    assert set(r.forced_zero) == {"dI2", "dJ2", "dI3", "dJ3"}
    # independent: neither forced to zero nor in a condition (the summary's definition)
    involved = {name for c in r.conditions for name in c.terms}
    assert {"dI1", "dJ4", "dS3F", "dS4F"} <= involved
    assert r.summary()["independent"] == [n for n in r.names
                                          if n not in r.forced_zero and n not in involved]


@pytest.mark.ci
def test_crank_slider_symbolic_stationarity_agrees():
    """An independent derivation: the closure T1 = T2 of eqs. (4.9)-(4.12) written in SymPy with
    first-order defect rotations, linearised in the passive joints, projected on the left null
    space of their Jacobian, reduced with cos² + sin² = 1 and required to vanish for every crank
    angle (the thesis's stationarity, done symbolically)."""
    sp = pytest.importorskip("sympy")
    names = ["dI2", "dJ2", "da2", "db2", "dI3", "dJ3", "da3", "db3", "dJ4", "dK4"]
    rows = _symbolic_conditions(sp, names)
    a = sp.Matrix(rows)
    assert a.rank() == 5
    ns = a.nullspace()
    assert len(ns) == 5
    forced = tuple(names[i] for i in range(10) if all(v[i] == 0 for v in ns))
    assert forced == CRANK_FORCED
    numeric = compatibility(pkmkit.machine("crank-slider"), reference_nominal=True,
                            exclude="*F")
    assert numeric.compatible_dimension == len(ns)


def _symbolic_conditions(sp, names):
    """Rows of the linear conditions on the defects ``names`` that make the crank–slider's
    linearised closure solvable in (θ2, θ3, x4) for every crank angle θ1."""
    l1, l2, l3, l4 = (sp.Rational(1, 10), sp.Rational(3, 10), sp.Rational(1, 20),
                      sp.Rational(1, 5))
    th1, th2, th3, x4 = sp.symbols("th1 th2 th3 x4")
    d = dict(zip(names, sp.symbols(names), strict=True))
    eye = sp.eye(3)

    def hom(rot, p):
        return sp.Matrix(sp.BlockMatrix([[sp.Matrix(rot), sp.Matrix(p)],
                                         [sp.zeros(1, 3), sp.ones(1, 1)]]))

    def skew(w):
        return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])

    def turn(t):
        return hom([[sp.cos(t), -sp.sin(t), 0], [sp.sin(t), sp.cos(t), 0], [0, 0, 1]],
                   [0, 0, 0])

    def tilt(axis, change):
        # first-order rotation taking the unit axis a to a + change (change ⟂ a): ω = a × change
        return eye + skew(sp.Matrix(axis).cross(sp.Matrix(change)))

    # Table 4.1 and eqs. (4.10)-(4.12), defects as in (4.14) at first order
    d1 = hom([[1, 0, 0], [0, 0, -1], [0, 1, 0]], [0, 0, 0])
    d2 = hom(tilt([0, 0, 1], [d["dI2"], d["dJ2"], 0]), [l1 + d["da2"], d["db2"], 0])
    d3 = hom(tilt([0, 0, 1], [d["dI3"], d["dJ3"], 0]), [l2 + d["da3"], d["db3"], 0])
    j3 = hom([[1, 0, 0], [0, 0, 1], [0, -1, 0]], [l3, 0, 0])
    d4 = hom(tilt([1, 0, 0], [0, d["dJ4"], d["dK4"]]) * sp.Matrix([[0, 0, 1], [1, 0, 0],
                                                                   [0, 1, 0]]), [l4, 0, 0])
    j4 = hom([[0, 1, 0], [0, 0, 1], [1, 0, 0]], [0, 0, 0])
    t1 = d1 * turn(th1) * d2 * turn(th2) * d3 * turn(th3) * j3
    t2 = d4 * hom(eye, [0, 0, x4]) * j4
    f = sp.Matrix(list((t1 - t2)[:3, :]))
    dv = sp.Matrix([d[n] for n in names])
    zero = dict.fromkeys(dv, 0)
    c1, s1, c3 = sp.symbols("c1 s1 c3")
    s3 = l1 / l2 * s1  # (4.8): L1 sin θ1 = L2 sin θ3
    nominal = {th2: -th1 - th3, x4: l1 * sp.cos(th1) + l2 * sp.cos(th3) + l3 - l4}

    def at_nominal(expr):
        e = sp.expand(sp.expand_trig(expr.subs(zero).subs(nominal)))
        return sp.expand(e.subs({sp.cos(th1): c1, sp.sin(th1): s1, sp.cos(th3): c3,
                                 sp.sin(th3): s3}))

    passive = f.jacobian([th2, th3, x4]).applyfunc(at_nominal)
    defects = f.jacobian(dv).applyfunc(at_nominal)
    rows = []
    for n in passive.T.nullspace():  # left null space of the passive Jacobian
        e = sp.together((n.applyfunc(sp.together).T * defects * dv)[0])
        num = sp.expand(sp.numer(e))
        reduced = 0  # with c1² = 1 − s1² and c3² = 1 − s3²
        for (a, b), coeff in sp.Poly(num, c1, c3).terms():
            reduced += (coeff * c1 ** (a % 2) * (1 - s1 ** 2) ** (a // 2) * c3 ** (b % 2)
                        * (1 - s3 ** 2) ** (b // 2))
        for coeff in sp.Poly(sp.expand(reduced), c1, c3, s1).coeffs():
            rows.append([coeff.coeff(v) for v in dv])  # every θ1: each coefficient vanishes
    return rows


def test_tripteor_orientation_only_reproduces_table_4_6_legs_1_and_3(tripteor):
    r = compatibility(tripteor, orientation_only=True, reference_nominal=True)
    assert r.forced_zero == TRIPTEOR_ORIENTATION_FORCED
    assert r.conditions == ()
    assert tuple(r.free) == TRIPTEOR_ORIENTATION_FREE
    assert r.compatible_dimension == 16 and r.hyperstatism == 2
    assert r.gap_ratio > 1e8


def test_tripteor_with_positions_forces_psi_collinearity(tripteor):
    r = compatibility(tripteor, reference_nominal=True, exclude=NOTES_EXTRA)
    assert set(r.forced_zero) == set(TRIPTEOR_ORIENTATION_FORCED) | {"da13", "dc13"}
    assert len(r.names) == 50 and r.compatible_dimension == 36
    # our fuller set: the junction offset dc63 couples with the θ-axis tilts
    full = compatibility(tripteor, reference_nominal=True)
    texts = [c.text() for c in full.conditions]
    assert len(texts) == 2 and all("dc63" in t for t in texts)
    assert {"dK21", "dK23"} & set(full.forced_zero) == set()
    # with the base joint free: ψ1 and ψ3 stay collinear (A3 = A1 + L·axis tilt)
    base = compatibility(tripteor)
    texts = [c.text() for c in base.conditions]
    assert "dI11 − dI13 = 0" in texts and "dK11 − dK13 = 0" in texts
    assert any(t.startswith("da11 + 1.0006·dI13 − da13") for t in texts)


def test_leg_2_defects_close_exactly_unlike_the_forced_ones(tripteor):
    """Evidence for the disagreement with the thesis's leg-2 conditions: the exact nonlinear
    closure with a 0.01 defect (the thesis's 1 %) is exact for dI42, dJ42, dK52, dK62 at many
    configurations, and leaves a residual for a forced defect."""
    q = np.tile(tripteor.home_q, (12, 1))
    q[:, :3] += np.random.default_rng(3).uniform(-0.1, 0.1, (12, 3))
    for name in ("dI42", "dJ42", "dK52", "dK62"):
        res = with_defects(tripteor, {name: 0.01}).fk(q, full_output=True)
        assert res.closure_residual.max() < 1e-12, name
    res = with_defects(tripteor, {"dK21": 0.01}).fk(q, full_output=True)
    assert res.closure_residual.min() > 1e-4
    # and the left null space of the closure lives on legs 1 and 3 only
    from pkmkit.geometric_errors.model import closure_linearisation

    cu = closure_linearisation(tripteor, q).unknowns
    u, _, _ = np.linalg.svd(cu)
    left = u[:, :, 16:]
    assert np.abs(left[:, 6:12]).max() < 1e-10  # rows of leg 2


def test_rod_machines_have_no_condition():
    r = compatibility(pkmkit.machine("gough-stewart"), n_configurations=5)
    assert r.forced_zero == () and r.conditions == () and r.hyperstatism == 0
    assert r.compatible_dimension == len(r.names)


def test_bad_selections(tripteor):
    with pytest.raises(ParameterError, match="unknown defect or owner 'dZ99'"):
        compatibility(tripteor, exclude="dZ99")
    with pytest.raises(ParameterError, match="matches no defect"):
        compatibility(tripteor, parameters="dQ*")
    with pytest.raises(ParameterError, match="unknown defect kind"):
        compatibility(tripteor, kinds="wobble")


def test_every_compatible_direction_closes_on_the_exact_model(tripteor):
    """Each basis vector of the compatible subspace (SI, defects of mixed units: direction
    components and lengths, e.g. ``da11 + 1.0006·dI13 − da13 = 0``) is a defect the exact
    nonlinear closure absorbs to second order (1e-6 steps: residual < 1e-10 m), at
    configurations other than those analysed; a direction that breaks one of the conditions
    leaves a first-order residual."""
    r = compatibility(tripteor)
    assert r.conditions  # mixed-unit conditions are present
    q = np.tile(tripteor.home_q, (6, 1))
    q[:, :3] += np.random.default_rng(11).uniform(-0.08, 0.08, (6, 3))
    for j, name in enumerate(r.free):
        step = 1e-6 * r.basis[:, j] / np.abs(r.basis[:, j]).max()
        res = with_defects(tripteor, dict(zip(r.names, step, strict=True))).fk(
            q, full_output=True)
        assert res.closure_residual.max() < 1e-10, name
    # breaking the first condition: move only its first defect
    first = next(iter(r.conditions[0].terms))
    res = with_defects(tripteor, {first: 1e-6}).fk(q, full_output=True)
    assert res.closure_residual.max() > 1e-8


def test_compatibility_from_a_single_configuration(tripteor):
    """One configuration is a valid (weaker) input: its conditions are a subset of those of
    many configurations, so its compatible subspace is at least as large."""
    many = compatibility(tripteor, orientation_only=True)
    one = compatibility(tripteor, orientation_only=True, q=many.q[:1])
    assert one.configurations == 1
    assert one.rank <= many.rank
    assert set(one.forced_zero) <= set(many.forced_zero)
