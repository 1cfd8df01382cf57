import math

import numpy as np
import pytest

from pkmkit.dynamics.arms import Material, analyse_arm, seed_tables, size_arm
from pkmkit.exceptions import InputError


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
    """Every formula at a length, diameters and material far from 1, so that a wrong power of
    ℓ, D or d shows: ℓ = 0.7 m, D = 40 mm, d = 26 mm, E = 70 GPa, ρ = 2700 kg/m³."""
    ell, big, small, accel = 0.7, 0.04, 0.026, 35.0
    alu = Material(E=7e10, density=2700.0, yield_strength=2.6e8)
    a = analyse_arm(ell, big, small, axial_force=-1500.0, transverse_accel=accel, material=alu)
    area = math.pi / 4 * (big**2 - small**2)
    inertia = math.pi / 64 * (big**4 - small**4)
    mass = 2700 * area * ell
    w = mass * accel / ell  # distributed load, N/m
    bending = w * ell**2 / 8 * (big / 2) / inertia
    exact = {
        "area": area, "mass": mass, "axial_stress": -1500 / area,
        "axial_stiffness": 7e10 * area / ell,
        "buckling_load": math.pi**2 * 7e10 * inertia / ell**2,
        "buckling_safety": math.pi**2 * 7e10 * inertia / ell**2 / 1500,
        "bending_stress": bending,
        "deflection": 5 * w * ell**4 / (384 * 7e10 * inertia),
        "combined_stress": 1500 / area + bending,
        "stress_safety": 2.6e8 / (1500 / area + bending),
    }
    for name, value in exact.items():
        assert getattr(a, name) == pytest.approx(value, rel=1e-14), name
    # the bending stress of a solid bar is ρ a ℓ² / D: a second, simpler form
    solid = analyse_arm(ell, big, transverse_accel=accel, material=alu)
    assert solid.bending_stress == pytest.approx(2700 * accel * ell**2 / big, rel=1e-14)
    assert solid.stress_safety == pytest.approx(2.6e8 / solid.bending_stress, rel=1e-14)


def test_sizing_where_the_combined_stress_binds():
    """Short aluminium rod under a large transverse acceleration: neither buckling nor the
    axial stress alone binds, the sum |N|/A + σ_b does. For a solid bar σ_b = ρ a ℓ²/D, so the
    lightest diameter solves 4N/(πD²) + ρ a ℓ²/D = σ_y/s (a quadratic in 1/D)."""
    alu = Material(E=7e10, density=2700.0, yield_strength=95e6)
    force, ell, accel, safety = 5000.0, 0.2, 700.0, 2.0
    design = size_arm(axial_force=force, length=ell, transverse_accel=accel, material=alu,
                      stress_safety=safety)
    quad, lin = 4 * force / math.pi, 2700 * accel * ell**2
    inv = (-lin + math.sqrt(lin**2 + 4 * quad * 95e6 / safety)) / (2 * quad)
    a = design.analysis
    assert design.feasible and design.constraints["buckling"] > 0.3
    assert a.bending_stress > 0.1 * a.combined_stress  # the bending part matters
    assert a.outer_diameter == pytest.approx(1 / inv, rel=1e-9)
    assert a.stress_safety == pytest.approx(safety, rel=1e-9)


@pytest.mark.ci
def test_sizing_is_the_lightest_admissible_rod():
    design = size_arm(axial_force=1000.0, length=1.04, buckling_safety=3.0)
    assert design.feasible
    d = design.analysis.outer_diameter
    # buckling binds: N_cr = 3 × 1000 N for a solid bar
    assert design.analysis.buckling_safety == pytest.approx(3.0, rel=1e-9)
    expected = (3000 * 1.04**2 * 64 / (math.pi**3 * 210e9)) ** 0.25
    assert d == pytest.approx(expected, rel=1e-9)
    stiff = size_arm(axial_force=1000.0, length=1.04, hollow=True, min_stiffness=5e7)
    assert stiff.feasible and stiff.analysis.axial_stiffness >= 5e7 * (1 - 1e-6)
    assert stiff.analysis.mass == pytest.approx(7700 * 5e7 * 1.04**2 / 210e9, rel=1e-8)


@pytest.mark.ci
def test_infeasible_and_bad_sizing():
    design = size_arm(axial_force=1e7, length=1.04, diameter_range=(0.005, 0.02))
    assert not design.feasible and "buckling" in design.message
    with pytest.raises(InputError):
        analyse_arm(1.0, 0.02, 0.03)
    for length, big in ((1.0, -0.02), (1.0, 0.0), (1.0, math.inf), (-1.0, 0.02), (0.0, 0.02),
                        (math.nan, 0.02)):
        with pytest.raises(InputError, match=r"must be (> 0|finite)"):
            analyse_arm(length, big)
    with pytest.raises(InputError):
        size_arm(axial_force=10.0, length=1.0, diameter_range=(0.05, 0.01))
    with pytest.raises(InputError):
        Material(E=-1.0)
    assert np.isinf(analyse_arm(1.0, 0.02, axial_force=10.0).buckling_safety)


@pytest.mark.parametrize("force", [56.0, 1000.0, 2e4])
@pytest.mark.ci
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
    assert a.outer_diameter == pytest.approx(hi, rel=1e-8)
    assert a.outer_diameter - a.inner_diameter == pytest.approx(0.002, rel=1e-8)


@pytest.mark.ci
def test_tube_with_a_fixed_bore():
    """The seed's tubes have a 25 mm bore: the lightest tube with that bore has the outer
    diameter where buckling reaches its safety factor (bisection here), at least 2 walls wider;
    a bore leaving no wall within the diameter range is refused."""
    design = size_arm(axial_force=20e3, length=0.9, hollow=True, inner_diameter=0.025)
    a = design.analysis
    assert design.feasible and a.inner_diameter == 0.025

    def critical(big):
        return math.pi**3 * 210e9 * (big**4 - 0.025**4) / 64 / 0.9**2

    lo, hi = 0.027, 0.1
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if critical(mid) < 3 * 20e3 else (lo, mid)
    assert a.outer_diameter == pytest.approx(hi, rel=1e-8)
    thin = size_arm(axial_force=10.0, length=0.9, hollow=True, inner_diameter=0.025)
    assert thin.analysis.outer_diameter == pytest.approx(0.025 + 2 * 0.001, rel=1e-9)
    with pytest.raises(InputError, match="no wall"):
        size_arm(axial_force=10.0, length=0.9, hollow=True, inner_diameter=0.1 - 2 * 0.001)


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
