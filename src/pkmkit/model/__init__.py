"""Machine descriptions as data: parameters with units, rod-leg models, machine files."""

from pkmkit.model.machine_file import MachineDocument, read_machine_document
from pkmkit.model.mobility import GrublerCount, grubler_count
from pkmkit.model.parameters import LENGTH_UNITS, ParameterSpec, length_scale, resolve_parameters
from pkmkit.model.rods import SLIDE, STRUT, LegSpec, RodModel, build_rod_model

__all__ = [
    "LENGTH_UNITS",
    "SLIDE",
    "STRUT",
    "GrublerCount",
    "LegSpec",
    "MachineDocument",
    "ParameterSpec",
    "RodModel",
    "build_rod_model",
    "grubler_count",
    "length_scale",
    "read_machine_document",
    "resolve_parameters",
]
