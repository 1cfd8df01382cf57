"""Isotropic design of the five-bar with prismatic actuators (seed 004 §2.4–2.5).

1. **Slide orientations from the isotropy of J⁻¹.** Row i of J⁻¹ is
   ``(cos θ_i, sin θ_i) / cos(θ_i − α_i)`` (θ_i: direction of leg i). Asking J⁻¹ = I at some
   configuration — the machine then behaves like a PP table there — gives four equations in
   (θ1, θ2, α1, α2); :func:`isotropic_orientations` solves them from many starting points and
   returns the distinct solutions: α1 = 0 and α2 = 90° (mod 180°).
2. **Sizing for a prescribed square.** The useful workspace (seed 004's procedure, see
   :func:`pkmkit.analysis.useful_workspace`) scales with L and does not depend on |AB| (moving B
   along its slide only offsets ρ2). So one unit-length study gives the inscribed square per unit L;
   then L = S / (side per L), A and B scale with L, and the joint stops are the useful zone.
3. **Comparison** with the biglide (α1 = α2 = 0) sized for the same square by the same procedure.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pkmkit.analysis.joint_space import useful_workspace
from pkmkit.analysis.workspace import Criteria, RegionCheck, check_region
from pkmkit.design.checks import degenerate_note, relaxed, require_side
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import machine as builtin_machine
from pkmkit.numerics.arrays import real_pair


def _isotropy_residual(v: np.ndarray) -> np.ndarray:
    theta1, theta2, alpha1, alpha2 = v
    rows = []
    for theta, alpha, target in ((theta1, alpha1, (1.0, 0.0)), (theta2, alpha2, (0.0, 1.0))):
        c = math.cos(theta - alpha)
        rows += [math.cos(theta) - target[0] * c, math.sin(theta) - target[1] * c]
    return np.array(rows)


def isotropic_orientations(starts: int = 64, seed: int = 0,
                           tol_deg: float = 0.01) -> list[tuple[float, float]]:
    """Distinct slide orientations (α1, α2) in degrees, modulo 180°, for which some
    configuration has J⁻¹ = I (least squares from ``starts`` random points).

    The roots are double (cos α1 = 1 at the solution), so least squares only reaches them to
    about √eps; solutions within ``tol_deg`` are merged and rounded to that precision.
    """
    from scipy.optimize import least_squares  # at first use, not at `pkmkit design --help`

    rng = np.random.default_rng(seed)
    found: list[tuple[float, float]] = []
    for _ in range(starts):
        res = least_squares(_isotropy_residual, rng.uniform(-math.pi, math.pi, 4), xtol=1e-15,
                            ftol=1e-15, gtol=1e-15)
        theta1, _, a1, _ = res.x
        if res.cost > 1e-16 or abs(math.cos(theta1 - a1)) < 1e-6:
            continue
        pair = np.degrees(res.x[2:]) % 180.0
        pair = np.where(pair > 180.0 - tol_deg, pair - 180.0, pair)
        if not any(np.abs(pair - np.array(f)).max() < tol_deg for f in found):
            found.append(tuple(float(v) for v in pair))
    digits = max(0, -math.floor(math.log10(tol_deg)))
    return sorted((round(a, digits) + 0.0, round(b, digits) + 0.0) for a, b in found)


@dataclass(frozen=True)
class FiveBarSizing:
    """A five-bar sized for a prescribed square (lengths in m).

    Attributes:
        design: ``"isotropic"`` or ``"biglide"``.
        square_side: prescribed side S.
        bounds: transmission-factor bounds.
        L: leg length.
        A, B: slide origins ``(2,)``.
        q_min, q_max: joint stops ``(2,)`` (the useful zone).
        stroke: joint stroke (the same for both actuators).
        square_center: ``(2,)`` centre of the square in the workspace.
        side_per_L: inscribed square side of the unit design.
        check: dense verification of the square with these joint stops (factors within a
            relative :data:`~pkmkit.design.checks.VERIFY_RTOL` of the bounds).
        machine: the sized machine.
        notes: remarks on the specification (e.g. a degenerate one).
    """

    design: str
    square_side: float
    bounds: tuple[float, float]
    L: float
    A: np.ndarray
    B: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    stroke: float
    square_center: np.ndarray
    side_per_L: float
    check: RegionCheck
    machine: Machine
    notes: tuple[str, ...] = ()


def size_five_bar(square_side: float, bounds: tuple[float, float], *,
                  design: str = "isotropic", resolution: int = 301) -> FiveBarSizing:
    """Size a five-bar (``"isotropic"`` or ``"biglide"``) for a prescribed square workspace.

    Args:
        square_side: prescribed square side S, m (between 1e-6 m and 1e6 m).
        bounds: (λ_min, λ_max) bounds on the velocity transmission factors.
        design: ``"isotropic"`` (α = (0°, 90°)) or ``"biglide"`` (α = (0°, 0°)).
        resolution: grid points along the longest side of the useful-workspace study.

    Raises:
        InputError: bad side or bounds, bounds excluding the home configuration, unknown design,
            or a final check that fails.
    """
    square_side = require_side(square_side, "square side")
    preset = {"isotropic": "five-bar-isotropic", "biglide": "five-bar-biglide"}.get(design)
    if preset is None:
        raise InputError(f"unknown design {design!r}; use 'isotropic' or 'biglide'")
    criteria = Criteria(bounds=real_pair(bounds, "the transmission-factor bounds"))
    base = builtin_machine(preset)
    unit = base.with_params(L=1.0, B=tuple(np.asarray(base.params["B"]) / base.params["L"]),
                            q_min=(-10.0, -10.0), q_max=(10.0, 10.0))
    home = unit.jacobian(unit.home_pose)
    lo, hi = criteria.bounds
    if not (home.singular_values[-1] >= lo and home.singular_values[0] <= hi):
        raise InputError(
            f"bounds [{lo:g}, {hi:g}] exclude the home configuration of the {design} design "
            f"(transmission factors {np.round(home.singular_values, 4).tolist()} there)"
        )
    useful = useful_workspace(unit, criteria, resolution=resolution)
    if useful.inscribed is None:
        raise InputError("the useful workspace has no inscribed square")
    per_l = useful.inscribed.side
    length = square_side / per_l
    stroke = useful.joint_square.side * length
    # every length scales with L (A, B, the joint stops, the square)
    q_min = useful.joint_square.lower * length
    sized = base.with_params(L=length, A=tuple(np.asarray(unit.params["A"]) * length),
                             B=tuple(np.asarray(unit.params["B"]) * length),
                             q_min=tuple(q_min), q_max=tuple(q_min + stroke))
    scale_center = useful.inscribed.center * length
    check = check_region(sized, scale_center, square_side, relaxed(criteria), samples=61)
    if not check.feasible:
        raise InputError(f"the sized square fails its check: {check.worst}")
    note = degenerate_note(length, square_side, (lo, hi))
    return FiveBarSizing(
        design=design, square_side=float(square_side), bounds=(float(lo), float(hi)),
        L=float(length), A=np.asarray(sized.params["A"]), B=np.asarray(sized.params["B"]),
        q_min=q_min, q_max=q_min + stroke, stroke=float(stroke), square_center=scale_center,
        side_per_L=float(per_l), check=check, machine=sized, notes=(note,) if note else (),
    )
