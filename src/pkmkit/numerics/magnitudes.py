"""Largest physical magnitudes pkmkit accepts as input (issue 18 §5).

A value orders of magnitude beyond anything a machine tool meets is a unit slip or a typo;
computing with it gives ``inf``/``nan`` or a number nobody can use. Every reader and command
refuses beyond these bounds with a typed error naming the value (lengths: ``MAX_LENGTH`` of
:mod:`pkmkit.model.parameters`, 10⁶ m).
"""

from __future__ import annotations

import math

import numpy as np

#: Largest force (N) or moment (N·m) of a wrench: about 100,000 tonnes-force.
MAX_FORCE = 1e9
#: Heaviest moving part (kg): 1000 tonnes, beyond the largest machine tools' moving masses.
MAX_MASS = 1e6
#: Largest gravity (or steady acceleration field) magnitude, m/s² (about 100 g).
MAX_GRAVITY = 1e3
#: Largest moment of inertia, kg·m² (1000 t at a 3 m radius of gyration).
MAX_INERTIA = 1e7
#: Densest material, kg/m³ (osmium: 22,590).
MAX_DENSITY = 1e5

#: Plausible ranges of user limits and options, SI: (lowest, highest, unit). A value outside is
#: a unit slip or a placeholder for "no limit" (leave the option out instead): a 1e300 N force
#: limit, a 0 m/s speed limit.
PLAUSIBLE = {
    "speed": (1e-6, 1e3, "m/s"),            # µm/s to Mach 3 (rad/s for rotating actuators)
    "acceleration": (1e-6, 1e6, "m/s²"),    # 100,000 g
    "force": (1e-3, MAX_FORCE, "N"),
    "deflection": (1e-9, 1.0, "m"),         # 1 nm to 1 m
    "stiffness": (1e-3, 1e13, "N/m"),       # 1e13 N/m = 1e7 N/µm, stiffer than any machine
    "noise": (0.0, 1.0, "m"),               # standard deviation of a reading
    "condition": (1.0, 1e15, ""),           # beyond, a Jacobian is singular in doubles
    "ratio": (0.0, 1.0, ""),
    "length": (1e-9, 1e3, "m"),             # a dimension, region side or path step
    "correction": (1e-9, 1.0, "m"),         # a geometric correction or interpolation error
    "cutter": (1e-6, 1.0, "m"),             # a milling cutter's diameter
    "probe": (0.0, 0.1, "m"),               # a CMM probe tip's radius (0: a point)
    "modulus": (1e6, 1e13, "Pa"),           # Young's modulus of engineering materials
    "offset": (-1e3, 1e3, "m"),             # a signed position or offset on a machine
    "angle": (-4 * math.pi, 4 * math.pi, "rad"),  # two turns either way (a region, a pose)
    "factor": (1e-6, 1e6, ""),              # a velocity transmission factor
}

#: The kinds of :data:`PLAUSIBLE` that bound a result (leaving the option out: no bound).
LIMITS = ("speed", "acceleration", "force", "deflection", "stiffness", "condition")


def check_plausible(option: str, value: float | None, kind: str, *, scale: float = 1.0,
                    unit: str | None = None, low_inclusive: bool = True) -> float | None:
    """``value`` (in the option's unit, ``scale`` SI per unit) if finite and within the
    :data:`PLAUSIBLE` range of ``kind``, else :class:`~pkmkit.exceptions.InputError` naming
    ``option``, the value and the range in the option's unit (``unit``, default the SI one).
    None passes (an option left out)."""
    from pkmkit.exceptions import InputError

    if value is None:
        return None
    lo, hi, si_unit = PLAUSIBLE[kind]
    unit = si_unit if unit is None else unit
    v = float(value)
    si = v * scale
    inside = (lo <= si if low_inclusive else lo < si) and si <= hi
    if not (math.isfinite(si) and inside):
        space = f" {unit}" if unit else ""
        bracket = "[" if low_inclusive else "("
        tail = ("check the unit, or leave the option out for no limit" if kind in LIMITS
                else "check the value and its unit")
        raise InputError(f"{option} {v:g}{space} is outside the plausible range "
                         f"{bracket}{lo / scale:g}, {hi / scale:g}]{space}: {tail}")
    return value


#: Most configurations a study draws or is given (sensitivity, identifiability, pose
#: selection): each costs a closure solve and a Jacobian of every defect.
MAX_CONFIGURATIONS = 100_000
#: Most sampled machine evaluations of a Monte Carlo analysis (samples × configurations).
MAX_SAMPLED = 50_000_000


def check_count(value: object, name: str, limit: int, *, lower: str = "") -> int:
    """``value`` as an int if it is a whole number in [1, ``limit``], else
    :class:`~pkmkit.exceptions.InputError` naming ``name`` and the limit, before any work
    (``lower`` says what to change). Booleans, fractions, NaN and strings are refused."""
    from pkmkit.exceptions import InputError

    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer,
                                                         np.floating)):
        raise InputError(f"{name} must be a whole number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v == int(v)):
        raise InputError(f"{name} must be a whole number, got {value!r}")
    if v < 1:
        raise InputError(f"{name} must be ≥ 1, got {int(v)}")
    if v > limit:
        raise InputError(f"{name} = {v:.3g} is above the limit of {limit:.3g} (memory and "
                         f"time){'; ' + lower if lower else ''}")
    return int(v)
