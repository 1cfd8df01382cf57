"""The machine library: kinds, presets, machine files, and the :class:`Machine` API."""

from pkmkit.machines.machine import Machine, MachineKind
from pkmkit.machines.registry import KINDS, load, machine, machine_from_document, machines
from pkmkit.machines.results import (
    AssemblyModes,
    DirectResult,
    InverseResult,
    JacobianRates,
    Jacobians,
    Singularity,
)

__all__ = [
    "KINDS",
    "AssemblyModes",
    "DirectResult",
    "InverseResult",
    "JacobianRates",
    "Jacobians",
    "Machine",
    "MachineKind",
    "Singularity",
    "load",
    "machine",
    "machine_from_document",
    "machines",
]
