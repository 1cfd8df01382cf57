"""Largest physical magnitudes pkmkit accepts as input (issue 18 §5).

A value orders of magnitude beyond anything a machine tool meets is a unit slip or a typo;
computing with it gives ``inf``/``nan`` or a number nobody can use. Every reader and command
refuses beyond these bounds with a typed error naming the value (lengths: ``MAX_LENGTH`` of
:mod:`pkmkit.model.parameters`, 10⁶ m).
"""

from __future__ import annotations

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
