"""Seed 003's machined-part method, all of it: a test part programmed in G-code, machined by a
machine with defects (:mod:`.sweep`), probed on a CMM per section (:mod:`.cmm`), the tool-centre
positions reconstructed from the probe points and the cutter radii (:mod:`.reconstruct`), then
identified by pkmkit's existing joint-space machined-part identification (:mod:`.study`).
Also seed 003's ball-bar protocol as a ready plan (:mod:`.ballbar_plan`).

This sub-package sits beside :mod:`pkmkit.calibration` (it uses it) and imports no command line
or plotting code.
"""

from pkmkit.machining.part import Cutters, Pass, Placement, part_passes, seed_part_program
from pkmkit.machining.reconstruct import reconstruct, reconstructed_measurements
from pkmkit.machining.sweep import machine_part

__all__ = ["Cutters", "Pass", "Placement", "machine_part", "part_passes", "reconstruct",
           "reconstructed_measurements", "seed_part_program"]
