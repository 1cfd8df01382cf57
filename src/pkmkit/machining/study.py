"""Seed 003's machined-part method end to end, on the (illustrative) Verne-type module: G-code →
machining by the machine with defects → CMM sections → reconstructed tool centres →
pkmkit's joint-space identification (42 rod-geometry defects of which the identifiable ones, and
the placement Δx, Δy, Δz, φ) → a validation part machined with and without compensation,
beside the seed's figures.

**What differs from the seed** (and so why the figures are not comparable number for number):
the machine is pkmkit's Verne-type module, whose dimensions the seed does not give (illustrative);
its defects are random draws of realistic magnitude, not the real Verne's; the part's layout
and size are pkmkit's (the seed gives none); the CMM is simulated (Gaussian, σ = 1.5 µm by
default) and the cutter axis is vertical (the seed's perfect-orientation hypothesis); nothing
outside the 42-parameter model (thermal drift, cutting forces and deflection, servo errors, tool
wear, the serial table) exists in the simulation — the real part's < 20 / < 40 µm include all
of those.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.calibration.identify import CalibrationResult, calibrate
from pkmkit.calibration.simulate import random_defects
from pkmkit.calibration.studies import machined_errors
from pkmkit.machining.cmm import CMM_SIGMA, CmmPoints, probe
from pkmkit.machining.part import Placement, part_passes, seed_part_program
from pkmkit.machining.reconstruct import reconstruct, reconstructed_measurements
from pkmkit.machining.sweep import machine_part
from pkmkit.model.defect_rule import add_defects
from pkmkit.motion.gcode import read_gcode

#: Seed 003's result: machined dimensions after identification, along x and y (m).
SEED_AFTER = {"along_x": 20e-6, "along_y": 40e-6}
#: What the seed's figures include and the simulation does not (see the module docstring).
SUBSTITUTIONS = (
    "machine: pkmkit's Verne-type module, illustrative dimensions (the seed gives none)",
    "defects: random draws of realistic magnitude (0.1 mm, 0.5°), not the real Verne's",
    "part: pkmkit's layout and size (the seed gives none)",
    "CMM: simulated, Gaussian σ per coordinate",
    "cutter axis vertical (the seed's hypothesis, §4.3); the Verne-type model's platform tilts "
    "by up to 4° with position and would tilt the walls",
    "nothing outside the geometric model: no thermal drift, cutting forces, servo errors, "
    "tool wear or serial table, all of which are in the seed's real part",
)


def default_placement(machine) -> Placement:
    """The part's placement of the studies: its frame at the default box's lower corner, turned
    0.3° about z (as :func:`pkmkit.calibration.simulate.simulate_part`)."""
    corner = np.asarray(machine.default_box()[0], dtype=float)[:3]
    return Placement(*corner, np.radians(0.3))


@dataclass
class MachiningStudy:
    """Outcome of :func:`machined_part_study` (SI)."""

    result: CalibrationResult
    placement: Placement
    cmm: CmmPoints
    validation_cmm: CmmPoints
    reconstruction_error: np.ndarray
    machined: dict[str, dict[str, float]]
    program: str

    def summary(self, scale: float = 1e-6) -> dict[str, Any]:
        """JSON-ready numbers (lengths divided by ``scale``: default µm; φ in degrees)."""
        r = self.result
        setup = dict(zip(r.setup_names, r.setup_values, strict=True))
        setup_std = dict(zip(r.setup_names, r.setup_std, strict=True))
        true = dict(zip(("part_x", "part_y", "part_z", "part_phi"), self.placement.vector,
                        strict=True))
        placement = {n: {"identified": (np.degrees(setup[n]) if n == "part_phi"
                                        else setup[n] / scale),
                         "std": np.degrees(setup_std[n]) if n == "part_phi"
                         else setup_std[n] / scale,
                         "true": np.degrees(true[n]) if n == "part_phi" else true[n] / scale}
                     for n in true}
        return {
            "machine": f"{r.nominal.id} (illustrative dimensions)",
            "sections": len(self.cmm.label) // 3, "cmm_points": len(self.cmm.label),
            "reconstruction_rms": float(np.sqrt(np.mean(self.reconstruction_error ** 2)))
            / scale,
            "identified": len(r.names), "candidates": r.candidates, "rank": r.rank,
            "identification": {"rms_before": r.before.rms / scale, "rms": r.after.rms / scale},
            "validation": {"rms_before": r.validation.before.rms / scale,
                           "rms": r.validation.after.rms / scale},
            "placement": placement,
            "machined": {k: {kk: vv / scale for kk, vv in v.items()}
                         for k, v in self.machined.items()},
            "seed": {k: v / scale for k, v in SEED_AFTER.items()},
            "substitutions": list(SUBSTITUTIONS),
        }


def simulate_cmm(true_machine, nominal, program: str, rng: np.random.Generator, *,
                 placement: Placement | None = None, sections: int = 240,
                 sigma: float = CMM_SIGMA, points: str = "surface",
                 probe_radius: float = 0.001, origin=(0.0, 0.0, 0.0)) -> tuple[CmmPoints, Any]:
    """Machine ``program`` (G-code text or file) with ``true_machine`` under ``nominal``'s
    controller and probe it: the CMM points and the machined part (its truth)."""
    passes = part_passes(read_gcode(program, origin=origin))
    part = machine_part(true_machine, nominal, passes, placement=placement, sections=sections,
                        probe_radius=probe_radius)
    return probe(part, rng, sigma=sigma, points=points), part


def machined_part_study(*, seed: int = 1, sections: int = 240, sigma: float = CMM_SIGMA,
                        machine=None, defects: np.ndarray | None = None,
                        parameters: Any = "auto") -> MachiningStudy:
    """The whole chain (module docstring) on seed 003's test part (:func:`seed_part_program`),
    ``sections`` CMM sections for identification and half as many others (another probing of
    the part, elsewhere along its passes) for validation; ``defects`` (default random) and
    ``parameters`` as :func:`~pkmkit.calibration.identify.calibrate`'s."""
    import pkmkit

    m = machine if machine is not None else pkmkit.machine("verne")
    rng = np.random.default_rng(seed)
    delta = random_defects(m, rng) if defects is None else np.asarray(defects, dtype=float)
    true = add_defects(m, delta)
    program = seed_part_program(m)
    placement = default_placement(m)
    cmm, part = simulate_cmm(true, m, program, rng, placement=placement, sections=sections,
                             sigma=sigma)
    check, _ = simulate_cmm(true, m, program, rng, placement=placement,
                            sections=max(sections // 2, 12) + 1, sigma=sigma)
    passes = part_passes(read_gcode(program))
    rec = reconstruct(cmm)
    data = reconstructed_measurements(rec, passes)
    valid = reconstructed_measurements(reconstruct(check), passes)
    result = calibrate(m, data, validation=valid, parameters=parameters)
    return MachiningStudy(result=result, placement=placement, cmm=cmm, validation_cmm=check,
                          reconstruction_error=rec.centre - part.centre,
                          machined=machined_errors(true, m, result.machine), program=program)
