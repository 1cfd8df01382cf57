"""Figures and numbers of docs/calibration.md: ``python docs/make_calibration_figures.py``.

Runs the seed reproductions of :mod:`pkmkit.calibration.studies` at full size (the Tripteor's
"thesis way" identification takes a few minutes), writes ``docs/figures/calibration-*.png``
and ``docs/figures/calibration-summary.json`` (the numbers quoted in the docs).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pkmkit.calibration import studies
from pkmkit.io.json_io import to_jsonable
from pkmkit.plot.calibration_figures import AFTER, BEFORE, plot_identifiability, plot_residuals

FIGURES = Path(__file__).parent / "figures"


def tripteor_comparison(summary: dict, path: Path) -> None:
    """Mean and max residuals: pkmkit on simulated readings (identification, validation; the
    residual is the injected tracker noise) vs seed 002's real readings and baselines."""
    rows = [("pkmkit, simulated readings: identification", summary["identification"]["mean"],
             summary["identification"]["max"]),
            ("pkmkit, simulated readings: validation", summary["validation"]["mean"],
             summary["validation"]["max"])]
    rows += [(k, v["mean"], v["max"]) for k, v in summary["thesis"].items()]
    fig = Figure(figsize=(8.0, 3.4), layout="constrained")
    ax = fig.add_subplot()
    y = np.arange(len(rows))[::-1]
    ax.barh(y + 0.18, [r[1] * 1e3 for r in rows], 0.36, color=AFTER, label="mean")
    ax.barh(y - 0.18, [r[2] * 1e3 for r in rows], 0.36, color=BEFORE, alpha=0.7, label="max")
    ax.set_yticks(y, [r[0] for r in rows], fontsize=8)
    ax.set_xlabel("tool-point error [µm]")
    ax.legend(fontsize=8)
    ax.grid(True, axis="x", alpha=0.3)
    fig.savefig(path, dpi=100)


def part_comparison(part: dict, ball: dict, path: Path) -> None:
    """Machined validation part: deviations along x and y, nominal vs compensated."""
    fig = Figure(figsize=(7.5, 3.0), layout="constrained")
    ax = fig.add_subplot()
    labels, values = [], []
    for name, study in (("machined part", part), ("ball-bar", ball)):
        for state in ("nominal", "compensated"):
            for axis in ("x", "y"):
                labels.append(f"{name}\n{state}, along {axis}")
                values.append(study["machined"][state][f"along_{axis}"] * 1e3)
    colors = [BEFORE if "nominal" in lab else AFTER for lab in labels]
    ax.bar(range(len(values)), values, color=colors)
    ax.set_yscale("log")
    ax.axhline(20.0, color="k", ls="--", lw=0.8)
    ax.axhline(40.0, color="k", ls=":", lw=0.8)
    ax.text(len(values) - 0.5, 21, "seed 003: 20 µm (x)", ha="right", fontsize=7)
    ax.text(len(values) - 0.5, 42, "40 µm (y)", ha="right", fontsize=7)
    ax.set_xticks(range(len(values)), labels, fontsize=6)
    ax.set_ylabel("largest deviation [µm]")
    fig.savefig(path, dpi=100)


def bed_maps(study, path: Path) -> None:
    fig = Figure(figsize=(8.5, 3.6), layout="constrained")
    axes = fig.subplots(1, 2)
    for ax, label in zip(axes, ("nominal", "compensated"), strict=True):
        xx, yy, h = study.maps[label]
        im = ax.contourf(xx * 1e3, yy * 1e3, h * 1e6, levels=20, cmap="RdBu_r")
        ax.set_aspect("equal")
        ax.set_title(f"{label}: flatness {study.flatness[label] * 1e6:.1f} µm", fontsize=9)
        ax.set_xlabel("x [mm]")
        ax.set_ylabel("y [mm]")
        fig.colorbar(im, ax=ax, label="height error [µm]", shrink=0.8)
    fig.savefig(path, dpi=100)


def main() -> None:
    FIGURES.mkdir(exist_ok=True)
    out = {}
    t = time.perf_counter()
    trip = studies.tripteor_laser_tracker(thesis_way="--quick" not in sys.argv)
    out["tripteor"] = trip.summary()
    print(f"tripteor {time.perf_counter() - t:.1f} s", flush=True)
    tripteor_comparison(out["tripteor"], FIGURES / "calibration-tripteor-comparison.png")
    plot_residuals(trip.result, units="mm", path=FIGURES / "calibration-tripteor-residuals.png")
    plot_identifiability(trip.result, path=FIGURES / "calibration-tripteor-identifiability.png")
    part = studies.verne_part()
    ball = studies.verne_ballbar()
    out["verne_part"], out["verne_ballbar"] = part.summary(), ball.summary()
    part_comparison(out["verne_part"], out["verne_ballbar"], FIGURES / "calibration-verne.png")
    plot_residuals(part.result, units="mm", path=FIGURES / "calibration-verne-part-residuals.png")
    delta = studies.delta_height_probe()
    out["delta_height"] = delta.summary()
    bed_maps(delta, FIGURES / "calibration-delta-bed.png")
    (FIGURES / "calibration-summary.json").write_text(json.dumps(to_jsonable(out), indent=1)
                                                       + "\n")
    print(json.dumps(to_jsonable(out), indent=1))


if __name__ == "__main__":
    main()
