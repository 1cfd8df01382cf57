"""Calibration part of ``pkmkit demo`` (to be called by :mod:`pkmkit.demos.run`): a full
calibration study on synthetic data — the Tripteor X7 with seed 002's laser-tracker protocol and
the Verne-type module with seed 003's machined part — each written as a calibration directory
(measurements, calibrated machine file, figures, ``report.html``).

:func:`run_calibration_demo` returns a JSON-ready summary; the numbers are those of
docs/calibration.md (``docs/make_calibration_figures.py`` calls the same study functions).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from pkmkit.calibration.studies import tripteor_laser_tracker, verne_part
from pkmkit.io.json_io import to_jsonable
from pkmkit.io.measurements import write_measurements
from pkmkit.machines.registry import preset_path
from pkmkit.plot.calibration_report import write_calibration_outputs


def run_calibration_demo(out_dir: str | Path, *, echo: bool = True) -> dict[str, Any]:
    """Run the calibration studies into ``out_dir`` (``calibration-tripteor/`` and
    ``calibration-verne-part/``) and return their summary (lengths in mm).

    Each directory holds ``measurements.csv`` and ``validation.csv`` (the synthetic readings,
    so that ``pkmkit calibrate`` can be rerun on them; the Tripteor's are in the tracker frame,
    registered in ``frame.json``), the calibrated machine file, ``calibration.json``,
    ``residuals.csv``, the figures and ``report.html``.
    """
    out = Path(out_dir)
    summary: dict[str, Any] = {}
    say = click.echo if echo else (lambda *_a, **_k: None)

    trip = tripteor_laser_tracker()
    folder = out / "calibration-tripteor"
    files = write_calibration_outputs(
        trip.result, folder, machine_source=preset_path("tripteor-x7"), units="mm",
        sources={"measurements": "measurements.csv", "validation": "validation.csv",
                 "protocol": "seed 002: 107 + 30 poses, two tools, tracker noise, frame "
                             "registered (Table 5.4) then identified"})
    m = trip.result.nominal
    from pkmkit.calibration.registration import save_registration

    save_registration(folder / "frame.json", trip.registration, units="mm")
    write_measurements(folder / "measurements.csv", trip.data, m, units="mm",
                       comment="seed 002 protocol, synthetic (pkmkit demo); tracker frame")
    write_measurements(folder / "validation.csv", trip.validation, m, units="mm",
                       comment="held-out poses (pkmkit demo)")
    summary["tripteor"] = {**trip.summary(), "report": files["report.html"]}
    t = summary["tripteor"]
    say(f"calibration, Tripteor X7 laser tracker: identification mean "
        f"{t['identification']['mean']:.4f} mm (max {t['identification']['max']:.4f}), "
        "validation mean "
        f"{t['validation']['mean']:.4f} mm (max {t['validation']['max']:.4f}) on simulated "
        "readings (the injected tracker noise, σ 0.015 mm); the thesis's real readings: 0.0216/"
        "0.0481 and 0.0441/0.0779 mm")

    part = verne_part()
    folder = out / "calibration-verne-part"
    files = write_calibration_outputs(
        part.result, folder, machine_source=preset_path("verne"), units="mm",
        sources={"measurements": "measurements.csv", "validation": "validation.csv",
                 "protocol": "seed 003: contours and slots along x and y, CMM sections, "
                             "unknown part placement"})
    write_measurements(folder / "measurements.csv", part.data, part.result.nominal,
                       units="mm", comment="machined part measured on a CMM (pkmkit demo)")
    write_measurements(folder / "validation.csv", part.validation, part.result.nominal,
                       units="mm", comment="second part (pkmkit demo)")
    summary["verne_part"] = {**part.summary(), "report": files["report.html"]}
    v = summary["verne_part"]["machined"]["compensated"]
    say(f"calibration, Verne machined part: compensated part within {v['along_x']:.4f} mm along"
        f" x and {v['along_y']:.4f} mm along y (seed 003: < 0.02 and < 0.04 mm)")

    from pkmkit.demos.machining import run_machining_demo

    summary["verne_cmm"] = run_machining_demo(out, say)
    return to_jsonable(summary)
