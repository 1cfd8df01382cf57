"""The Tripteor X7's hyperstatic compatibility derived in exact arithmetic (SymPy), independently
of pkmkit's model, and compared with pkmkit's numeric rank test (issue 21 §3).

The oracle is built here from the thesis alone: the chains of eq. (4.19) for legs 1 and 3 with
Table 4.2's invariants, each frame by (4.6) (x = z_prev ∧ z normalised, y = z ∧ x), a defect as
the minimal first-order rotation tilting the axis to z + δ about the frame's point (plus a shift;
a spin about the axis for a fixed frame), the convention of docs/errors.md §1. Only the loop
legs 1–3 is modelled: it carries the whole hyperstatism (degree 2); leg 2's rows hold no left
null vector (``test_compatibility.py::test_leg_2_defects_close_exactly_unlike_the_forced_ones``).

Configurations are *rational points*: ψ1 = ψ3, θ1, θ3 and the platform angle α = θ1 + φ1 =
θ3 + φ3 have rational tangents of the half-angle, so every cosine and sine is rational, the
strokes Q1, Q3 follow from the (linear) nominal closure, and every Jacobian, left null space
and rank below is exact — no tolerance. The compatible subspace found on a few configurations
contains the true one; it is then checked to be compatible at configurations drawn afresh
(a non-zero rational function vanishes at a random rational point with negligible chance).
"""

from __future__ import annotations

import importlib.util
import random
from functools import cache

import pytest

import pkmkit
from pkmkit.geometric_errors.compatibility import compatibility

if importlib.util.find_spec("sympy") is None:
    pytest.skip("could not import 'sympy'", allow_module_level=True)


class _Lazy:
    """A module or class imported at its first use, not when the file is collected: every
    pytest-xdist worker collects this file and one runs it, and SymPy's import costs ≈ 0.4 s
    of CPU (docs/testing.md, "Seventh round")."""

    def __init__(self, load):
        self._load = load

    def __getattr__(self, name):
        if name.startswith("_"):  # pytest's collection asks for __test__, _pytestfixturefunction
            raise AttributeError(name)
        return getattr(self._load(), name)


def _sympy():
    import sympy

    return sympy


def _domain_matrix():
    from sympy.polys.matrices import DomainMatrix

    return DomainMatrix


sp = _Lazy(_sympy)
DomainMatrix = _Lazy(_domain_matrix)

#: Table 5.6's dimensions as used by the preset (m), exact: the decimal texts of ``L`` and ``l``.
L_TEXT, SMALL_L_TEXT = "1.0006254", "0.38986"
PASSIVE = ("psi1", "theta1", "phi1", "psi3", "theta3", "phi3")


def _elements_table():
    """Loop 1–3's elements after the reference joint 11: label, axis, point (Table 4.2), kind."""
    L, SMALL_L = sp.Rational(L_TEXT), sp.Rational(SMALL_L_TEXT)
    return (("21", (1, 0, 0), (0, 0, 0), "R"), ("41", (1, 0, 0), (0, 0, 0), "P"),
            ("51", (0, 1, 0), (0, 0, 0), "R"), ("13", (0, -1, 0), (0, -L, 0), "R"),
            ("23", (1, 0, 0), (0, 0, 0), "R"), ("43", (1, 0, 0), (0, 0, 0), "P"),
            ("53", (0, 1, 0), (0, 0, 0), "R"), ("63", (0, 0, 1), (SMALL_L, 0, 0), "F"))


def _hom(rotation, point):
    out = sp.eye(4)
    out[:3, :3] = sp.Matrix(rotation)
    out[:3, 3] = sp.Matrix(point)
    return out


def _skew(w):
    return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def frame_4_6(axis):
    """(4.6) as the text defines it: x = z_prev ∧ z / ‖·‖, y = z ∧ x (direct basis); where z
    is along z_prev, (4.6) is undefined and the previous x is kept (docs/joint-chains.md)."""
    z = sp.Matrix(axis)
    x = sp.Matrix([0, 0, 1]).cross(z)
    if x.norm() == 0:
        return sp.eye(3)
    x = x / x.norm()
    return sp.Matrix.hstack(x, z.cross(x), z)


def element(label: str, axis, point, kind: str):
    """The nominal matrix of an element and its derivative by each of its defects at zero.
    Defects: the axis components other than its largest (dI, dJ, dK), for a revolute the two
    point components across it, for a fixed frame all three and a spin dS; none of position
    for a prismatic joint."""
    a = sp.Matrix(axis)
    big = max(range(3), key=lambda i: abs(a[i]))
    tilt, symbols = [0, 0, 0], []
    for i in range(3):
        if i != big:
            s = sp.Symbol(f"d{'IJK'[i]}{label}")
            symbols.append(s)
            tilt[i] = s
    rotation = (sp.eye(3) + _skew(a.cross(sp.Matrix(tilt)))) * frame_4_6(axis)
    if kind == "F":
        spin = sp.Symbol(f"dS{label}")
        symbols.append(spin)
        rotation = (sp.eye(3) + _skew(a * spin)) * rotation
    p = sp.Matrix(point)
    if kind != "P":
        for i in range(3):
            if i != big or kind == "F":
                s = sp.Symbol(f"d{'abc'[i]}{label}")
                symbols.append(s)
                p[i] += s
    matrix = _hom(rotation, p)
    zero = dict.fromkeys(symbols, 0)
    return matrix.subs(zero), {str(s): matrix.diff(s).subs(zero) for s in symbols}


@cache
def elements():
    return {label: element(label, axis, point, kind)
            for label, axis, point, kind in _elements_table()}


def defect_names() -> list[str]:
    return [name for _, derivatives in elements().values() for name in derivatives]


def _turn(cs):
    c, s = cs
    return _hom([[c, -s, 0], [s, c, 0], [0, 0, 1]], [0, 0, 0])


def _turn_rate(cs):
    c, s = cs
    out = sp.zeros(4)
    out[:3, :3] = sp.Matrix([[-s, -c, 0], [c, -s, 0], [0, 0, 0]])
    return out


def _chain(factors):
    """Product of ``(matrix, {name: derivative})`` factors and its derivative by each name."""
    before = [sp.eye(4)]
    for m, _ in factors:
        before.append(before[-1] * m)
    after = [sp.eye(4)]
    for m, _ in reversed(factors):
        after.append(m * after[-1])
    after.reverse()
    rates = {}
    for k, (_, derivatives) in enumerate(factors):
        for name, dm in derivatives.items():
            rates[name] = rates.get(name, sp.zeros(4)) + before[k] * dm * after[k + 1]
    return before[-1], rates


def _on_circle(t):
    """(cos, sin) of the angle whose half-angle tangent is ``t`` (rational for rational t)."""
    return (1 - t**2) / (1 + t**2), 2 * t / (1 + t**2)


def _minus(a, b):
    return a[0] * b[0] + a[1] * b[1], a[1] * b[0] - a[0] * b[1]


def configuration(tangents):
    """Nominal joint (cos, sin) of loop 1–3 from four half-angle tangents (ψ, θ1, θ3, α) and
    the strokes Q1, Q3 that close it (exact); the closure is checked to vanish exactly."""
    psi, th1, th3, alpha = (_on_circle(sp.Rational(t)) for t in tangents)
    cs = {"psi1": psi, "theta1": th1, "phi1": _minus(alpha, th1), "psi3": psi, "theta3": th3,
          "phi3": _minus(alpha, th3)}
    q1, q3 = sp.symbols("Q1 Q3")
    t1, _ = _chain(_leg(1, cs, q1))
    t3, _ = _chain(_leg(3, cs, q3))
    gap = t1 - t3
    solution = sp.solve([gap[0, 3], gap[1, 3], gap[2, 3]], [q1, q3], dict=True)
    assert len(solution) == 1
    assert gap.subs(solution[0]) == sp.zeros(4)             # the nominal loop closes exactly
    return cs, solution[0][q1], solution[0][q3]


def _leg(k: int, cs, stroke):
    e = elements()
    joint = {name: (_turn(cs[name]), {name: _turn_rate(cs[name])}) for name in PASSIVE}
    slide = (_hom(sp.eye(3), [0, 0, stroke]), {})
    if k == 1:
        base = (_hom(frame_4_6((0, -1, 0)), (0, 0, 0)), {})   # D_ICS^L11: the reference
        return [base, joint["psi1"], e["21"], joint["theta1"], e["41"], slide, e["51"],
                joint["phi1"]]
    return [e["13"], joint["psi3"], e["23"], joint["theta3"], e["43"], slide, e["53"],
            joint["phi3"], e["63"]]


def projected_defects(tangents):
    """``(8, d)`` exact rows Nᵀ C_δ of one configuration (N: left null space of the passive
    Jacobian of T1 − T3's 12 entries), the passive Jacobian's rank and that of the passive and
    defect Jacobians side by side."""
    cs, q1, q3 = configuration(tangents)
    _, rates1 = _chain(_leg(1, cs, q1))
    _, rates3 = _chain(_leg(3, cs, q3))

    def column(name):
        diff = rates1.get(name, sp.zeros(4)) - rates3.get(name, sp.zeros(4))
        return sp.Matrix(list(diff[:3, :]))

    passive = sp.Matrix.hstack(*[column(n) for n in PASSIVE])
    defects = sp.Matrix.hstack(*[column(n) for n in defect_names()])
    transposed = DomainMatrix.from_Matrix(passive.T).convert_to(sp.QQ)
    left = transposed.nullspace().to_Matrix()
    both = DomainMatrix.from_Matrix(sp.Matrix.hstack(passive, defects)).convert_to(sp.QQ)
    return left * defects, transposed.rank(), both.rank()


def _tangents(rng: random.Random, size: int) -> list[str]:
    return [f"{rng.randint(-size, size)}/{size + 1}" for _ in range(4)]


@pytest.fixture(scope="module")
def exact():
    """The stacked exact conditions over 8 rational configurations."""
    rng = random.Random(1)
    blocks = []
    for _ in range(8):
        block, rank, with_defects = projected_defects(_tangents(rng, 9))
        assert rank == 4          # 6 passive joints, 2 motions left with Q1, Q3 held
        # the 12 entries carry 6 closure equations (a first-order rotation has 3 of its 9
        # entries free): defects reach 2 directions no passive motion does, the hyperstatism
        assert with_defects == 6 and block.rows == 12 - rank
        blocks.append(block)
    stacked = DomainMatrix.from_Matrix(sp.Matrix.vstack(*blocks)).convert_to(sp.QQ)
    kernel = stacked.nullspace().to_Matrix()   # rows: a basis of the compatible subspace
    reduced, pivots = stacked.rref()
    return stacked.rank(), kernel, reduced.to_Matrix(), pivots


def _forced(kernel, names):
    return [n for i, n in enumerate(names) if all(kernel[r, i] == 0 for r in range(kernel.rows))]


def _conditions(reduced, pivots, names):
    out = []
    for r in range(len(pivots)):
        terms = {names[j]: reduced[r, j] for j in range(len(names)) if reduced[r, j] != 0}
        if len(terms) > 1:
            out.append(terms)
    return out


@pytest.fixture(scope="module")
def numeric():
    return compatibility(pkmkit.machine("tripteor-x7"), reference_nominal=True)


def test_the_printed_4_6_is_not_a_rotation():
    """Erratum: (4.6) prints +J·K/√(I²+J²) in row 2, column 2; the text's own y = z ∧ x gives
    −J·K/√(I²+J²). As printed, x·y = 2IJK/(I²+J²): not orthogonal for any axis with I, J, K
    all non-zero."""
    i, j, k = sp.symbols("I J K", real=True)
    rho = sp.sqrt(i**2 + j**2)
    x = sp.Matrix([-j, i, 0]) / rho
    printed_y = sp.Matrix([-i * k, j * k, rho**2]) / rho
    z = sp.Matrix([i, j, k])
    assert sp.simplify(x.dot(printed_y) - 2 * i * j * k / rho**2) == 0
    assert sp.simplify(z.cross(x) - sp.Matrix([-i * k, -j * k, rho**2]) / rho) == sp.zeros(3, 1)
    # the corrected matrix is a rotation for every unit axis off z_prev
    corrected = sp.Matrix.hstack(x, z.cross(x), z)
    on_unit = {k: sp.sqrt(1 - i**2 - j**2)}
    assert sp.simplify((corrected.T * corrected).subs(on_unit)) == sp.eye(3)


@pytest.mark.ci
def test_loop_1_3_compatibility_in_exact_arithmetic_agrees_with_the_numeric_rank(exact, numeric):
    """Forced defects and conditions, exact: the same twelve forced defects as pkmkit's numeric
    rank test, and its two conditions with the exact coefficient 1/L (dK21 + dc63/L = 0:
    tilting ψ1's axis is compatible when leg 3's junction follows along z)."""
    rank, kernel, reduced, pivots = exact
    names = defect_names()
    assert len(names) == 30 and rank == 14
    forced = _forced(kernel, names)
    loop = [n for n in numeric.forced_zero if n in names]
    assert forced == loop == list(numeric.forced_zero)        # all forced defects are in loop 1–3
    conditions = _conditions(reduced, pivots, names)
    inverse = 1 / sp.Rational(L_TEXT)
    assert conditions == [{"dK21": 1, "dc63": inverse}, {"dK23": 1, "dc63": inverse}]
    numeric_terms = [c.terms for c in numeric.conditions]
    assert [list(t) for t in numeric_terms] == [list(c) for c in conditions]
    for terms, exact_terms in zip(numeric_terms, conditions, strict=True):
        assert list(terms.values()) == pytest.approx([float(v) for v in exact_terms.values()],
                                                     rel=1e-9)
    # compatible dimension: loop 1–3 keeps 30 − 14; every leg-2 defect is free
    leg_2 = [n for n in numeric.names if n not in names]
    assert len(leg_2) == 24 and numeric.compatible_dimension == 30 - 14 + len(leg_2)
    assert kernel.rows == 30 - 14


def test_orientation_only_gives_the_twelve_forced_of_legs_1_and_3(exact, numeric):
    """The thesis's orientation-only study (Table 4.6, legs 1 and 3): without position
    defects, dK21 and dK23 are forced too; 4 of the 16 loop orientations stay free (the
    θ and slide tilts across the plane: dJ21, dJ41, dJ23, dJ43)."""
    _, _, reduced, _ = exact
    names = defect_names()
    keep = [i for i, n in enumerate(names) if n[1] in "IJK"]
    sub = DomainMatrix.from_Matrix(reduced[:, keep]).convert_to(sp.QQ)
    kernel = sub.nullspace().to_Matrix()
    orientation = [names[i] for i in keep]
    forced = _forced(kernel, orientation)
    r = compatibility(pkmkit.machine("tripteor-x7"), orientation_only=True,
                      reference_nominal=True)
    assert forced == list(r.forced_zero) and len(forced) == 12
    assert sorted(set(orientation) - set(forced)) == ["dJ21", "dJ23", "dJ41", "dJ43"]
    assert kernel.rows == 4 and r.compatible_dimension == 4 + 12   # + leg 2's twelve


def test_the_compatible_subspace_holds_at_fresh_configurations(exact):
    """Each basis vector of the compatible subspace, found on 8 configurations, is compatible
    at 4 configurations drawn afresh with finer rationals (exactly zero), and an incompatible
    defect is not."""
    _, kernel, _, _ = exact
    rng = random.Random(20261126)
    names = defect_names()
    for _ in range(4):
        block, _, _ = projected_defects(_tangents(rng, 97))
        assert block * kernel.T == sp.zeros(block.rows, kernel.rows)
        forced = block[:, names.index("da13")]
        assert forced != sp.zeros(block.rows, 1)
