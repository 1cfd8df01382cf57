import math

import numpy as np
import pytest

from pkmkit.dynamics.arms import Material, analyse_arm, seed_tables, size_arm
from pkmkit.errors import InputError


def test_seed_tables_iv2_iv3():
    """Masses exact with ρ = 1000 kg/m³; FE stresses 1.04–1.13 × the nominal axial stress F/A."""
    rows = seed_tables()
    assert len(rows) == 14
    for r in rows:
        assert r["mass_g"] == pytest.approx(r["seed_mass_g"], abs=0.006)
        assert 1.04 <= r["stress_ratio"] <= 1.13
    steel = seed_tables(density=7700.0)
    optimum = next(r for r in steel if r["table"].startswith("IV.2") and r["design"] == "Optimale")
    assert optimum["mass_g"] == pytest.approx(12924.6, abs=1)  # what 7700 kg/m³ would weigh


def test_handbook_values_of_a_steel_rod():
    """Ø40 mm solid steel bar, 1.04 m, pinned at both ends, hand-computed: A = 1256.6 mm²,
    I = 125 664 mm⁴, N_cr = π²EI/ℓ² = 240.8 kN, self-weight q = ρgA = 94.92 N/m, mid-span moment
    qℓ²/8 = 12.83 N·m, bending stress M c / I = 2.04 MPa, deflection 5qℓ⁴/(384EI) = 0.055 mm,
    mass 10.06 kg, axial stiffness EA/ℓ = 253.7 N/µm."""
    a = analyse_arm(1.04, 0.040, axial_force=-1000.0, transverse_accel=9.81,
                    material=Material(E=210e9, density=7700.0))
    assert a.area * 1e6 == pytest.approx(1256.6, abs=0.1)
    assert a.buckling_load == pytest.approx(240.8e3, rel=1e-3)
    assert a.bending_stress == pytest.approx(2.04e6, rel=2e-3)
    assert a.deflection == pytest.approx(0.055e-3, rel=1e-2)
    assert a.mass == pytest.approx(10.06, abs=0.01)
    assert a.axial_stiffness == pytest.approx(253.7e6, rel=1e-3)
    assert a.axial_stress == pytest.approx(-0.796e6, rel=1e-3)


def test_analysis_formulas():
    a = analyse_arm(1.0, 0.04, 0.02, axial_force=-1000.0, transverse_accel=9.81,
                    material=Material(E=2e11, density=8000.0, yield_strength=5e8))
    area = math.pi / 4 * (0.04**2 - 0.02**2)
    inertia = math.pi / 64 * (0.04**4 - 0.02**4)
    assert a.area == pytest.approx(area) and a.axial_stress == pytest.approx(-1000 / area)
    assert a.buckling_load == pytest.approx(math.pi**2 * 2e11 * inertia)
    assert a.buckling_safety == pytest.approx(a.buckling_load / 1000)
    w = 8000 * area * 9.81
    assert a.bending_stress == pytest.approx(w / 8 * 0.02 / inertia)
    assert a.deflection == pytest.approx(5 * w / (384 * 2e11 * inertia))
    assert a.axial_stiffness == pytest.approx(2e11 * area)


def test_sizing_is_the_lightest_admissible_rod():
    design = size_arm(axial_force=1000.0, length=1.04, buckling_safety=3.0)
    assert design.feasible
    d = design.analysis.outer_diameter
    # buckling binds: N_cr = 3 × 1000 N for a solid bar
    assert design.analysis.buckling_safety == pytest.approx(3.0, rel=1e-4)
    expected = (3000 * 1.04**2 * 64 / (math.pi**3 * 210e9)) ** 0.25
    assert d == pytest.approx(expected, rel=1e-4)
    stiff = size_arm(axial_force=1000.0, length=1.04, hollow=True, min_stiffness=5e7)
    assert stiff.feasible and stiff.analysis.axial_stiffness >= 5e7 * (1 - 1e-6)
    assert stiff.analysis.mass == pytest.approx(7700 * 5e7 * 1.04**2 / 210e9, rel=1e-3)


def test_infeasible_and_bad_sizing():
    design = size_arm(axial_force=1e7, length=1.04, diameter_range=(0.005, 0.02))
    assert not design.feasible and "buckling" in design.message
    with pytest.raises(InputError):
        analyse_arm(1.0, 0.02, 0.03)
    with pytest.raises(InputError):
        size_arm(axial_force=10.0, length=1.0, diameter_range=(0.05, 0.01))
    with pytest.raises(InputError):
        Material(E=-1.0)
    assert np.isinf(analyse_arm(1.0, 0.02, axial_force=10.0).buckling_safety)


@pytest.mark.parametrize("force", [56.0, 1000.0, 2e4])
def test_free_bore_tube_is_the_thinnest_wall_at_the_buckling_limit(force):
    """With the bore free, the lightest tube has the thinnest allowed wall (1 mm) and the outer
    diameter where Euler buckling reaches its safety factor: found here by bisection."""
    design = size_arm(axial_force=force, length=1.04, hollow=True)
    assert design.feasible

    def critical(big):
        small = big - 0.002
        return math.pi**3 * 210e9 * (big**4 - small**4) / 64 / 1.04**2

    lo, hi = 0.0021, 0.1
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if critical(mid) < 3 * force else (lo, mid)
    a = design.analysis
    assert a.outer_diameter == pytest.approx(hi, rel=1e-5)
    assert a.outer_diameter - a.inner_diameter == pytest.approx(0.002, rel=1e-6)


@pytest.mark.parametrize("kwargs, message", [
    ({"stress_safety": 0.0}, "stress safety"),
    ({"buckling_safety": -3.0}, "buckling safety"),
    ({"min_stiffness": -5.0}, "minimum stiffness"),
    ({"axial_force": float("nan")}, "finite"),
])
def test_bad_sizing_requirements(kwargs, message):
    args = {"axial_force": 1000.0, "length": 1.0, **kwargs}
    with pytest.raises(InputError, match=message):
        size_arm(**args)
