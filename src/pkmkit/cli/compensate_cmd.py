"""``pkmkit compensate``: corrected commands for the nominal controller from a calibrated
machine — a corrected G-code program (``--gcode``) or a corrected table of targets (``--grid``,
``--targets``), optionally aiming the loaded tool point (``--gravity``).

Units at this boundary: lengths in ``--units`` (or a targets file's ``# units:`` line),
orientations as a tool axis or a rotation vector in degrees.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible

from .calibration_cmds import _numbers
from .calibration_options import CAL_UNITS_OPTION
from .gravity_option import GRAVITY_OPTION, aimed_targets, gravity_line
from .limits import MAX_PIECES, check_count, check_tool_lengths
from .options import JSON_OPTION, emit_json, resolve_machine


def register(cli: click.Group) -> None:
    """Add ``compensate`` to the ``pkmkit`` group."""
    cli.add_command(compensate_cmd)


@click.command("compensate")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--calibrated", required=True, type=click.Path(dir_okay=False),
              help="The calibrated machine file (pkmkit calibrate --out).")
@click.option("--gcode", type=click.Path(dir_okay=False),
              help="G-code program to correct (3-axis moves; arcs become short lines).")
@click.option("--origin", metavar="X,Y,Z", help="Work offset of the G-code program.")
@click.option("--step", type=float,
              help="Spacing of the points where the correction of a feed move is checked "
                   "(length unit; default 1 mm).")
@click.option("--tolerance", type=float,
              help="Largest deviation between the corrected points and the corrected move "
                   "the controller interpolates; a feed move is subdivided only where it is "
                   "exceeded (length unit; default 0.001 mm).")
@click.option("--max-correction", type=float,
              help="Largest correction accepted; a block needing more is refused with its "
                   "G-code line and no program is written (length unit; default 1 % of the "
                   "machine's characteristic length: 13 mm for the linear Delta).")
@click.option("--grid", "grid_text", metavar="X0,Y0,Z0:X1,Y1,Z1:NX,NY,NZ",
              help="Correction table on a regular grid.")
@click.option("--targets", "targets_file", type=click.Path(dir_okay=False),
              help="CSV of targets x, y, z (and i, j, k tool axes for a 5-axis machine, or "
                   "rx, ry, rz rotation vectors in degrees for a six-actuator machine).")
@click.option("--tool-length", type=float, help="Tool length (length unit).")
@click.option("--truth", type=click.Path(dir_okay=False),
              help="A true machine file (simulations): report the error left after "
                   "compensation at the targets.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Corrected program (.nc) or correction table (.csv).")
@GRAVITY_OPTION
@CAL_UNITS_OPTION
@JSON_OPTION
def compensate_cmd(machine_name, calibrated, gcode, origin, step, tolerance, max_correction,
                   grid_text, targets_file, tool_length, truth, out_file, gravity, units, as_json):
    """Corrected commands for the nominal controller from a calibrated machine."""
    from pkmkit import load
    from pkmkit.calibration.compensation import check_compensation
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text

    given = [g for g in (gcode, grid_text, targets_file) if g]
    if len(given) != 1:
        raise click.UsageError("give exactly one of --gcode, --grid, --targets")
    ctx = _compensation_context(machine_name, calibrated, targets_file, tool_length, step,
                                tolerance, max_correction, gcode, units)
    corrected = flags = described = None
    if gcode:
        targets, fixed, corrected, sag, text = _compensate_program(
            ctx, gcode, origin, step, tolerance, gravity, as_json)
    else:
        targets, fixed, flags, described, sag, text = _compensate_targets(
            ctx, grid_text, gravity, as_json)
    ok = np.isfinite(fixed).all(axis=1)
    check = None
    if truth and ok.any():
        check = check_compensation(load(truth), ctx.nominal, ctx.identified, targets[ok],
                                   tool_length=ctx.tool_length)
    atomic_write_text(out_file, text)
    corr = np.linalg.norm(fixed[ok, :3] - targets[ok, :3], axis=1) / ctx.scale
    payload = _compensation_payload(ctx, out_file, targets, corr, ok, check, sag, corrected,
                                    flags, described)
    if as_json:
        emit_json(payload)
    else:
        _print_compensation(payload, corrected, len(targets), out_file, corr, check, ctx.scale,
                            ctx.unit, ok.any())
    if payload.get("flagged"):
        import sys

        from .options import EXIT_PARTIAL

        sys.exit(EXIT_PARTIAL)


@dataclasses.dataclass(frozen=True)
class _Compensation:
    """What every ``compensate`` path shares: the machines, the unit, the tool length (m),
    the correction bound (m) and a targets file's table (or None)."""

    nominal: Any
    identified: Any
    calibrated: str
    unit: str
    scale: float
    tool_length: float | None
    bound: float
    table: Any


def _compensation_context(machine_name, calibrated, targets_file, tool_length, step, tolerance,
                          max_correction, gcode, units) -> _Compensation:
    """Read and check what ``compensate`` is given: the targets file (whose ``# units:`` line
    sets the unit of the options and of the output), the calibrated machine (a calibration of
    MACHINE, by its kind and by where it puts the tool at the nominal home), the tool length
    and the step, tolerance and correction bound."""
    from pkmkit import load
    from pkmkit.calibration.compensation import home_offset
    from pkmkit.calibration.corrected_program import default_max_correction

    table = None
    if targets_file:
        from pkmkit.io.measurements import read_csv_table

        table = read_csv_table(targets_file, ("x", "y", "z"),
                               ("i", "j", "k", "rx", "ry", "rz", "id"), units=units)
    unit = units or (table.unit if table is not None else "m")
    scale = length_scale(unit)
    nominal = resolve_machine(machine_name, (), "m")
    identified = load(calibrated)
    if identified.n_actuators != nominal.n_actuators or type(identified) is not type(nominal):
        raise InputError(f"{calibrated} is not a calibration of {nominal.id!r}")
    tl = None if tool_length is None else tool_length * scale
    if tl is not None and not (np.isfinite(tl) and tl >= 0):
        raise InputError(f"--tool-length must be a finite number ≥ 0, got {tool_length:g} {unit}")
    if tl is not None:
        check_tool_lengths(np.array([tl]), unit, "--tool-length")
    for name, value in (("--step", step), ("--tolerance", tolerance),
                        ("--max-correction", max_correction)):
        if value is not None and not (np.isfinite(value) and value > 0
                                      and np.isfinite(value * scale) and value * scale > 0):
            raise InputError(f"{name} must be a finite number > 0, got {value:g} {unit}")
    check_plausible("--step", step, "length", scale=scale, unit=unit)
    check_plausible("--tolerance", tolerance, "correction", scale=scale, unit=unit)
    check_plausible("--max-correction", max_correction, "correction", scale=scale, unit=unit)
    if not gcode and (step is not None or tolerance is not None):
        raise click.UsageError("--step and --tolerance apply to a corrected program (--gcode)")
    bound = default_max_correction(nominal) if max_correction is None else max_correction * scale
    offset = home_offset(nominal, identified, tl)
    similar = max(bound, default_max_correction(nominal))
    if offset > similar:
        raise InputError(
            f"{calibrated} is not a calibration of {nominal.id!r}: at the nominal home actuator "
            f"positions it places the tool {offset / scale:.4g} {unit} from the nominal machine's"
            f" tool point, beyond the largest correction {similar / scale:g} {unit} (a machine "
            "of other dimensions, or a file in another unit; --max-correction sets the bound)")
    return _Compensation(nominal, identified, calibrated, unit, scale, tl, bound, table)


def _compensate_program(ctx: _Compensation, gcode: str, origin, step, tolerance, gravity: bool,
                        as_json: bool) -> tuple:
    """``compensate --gcode``: ``(targets, corrected moves, CorrectedPath, sag, G-code)``;
    blocks whose correction exceeds the bound are refused with their line."""
    from pkmkit.calibration.controller import target_width
    from pkmkit.calibration.corrected_program import (
        DEFAULT_STEP,
        DEFAULT_TOLERANCE,
        CorrectionRefused,
        correct_path,
    )
    from pkmkit.io.compensation_files import corrected_gcode
    from pkmkit.motion.gcode import read_gcode

    nominal, scale, unit = ctx.nominal, ctx.scale, ctx.unit
    if target_width(nominal) != 3:
        raise InputError("G-code correction is for machines whose commands are tool "
                         "points; a 5-axis or six-actuator machine's correction includes "
                         "the orientation: use --grid or --targets")
    shift = (np.asarray(_numbers(origin, "--origin")) * scale if origin else np.zeros(3))
    if shift.shape != (3,):
        raise InputError("--origin needs X,Y,Z")
    path = read_gcode(gcode, origin=shift)
    settings = {name: (default if value is None else value * scale)
                for name, value, default in (("step", step, DEFAULT_STEP),
                                             ("tolerance", tolerance, DEFAULT_TOLERANCE),
                                             ("max_correction", None, ctx.bound))}
    check_count(path.length / settings["step"], MAX_PIECES,
                f"pieces of {settings['step'] / scale:g} {unit} (--step) over the "
                f"program's {path.length / scale:.6g} {unit}", "give a longer --step")
    aim = None
    if gravity:
        from pkmkit.calibration.gravity import LoadedAim

        aim = LoadedAim(ctx.identified, ctx.tool_length, masses_of=nominal)
    try:
        corrected = correct_path(nominal, ctx.identified, path, tool_length=ctx.tool_length,
                                 progress=not as_json, aim=aim, **settings)
    except CorrectionRefused as exc:
        _refuse_blocks(exc, Path(gcode).name, settings["max_correction"], scale, unit, as_json)
    sag = None if aim is None else aim.summary(scale)
    if sag is not None and not as_json:
        gravity_line(sag, unit, "program points")
    text = corrected_gcode(corrected, origin=shift, header=(
        f"corrected by pkmkit compensate {nominal.id} --calibrated {Path(ctx.calibrated).name}"
        + (" --gravity (the loaded tool point aimed at the program)" if gravity else "")
        + f"\nfrom {Path(gcode).name}: {len(corrected.corrected)} moves for its "
        f"{corrected.blocks} blocks (tolerance {corrected.tolerance / scale:g} {unit})"))
    return corrected.targets, corrected.corrected, corrected, sag, text


def _table_targets(ctx: _Compensation, grid_text: str | None) -> np.ndarray:
    """``(N, 3|6)`` targets (m; orientation as a tool axis or a rotation vector in rad) of
    ``--grid X0,Y0,Z0:X1,Y1,Z1:NX,NY,NZ`` or of the targets file."""
    from pkmkit.calibration.compensation import grid_targets

    if grid_text:
        parts = grid_text.split(":")
        if len(parts) != 3:
            raise InputError("--grid needs X0,Y0,Z0:X1,Y1,Z1:NX,NY,NZ")
        lo, hi = (np.asarray(_numbers(p, "--grid")) * ctx.scale for p in parts[:2])
        counts = _numbers(parts[2], "--grid counts")
        if any(c != int(c) for c in counts):
            raise InputError("--grid counts must be integers")
        return grid_targets(lo, hi, counts)
    t = ctx.table
    targets = np.column_stack([t.numbers[c] for c in "xyz"]) * t.scale
    if all(c in t.numbers for c in "ijk"):
        targets = np.column_stack([targets] + [t.numbers[c] for c in "ijk"])
    elif all(c in t.numbers for c in ("rx", "ry", "rz")):
        targets = np.column_stack([targets] + [np.radians(t.numbers[c])
                                               for c in ("rx", "ry", "rz")])
    return targets


def _compensate_targets(ctx: _Compensation, grid_text: str | None, gravity: bool,
                        as_json: bool) -> tuple:
    """``compensate --grid|--targets``: ``(targets, corrected, flags, row notes, sag,
    table text)``; rows beyond the bound or the strokes are flagged, the others kept."""
    from pkmkit.calibration.compensation import correct_table
    from pkmkit.calibration.controller import as_targets
    from pkmkit.io.compensation_files import correction_table

    nominal, identified = ctx.nominal, ctx.identified
    targets = _table_targets(ctx, grid_text)
    aimed, sag = aimed_targets(identified, targets, ctx.tool_length, gravity, ctx.scale,
                               ctx.unit, as_json, nominal)
    fixed, flags = correct_table(nominal, identified, aimed, max_correction=ctx.bound,
                                 tool_length=ctx.tool_length, progress=not as_json)
    targets = as_targets(identified, targets)
    orientation = nominal.pose_orientation or "rotvec"
    described = [flags.describe(k, ctx.bound, ctx.scale, ctx.unit) for k in range(len(targets))]
    text = correction_table(targets, fixed, units=ctx.unit, orientation=orientation, comment=(
        f"corrected targets for the nominal controller of {nominal.id} "
        f"(pkmkit compensate --calibrated {Path(ctx.calibrated).name})"), status=described)
    return targets, fixed, flags, described, sag, text


def _compensation_payload(ctx: _Compensation, out_file: str, targets: np.ndarray,
                          corr: np.ndarray, ok: np.ndarray, check, sag, corrected, flags,
                          described) -> dict:
    """The JSON of ``compensate`` (and what its text prints)."""
    scale = ctx.scale
    payload = {"machine": ctx.nominal.id, "calibrated": ctx.calibrated, "out": out_file,
               "units": ctx.unit, "targets": len(targets),
               "correction_mean": float(np.mean(corr)) if ok.any() else None,
               "correction_max": float(np.max(corr)) if ok.any() else None,
               "max_correction": ctx.bound / scale,
               "check": None if check is None else check.to_dict(scale)}
    payload["gravity"] = sag
    if corrected is None:
        table = ctx.table
        payload["flagged"] = [{"row": int(k) + 1,
                               "line": table.lines[k] if table is not None else None,
                               "status": str(flags.status[k]), "reason": described[k]}
                              for k in np.flatnonzero(flags.flagged)]
    else:
        payload["program"] = {
            "blocks": corrected.blocks, "moves": len(corrected.corrected),
            "subdivided_blocks": corrected.subdivided,
            "tolerance": corrected.tolerance / scale, "step": corrected.step / scale,
            "max_correction": corrected.max_correction / scale,
            "deviation_max": corrected.deviation / scale}
    return payload


def _print_compensation(payload, corrected, count, out_file, corr, check, scale, unit,
                        any_ok) -> None:
    if corrected is not None:
        fixed = corrected.corrected
        click.echo(f"{corrected.blocks} blocks → {len(fixed)} corrected moves → {out_file} "
                   f"({corrected.subdivided} block(s) subdivided for a tolerance of "
                   f"{corrected.tolerance / scale:.4g} {unit}); correction mean "
                   f"{corr.mean():.4g}, max {corr.max():.4g} {unit}")
    elif any_ok:
        click.echo(f"{count} corrected targets → {out_file}; correction mean "
                   f"{corr.mean():.4g}, max {corr.max():.4g} {unit}")
    flagged = payload.get("flagged", [])
    if flagged:
        click.echo(f"  {len(flagged)} of {count} target(s) flagged (no corrected values in "
                   "the table):")
        for f in flagged[:20]:
            where = f["line"] or f"row {f['row']}"
            click.echo(f"    {where}: {f['reason']}")
        if len(flagged) > 20:
            click.echo(f"    … {len(flagged) - 20} more (--json)")
    if check is not None:
        c = check.to_dict(scale)
        click.echo(f"  error of the true machine at the targets: RMS {c['rms_before']:.4g} → "
                   f"{c['rms_after']:.4g}, max {c['max_before']:.4g} → {c['max_after']:.4g} "
                   f"{unit}")
        click.echo(f"  with the workpiece set-up (a rigid motion) removed: mean "
                   f"{c['mean_after_rigid']:.4g}, max {c['max_after_rigid']:.4g} {unit}")


def _refuse_blocks(exc, program: str, bound: float, scale: float, unit: str,
                   as_json: bool) -> None:
    """Report the refused blocks of a program (``bound`` in m) and exit with status 3: nothing
    is written."""
    import sys

    from pkmkit.calibration.corrected_program import refusal_reason

    from .options import EXIT_PARTIAL

    if as_json:
        emit_json({"refused": [{"line": line, "block": text,
                                "correction": None if not np.isfinite(c) else c / scale,
                                "reason": ("out-of-stroke" if np.isinf(c) else "out-of-reach"
                                           if np.isnan(c) else "correction")}
                               for line, text, c in exc.blocks],
                   "max_correction": bound / scale, "units": unit})
    click.echo(f"Refused: {len(exc.blocks)} block(s) of {program} (largest correction "
               f"accepted: {bound / scale:g} {unit}, --max-correction); no program written",
               err=True)
    strokes = {line: (name, by, rad) for line, _, name, by, rad in exc.strokes}
    for line, text, c in exc.blocks:
        reason = refusal_reason(c, bound, scale, unit)
        if line in strokes:
            name, by, rad = strokes[line]
            amount = f"{np.degrees(by):.4g} deg" if rad else f"{by / scale:.4g} {unit}"
            reason = f"{name} out of stroke by {amount}"
        click.echo(f"  {program}:{line}: {text}: {reason}", err=True)
    sys.exit(EXIT_PARTIAL)
