"""Orthoglide sizing rule (seed 001 §3.4, Chablat & Wenger).

Given a prescribed cube of side Lw and bounds [ψmin, ψmax] on the velocity transmission factors:

1. the Orthoglide has a single length, L, so every point of its kinematics scales with L. Along the
   cube diagonal through the isotropic point, ``feasible_interval`` finds, for L = 1, the points
   Q1 = t1 (1, 1, 1) and Q2 = t2 (1, 1, 1) where a transmission factor first reaches a bound;
2. the prescribed cube has Q1 and Q2 as opposite corners, so ``L = Lw / (t2 − t1)``;
3. the slider positions and strokes are the range of ρ_i over that cube (direct model at the
   corners in the seed; here the whole cube is sampled), and the compactness is Lw / stroke.

Every result is verified by an independent brute-force evaluation of the whole cube (a dense grid
through :func:`pkmkit.analysis.check_region`): the transmission factors must stay within the
bounds everywhere, not only at Q1 and Q2. Q1 and Q2 are where a factor *equals* a bound, so the
verification accepts factors within a relative :data:`~pkmkit.design.checks.VERIFY_RTOL`
(1e-9) of the bounds (rounding ties at the corners).

With very wide bounds (e.g. [1e-9, 1e9]) the diagonal interval ends at a singularity rather than
at a bound, and the cube between its ends crosses singular configurations: the rule of the seed
does not apply as such. Q1 and Q2 are then moved toward the isotropic point by a common factor
until the brute-force check passes, and the result says so in ``notes``.

For [0.5, 2] and Lw = 200 mm this gives L = 310.6 mm, a 257.0 mm stroke and r = 0.778 — the
seed's prototype (310 mm, 257 mm, 0.78).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pkmkit.analysis.workspace import (
    Criteria,
    RegionCheck,
    check_region,
    evaluate_poses,
    feasible_interval,
    region_grid,
)
from pkmkit.design.checks import degenerate_note, relaxed, require_side
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import machine as builtin_machine
from pkmkit.numerics.arrays import real_pair


@dataclass(frozen=True)
class OrthoglideSizing:
    """Result of :func:`size_orthoglide` (lengths in m).

    Attributes:
        cube_side: prescribed Lw.
        bounds: (ψmin, ψmax).
        L: leg length.
        Q1, Q2: ``(3,)`` reference points, opposite corners of the cube.
        q_min, q_max: ``(3,)`` slider positions at the ends of the strokes.
        stroke: slider stroke (the same for the three sliders).
        compactness: Lw / stroke.
        side_over_L: Lw / L.
        check: brute-force verification of the whole cube.
        machine: the sized machine (strokes set to ``q_min``, ``q_max``).
        notes: remarks on the specification (a degenerate one, or a cube limited by a
            singularity rather than by the bounds).
    """

    cube_side: float
    bounds: tuple[float, float]
    L: float
    Q1: np.ndarray
    Q2: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    stroke: float
    compactness: float
    side_over_L: float
    check: RegionCheck
    machine: Machine
    notes: tuple[str, ...] = ()


def _cube_ok(machine: Machine, t1: float, t2: float, criteria: Criteria, samples: int) -> bool:
    """Every criterion holds on a ``samples³`` lattice of the cube with opposite corners
    ``t1 (1, 1, 1)`` and ``t2 (1, 1, 1)``."""
    grid = region_grid(machine, np.full(3, 0.5 * (t1 + t2)), t2 - t1, samples=samples)
    return bool(evaluate_poses(machine, grid.points, criteria).feasible.all())


def _shrink(unit: Machine, t1: float, t2: float, criteria: Criteria) -> float:
    """Largest factor s ≤ 1 (to 1e-6) for which the cube between s t1 (1, 1, 1) and
    s t2 (1, 1, 1) passes :func:`_cube_ok` (21³ poses).

    Raises:
        InputError: no such cube (the criteria fail arbitrarily close to the isotropic point).
    """
    good, bad = 0.0, 1.0
    while bad - good > 1e-6:
        mid = 0.5 * (good + bad)
        good, bad = (mid, bad) if _cube_ok(unit, mid * t1, mid * t2, criteria, 21) else (good, mid)
    if good == 0.0:
        raise InputError("no cube around the isotropic point satisfies the bounds")
    return good


def size_orthoglide(cube_side: float, bounds: tuple[float, float], *,
                    samples: int = 41, max_leg: float | None = None) -> OrthoglideSizing:
    """Size an Orthoglide for a prescribed cube (see the module docstring).

    Args:
        cube_side: prescribed cube side Lw, m (between 1e-6 m and 1e6 m).
        bounds: (ψmin, ψmax) bounds on every velocity transmission factor.
        samples: points per cube edge of the brute-force verification.
        max_leg: optional largest admissible leg length, m.

    Raises:
        InputError: a side that is not positive or out of range, bounds that exclude the
            isotropic configuration (λ = 1 there), a leg longer than ``max_leg``, or a
            verification that fails.
    """
    cube_side = require_side(cube_side, "cube side")
    if max_leg is not None and not (np.isfinite(max_leg) and max_leg > 0):
        raise InputError(f"the largest admissible leg length must be > 0, got {max_leg}")
    lo, hi = real_pair(bounds, "the transmission-factor bounds")
    criteria = Criteria(bounds=(lo, hi), strokes=False)  # validates 0 < lo < hi
    if not lo < 1.0 < hi:
        raise InputError(
            f"bounds [{lo:g}, {hi:g}] exclude the isotropic configuration, where every "
            "transmission factor equals 1: no Orthoglide can satisfy them around it"
        )
    verify = relaxed(criteria)
    unit = builtin_machine("orthoglide", L=1.0, q_min=(-3.0,) * 3, q_max=(3.0,) * 3)
    t1, t2 = feasible_interval(unit, np.zeros(3), np.ones(3), criteria)
    notes: list[str] = []
    shrink = 1.0 if _cube_ok(unit, t1, t2, verify, min(samples, 21)) else _shrink(
        unit, t1, t2, verify)
    for attempt in range(20):
        length = cube_side / (shrink * (t2 - t1))
        if max_leg is not None and length > max_leg:
            raise InputError(
                f"the cube needs legs of {length:.6g} m, longer than the admissible {max_leg:g} m"
            )
        q1, q2 = np.full(3, shrink * t1 * length), np.full(3, shrink * t2 * length)
        wide = builtin_machine("orthoglide", L=length, q_min=(-3 * length,) * 3,
                               q_max=(3 * length,) * 3)
        check = check_region(wide, 0.5 * (q1 + q2), cube_side, verify, samples=samples)
        if check.feasible:
            break
        # the denser verification found a failure the search grid missed: pull in further
        shrink = (_shrink(unit, t1, t2, verify) if attempt == 0 and shrink == 1.0
                  else shrink) * 0.999
    else:
        raise InputError(f"the cube between Q1 and Q2 fails the brute-force check: {check.worst}")
    if shrink < 1.0:
        failed = check_region(unit, np.full(3, 0.5 * (t1 + t2)), t2 - t1, verify, samples=21)
        kinds = sorted(failed.failures) or ["bounds"]
        why = (": the bounds are so wide that the diagonal runs up to a singularity, and the "
               "cube between its ends crosses singular configurations"
               if {"mode", "reachable"} & set(kinds) else "")
        notes.append(
            f"the cube between the ends of the diagonal interval where [{lo:g}, {hi:g}] hold "
            f"fails the brute-force check ({', '.join(kinds)}){why}; Q1 and Q2 were moved toward "
            f"the isotropic point by the factor {shrink:.6g} until the whole cube passes")
    note = degenerate_note(length, cube_side, (lo, hi))
    if note:
        notes.append(note)
    q_min, q_max = check.q_range
    stroke = float((q_max - q_min).max())
    sized = builtin_machine("orthoglide", L=length, q_min=tuple(q_min), q_max=tuple(q_max))
    return OrthoglideSizing(
        cube_side=float(cube_side), bounds=(float(lo), float(hi)), L=float(length), Q1=q1,
        Q2=q2, q_min=q_min, q_max=q_max, stroke=stroke, compactness=float(cube_side / stroke),
        side_over_L=float(cube_side / length), check=check, machine=sized, notes=tuple(notes),
    )
