"""``pkmkit machined-part``: seed 003's machined-part chain on the command line.

- ``program MACHINE --out part.nc``: the seed's test part as G-code (straight passes along x and
  y; dimensions sized to the machine model);
- ``simulate MACHINE --gcode part.nc --out cmm.csv``: the part machined by the machine with
  defects under the nominal controller and probed on a simulated CMM (Q, M, N per section);
- ``reconstruct cmm.csv --gcode part.nc --out centres.csv``: tool centres from a CMM file (yours
  or simulated) and the cutter radii, written as ``part`` measurements for ``pkmkit calibrate
  MACHINE --measure part``;
- ``ballbar-plan MACHINE --out plan.csv``: seed 003's ball-bar protocol (324 points on a
  hemisphere × 3 table positions × 2 tool lengths), for ``pkmkit simulate-measurements MACHINE
  --measure ballbar --poses plan.csv``; the seed's iteration is that command and ``pkmkit
  calibrate`` repeated with the calibrated machine file as MACHINE.

File formats: docs/calibration.md (§ Seed 003's chain).
"""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible

from .calibration_cmds import CAL_UNITS_OPTION, _defects_file, _numbers
from .limits import check_tool_lengths
from .options import (
    JSON_OPTION,
    check_each,
    emit_json,
    machine_document_path,
    resolve_machine,
)

GCODE_OPTION = click.option("--gcode", required=True, type=click.Path(dir_okay=False),
                            help="The part program (G-code; its straight G1 passes along x or "
                                 "y are the measured ones, named by their file line).")
ORIGIN_OPTION = click.option("--origin", metavar="X,Y,Z",
                             help="Work offset of the program (length unit; default 0,0,0).")


def register(cli: click.Group) -> None:
    """Add the ``machined-part`` group to the ``pkmkit`` group."""
    cli.add_command(machined_part)


@click.group("machined-part")
def machined_part():
    """Seed 003's machined part: G-code → machining → CMM → tool centres (then calibrate)."""


def _origin(text: str | None, scale: float, unit: str) -> np.ndarray:
    """``--origin X,Y,Z`` in ``unit`` (``scale`` m each) → SI ``(3,)``, each coordinate within
    the plausible range of a position."""
    if not text:
        return np.zeros(3)
    values = _numbers(text, "--origin")
    if len(values) != 3:
        raise InputError(f"--origin expects X,Y,Z, got {text!r}")
    check_each("--origin", values, [scale] * 3, [unit] * 3, labels="XYZ")
    return np.array(values) * scale


@machined_part.command("program")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--levels", type=click.IntRange(1, 100), default=2, show_default=True,
              help="Heights of passes (30 mm apart).")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Output G-code file (mm).")
def program_cmd(machine_name, levels, out_file):
    """Seed 003's test part as G-code, sized to MACHINE (illustrative)."""
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text
    from pkmkit.machining.part import part_passes, seed_part_program
    from pkmkit.motion.gcode import read_gcode

    machine = resolve_machine(machine_name, (), "m")
    text = seed_part_program(machine, levels=levels)
    passes = part_passes(read_gcode(text))
    atomic_write_text(out_file, text)
    click.echo(f"{machine.name}: seed 003 test part, {len(passes)} straight passes "
               f"({sum(p.axis == 0 for p in passes)} along x, "
               f"{sum(p.axis == 1 for p in passes)} along y) → {out_file}")


@machined_part.command("simulate")
@click.argument("machine_name", metavar="MACHINE")
@GCODE_OPTION
@ORIGIN_OPTION
@click.option("--defects", "defects_spec", default=None, metavar="FILE|random",
              help="Defects of the machine that cuts the part: 'random' (the true machine file "
                   "is written beside --out) or a file with a [defects] table. Default: none.")
@click.option("--seed", type=int, default=0, show_default=True, help="Random seed.")
@click.option("--sections", type=click.IntRange(1, 100_000), default=240, show_default=True,
              help="CMM sections laid out over the passes (those near a crossing dropped).")
@click.option("--sigma", type=float,
              help="CMM noise σ per coordinate (length unit; default 1.5 µm).")
@click.option("--placement", metavar="DX,DY,DZ,PHI",
              help="The part frame in the machine frame (length unit, PHI in degrees); "
                   "default: the lower corner of the machine's default box, 0.3°.")
@click.option("--points", type=click.Choice(["surface", "tip"]), default="surface",
              show_default=True, help="Report surface points or probe-tip centres.")
@click.option("--probe-radius", type=float,
              help="Probe tip radius (length unit; default 1 mm).")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Output CMM file (CSV).")
@CAL_UNITS_OPTION
@JSON_OPTION
def simulate_cmd(machine_name, gcode, origin, defects_spec, seed, sections, sigma, placement,
                 points, probe_radius, out_file, units, as_json):
    """Machine a part program with a machine with defects and probe it on a CMM."""
    from pkmkit.calibration.simulate import random_defects
    from pkmkit.io.atomic import write_files_atomic
    from pkmkit.io.machine_defects import machine_text_with_defects
    from pkmkit.machining.cmm import CMM_SIGMA, format_cmm
    from pkmkit.machining.part import Placement
    from pkmkit.machining.study import default_placement, simulate_cmm
    from pkmkit.model.defect_rule import add_defects

    unit = units or "mm"
    scale = length_scale(unit)
    check_plausible("--sigma", sigma, "noise", scale=scale, unit=unit)
    check_plausible("--probe-radius", probe_radius, "probe", scale=scale, unit=unit)
    nominal = resolve_machine(machine_name, (), "m")
    rng = np.random.default_rng(seed)
    true, delta = nominal, None
    if defects_spec == "random":
        delta = random_defects(nominal, rng)
        true = add_defects(nominal, delta)
    elif defects_spec:
        true, _ = _defects_file(defects_spec, nominal, unit)
    if placement:
        v = _numbers(placement, "--placement")
        if len(v) != 4:
            raise InputError(f"--placement expects DX,DY,DZ,PHI, got {placement!r}")
        for value in v[:3]:
            check_plausible("--placement", value, "offset", scale=scale, unit=unit)
        if not abs(v[3]) <= 360:
            raise InputError(f"--placement: PHI = {v[3]:g}° is outside [-360, 360]°")
        place = Placement(v[0] * scale, v[1] * scale, v[2] * scale, float(np.radians(v[3])))
    else:
        place = default_placement(nominal)
    cmm, part = simulate_cmm(
        true, nominal, gcode, rng, placement=place, sections=sections,
        sigma=CMM_SIGMA if sigma is None else sigma * scale, points=points,
        probe_radius=0.001 if probe_radius is None else probe_radius * scale,
        origin=_origin(origin, scale, unit))
    note = (f"pkmkit machined-part simulate {nominal.id} --gcode {Path(gcode).name} "
            f"--seed {seed}\nCMM sections of seed 003's part (simulated; {nominal.id}: "
            "illustrative dimensions)")
    texts = {}
    truth_path = None
    if delta is not None:
        out = Path(out_file)
        source = machine_document_path(machine_name)
        truth_path = out.with_name(f"{out.stem}.truth{Path(source).suffix}")
        texts[truth_path] = machine_text_with_defects(
            source, nominal, delta, note=f"true machine of {out.name} (random defects, seed "
                                         f"{seed})")
        note += f"\ntrue machine: {truth_path.name}"
    texts[Path(out_file)] = format_cmm(cmm, units=unit, comment=note)
    write_files_atomic(texts)  # the CMM file and its true machine together or not at all
    payload = {"machine": nominal.id, "sections": len(part.s), "points": len(cmm.label),
               "passes": len(set(part.path)), "out": str(out_file), "units": unit,
               "truth": None if truth_path is None else str(truth_path),
               "placement": {"dx": place.dx / scale, "dy": place.dy / scale,
                             "dz": place.dz / scale, "phi_deg": float(np.degrees(place.phi))}}
    if as_json:
        emit_json(payload)
        return
    click.echo(f"{nominal.name}: {len(set(part.path))} passes machined, {len(part.s)} sections "
               f"probed ({len(cmm.label)} points, {points}) → {out_file} ({unit})")
    if truth_path is not None:
        click.echo(f"  true machine (random defects, seed {seed}) → {truth_path}")


@machined_part.command("reconstruct")
@click.argument("cmm_file", metavar="CMM")
@GCODE_OPTION
@ORIGIN_OPTION
@click.option("--end-mill", type=float, default=None,
              help="Diameter of the contouring end mill (length unit; default 20 mm).")
@click.option("--ball-end", type=float, default=None,
              help="Diameter of the slotting ball-end mill (length unit; default 16 mm).")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Output: part measurements (CSV) for pkmkit calibrate --measure part.")
@CAL_UNITS_OPTION
@JSON_OPTION
def reconstruct_cmd(cmm_file, gcode, origin, end_mill, ball_end, out_file, units, as_json):
    """Tool centres from a CMM file of the part and the cutter radii (seed 003 §4.2)."""
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text
    from pkmkit.io.measurements import format_measurements
    from pkmkit.machining.cmm import read_cmm
    from pkmkit.machining.part import SEED_BALL_RADIUS, SEED_END_MILL_RADIUS, Cutters, part_passes
    from pkmkit.machining.reconstruct import (
        LEAN_LIMIT,
        reconstruct,
        reconstructed_measurements,
    )
    from pkmkit.motion.gcode import read_gcode

    cmm = read_cmm(cmm_file, units=units)
    unit = units or _unit_of(cmm_file) or "m"
    scale = length_scale(unit)
    check_plausible("--end-mill", end_mill, "cutter", scale=scale, unit=unit)
    check_plausible("--ball-end", ball_end, "cutter", scale=scale, unit=unit)
    cutters = Cutters(SEED_END_MILL_RADIUS if end_mill is None else end_mill * scale / 2,
                      SEED_BALL_RADIUS if ball_end is None else ball_end * scale / 2)
    passes = part_passes(read_gcode(gcode, origin=_origin(origin, scale, unit)))
    rec = reconstruct(cmm, cutters)
    data = reconstructed_measurements(rec, passes, program=str(gcode))
    leaning = rec.leaning()
    if leaning.size:  # flagged sections stay out of the file (as a batch's flagged rows)
        if leaning.size == len(data):
            raise InputError(f"{cmm_file}: every section's wall leans by more than "
                             f"{LEAN_LIMIT * 1e3:g} mrad: the cutter was not vertical (seed "
                             "003's hypothesis); no tool centre can be reconstructed")
        data = data.subset(np.setdiff1d(np.arange(len(data)), leaning))
    text = format_measurements(data, None, units=unit,
                               comment=f"tool centres reconstructed from {Path(cmm_file).name} "
                                       f"(end mill Ø{2 * cutters.end_mill / scale:g}, ball-end "
                                       f"Ø{2 * cutters.ball / scale:g} {unit}; "
                                       f"program {Path(gcode).name})")
    atomic_write_text(out_file, text)
    slopes = np.abs(rec.slopes).max(axis=0)
    lean = float(np.nanmax(np.abs(rec.lean), initial=0.0))
    payload = {"sections": len(rec.section), "centres": len(data), "passes": len(set(rec.path)),
               "out": str(out_file),
               "units": unit, "points": cmm.points_kind,
               "largest_slopes": {"wall": float(slopes[0]), "slot": float(slopes[1])},
               "largest_wall_lean_mrad": lean * 1e3,
               "leaning_sections": [rec.lines[i] for i in leaning]}
    if as_json:
        emit_json(payload)
    else:
        click.echo(f"{cmm_file}: {len(rec.section)} sections of {len(set(rec.path))} passes → "
                   f"{len(data)} tool centres (part frame) → {out_file} ({unit})")
        click.echo(f"  largest slope across the sections: wall {slopes[0]:.3g}, slot bottom "
                   f"{slopes[1]:.3g}; largest wall lean {lean * 1e3:.3g} mrad")
    if leaning.size:
        worst = leaning[np.argmax(np.abs(rec.lean[leaning]))]
        click.echo(f"  {leaning.size} section(s) with a wall leaning by more than "
                   f"{LEAN_LIMIT * 1e3:g} mrad, the worst {abs(rec.lean[worst]) * 1e3:.3g} mrad at "
                   f"{rec.lines[worst]}: the cutter was not vertical (seed 003's hypothesis); "
                   "those sections are left out", err=True)
        raise SystemExit(3)


def _unit_of(path: str) -> str | None:
    from pkmkit.io.measurements import file_unit

    return file_unit(path)


@machined_part.command("ballbar-plan")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--bar-length", type=float, help="Bar length (length unit; default 150 mm).")
@click.option("--tool-lengths", metavar="L1,L2", help="Tool lengths (length unit; default 0,100 "
                                                      "mm).")
@click.option("--table-points", metavar="X,Y,Z;X,Y,Z;...",
              help="Table points (length unit; default three under the default box).")
@click.option("--points", type=click.IntRange(1, 100_000), default=324, show_default=True,
              help="Points per hemisphere (seed 003: 324).")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Output plan (CSV) for pkmkit simulate-measurements --measure ballbar "
                   "--poses.")
@CAL_UNITS_OPTION
def ballbar_plan_cmd(machine_name, bar_length, tool_lengths, table_points, points, out_file,
                     units):
    """Seed 003's ball-bar protocol: hemisphere points × 3 table points × 2 tools."""
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text
    from pkmkit.machining.ballbar_plan import BAR_LENGTH, TOOL_LENGTHS, ballbar_plan, format_plan

    unit = units or "mm"
    scale = length_scale(unit)
    check_plausible("--bar-length", bar_length, "length", scale=scale, unit=unit)
    machine = resolve_machine(machine_name, (), "m")
    tables = None
    if table_points:
        tables = [np.array(_numbers(t, "--table-points")) * scale
                  for t in table_points.split(";")]
        if any(len(t) != 3 for t in tables):
            raise InputError(f"--table-points expects X,Y,Z;X,Y,Z;..., got {table_points!r}")
        for value in np.concatenate(tables):
            check_plausible("--table-points", value / scale, "offset", scale=scale, unit=unit)
    if tool_lengths:
        check_tool_lengths(np.array(_numbers(tool_lengths, "--tool-lengths")) * scale, unit)
    plan = ballbar_plan(machine, bar_length=BAR_LENGTH if bar_length is None
                        else bar_length * scale, table_points=tables,
                        tool_lengths=TOOL_LENGTHS if tool_lengths is None
                        else np.array(_numbers(tool_lengths, "--tool-lengths")) * scale,
                        points=points)
    atomic_write_text(out_file, format_plan(
        plan, units=unit, comment=f"pkmkit machined-part ballbar-plan {machine.id}: seed 003's "
                                  "ball-bar protocol (pattern, table points, bar and tools are "
                                  "pkmkit's choices)"))
    n_tables = len(np.unique(plan.pivot, axis=0))
    n_tools = len(set(plan.tool))
    click.echo(f"{machine.name}: {points} points × {n_tables} table points × {n_tools} tools = "
               f"{len(plan)} ball-bar readings ({n_tables * n_tools} acquisitions, bar "
               f"{plan.bar_length / scale:g} {unit}) → {out_file}")


@machined_part.command("check")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--calibrated", required=True, type=click.Path(dir_okay=False),
              help="The calibrated machine file (pkmkit calibrate --out).")
@click.option("--truth", required=True, type=click.Path(dir_okay=False),
              help="The true machine file (simulations: written by machined-part simulate "
                   "--defects random).")
@JSON_OPTION
def check_cmd(machine_name, calibrated, truth, as_json):
    """A validation part machined with the nominal and the compensated controller, beside
    seed 003's figures (simulations)."""
    from pkmkit import load
    from pkmkit.calibration.studies import machined_errors
    from pkmkit.machining.study import SEED_AFTER

    nominal = resolve_machine(machine_name, (), "m")
    errors = machined_errors(load(truth), nominal, load(calibrated))
    payload = {"machine": f"{nominal.id} (illustrative dimensions)",
               **{k: {kk: vv * 1e6 for kk, vv in v.items()} for k, v in errors.items()},
               "seed": {k: v * 1e6 for k, v in SEED_AFTER.items()}, "units": "µm"}
    worse = any(errors["compensated"][k] > errors["nominal"][k] for k in ("along_x", "along_y"))
    payload["compensation_worse"] = worse
    if as_json:
        emit_json(payload)
        if worse:
            raise SystemExit(3)
        return
    click.echo(f"{nominal.name}: validation part (lines along x and y, three heights 40 mm "
               "apart), largest deviation from the programmed lines (µm):")
    click.echo("                          along x   along y")
    for key, label in (("nominal", "nominal controller"), ("compensated", "compensated")):
        click.echo(f"  {label:22s} {payload[key]['along_x']:8.1f}  {payload[key]['along_y']:8.1f}")
    click.echo(f"  {'seed 003 (real Verne)':22s}     < 20      < 40")
    click.echo("  (simulation: the geometric model only, illustrative machine; the seed's real "
               "part also carries thermal, force, servo and tool errors)")
    if worse:
        click.echo("  the compensated controller machines worse than the nominal one: do not use "
                   "this calibration", err=True)
        raise SystemExit(3)
