"""``pkmkit view``: a machine in 3-D in one self-contained HTML page (:mod:`pkmkit.export.view`)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import click
import numpy as np

from pkmkit.boundary.coordinates import parse_actuators
from pkmkit.exceptions import InputError
from pkmkit.io.atomic import write_text_atomic

from .options import (
    EXIT_PARTIAL,
    JSON_OPTION,
    SET_OPTION,
    emit_json,
    is_machine_file,
    parse_vector,
    resolve_machine,
)


def register(cli: click.Group) -> None:
    """Add the view command to the ``pkmkit`` group."""
    cli.add_command(view_cmd)


def calibrated_machine_path(path: str | Path) -> Path:
    """The calibrated machine file of ``path``: the file itself, or the one a ``pkmkit
    calibrate --out DIR`` run wrote in DIR (named in its ``calibration.json``).

    Raises:
        InputError: no such file, or a calibration directory without a calibrated machine
            (a failed verdict writes none).
    """
    p = Path(path)
    if p.is_file():
        return p
    summary = p / "calibration.json"
    if not summary.is_file():
        raise InputError(f"--calibration {path}: neither a calibrated machine file nor a "
                         "directory written by `pkmkit calibrate --out` (no calibration.json)")
    try:
        name = json.loads(summary.read_text(encoding="utf-8")).get("files", {}).get("machine")
    except (OSError, ValueError, AttributeError) as exc:
        raise InputError(f"{summary}: cannot read it ({exc})") from None
    if not name or not (p / name).is_file():
        raise InputError(f"--calibration {path}: the calibration wrote no calibrated machine "
                         "file (its verdict failed: see report.html); nothing to draw")
    return p / name


@click.command("view")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--q", "q_text", metavar="Q1,Q2,...", default=None,
              help="Actuator values of the configuration shown first (lengths in --units, "
                   "angles in degrees; default home).")
@click.option("--workspace", is_flag=True,
              help="Draw the workspace (the default criteria over the machine's study box) as "
                   "a surface.")
@click.option("--resolution", type=click.IntRange(5, 41), default=15, show_default=True,
              help="Grid points along the longest side of the workspace (and of the "
                   "calibration's error vectors, half as many).")
@click.option("--path", "gcode", type=click.Path(exists=True, dir_okay=False), default=None,
              help="A G-code program: its tool path (home orientation held), the points out "
                   "of reach or stroke in red (exit status 3 when there are some).")
@click.option("--origin", metavar="X,Y,Z", default=None,
              help="Work offset of --path in --units (default 0,0,0).")
@click.option("--calibration", "calibration", type=click.Path(exists=True), default=None,
              help="A calibrated machine file, or the directory of `pkmkit calibrate --out`: "
                   "the tool error its calibration corrects, as vectors over the workspace.")
@click.option("--steps", type=click.IntRange(2, 201), default=21, show_default=True,
              help="Positions of each actuator's slider.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="The HTML page to write (self-contained: opens without a network).")
@click.option("--units", type=click.Choice(["mm", "in", "m"]), default="mm", show_default=True,
              help="Unit of --set, --q and --origin lengths (the page draws in mm).")
@JSON_OPTION
def view_cmd(machine_name, assignments, q_text, workspace, resolution, gcode, origin,
             calibration, steps, out_file, units, as_json):
    """Write a 3-D view of MACHINE: one HTML page a browser opens without a network, a slider
    per actuator moving the machine through pkmkit's direct model, and on request its
    workspace, a tool path and a calibration's error vectors."""
    from pkmkit.export.view import view_html

    m = resolve_machine(machine_name, assignments, units)
    q = None
    if q_text is not None:
        q = parse_actuators(q_text, m, units)
    origin_m = (np.zeros(3) if origin is None else
                np.asarray(parse_vector(origin, 3, "--origin", units), dtype=float))
    calibrated = None
    if calibration is not None:
        target = calibrated_machine_path(calibration)
        calibrated = resolve_machine(str(target), (), units)
        if (tuple(calibrated.actuator_names) != tuple(m.actuator_names)
                or tuple(calibrated.pose_names) != tuple(m.pose_names)):
            raise InputError(f"--calibration {calibration}: {calibrated.id!r} is not a "
                             f"calibration of {m.id!r} (other actuators or pose coordinates)")
    if Path(out_file).suffix.lower() not in (".html", ".htm"):
        raise click.BadParameter("the view is an HTML page: give NAME.html", param_hint="--out")
    html, content = view_html(m, q=q, workspace=workspace, gcode=gcode, origin=origin_m,
                              calibrated=calibrated, steps=steps, resolution=resolution)
    write_text_atomic(out_file, html)
    payload = {"machine": m.id, "out": str(out_file), "bytes": len(html.encode("utf-8")),
               "sliders": content.steps, "slider_positions_without_assembly": content.skipped,
               "workspace_points": content.workspace_points, "path_points": content.path_points,
               "path_out_of_reach_or_stroke": content.path_refused,
               "error_vectors": content.error_vectors,
               "error_max_um": None if content.error_max is None else content.error_max * 1e6,
               "source": machine_name if is_machine_file(machine_name) else None}
    if as_json:
        emit_json(payload)
    else:
        sliders = ", ".join(f"{n} {k}" for n, k in content.steps.items())
        click.echo(f"{m.name}: 3-D view, sliders {sliders} positions"
                   + (f" ({sum(content.skipped.values())} without assembly left out)"
                      if any(content.skipped.values()) else ""))
        if content.workspace_points is not None:
            click.echo(f"  workspace: {content.workspace_points} feasible grid points drawn "
                       "as a surface")
        if content.error_vectors is not None:
            click.echo(f"  calibration: {content.error_vectors} error vectors, largest "
                       f"{content.error_max * 1e6:.1f} µm")
        if content.path_points is not None:
            click.echo(f"  path: {content.path_points} points, {content.path_refused} out of "
                       "reach or stroke" + (f" (the first at point {content.path_first_refused})"
                                            if content.path_refused else ""))
        click.echo(f"  → {out_file} (one page, Plotly inlined: opens without a network)")
    if content.path_refused:
        click.echo(f"the path leaves the reach or the strokes of {m.id} at "
                   f"{content.path_refused} of its {content.path_points} points (red in the "
                   "view): check --origin and the program's units", err=True)
        sys.exit(EXIT_PARTIAL)
