"""Arm (rod) sizing: solid and hollow circular sections under the loads of the dynamics.

For a rod of length ℓ, outer diameter D, inner diameter d (0: solid), material (E, ρ, σ_y), under
an axial force N (tension > 0) and a transverse acceleration a_t (its own weight and inertia):

- area A = π(D² − d²)/4, mass m = ρ A ℓ, second moment I = π(D⁴ − d⁴)/64;
- axial stress σ_N = N / A; axial stiffness k = E A / ℓ;
- Euler buckling (pinned–pinned: spherical joints at both ends) N_cr = π² E I / ℓ²; safety
  factor N_cr / max(−N, 0);
- bending as a simply supported beam under its distributed load w = m a_t / ℓ: M = w ℓ²/8,
  σ_b = M (D/2) / I, mid-span deflection 5 w ℓ⁴ / (384 E I);
- combined stress |σ_N| + σ_b compared with σ_y / safety.

:func:`size_arm` minimises the mass over D (and d, and ℓ if allowed) subject to the stress,
buckling, stiffness and deflection constraints (differential evolution with feasibility rules,
then a local polish: the constraints are not convex in the tube's two diameters).
:func:`seed_tables` reproduces Tables IV.2 and IV.3 of seed 000 (its masses need
ρ = 1000 kg/m³, see docs/seed-errata.md).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.arrays import real, real_pair
from pkmkit.numerics.magnitudes import MAX_DENSITY

#: Admissible (lowest, highest, unit) of each material property: from soft polymers and foams
#: to diamond, osmium and the strongest fibres; outside, a value is a unit slip (a density of
#: 1e300 kg/m³ crashed the optimiser, one of 1e-300 sized an arm of 5e-305 kg).
MATERIAL_RANGES = {"E": (1e6, 1e13, "Pa"), "density": (1.0, MAX_DENSITY, "kg/m³"),
                   "yield_strength": (1e5, 1e11, "Pa")}


@dataclass(frozen=True)
class Material:
    """Elastic material (SI units). Default: alloy steel (E 210 GPa, ρ 7700 kg/m³,
    σ_y 620 MPa — SolidWorks' "Alloy Steel", the library the seed's study used)."""

    E: float = 210e9
    density: float = 7700.0
    yield_strength: float = 620e6

    def __post_init__(self) -> None:
        for name in ("E", "density", "yield_strength"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise InputError(f"material {name} must be > 0, got {value}")
            lo, hi, unit = MATERIAL_RANGES[name]
            if not lo <= value <= hi:
                raise InputError(f"material {name} = {value:g} {unit} is outside [{lo:g}, "
                                 f"{hi:g}] {unit}, the range of engineering materials: check "
                                 "the units")


@dataclass(frozen=True)
class ArmAnalysis:
    """Mechanics of one rod (SI units)."""

    length: float
    outer_diameter: float
    inner_diameter: float
    area: float
    mass: float
    axial_stress: float
    axial_stiffness: float
    buckling_load: float
    buckling_safety: float
    bending_stress: float
    deflection: float
    combined_stress: float
    stress_safety: float

    def as_dict(self) -> dict:
        return asdict(self)


def analyse_arm(length: float, outer_diameter: float, inner_diameter: float = 0.0, *,
                axial_force: float = 0.0, transverse_accel: float = 9.81,
                material: Material | None = None) -> ArmAnalysis:
    """Stresses, buckling, deflection, mass and stiffness of a rod (see the module docstring).

    Raises:
        InputError: non-positive length or diameter, inner ≥ outer, non-finite loads.
    """
    material = material or Material()
    length = real(length, "the arm length", positive=True, limit=1e3)
    outer_diameter = real(outer_diameter, "the outer diameter", positive=True, limit=1e2)
    inner_diameter = real(inner_diameter, "the inner diameter", nonnegative=True, limit=1e2)
    if not inner_diameter < outer_diameter:
        raise InputError(f"the inner diameter must be in [0, {outer_diameter:g}), got "
                         f"{inner_diameter}")
    if min(length, outer_diameter - inner_diameter) < 1e-6:
        raise InputError(f"an arm {length:g} m long with a {outer_diameter - inner_diameter:g} "
                         "m thick section is below 1 µm; check the units")
    axial_force = real(axial_force, "the axial force", limit=1e12)
    transverse_accel = real(transverse_accel, "the transverse acceleration", limit=1e7)
    big, small = outer_diameter, inner_diameter
    area = math.pi / 4 * (big**2 - small**2)
    inertia = math.pi / 64 * (big**4 - small**4)
    mass = material.density * area * length
    axial = axial_force / area
    buckling = math.pi**2 * material.E * inertia / length**2
    compression = max(-axial_force, 0.0)
    w = mass * abs(transverse_accel) / length
    moment = w * length**2 / 8
    bending = moment * (big / 2) / inertia
    combined = abs(axial) + bending
    return ArmAnalysis(
        length=length, outer_diameter=big, inner_diameter=small, area=area, mass=mass,
        axial_stress=axial, axial_stiffness=material.E * area / length,
        buckling_load=buckling,
        buckling_safety=buckling / compression if compression > 0 else math.inf,
        bending_stress=bending,
        deflection=5 * w * length**4 / (384 * material.E * inertia),
        combined_stress=combined,
        stress_safety=material.yield_strength / combined if combined > 0 else math.inf,
    )


@dataclass(frozen=True)
class ArmDesign:
    """Result of :func:`size_arm`: the lightest admissible rod and its analysis."""

    analysis: ArmAnalysis
    constraints: dict[str, float]
    feasible: bool
    message: str


def size_arm(*, axial_force: float, length: float, transverse_accel: float = 9.81,
             hollow: bool = False, inner_diameter: float | None = None,
             diameter_range: tuple[float, float] = (0.005, 0.1),
             length_range: tuple[float, float] | None = None,
             stress_safety: float = 2.0, buckling_safety: float = 3.0,
             min_stiffness: float = 0.0, max_deflection: float = math.inf,
             min_wall: float = 0.001, material: Material | None = None) -> ArmDesign:
    """Lightest circular rod meeting the stress, buckling, stiffness and deflection limits.

    Args:
        axial_force: design axial load, N (|N| is applied both in tension and in compression).
        length: rod length, m (fixed unless ``length_range`` is given, e.g. when the machine's
            geometry allows some freedom).
        transverse_accel: transverse acceleration of the rod (gravity and inertia), m/s².
        hollow: tube instead of a solid bar; ``inner_diameter`` fixes the bore (the seed's 25 mm)
            or, if None, the bore is optimised too; the wall is at least ``min_wall`` (m).
        diameter_range: bounds on the outer diameter, m.
        length_range: optional bounds to optimise the length too.
        stress_safety, buckling_safety: required safety factors.
        min_stiffness: axial stiffness E A / ℓ at least this (N/m).
        max_deflection: mid-span deflection under the transverse load at most this (m).
        material: the material.

    Returns:
        :class:`ArmDesign`; ``feasible`` False (with a message naming the binding requirement)
        when no rod within the bounds meets them.
    """
    material = material or Material()
    lo_d, hi_d = real_pair(diameter_range, "the diameter range")
    if not 0 < lo_d < hi_d <= 1e2:
        raise InputError(f"empty diameter range {diameter_range}")
    _check_safeties(stress_safety, buckling_safety, min_wall, max_deflection, min_stiffness)
    axial_force = real(axial_force, "the axial force", limit=1e12)
    length = real(length, "the arm length", positive=True, limit=1e3)
    transverse_accel = real(transverse_accel, "the transverse acceleration", limit=1e7)
    lo_l = hi_l = length
    if length_range is not None:
        lo_l, hi_l = real_pair(length_range, "the length range")
        if not 0 < lo_l < hi_l <= 1e3:
            raise InputError(f"empty length range {length_range}")
    if hollow and inner_diameter is not None:
        if not 0 <= inner_diameter < hi_d - 2 * min_wall:
            raise InputError("the inner diameter leaves no wall within the diameter range")
        lo_d = max(lo_d, inner_diameter + 2 * min_wall)
    problem = _ArmSizing(lo_d, hi_d, lo_l, hi_l, hollow, inner_diameter, min_wall, length,
                         length_range, abs(float(axial_force)), transverse_accel, material,
                         stress_safety, buckling_safety, min_stiffness, max_deflection)
    from scipy.optimize import (  # at first use: ≈ 0.3–0.5 s of imports `path` need not pay
        NonlinearConstraint,
        differential_evolution,
    )

    x0, bounds = problem.start()
    names = ("stress", "buckling", "stiffness", "deflection")
    # margins capped: only their sign matters, and a vanishing load gives infinite ones
    feasible_set = NonlinearConstraint(
        lambda v: np.minimum([problem.margins(v)[k] for k in names], 1e6), 0.0, np.inf)
    with warnings.catch_warnings():  # SciPy's notes on the polish step are not for the user
        warnings.simplefilter("ignore")
        res = differential_evolution(problem.mass, bounds, constraints=(feasible_set,), seed=0,
                                     tol=1e-10, maxiter=300, polish=True, x0=np.array(x0))
    v = res.x
    final = problem.margins(v)
    feasible = all(val >= -1e-6 for val in final.values())
    big, small, ell = problem.unpack(v)
    analysis = analyse_arm(ell, big, small, axial_force=-problem.load,
                           transverse_accel=transverse_accel, material=material)
    if feasible:
        message = "ok"
    else:
        worst = min(final, key=final.get)
        message = (f"no rod within the bounds meets the {worst} requirement (best margin "
                   f"{final[worst]:+.3g}); widen the diameter range or relax it")
    return ArmDesign(analysis=analysis, constraints=final, feasible=feasible, message=message)


def _check_safeties(stress_safety: float, buckling_safety: float, min_wall: float,
                    max_deflection: float, min_stiffness: float) -> None:
    """Safety factors ≥ 1 (and finite), a positive wall and deflection bound, a stiffness
    bound ≥ 0."""
    for name, value in (("stress safety", stress_safety), ("buckling safety", buckling_safety),
                        ("minimum wall", min_wall)):
        real(value, f"the {name}", positive=True, limit=1e6)
    for name, value in (("stress safety", stress_safety), ("buckling safety", buckling_safety)):
        if value < 1:
            raise InputError(f"the {name} = {value:g} is below 1: it would size an arm that "
                             "yields or buckles under the design load")
    if not (isinstance(max_deflection, int | float) and max_deflection > 0):
        raise InputError(f"the maximum deflection must be > 0, got {max_deflection!r}")
    real(min_stiffness, "the minimum stiffness", nonnegative=True)


@dataclass(frozen=True)
class _ArmSizing:
    """The arm-sizing problem of :func:`size_arm`: the design vector is ``(outer diameter,
    [wall when the bore is free], [length when it is free])``, m."""

    lo_d: float
    hi_d: float
    lo_l: float
    hi_l: float
    hollow: bool
    inner_diameter: float | None
    min_wall: float
    length: float
    length_range: tuple[float, float] | None
    load: float
    transverse_accel: float
    material: Material
    stress_safety: float
    buckling_safety: float
    min_stiffness: float
    max_deflection: float

    def start(self) -> tuple[list[float], list[tuple[float, float]]]:
        """The optimiser's start and bounds."""
        x0 = [self.hi_d]
        bounds = [(self.lo_d, self.hi_d)]
        if self.hollow and self.inner_diameter is None:
            x0.append(0.5 * self.hi_d)
            bounds.append((self.min_wall, self.hi_d / 2))
        if self.length_range is not None:
            x0.append(0.5 * sum(self.length_range))
            bounds.append(tuple(self.length_range))
        return x0, bounds

    def unpack(self, v: np.ndarray) -> tuple[float, float, float]:
        """(outer, inner, length); a free bore is parameterised by the wall thickness."""
        big = min(max(float(v[0]), self.lo_d), self.hi_d)  # the polish step may leave them
        if not self.hollow:
            small = 0.0
        elif self.inner_diameter is not None:
            small = float(self.inner_diameter)
        else:  # the wall, kept within [min_wall, big/2] even where the optimiser steps outside
            small = max(big - 2 * min(max(float(v[1]), self.min_wall), big / 2), 0.0)
        ell = (min(max(float(v[-1]), self.lo_l), self.hi_l) if self.length_range is not None
               else float(self.length))
        return big, small, ell

    def margins(self, v: np.ndarray) -> dict[str, float]:
        """Relative margin of each requirement (≥ 0 met), compression and tension."""
        big, small, ell = self.unpack(v)
        a = analyse_arm(ell, big, small, axial_force=-self.load,
                        transverse_accel=self.transverse_accel, material=self.material)
        tension = analyse_arm(ell, big, small, axial_force=self.load,
                              transverse_accel=self.transverse_accel, material=self.material)
        return {
            "stress": min(a.stress_safety, tension.stress_safety) / self.stress_safety - 1.0,
            "buckling": a.buckling_safety / self.buckling_safety - 1.0 if self.load > 0
            else 1.0,
            "stiffness": (a.axial_stiffness / self.min_stiffness - 1.0)
            if self.min_stiffness > 0 else 1.0,
            "deflection": (1.0 - a.deflection / self.max_deflection)
            if np.isfinite(self.max_deflection) else 1.0,
        }

    def mass(self, v: np.ndarray) -> float:
        """The rod's mass, kg."""
        big, small, ell = self.unpack(v)
        return self.material.density * math.pi / 4 * (big**2 - small**2) * ell

#: Seed 000 Tables IV.2 (solid) and IV.3 (hollow, bore 25 mm): (label, L mm, D mm, mass g,
#: stress Pa) as printed.
SEED_TABLE_IV2 = [
    ("Actuelle", 1020, 46, 1695.14, 6.7933e5), ("Initiale", 1020, 46, 1695.14, 6.7933e5),
    ("Optimale", 1010, 46, 1678.52, 6.2991e5), ("Scenario 1", 980, 36, 997.518, 1.0317e6),
    ("Scenario 2", 990, 36, 1007.7, 1.0229e6), ("Scenario 3", 1000, 36, 1017.88, 1.0308e6),
    ("Scenario 4", 1010, 36, 1028.05, 1.0322e6),
]
SEED_TABLE_IV3 = [
    ("Actuelle", 1000, 45, 1099.56, 9.7974e5), ("Initiale", 1000, 45, 1099.56, 9.7974e5),
    ("Optimale", 1130, 55, 2130.0, 5.6174e5), ("Scenario 1", 980, 35, 461.814, 2.3597e6),
    ("Scenario 2", 1030, 35, 485.376, 2.3373e6), ("Scenario 3", 1080, 35, 508.938, 2.3423e6),
    ("Scenario 4", 1130, 35, 532.5, 2.3261e6),
]


def seed_tables(density: float = 1000.0, load: float = 1000.0) -> list[dict]:
    """Tables IV.2 and IV.3 recomputed: masses with ``density`` and nominal axial stresses
    F/A with ``load`` (N), next to the printed values."""
    rows = []
    for table, bore in (("IV.2 solid", 0.0), ("IV.3 hollow", 25.0)):
        data = SEED_TABLE_IV2 if bore == 0 else SEED_TABLE_IV3
        for label, ell, big, mass_g, stress in data:
            a = analyse_arm(ell * 1e-3, big * 1e-3, bore * 1e-3, axial_force=load,
                            material=Material(density=density))
            rows.append({"table": table, "design": label, "L_mm": ell, "D_mm": big,
                         "d_mm": bore, "mass_g": a.mass * 1e3, "seed_mass_g": mass_g,
                         "stress_Pa": a.axial_stress, "seed_stress_Pa": stress,
                         "stress_ratio": stress / a.axial_stress})
    return rows
