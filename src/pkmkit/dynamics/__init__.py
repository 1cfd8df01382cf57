"""Inverse dynamics of rod-leg machines and arm (rod) sizing."""

from pkmkit.dynamics.arms import (
    ArmAnalysis,
    ArmDesign,
    Material,
    analyse_arm,
    seed_tables,
    size_arm,
)
from pkmkit.dynamics.defaults import default_masses
from pkmkit.dynamics.inverse import ForceResult, inverse_dynamics, mechanical_energy
from pkmkit.dynamics.masses import (
    MassProperties,
    load_masses,
    mass_properties,
    rod_section_mass,
    strut_tube_lengths,
)
from pkmkit.dynamics.wrench import WrenchSeries, load_wrench_series

__all__ = [
    "ArmAnalysis",
    "ArmDesign",
    "ForceResult",
    "MassProperties",
    "Material",
    "WrenchSeries",
    "analyse_arm",
    "default_masses",
    "inverse_dynamics",
    "load_masses",
    "load_wrench_series",
    "mass_properties",
    "mechanical_energy",
    "rod_section_mass",
    "seed_tables",
    "size_arm",
    "strut_tube_lengths",
]
