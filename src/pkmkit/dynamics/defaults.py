"""Illustrative mass properties of the built-in machine kinds.

The source documents give no masses. These values are plausible orders of magnitude, stated here
so every result that uses them can be traced; pass a masses file for a real machine.

- linear Delta (seed 000 scale): carriage (moving part of a linear motor and its slide) 8 kg;
  arms Ø40 mm solid with ρ = 1000 kg/m³ — what the thesis's CAD models used (its arm masses imply
  that density, see docs/seed-errata.md), 1.3 kg for 1.04 m; nacelle with spindle and tool 15 kg;
- Orthoglide (prototype scale): carriages 2 kg, rods Ø10 mm aluminium, platform 2 kg;
- five-bar: carriages 5 kg, rods Ø20 mm aluminium, platform (tool table) 5 kg;
- any other machine: carriages 5 kg, rods Ø20 mm aluminium, platform 5 kg; a strut leg is a
  cylinder and a piston, Ø20 mm aluminium tubes of 0.6 × its length at q = 0 each, and its
  "carriage" is the motor's equivalent translating inertia.
Gravity is (0, 0, −9.81) m/s² (z up) for all.
"""

from __future__ import annotations

import numpy as np

from pkmkit.dynamics.masses import MassProperties, mass_properties, rod_section_mass
from pkmkit.machines.machine import Machine

_DEFAULTS = {
    "linear-delta": {"carriage": 8.0, "diameter": 0.040, "density": 1000.0, "platform": 15.0},
    "orthoglide": {"carriage": 2.0, "diameter": 0.010, "density": 2700.0, "platform": 2.0},
    "five-bar": {"carriage": 5.0, "diameter": 0.020, "density": 2700.0, "platform": 5.0},
}
_GENERIC = {"carriage": 5.0, "diameter": 0.020, "density": 2700.0, "platform": 5.0}


def default_masses(machine: Machine, *, tubes_at_home: bool = False) -> MassProperties:
    """The illustrative mass properties of ``machine``'s kind (see the module docstring).

    Args:
        tubes_at_home: size each strut's cylinder and piston on its length at the home
            configuration instead of at q = 0 (for machines whose strut coordinate is the whole
            strut length, ℓ0 = 0, whose tubes would otherwise have no length).
    """
    from pkmkit.dynamics.inverse import require_linear_actuators
    from pkmkit.dynamics.masses import STRUT_TUBE_FRACTION
    from pkmkit.model.rods import STRUT

    require_linear_actuators(machine, "a mass model")
    spec = _DEFAULTS.get(machine.kind.kind if machine.kind else "", _GENERIC)
    tubes = None
    if tubes_at_home:
        model = machine.model
        home = model.rod_length + np.where(model.rod_kind == STRUT,
                                           machine.home_q[model.rod_actuator], 0.0)
        tubes = STRUT_TUBE_FRACTION * home
    rod, radius, piston = rod_section_mass(machine, spec["diameter"], spec["density"],
                                           cylinder_length=tubes, piston_length=tubes)
    return mass_properties(machine, carriage=spec["carriage"], rod=rod, rod_radius=radius,
                           platform=spec["platform"], piston=piston, cylinder_length=tubes,
                           piston_length=tubes)
