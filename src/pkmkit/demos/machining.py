"""Seed 003's machined-part chain in ``pkmkit demo`` (called by :mod:`pkmkit.demos.calibration`):
the test part's G-code machined by the Verne-type module (illustrative dimensions) with random
defects, probed on a simulated CMM, the tool centres reconstructed, the machine identified,
compensated, and the validation part's deviations printed beside the seed's figures. Writes
``calibration-verne-cmm/``: ``part.nc``, ``cmm.csv`` (rerun ``pkmkit machined-part reconstruct``
on it), ``centres.csv`` (rerun ``pkmkit calibrate verne --measure part``) and the calibration
outputs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pkmkit.io.atomic import write_text_atomic as atomic_write_text
from pkmkit.io.measurements import format_measurements
from pkmkit.machines.registry import preset_path
from pkmkit.machining.cmm import format_cmm
from pkmkit.machining.part import part_passes
from pkmkit.machining.reconstruct import reconstruct, reconstructed_measurements
from pkmkit.machining.study import machined_part_study
from pkmkit.motion.gcode import read_gcode
from pkmkit.plot.calibration_report import write_calibration_outputs


def run_machining_demo(out_dir: str | Path, say) -> dict[str, Any]:
    """Run :func:`~pkmkit.machining.study.machined_part_study` into ``out_dir`` and return its
    summary (µm)."""
    study = machined_part_study()
    folder = Path(out_dir) / "calibration-verne-cmm"
    files = write_calibration_outputs(
        study.result, folder, machine_source=preset_path("verne"), units="mm",
        sources={"measurements": "centres.csv", "cmm": "cmm.csv", "program": "part.nc",
                 "protocol": "seed 003: G-code machined by the defected machine, CMM sections "
                             "(Q, M, N), tool centres reconstructed; Verne-type module with "
                             "illustrative dimensions"})
    atomic_write_text(folder / "part.nc", study.program)
    atomic_write_text(folder / "cmm.csv", format_cmm(
        study.cmm, units="mm", comment="seed 003 part, simulated CMM (pkmkit demo)"))
    centres = reconstructed_measurements(reconstruct(study.cmm),
                                         part_passes(read_gcode(study.program)))
    atomic_write_text(folder / "centres.csv", format_measurements(
        centres, None, units="mm", comment="tool centres reconstructed from cmm.csv"))
    summary = {**study.summary(), "report": files["report.html"]}
    c = summary["machined"]["compensated"]
    say(f"calibration, Verne-type (illustrative) machined part from G-code and CMM points: "
        f"{summary['sections']} sections, compensated part within {c['along_x']:.1f} µm along x "
        f"and {c['along_y']:.1f} µm along y (seed 003, real Verne: < 20 and < 40 µm)")
    return summary
