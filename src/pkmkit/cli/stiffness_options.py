"""Stiffness options of ``analyze``, ``map`` and ``workspace`` (docs/stiffness.md §5).

Stiffnesses on the command line and in the text and JSON outputs of these commands are in N/µm
(the machine-tool figure), deflections in µm; the elastic data as for ``pkmkit stiffness``
(``--set actuator_stiffness=…`` etc., always SI).
"""

from __future__ import annotations

from typing import Any

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.numerics.magnitudes import check_plausible
from pkmkit.stiffness.indices import (
    DISPLAY_FACTOR,
    DISPLAY_UNIT,
    STIFFNESS_INDICES,
    stiffness_figures,
    stiffness_index,
)

from .options import fmt
from .stiffness_cmds import PER_MICRO, parse_wrench

WRENCH_OPTION = click.option(
    "--wrench", "wrench_text", metavar="FX,FY,FZ[,MX,MY,MZ]",
    help="Load at the reference point for the deflection (N, N·m; docs/stiffness.md).")
MIN_STIFFNESS_OPTION = click.option(
    "--min-stiffness", type=float, metavar="N/µm",
    help="Keep poses whose smallest translational stiffness is at least this (N/µm; elastic "
         "data as for `pkmkit stiffness`, --set actuator_stiffness=...).")
MAX_DEFLECTION_OPTION = click.option(
    "--max-deflection", type=float, metavar="µm",
    help="Keep poses whose deflection under --wrench is at most this (µm).")


def _positive(name: str, value: float | None) -> float | None:
    if value is not None and not (np.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a finite number > 0, got {value:g}")
    return value


def stiffness_criteria(m, data, min_stiffness: float | None, max_deflection: float | None,
                       wrench_text: str | None) -> tuple[dict[str, Any], str]:
    """Keyword arguments of :class:`~pkmkit.analysis.criteria.Criteria` for the stiffness
    options (SI), and a note on a wrench's dropped moments."""
    _positive("--min-stiffness", min_stiffness)
    _positive("--max-deflection", max_deflection)
    check_plausible("--min-stiffness", min_stiffness, "stiffness", scale=PER_MICRO,
                    unit="N/µm")
    check_plausible("--max-deflection", max_deflection, "deflection", scale=1 / PER_MICRO,
                    unit="µm")
    wrench, note = parse_wrench(wrench_text, m)
    if max_deflection is not None and wrench is None:
        raise InputError("--max-deflection needs --wrench (the load that causes it)")
    if min_stiffness is None and max_deflection is None and wrench is None:
        return {}, note
    return {"min_stiffness": None if min_stiffness is None else min_stiffness * PER_MICRO,
            "max_deflection": None if max_deflection is None else max_deflection / PER_MICRO,
            "wrench": None if wrench is None else tuple(wrench),
            "stiffness_data": data}, note


def stiffness_map_values(m, points: np.ndarray, name: str, data, wrench,
                         summary: dict[str, Any]) -> tuple[np.ndarray, str, str]:
    """``pkmkit map --index stiffness|deflection``: the values at ``points`` in N/µm or µm,
    the colour-bar label and the title; the unit and the elastic data go into ``summary``."""
    values = stiffness_index(m, points, name, data=data, wrench=wrench) * DISPLAY_FACTOR[name]
    summary["index_unit"] = DISPLAY_UNIT[name]
    summary["elastic_data"] = list(data.notes)
    return values, f"{name} ({DISPLAY_UNIT[name]})", STIFFNESS_INDICES[name]


def criteria_fields(criteria) -> dict[str, Any]:
    """JSON fields of the stiffness criterion (N/µm, µm, N), empty without one."""
    out: dict[str, Any] = {}
    if criteria.min_stiffness is not None:
        out["min_stiffness"] = criteria.min_stiffness / PER_MICRO
    if criteria.max_deflection is not None:
        out["max_deflection"] = criteria.max_deflection * PER_MICRO
    if criteria.wrench is not None:
        out["wrench"] = list(criteria.wrench)
    return out


def workspace_stiffness(m, wmap, data, scale: float) -> dict[str, Any]:
    """Stiffness over the workspace's feasible grid points: the smallest translational
    stiffness's range (N/µm) and where it is least, the largest deflection (µm) under the
    criteria's wrench and where. The figures of the evaluation when it has them, else one
    batched evaluation of the feasible points."""
    grid = wmap.grid
    feasible = wmap.feasible.reshape(-1)
    points = grid.points[feasible]
    if wmap.stiffness is not None:
        smallest = wmap.stiffness.reshape(-1)[feasible]
        deflection = None if wmap.deflection is None else wmap.deflection.reshape(-1)[feasible]
    else:
        q = wmap.q.reshape(-1, wmap.q.shape[-1])[feasible]
        fig = stiffness_figures(m, points, q=q, data=data, wrench=wmap.criteria.wrench)
        smallest, deflection = fig.smallest, fig.deflection
    if not np.isfinite(smallest).any():
        raise InputError("no feasible pose has a stiffness (every one is singular)")
    p = min(grid.base.size, 3)
    k = int(np.nanargmin(smallest))
    out: dict[str, Any] = {
        "unit": "N/µm", "min": float(smallest[k]) / PER_MICRO,
        "max": float(np.nanmax(smallest)) / PER_MICRO, "at_min": points[k, :p] / scale,
        "singular_points": int((~np.isfinite(smallest)).sum()),
        "elastic_data": list(data.notes)}
    if deflection is not None:
        j = int(np.nanargmax(deflection))
        out.update({"deflection_unit": "µm", "deflection_max": float(deflection[j]) * PER_MICRO,
                    "at_deflection_max": points[j, :p] / scale})
    return out


def print_workspace_stiffness(s: dict[str, Any], units: str, criteria: dict[str, Any]) -> None:
    """Text lines of :func:`workspace_stiffness`."""
    bound = ""
    if "min_stiffness" in criteria:
        bound = f" (criterion ≥ {criteria['min_stiffness']:g} N/µm)"
    click.echo(f"  smallest translational stiffness over the workspace: {s['min']:.5g} .. "
               f"{s['max']:.5g} N/µm{bound}; least at {fmt(s['at_min'])} {units}")
    if "deflection_max" in s:
        bound = (f" (criterion ≤ {criteria['max_deflection']:g} µm)"
                 if "max_deflection" in criteria else "")
        click.echo(f"  largest deflection under {fmt(criteria['wrench'])} (N, N·m): "
                   f"{s['deflection_max']:.5g} µm{bound} at {fmt(s['at_deflection_max'])} "
                   f"{units}")
    click.echo(f"  elastic data: {'; '.join(s['elastic_data'])}")


def analyze_stiffness(m, data, x: np.ndarray, wrench: np.ndarray | None, units: str = "m"
                      ) -> dict[str, Any]:
    """Stiffness fields of ``pkmkit analyze`` at pose ``x`` (SI inside the dict, with the
    text lines under ``"lines"``; ``"beyond_linear_range"``: why the deflection is beyond the
    linear model, in ``units``, or ``""``)."""
    from pkmkit.stiffness import stiffness
    from pkmkit.stiffness.results import linear_range_problem

    r = stiffness(m, x, data=data, wrench=wrench)
    kt = np.asarray(r.translational)
    c = np.asarray(r.compliance)[:kt.size, :kt.size]
    u = np.linalg.eigh(c)[1][:, -1]
    u = u if u[np.argmax(np.abs(u))] > 0 else -u
    out: dict[str, Any] = {"translational_eigenvalues": kt, "weakest_direction": u,
                           "rigid_directions": int(r.rigid), "elastic_data": list(data.notes),
                           "si_units": "N/m, m, rad"}
    lines = [f"  translational stiffness (pure force): {fmt(kt / PER_MICRO, 5)} N/µm; smallest "
             f"along {fmt(u, 4)}"]
    if r.rotational is not None:
        out["rotational_eigenvalues"] = r.rotational
        lines.append(f"  rotational stiffness (pure moment): "
                     f"{fmt(np.asarray(r.rotational) / PER_MICRO, 5)} N·m/µrad")
    if wrench is not None:
        defl = np.asarray(r.deflection)
        out["wrench"] = wrench
        out["deflection"] = defl
        text = f"{fmt(defl[:min(3, defl.size)] * PER_MICRO, 5)} µm"
        if defl.size == 6:
            text += f", rotation {fmt(defl[3:] * PER_MICRO, 5)} µrad"
        lines.append(f"  deflection under {fmt(wrench)} (N, N·m): {text}")
        out["beyond_linear_range"] = linear_range_problem(defl, m.length_scale, units)
    lines.append(f"  elastic data: {'; '.join(data.notes)}")
    out["lines"] = lines
    return out
