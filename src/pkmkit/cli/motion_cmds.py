"""``pkmkit path`` and ``pkmkit arm-sizing``."""

from __future__ import annotations

import sys

import click
import numpy as np

from pkmkit.dynamics.arms import Material, analyse_arm, seed_tables, size_arm
from pkmkit.dynamics.masses import load_masses
from pkmkit.dynamics.trajectory import simulate_path
from pkmkit.dynamics.wrench import load_wrench_series
from pkmkit.exceptions import InputError
from pkmkit.io.atomic import check_output_dir
from pkmkit.io.table import TableWriter
from pkmkit.model.parameters import length_scale
from pkmkit.motion.gcode import read_gcode
from pkmkit.motion.joints import Limits
from pkmkit.motion.limits import limit_bounds
from pkmkit.motion.paths import circle, helix, line, raster
from pkmkit.motion.timelaw import DEFAULT_JERK_PER_ACCEL, PROFILES
from pkmkit.numerics.magnitudes import check_plausible
from pkmkit.stiffness.along_path import path_deflection

from .limits import check_feed_reached, check_wrench
from .options import (
    EXIT_PARTIAL,
    JSON_OPTION,
    SET_OPTION,
    UNITS_OPTION,
    check_each,
    emit_json,
    fmt,
)
from .path_deflection import deflection_columns, deflection_summary, print_deflection
from .stiffness_cmds import machine_and_data


def register(cli: click.Group) -> None:
    """Add the motion commands to the ``pkmkit`` group."""
    cli.add_command(path_cmd)
    cli.add_command(arm_sizing)


def _numbers(text: str, count: int | tuple[int, ...], what: str) -> list[float]:
    try:
        values = [float(v) for v in text.replace(":", ",").split(",")]
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as numbers") from None
    counts = (count,) if isinstance(count, int) else count
    if len(values) not in counts:
        raise InputError(f"{what} needs {' or '.join(map(str, counts))} numbers, got "
                         f"{len(values)}")
    if not np.isfinite(values).all():
        raise InputError(f"{what}: numbers must be finite")
    return values


def _check_positive(name: str, value: float | None, unit: float, units: str) -> None:
    """A positive, finite option whose value in SI units is still positive and finite."""
    if value is None:
        return
    if not (np.isfinite(value) and value > 0):
        raise InputError(f"{name} must be a finite number > 0, got {value:g}")
    si = value * unit
    if not (np.isfinite(si) and si > 0):
        raise InputError(f"{name} {value:g} {'overflows' if si else 'underflows to 0'} in SI "
                         f"units (from {units})")


def build_path(machine, scale: float, gcode, origin, line_text, circle_text, helix_text,
               raster_text, units: str = "m"):
    """The tool path from exactly one of the path options (lengths in CLI units ``units``,
    ``scale`` m each): positions within the plausible range of a position, and every refusal
    of the path's shape naming its option."""
    given = [t for t in (gcode, line_text, circle_text, helix_text, raster_text) if t]
    if len(given) != 1:
        raise click.UsageError("give exactly one of --gcode, --line, --circle, --helix, --raster")
    dims = machine.dims
    if origin and not gcode:
        raise click.UsageError("--origin is the work offset of a G-code program (--gcode)")
    names = "XYZ"[:dims]

    def positions(option: str, values, labels) -> None:
        check_each(option, values, [scale] * len(values), [units] * len(values), labels=labels)

    if gcode:
        shift = np.zeros(dims)
        if origin:
            values = _numbers(origin, (dims,), "--origin")
            positions("--origin", values, names)
            shift = np.asarray(values) * scale
        return read_gcode(gcode, origin=np.pad(shift, (0, 3 - dims)))
    option = next(o for o, t in (("--line", line_text), ("--circle", circle_text),
                                 ("--helix", helix_text), ("--raster", raster_text)) if t)
    try:
        return _shape(option, dims, scale, positions, line_text, circle_text, helix_text,
                      raster_text)
    except InputError as exc:
        if str(exc).startswith(option):
            raise
        raise InputError(f"{option}: {exc}") from None


def _shape(option, dims, scale, positions, line_text, circle_text, helix_text, raster_text):
    """The path of ``--line``, ``--circle``, ``--helix`` or ``--raster`` (``option``)."""
    names = "XYZ"[:dims]
    if line_text:
        values = _numbers(line_text, (2 * dims,), "--line")
        positions("--line", values, [f"{e} {n}" for e in ("start", "end") for n in names])
        v = np.asarray(values) * scale
        return line(v[:dims], v[dims:])
    if circle_text:
        v = _numbers(circle_text, (dims + 1,), "--circle")
        positions("--circle", v[:dims], [f"centre {n}" for n in names])
        return circle(np.asarray(v[:dims]) * scale, v[dims] * scale)
    if helix_text:
        v = _numbers(helix_text, (6,), "--helix")
        if dims != 3:
            raise InputError("a helix needs a spatial machine")
        positions("--helix", v[:3], [f"centre {n}" for n in names])
        return helix(np.asarray(v[:3]) * scale, v[3] * scale, pitch=v[4] * scale, turns=v[5])
    parts = raster_text.split(",")
    strategy = "zigzag"
    if parts[-1].strip() in ("zigzag", "one-way"):
        strategy = parts.pop().strip()
    v = _numbers(",".join(parts), (6,), "--raster")
    if not float(v[5]).is_integer():
        raise InputError(f"--raster: the number of passes must be an integer, got {v[5]:g}")
    if dims != 3:
        raise InputError("raster facing needs a spatial machine (it retracts along z)")
    positions("--raster", v[:3], ["X0", "Y0", "Z"])
    return raster(np.asarray(v[:3]) * scale, v[3] * scale, v[4] * scale, int(v[5]),
                  strategy=strategy)


@click.command("path")
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--gcode", type=click.Path(dir_okay=False), help="G-code program (units G20/G21).")
@click.option("--origin", help="Work offset added to the G-code coordinates, X,Y[,Z].")
@click.option("--line", "line_text", metavar="X0,Y0,Z0:X1,Y1,Z1", help="Straight move.")
@click.option("--circle", "circle_text", metavar="CX,CY,CZ,R", help="Full circle (horizontal).")
@click.option("--helix", "helix_text", metavar="CX,CY,CZ,R,PITCH,TURNS", help="Helix along z.")
@click.option("--raster", "raster_text", metavar="X0,Y0,Z,W,H,PASSES[,zigzag|one-way]",
              help="Facing of a rectangle in passes along x.")
@click.option("--feed", type=float,
              help="Feed rate (length unit per second); required except with --gcode, whose F "
                   "words set the feeds (--feed then only sets the default rapid speed).")
@click.option("--rapid-feed", type=float,
              help="Speed of rapid moves (default 5 × feed; with --gcode and no --feed, 5 × the "
                   "program's highest F).")
@click.option("--accel", type=float, required=True, help="Tool acceleration limit.")
@click.option("--jerk", type=float,
              help=f"Tool jerk limit of the S-curve (default {DEFAULT_JERK_PER_ACCEL:g} × "
                   f"--accel: the acceleration builds up in {1 / DEFAULT_JERK_PER_ACCEL:g} s).")
@click.option("--profile", type=click.Choice(PROFILES), default="scurve", show_default=True)
@click.option("--period", type=float, default=0.005, show_default=True, help="Sampling period, s.")
@click.option("--masses", type=click.Path(dir_okay=False),
              help="Masses file (default: the kind's illustrative masses, see docs/motion.md).")
@click.option("--wrench", help="Constant force on the tool FX,FY,FZ in N.")
@click.option("--wrench-file", type=click.Path(dir_okay=False),
              help="Force on the tool against time: CSV with columns t,fx,fy,fz (s, N), "
                   "interpolated, held at the ends.")
@click.option("--speed-limit", type=float, help="Actuator speed limit.")
@click.option("--accel-limit", type=float, help="Actuator acceleration limit.")
@click.option("--force-limit", type=float, help="Actuator force limit, N.")
@click.option("--deflection", "with_deflection", is_flag=True,
              help="Tool-point deflection under the weight of the moving parts and the tool "
                   "force, per block (µm; elastic data as for `pkmkit stiffness`).")
@click.option("--max-deflection", type=float, metavar="µm",
              help="Deflection limit (implies --deflection; exit status 3 when exceeded).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              help="Directory for motion.png, path.png and trajectory.csv (and deflection.png).")
@UNITS_OPTION
@JSON_OPTION
def path_cmd(machine_name, assignments, gcode, origin, line_text, circle_text, helix_text,
             raster_text, feed, rapid_feed, accel, jerk, profile, period, masses, wrench,
             wrench_file, speed_limit, accel_limit, force_limit, with_deflection,
             max_deflection, out_dir, units, as_json):
    """Move along a tool path: duration, actuator strokes, speeds, accelerations, forces and
    powers, with a check of the actuator limits (exit status 3 when a limit is exceeded).

    With --deflection, the tool-point deflection under gravity and the tool force."""
    m, elastic = machine_and_data(machine_name, assignments, units)
    if m.pose_orientation is not None:  # poses with an orientation
        raise InputError(
            f"path follows tool paths with translational machines (position-only poses and "
            f"their mass models); {m.id!r} is a {m.family} machine: run its poses through "
            f"`pkmkit ik {machine_name} --input poses.csv --output q.csv` instead")
    scale = length_scale(units)
    out = check_output_dir(out_dir) if out_dir else None
    tool_path = build_path(m, scale, gcode, origin, line_text, circle_text, helix_text,
                           raster_text, units)
    feed, jerk, defaults = _time_law_defaults(tool_path, scale, units, feed, accel, jerk,
                                              rapid_feed, profile, bool(gcode))
    props, file_wrench = load_masses(masses, m) if masses else (None, None)
    force = _path_wrench(file_wrench, wrench, wrench_file)
    limits = _path_limits(units, scale, feed, accel, jerk, rapid_feed, speed_limit,
                          accel_limit, force_limit, period, max_deflection)
    result = simulate_path(m, tool_path, feed=feed * scale, accel=accel * scale,
                           jerk=None if jerk is None else jerk * scale, profile=profile,
                           rapid_feed=None if rapid_feed is None else rapid_feed * scale,
                           period=period, masses=props, wrench=force, limits=limits)
    summary = result.summary()
    check_feed_reached(feed * scale, summary["tool_speed_max"], units)
    _summary_in_units(summary, m, result, scale, units, profile)
    summary["defaults"] = defaults
    bent = None
    if with_deflection or max_deflection is not None:
        bent = path_deflection(m, result.motion.trajectory, result.masses, force=force,
                               data=elastic)
        summary["deflection"] = deflection_summary(bent, elastic, scale, max_deflection)
    if out is not None:
        summary["files"] = _write_path_outputs(m, result, limits, bent, summary, out, scale,
                                               units)
    if as_json:
        emit_json(summary)
    else:
        _print_path_summary(m, summary, profile, units)
        if bent is not None:
            print_deflection(summary["deflection"], units)
        for note in defaults:
            click.echo(f"  default {note['option']} {note['value']:.6g} {note['unit']} "
                       f"({note['rule']})")
    if summary["violations"] or summary.get("deflection", {}).get("exceeded"):
        sys.exit(EXIT_PARTIAL)


def _path_wrench(file_wrench, wrench: str | None, wrench_file: str | None):
    """The tool wrench of ``path``: ``--wrench FX,FY,FZ`` (N), a ``--wrench-file`` series, or
    the masses file's; the two options are exclusive."""
    if wrench and wrench_file:
        raise click.UsageError("--wrench and --wrench-file are exclusive")
    if wrench:
        return check_wrench(np.asarray(_numbers(wrench, (3,), "--wrench")))
    if wrench_file:
        return load_wrench_series(wrench_file)
    return file_wrench


def _path_limits(units: str, scale: float, feed, accel, jerk, rapid_feed, speed_limit,
                 accel_limit, force_limit, period, max_deflection) -> Limits:
    """The time-law and limit options checked (finite, > 0, plausible) and the actuator
    :class:`Limits` in SI."""
    for name, value, unit in (("--feed", feed, scale), ("--accel", accel, scale),
                              ("--jerk", jerk, scale), ("--rapid-feed", rapid_feed, scale),
                              ("--speed-limit", speed_limit, scale),
                              ("--accel-limit", accel_limit, scale),
                              ("--force-limit", force_limit, 1.0), ("--period", period, 1.0),
                              ("--max-deflection", max_deflection, 1e-6)):
        _check_positive(name, value, unit, units)
    check_plausible("--speed-limit", speed_limit, "speed", scale=scale, unit=f"{units}/s")
    check_plausible("--accel-limit", accel_limit, "acceleration", scale=scale,
                    unit=f"{units}/s²")
    check_plausible("--force-limit", force_limit, "force")
    check_plausible("--max-deflection", max_deflection, "deflection", scale=1e-6, unit="µm")
    return Limits(speed=None if speed_limit is None else speed_limit * scale,
                  accel=None if accel_limit is None else accel_limit * scale,
                  force=force_limit)


def _summary_in_units(summary: dict, m, result, scale: float, units: str,
                      profile: str) -> None:
    """The path simulation's summary with its lengths in ``units`` (forces stay in N), in
    place, and the machine, units, profile, actuators and moving mass added."""
    lengths = ("length", "cutting_length", "q_min", "q_max", "stroke", "qd_max", "qdd_max",
               "tool_speed_max", "tool_accel_max")
    for key in lengths:
        summary[key] = np.asarray(summary[key]) / scale
    summary["qd_range"] = [np.asarray(v) / scale for v in summary["qd_range"]]
    for v in summary["violations"]:
        if v["limit"] != "force":
            for item in (v, *v["spans"]):
                item["value"] /= scale
                item["excess"] /= scale
            v["lower"] /= scale
            v["upper"] /= scale
        v["pose"] = np.asarray(v["pose"]) / scale
    summary.update({"machine": m.id, "units": units, "profile": profile,
                    "actuators": list(m.actuator_names), "total_mass": result.masses.total_mass})


def _write_path_outputs(m, result, limits: Limits, bent, summary: dict, out, scale: float,
                        units: str) -> list[str]:
    """``motion.png``, ``path.png``, ``trajectory.csv`` (and ``deflection.png``) in ``out``;
    returns the names written."""
    # matplotlib (≈ 0.5 s of imports) only when figures are written, not for `--help`
    from pkmkit.plot.deflection_figures import plot_path_deflection
    from pkmkit.plot.motion_figures import plot_joint_motion, plot_tool_path

    motion = result.motion
    plot_joint_motion(motion, m.actuator_names, forces=result.forces.force,
                      title=f"{m.name}: {summary['duration']:.3f} s", length_unit=units,
                      limits={kind: (lo, hi) for kind, _, lo, hi in limit_bounds(m, limits)},
                      violations=result.violations, path=out / "motion.png")
    plot_tool_path(motion, title=m.name, length_unit=units, path=out / "path.png")
    names = m.actuator_names
    header = ["t", *m.pose_names, *names, *[f"{n}_dot" for n in names],
              *[f"{n}_ddot" for n in names], *[f"f_{n}" for n in names]]
    rows = np.column_stack([motion.t, motion.x / scale, motion.q / scale, motion.qd / scale,
                            motion.qdd / scale, result.forces.force])
    columns = {name: rows[:, j] for j, name in enumerate(header)}
    files = ["motion.png", "path.png", "trajectory.csv"]
    if bent is not None:
        columns.update(deflection_columns(bent, m.pose_names))
        plot_path_deflection(motion, m.actuator_names, bent, length_unit=units,
                             title=f"{m.name}: tool deflection", path=out / "deflection.png")
        files.append("deflection.png")
    with TableWriter(out / "trajectory.csv", units=units) as writer:
        writer.write(columns)
    return files


def _print_path_summary(m, summary: dict, profile: str, units: str) -> None:
    u = units
    click.echo(f"{m.name}: {summary['length']:.6g} {u} of path in {summary['duration']:.4f} s "
               f"({summary['samples']} samples, {profile}); figures over the continuous motion "
               f"(to {summary['between_samples']['rtol']:.0e} of each range)")
    click.echo(f"  actuator range {fmt(summary['q_min'])} .. {fmt(summary['q_max'])} {u}, "
               f"stroke {fmt(summary['stroke'])} {u}")
    click.echo(f"  speeds {fmt(summary['qd_range'][0])} .. {fmt(summary['qd_range'][1])} {u}/s; "
               f"|accelerations| up to {fmt(summary['qdd_max'])} {u}/s²")
    click.echo(f"  forces {fmt(summary['force_range'][0])} .. {fmt(summary['force_range'][1])} N"
               f" (moving mass {summary['total_mass']:.3g} kg); power up to "
               f"{fmt(summary['power_max'])} W")
    click.echo(f"  leg axial forces up to {fmt(summary['leg_axial_max'])} N (the load for "
               "`pkmkit arm-sizing --force`, divided among the leg's rods)")
    if summary["violations"]:
        for v in summary["violations"]:
            click.echo(_violation_line(v, units))
    else:
        click.echo("  every checked limit holds")


#: Excursion spans printed per violation (all of them in --json).
SHOWN_SPANS = 4


def _violation_line(v: dict, units: str) -> str:
    """One violated limit: the worst excess, where, and the excursions' spans and lines."""
    unit = {"stroke": units, "speed": f"{units}/s", "accel": f"{units}/s²",
            "force": "N"}.get(v["limit"], "")
    where = f", line {v['line']} {v['block']!r}" if v["line"] else ""
    spans = ", ".join(f"{s['start']:.4f}–{s['end']:.4f} s (line {s['start_line']})"
                      if s["start_line"] else f"{s['start']:.4f}–{s['end']:.4f} s"
                      for s in v["spans"][:SHOWN_SPANS])
    more = f", … {len(v['spans']) - SHOWN_SPANS} more (--json)" \
        if len(v["spans"]) > SHOWN_SPANS else ""
    return (f"  LIMIT {v['limit']} {v['actuator']}: worst excess {v['excess']:.6g} {unit} "
            f"({v['actuator']} = {v['value']:.6g} {unit} at t = {v['t_peak']:.4f} s{where}, pose "
            f"{fmt(v['pose'])}); {v['excursions']} excursion(s): {spans}{more}")


def _time_law_defaults(tool_path, scale: float, units: str, feed, accel, jerk, rapid_feed,
                       profile: str, gcode: bool):
    """Feed and jerk (CLI units) with the defaults filled in, and a note per default used:
    ``[{"option", "value", "unit", "rule"}]``."""
    notes = []
    if feed is None:
        programmed = [s.feed for s in tool_path.segments if getattr(s, "feed", None)]
        if not (gcode and programmed):
            raise click.UsageError("--feed is required (except with --gcode, whose F words set "
                                   "the feeds)")
        feed = max(programmed) / scale
        if rapid_feed is None:
            notes.append({"option": "--rapid-feed", "value": 5.0 * feed, "unit": f"{units}/s",
                          "rule": "5 × the program's highest feed; set --rapid-feed"})
    if profile == "scurve" and jerk is None and accel is not None and accel > 0:
        jerk = DEFAULT_JERK_PER_ACCEL * accel
        notes.append({"option": "--jerk", "value": jerk, "unit": f"{units}/s³",
                      "rule": f"{DEFAULT_JERK_PER_ACCEL:g} × --accel, the acceleration built up "
                              f"in {1 / DEFAULT_JERK_PER_ACCEL:g} s; set --jerk"})
    return feed, jerk, notes


def _machine_requirement(name, bound, side, units):
    """The rods' axial rigidity a machine needs for ``bound`` N/µm over a square/cube of
    ``side`` (``units``) about its home pose (:mod:`pkmkit.stiffness.arm_sizing`)."""
    if name is None and bound is None and side is None:
        return None
    if name is None or bound is None or side is None:
        raise click.UsageError("--machine, --machine-stiffness and --region go together")
    from pkmkit.design.metrics import Region
    from pkmkit.stiffness.arm_sizing import required_axial_rigidity

    from .stiffness_cmds import machine_and_data

    m, data = machine_and_data(name, (), units)
    points = Region(side * length_scale(units)).points(m, 9)
    requirement = required_axial_rigidity(m, points, bound * 1e6, data=data)
    if not requirement.feasible:
        raise InputError(f"{name}: its drives alone give {requirement.rigid_stiffness / 1e6:.6g} "
                         f"N/µm at the region's weakest pose: no arm meets {bound:g} N/µm")
    return requirement


def _fmt_pose(values) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


@click.command("arm-sizing")
@click.option("--force", "force", type=float, default=1000.0, show_default=True,
              help="Design axial force, N (|F|, tension and compression).")
@click.option("--length", "length", type=float, help="Arm length.")
@click.option("--section", type=click.Choice(["solid", "hollow"]), default="solid",
              show_default=True)
@click.option("--inner", type=float, help="Fixed bore of a hollow arm (default: optimised).")
@click.option("--diameter", type=float, help="Analyse this outer diameter instead of sizing.")
@click.option("--min-stiffness", type=float, default=0.0, help="Minimum axial stiffness, N/m.")
@click.option("--stress-safety", type=float, default=2.0, show_default=True)
@click.option("--buckling-safety", type=float, default=3.0, show_default=True)
@click.option("--transverse-accel", "transverse", type=float, default=9.81, show_default=True,
              help="Transverse acceleration of the arm (weight + inertia), m/s² whatever "
                   "--units.")
@click.option("--diameter-range", help="Bounds on the outer diameter LO,HI (length unit).")
@click.option("--density", type=float, default=7700.0, show_default=True, help="kg/m³.")
@click.option("--young", type=float, default=210e9, show_default=True, help="E, Pa.")
@click.option("--yield", "yield_strength", type=float, default=620e6, show_default=True,
              help="Yield strength, Pa.")
@click.option("--machine", "machine_name", help="A rod-leg machine whose smallest translational "
              "stiffness over --region must meet --machine-stiffness (its rods get the arm).")
@click.option("--machine-stiffness", type=float, help="Bound on the machine's smallest "
              "translational stiffness over the region, N/µm.")
@click.option("--region", "region_side", type=float, help="Side of the square/cube about the "
              "machine's home pose (length unit) for --machine-stiffness.")
@click.option("--seed-tables", "reproduce", is_flag=True,
              help="Reproduce seed 000 Tables IV.2 and IV.3 (masses at 1000 kg/m³).")
@UNITS_OPTION
@JSON_OPTION
def arm_sizing(force, length, section, inner, diameter, min_stiffness, stress_safety,
               buckling_safety, transverse, diameter_range, density, young, yield_strength,
               machine_name, machine_stiffness, region_side, reproduce, units, as_json):
    """Size (or analyse) a solid or hollow circular arm: stress, buckling, bending, mass,
    stiffness."""
    scale = length_scale(units)
    if reproduce:
        rows = seed_tables()
        if as_json:
            emit_json({"rows": rows})
            return
        for r in rows:
            click.echo(f"{r['table']:<12} {r['design']:<11} L {r['L_mm']:>5} D {r['D_mm']:>3} "
                       f"d {r['d_mm']:>3} mm: mass {r['mass_g']:9.3f} g (seed {r['seed_mass_g']}),"
                       f" F/A {r['stress_Pa']:.4g} Pa (seed {r['seed_stress_Pa']:.4g}, ratio "
                       f"{r['stress_ratio']:.3f})")
        return
    if length is None:
        raise click.UsageError("--length is required (or --seed-tables)")
    check_plausible("--young", young, "modulus")
    material = Material(E=young, density=density, yield_strength=yield_strength)
    if inner is not None and section != "hollow" and diameter is None:
        raise click.UsageError("--inner is the bore of a hollow arm: give --section hollow "
                               "(or an outer --diameter to analyse)")
    if inner is not None and not (np.isfinite(inner) and 0 <= inner * scale <= 100):
        raise InputError(f"--inner {inner:g} {units} must be a bore between 0 and "
                         f"{100 / scale:g} {units}")
    bore = None if inner is None else inner * scale
    check_plausible("--region", region_side, "length", scale=scale, unit=units)
    check_plausible("--machine-stiffness", machine_stiffness, "stiffness", scale=1e6,
                    unit="N/µm")
    if min_stiffness != 0:  # 0: no stiffness requirement
        check_plausible("--min-stiffness", min_stiffness, "stiffness")
    requirement = _machine_requirement(machine_name, machine_stiffness, region_side, units)
    if requirement is not None:
        min_stiffness = max(min_stiffness, requirement.arm_stiffness(length * scale))
    if diameter is not None:
        result = analyse_arm(length * scale, diameter * scale, bore or 0.0,
                             axial_force=-abs(force), transverse_accel=transverse,
                             material=material)
        payload = {"mode": "analysis", **result.as_dict()}
    else:
        bounds = (0.005, 0.1)
        if diameter_range:
            lo, hi = _numbers(diameter_range, (2,), "--diameter-range")
            check_each("--diameter-range", (lo, hi), (scale, scale), (units, units),
                       labels=("LO", "HI"), kind="length")
            bounds = (lo * scale, hi * scale)
        design = size_arm(axial_force=force, length=length * scale, diameter_range=bounds,
                          transverse_accel=transverse, hollow=section == "hollow",
                          inner_diameter=bore, stress_safety=stress_safety,
                          buckling_safety=buckling_safety, min_stiffness=min_stiffness,
                          material=material)
        payload = {"mode": "sizing", "feasible": design.feasible, "message": design.message,
                   "margins": design.constraints, **design.analysis.as_dict()}
    if requirement is not None:
        payload["machine_stiffness"] = {
            "machine": machine_name, "bound": requirement.bound,
            "rigid_rods": requirement.rigid_stiffness,
            "axial_rigidity": requirement.axial_rigidity,
            "worst_pose": requirement.worst_pose, "arm_stiffness": min_stiffness}
    if as_json:
        emit_json(payload)
        if payload.get("feasible") is False:
            raise InputError(payload["message"])
        return
    if requirement is not None:
        click.echo(f"  {machine_name}: smallest translational stiffness ≥ "
                   f"{requirement.bound / 1e6:.6g} N/µm over the region (rigid rods: "
                   f"{requirement.rigid_stiffness / 1e6:.6g} N/µm) needs rods of EA ≥ "
                   f"{requirement.axial_rigidity:.6g} N, binding at "
                   f"{_fmt_pose(requirement.worst_pose / scale)} {units}: arm axial stiffness ≥ "
                   f"{min_stiffness:.6g} N/m")
    for key in ("length", "outer_diameter", "inner_diameter"):
        click.echo(f"  {key} = {payload[key] / scale:.6g} {units}")
    click.echo(f"  mass {payload['mass']:.6g} kg, axial stiffness {payload['axial_stiffness']:.4g}"
               f" N/m")
    click.echo(f"  axial stress {payload['axial_stress']:.4g} Pa, bending "
               f"{payload['bending_stress']:.4g} Pa, stress safety {payload['stress_safety']:.3g}")
    click.echo(f"  Euler buckling load {payload['buckling_load']:.4g} N (safety "
               f"{payload['buckling_safety']:.3g}), mid-span deflection "
               f"{payload['deflection'] / scale:.4g} {units}")
    if payload.get("feasible") is False:
        raise InputError(payload["message"])
