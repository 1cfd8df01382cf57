"""``pkmkit path --deflection``: the tool-point deflection along the move (docs/stiffness.md).

Deflections in µm in the text, the JSON summary and ``trajectory.csv``; the elastic data as for
``pkmkit stiffness`` (``--set actuator_stiffness=…``, always SI).
"""

from __future__ import annotations

from typing import Any

import click
import numpy as np

from .options import fmt

MICRO = 1e6
#: Blocks listed in the text output (all of them in --json), largest deflection first.
SHOWN_BLOCKS = 3


def deflection_summary(pd, data, scale: float, max_deflection: float | None) -> dict[str, Any]:
    """JSON-ready figures of a :class:`~pkmkit.stiffness.along_path.PathDeflection` (µm,
    lengths of poses in the CLI unit), with the verdict against ``max_deflection`` (µm)."""
    peak = pd.peak
    out: dict[str, Any] = {
        "unit": "µm", "max": peak["value"] * MICRO, "t": peak["t"],
        "pose": np.asarray(peak["pose"]) / scale, "line": peak["line"], "block": peak["block"],
        "gravity_max": pd.gravity_peak * MICRO, "force_max": pd.force_peak * MICRO,
        "converged": pd.converged, "elastic_data": list(data.notes),
        "blocks": [{**b, "max": b["max"] * MICRO} for b in pd.blocks],
        "loads": "weight of the moving parts (the masses of the dynamics) and the tool force; "
                 "inertia not included"}
    if max_deflection is not None:
        out["limit"] = max_deflection
        out["exceeded"] = bool(out["max"] > max_deflection)
    return out


def print_deflection(s: dict[str, Any], units: str) -> None:
    """Text lines of :func:`deflection_summary`."""
    where = f", line {s['line']} {s['block']!r}" if s["line"] else ""
    click.echo(f"  tool deflection (weight of the moving parts + tool force): up to "
               f"{s['max']:.4g} µm at t = {s['t']:.4f} s{where}, pose {fmt(s['pose'])} {units}; "
               f"weight alone up to {s['gravity_max']:.4g} µm, force alone "
               f"{s['force_max']:.4g} µm")
    ranked = sorted(s["blocks"], key=lambda b: -b["max"])[:SHOWN_BLOCKS]
    if len(s["blocks"]) > 1:
        text = "; ".join((f"line {b['line']} {b['block']!r}" if b["line"]
                          else f"segment {b['segment'] + 1}") + f" {b['max']:.4g} µm"
                         for b in ranked)
        click.echo(f"  largest per block (output samples): {text}")
    if "limit" in s:
        verdict = "EXCEEDED" if s["exceeded"] else "holds"
        click.echo(f"  deflection limit {s['limit']:g} µm: {verdict}")
    click.echo(f"  elastic data: {'; '.join(s['elastic_data'])}")


def deflection_columns(pd, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """``trajectory.csv`` columns ``defl_x..`` (µm) and ``defl`` (the norm, µm)."""
    out = {f"defl_{name}": pd.total[:, k] * MICRO for k, name in enumerate(names)}
    out["defl"] = np.linalg.norm(pd.total, axis=1) * MICRO
    return out
