"""``pkmkit simulate-measurements``, ``register`` and ``calibrate`` (``compensate``:
:mod:`pkmkit.cli.compensate_cmd`).

File formats: docs/calibration.md (measurement CSV files: :mod:`pkmkit.io.measurements`).
Lengths are in metres unless ``--units`` or the files say otherwise; angles in degrees.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale

from .calibration_options import CAL_UNITS_OPTION, MEASURE_OPTION
from .limits import MAX_SIMULATED, check_count, check_noise, check_tool_lengths
from .options import JSON_OPTION, emit_json, machine_document_path, resolve_machine
from .register_cmd import register_cmd

#: Smallest reading noise ``calibrate --sigma`` accepts (m).
MIN_SIGMA = 1e-12


def register(cli: click.Group) -> None:
    """Add the calibration commands to the ``pkmkit`` group."""
    cli.add_command(simulate_cmd)
    cli.add_command(register_cmd)
    cli.add_command(calibrate_cmd)


# ---------------------------------------------------------------------------- simulate
@click.command("simulate-measurements")
@click.argument("machine_name", metavar="MACHINE")
@MEASURE_OPTION
@click.option("--poses", required=True, metavar="N|FILE",
              help="Number of rows to draw in the machine's default region (docs/calibration.md"
                   "), or a CSV file of actuator coordinates (columns named as the actuators), "
                   "or for ballbar a plan (pkmkit machined-part ballbar-plan).")
@click.option("--defects", "defects_spec", default=None, metavar="FILE|random",
              help="Defects of the simulated machine: 'random' (realistic magnitudes, compatible"
                   " for hyperstatic machines; the true machine file is written beside --out) "
                   "or a file with a [defects] table. Default: none.")
@click.option("--noise", default="realistic", show_default=True,
              metavar="none|realistic|tracker|cmm|probe|ballbar|SIGMA",
              help="Noise model; SIGMA is a standard deviation in the length unit.")
@click.option("--seed", type=int, default=0, show_default=True, help="Random seed.")
@click.option("--tool-lengths", metavar="L1,L2,...",
              help="Tool lengths cycled over the rows (default: seed 002's 169.889 and 110.006 "
                   "mm for a joint-chain machine, none otherwise).")
@click.option("--frame", "frame_file", type=click.Path(dir_okay=False),
              help="A registration JSON (pkmkit register --out): point and pose readings are "
                   "written in that measurement frame.")
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False),
              help="Output measurement CSV file.")
@CAL_UNITS_OPTION
@JSON_OPTION
def simulate_cmd(machine_name, kind, poses, defects_spec, noise, seed, tool_lengths, frame_file,
                 out_file, units, as_json):
    """Synthetic measurements of a machine with defects (for tests, studies and demos)."""
    from pkmkit.calibration.registration import load_registration
    from pkmkit.calibration.simulate import random_defects, simulate
    from pkmkit.io.atomic import write_text_atomic as atomic_write_text
    from pkmkit.io.machine_defects import machine_text_with_defects
    from pkmkit.io.measurements import format_measurements
    from pkmkit.model.defect_rule import add_defects

    unit = units or "m"
    scale = length_scale(unit)
    nominal = resolve_machine(machine_name, (), "m")
    rng = np.random.default_rng(seed)
    source = machine_document_path(machine_name)
    delta = np.zeros(0)
    truth_path = None
    true = nominal
    if defects_spec == "random":
        delta = random_defects(nominal, rng)
        true = add_defects(nominal, delta)
    elif defects_spec:
        true, delta = _defects_file(defects_spec, nominal, unit)
    q = plan = None
    count = None
    if poses.strip().isdigit():
        count = int(poses)
        if count < 1:
            raise InputError("--poses must be ≥ 1")
        check_count(count, MAX_SIMULATED, "simulated measurements (--poses)",
                    "simulate in several files")
    elif kind == "ballbar":
        plan = _read_plan(poses, units)
        count = len(plan)
    else:
        if kind == "part":
            raise InputError("--poses FILE is for point, pose and height measurements and "
                             "ball-bar plans; part measurements draw their own sections: give "
                             "a number (or use pkmkit machined-part simulate)")
        q = _read_configurations(poses, nominal, units)
        count = len(q)
    noise_spec = noise
    try:
        noise_spec = float(noise) * scale
    except ValueError:
        pass
    else:
        check_noise(noise_spec, unit)
    tl = None
    if tool_lengths:
        tl = check_tool_lengths(np.asarray(_numbers(tool_lengths, "--tool-lengths")) * scale,
                                unit)
    frame = load_registration(frame_file) if frame_file else None
    if plan is not None:
        data = _simulate_plan(true, nominal, plan, rng, noise_spec, str(out_file))
    else:
        data = simulate(true, nominal, kind, count, rng, noise=noise_spec, q=q,
                        tool_lengths=tl, frame=frame, source=str(out_file))
    note = (f"pkmkit simulate-measurements {nominal.id} --measure {kind} --seed {seed} "
            f"--noise {noise}")
    texts = {}
    if defects_spec == "random":
        out = Path(out_file)
        truth_path = out.with_name(f"{out.stem}.truth{Path(source).suffix}")
        texts[truth_path] = machine_text_with_defects(
            source, nominal, delta, note=f"true machine of {out.name} (random defects, seed "
                                         f"{seed})")
        note += f"\ntrue machine: {truth_path.name}"
    texts[Path(out_file)] = format_measurements(data, nominal, units=unit, comment=note)
    for path, text in texts.items():  # everything rendered before anything is written
        atomic_write_text(path, text)
    payload = {"machine": nominal.id, "measure": kind, "rows": len(data), "out": str(out_file),
               "units": unit, "seed": seed, "noise": noise,
               "truth": None if truth_path is None else str(truth_path),
               "defects": defects_spec or "none"}
    if as_json:
        emit_json(payload)
        return
    click.echo(f"{nominal.name}: {len(data)} {kind} measurements → {out_file} ({unit})")
    if truth_path is not None:
        click.echo(f"  true machine (random defects, seed {seed}) → {truth_path}")


def _read_plan(path: str, units: str | None):
    from pkmkit.machining.ballbar_plan import read_plan

    return read_plan(path, units=units)


def _simulate_plan(true, nominal, plan, rng, noise_spec, source: str):
    """Ball-bar readings of a plan (pkmkit machined-part ballbar-plan): the nominal
    controller commands its points, the table points are where they are to ±0.2 mm."""
    from pkmkit.calibration.simulate import Noise
    from pkmkit.machining.ballbar_plan import measure_plan, true_table_points

    sigma = float(Noise.parse(noise_spec, "ballbar").position_sigma(np.zeros((1, 3)))[0])
    return measure_plan(true, nominal, plan, rng, sigma=sigma,
                        true_pivots=true_table_points(plan, rng), source=source)


def _numbers(text: str, what: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if not values or not np.isfinite(values).all():
        raise InputError(f"{what}: numbers must be finite")
    return values


def _defects_file(path: str, machine, units: str):
    """The true machine of ``--defects FILE`` and its defect vector: a complete machine file
    (with a ``[machine]`` table, e.g. a ``.truth.toml`` written by this command) *is* the true
    machine; a file with only a ``[defects]`` table (and optionally ``units``) is applied on
    top of MACHINE."""
    from pkmkit import load
    from pkmkit.exceptions import ParameterError
    from pkmkit.model.defect_rule import add_defects
    from pkmkit.model.defects_table import defects_from_table
    from pkmkit.model.machine_file import read_machine_document

    doc = read_machine_document(path)
    table = doc.data.get("defects")
    if not isinstance(table, dict):
        raise doc.error("a defects file needs a [defects] table (name = value)")
    if isinstance(doc.data.get("machine"), dict):
        true = load(path)
        if tuple(true.actuator_names) != tuple(machine.actuator_names):
            raise InputError(f"{path} describes another machine (actuators "
                             f"{', '.join(true.actuator_names)})")
        return true, np.ones(1)
    unit = doc.data.get("units", units)
    try:
        delta = defects_from_table(machine, table, length_scale(unit))
    except ParameterError as exc:
        raise doc.error(str(exc), ("defects", exc.parameter) if exc.parameter else
                        ("defects",)) from None
    return add_defects(machine, delta), delta


def _read_configurations(path: str, machine, units: str | None) -> np.ndarray:
    from pkmkit.io.measurements import actuator_columns, read_csv_table

    names, angle = actuator_columns(machine)
    table = read_csv_table(path, names, ("id",), units=units,
                           what=f" (actuators of {machine.id!r})")
    return np.column_stack([np.radians(table.numbers[n]) if a else table.numbers[n] *
                            table.scale for n, a in zip(names, angle, strict=True)])


# ---------------------------------------------------------------------------- calibrate
@click.command("calibrate")
@click.argument("machine_name", metavar="MACHINE")
@MEASURE_OPTION
@click.option("--measurements", required=True, type=click.Path(dir_okay=False),
              help="Identification measurements (CSV, docs/calibration.md).")
@click.option("--validate", "validation_file", type=click.Path(dir_okay=False),
              help="Held-out measurements of the same type.")
@click.option("--parameters", default="auto", show_default=True, metavar="auto|NAMES",
              help="'auto' (every defect; the identifiable ones are selected) or "
                   "comma-separated defect names (candidates).")
@click.option("--frame", "frame_spec", metavar="FILE|identify",
              help="Point/pose readings in another frame: a registration JSON (pkmkit "
                   "register --out), or 'identify' (6 frame parameters identified with the "
                   "machine, from the identity).")
@click.option("--identify-frame", is_flag=True,
              help="With --frame FILE: refine that frame with the machine (6 parameters).")
@click.option("--robust", is_flag=True, help="Huber loss; outliers reported by row.")
@click.option("--prior", is_flag=True,
              help="Tolerances as priors (keeps every parameter the data see, weighted).")
@click.option("--tolerance", "tolerance_items", multiple=True, metavar="NAME=VALUE",
              help="Tolerance of a defect (repeatable): lengths in the length unit, direction "
                   "components dimensionless, angles in degrees. Default 0.1 mm, 0.005, "
                   "0.29°. Scales the identifiability analysis; the prior with --prior.")
@click.option("--sigma", type=float,
              help="Standard deviation of one reading (length unit; default by type).")
@click.option("--allow-incompatible", is_flag=True,
              help="Hyperstatic machines: identify incompatible defects too (least-squares "
                   "closure, as seed 002).")
@click.option("--keep-weak", is_flag=True,
              help="Keep the parameters the stated noise would determine worse than their "
                   "tolerance (default: left at nominal as 'weakly identifiable').")
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              help="Directory for the calibrated machine file, calibration.json, residuals.csv,"
                   " figures and report.html.")
@click.option("--view/--no-view", default=True,
              help="Embed the 3-D view (machine, sliders, corrected tool error) in report.html.")
@click.option("--write-anyway", is_flag=True,
              help="Write the calibrated machine file even when the verdict fails (the exit "
                   "status is still 3).")
@CAL_UNITS_OPTION
@JSON_OPTION
def calibrate_cmd(machine_name, kind, measurements, validation_file, parameters, frame_spec,
                  identify_frame, robust, prior, tolerance_items, sigma, allow_incompatible,
                  keep_weak, out_dir, view, write_anyway, units, as_json):
    """Identify a machine's geometric defects from measurements, validate, report.

    Every calibration is judged (a-posteriori against assumed noise, condition, identified
    values against the machine's size): a failed verdict names the likely cause, writes no
    calibrated machine file (unless --write-anyway) and exits with status 3."""
    from pkmkit.calibration.diagnosis import calibrate
    from pkmkit.calibration.registration import (
        Registration,
        load_registration,
        save_registration,
    )
    from pkmkit.io.measurements import file_unit, read_measurements

    machine = resolve_machine(machine_name, (), "m")
    data = read_measurements(measurements, machine, kind, units=units)
    unit = units or file_unit(measurements) or "m"
    validation = (read_measurements(validation_file, machine, kind, units=units or unit)
                  if validation_file else None)
    frame = None
    if frame_spec == "identify":
        frame = "identify"
    elif frame_spec:
        frame = load_registration(frame_spec)
        if identify_frame:
            frame = (frame, "identify")
    elif identify_frame:
        frame = "identify"
    tolerances = _tolerances(tolerance_items, machine, unit)
    if sigma is not None:
        sigma = check_noise(sigma * length_scale(unit), unit, "--sigma")
        if not sigma >= MIN_SIGMA:
            raise InputError(f"--sigma {sigma / length_scale(unit):g} {unit}: a reading noise "
                             f"below {MIN_SIGMA / length_scale(unit):g} {unit} (1 pm) weights "
                             "the readings beyond floating-point precision")
    result = calibrate(machine, data, validation=validation, parameters=parameters,
                       frame=frame, robust=robust, prior=prior, tolerances=tolerances,
                       sigma=sigma,
                       compatible=not allow_incompatible, progress=not as_json,
                       prune=not keep_weak, file_unit=unit)
    payload = result.to_json(unit)
    passed = result.verdict is None or result.verdict.passed
    if out_dir:
        from pkmkit.plot.calibration_report import write_calibration_outputs

        sources = {"machine": machine_document_path(machine_name), "measurements": measurements}
        if validation_file:
            sources["validation"] = validation_file
        written = write_calibration_outputs(
            result, out_dir, machine_source=machine_document_path(machine_name), units=unit,
            sources=sources, measurements=data, view=view,
            machine_file=(passed or write_anyway) and result.converged)
        if result.frame is not None and frame is not None and not isinstance(frame, Registration):
            # an identified or refined frame: reusable by --frame FILE (register's format)
            target = Path(out_dir) / "frame.json"
            save_registration(target, result.frame, units=unit)
            written = {**written, "frame.json": str(target)}
        payload["files"] = written
    if as_json:
        emit_json(payload)
    else:
        _print_calibration(result, payload, unit)
        if not passed and out_dir:
            click.echo("  calibrated machine file written anyway (--write-anyway)" if write_anyway
                       and result.converged else "  no calibrated machine file written" + (
                           " (not even with --write-anyway: no convergence)" * write_anyway))
    if not passed:
        sys.exit(3)


def _tolerances(items, machine, unit: str) -> dict[str, float]:
    from pkmkit.exceptions import ParameterError
    from pkmkit.geometric_errors.model import defect_set

    dset = defect_set(machine)
    out = {}
    for text in items:
        name, sep, value = text.partition("=")
        name = name.strip()
        if not sep:
            raise ParameterError(f"--tolerance expects NAME=VALUE, got {text!r}")
        k = dset.index(name)
        try:
            v = float(value)
        except ValueError:
            raise ParameterError(f"--tolerance {name}: {value!r} is not a number", name) from None
        u = dset.units[k]
        out[name] = v * length_scale(unit) if u == "m" else (np.radians(v) if u == "rad" else v)
    return out


def with_std(value: float, std: float) -> str:
    """``value ± std`` with the standard deviation to two significant digits and the value
    rounded at the same decimal place (GUM's convention: no digit finer than the uncertainty),
    e.g. ``+0.026 ± 0.025``; ``value``'s six significant digits where ``std`` is not a positive
    finite number."""
    if not (math.isfinite(std) and std > 0.0) or not math.isfinite(value):
        return f"{value:+.6g} ± {std:.2g}"
    std_text = f"{std:.2g}"
    place = math.floor(math.log10(float(std_text))) - 1  # decimal place of std's second digit
    if -10 <= place <= 0:
        return f"{round(value, -place):+.{-place}f} ± {std:.{-place}f}"
    if 0 < place <= 15 and abs(value) < 1e16:
        return f"{round(value, -place):+.0f} ± {float(std_text):.0f}"
    digits = max(1, math.floor(math.log10(abs(value))) - place + 1) if value else 1
    return f"{value:+.{digits}g} ± {std_text}"


def _print_calibration(result, payload: dict, unit: str) -> None:
    scale = length_scale(unit)
    click.echo(f"{result.nominal.name}: {result.kind} calibration, "
               f"{payload['poses']} observations, {len(result.names)} machine + "
               f"{len(result.setup_names)} set-up parameters identified of "
               f"{result.candidates} (rank {result.rank}, condition {result.condition:.3g})")
    click.echo(f"  residual before: mean {result.before.mean / scale:.4g}, RMS "
               f"{result.before.rms / scale:.4g}, max {result.before.max / scale:.4g} {unit}")
    click.echo(f"  residual after:  mean {result.after.mean / scale:.4g}, RMS "
               f"{result.after.rms / scale:.4g}, max {result.after.max / scale:.4g} {unit}")
    if result.validation is not None:
        v = result.validation
        click.echo(f"  validation ({v.after.per_pose.size}): RMS {v.before.rms / scale:.4g} → "
                   f"{v.after.rms / scale:.4g}, max {v.before.max / scale:.4g} → "
                   f"{v.after.max / scale:.4g} {unit}")
    click.echo(f"  σ assumed {result.sigma / scale:.3g}, a posteriori "
               f"{result.sigma_posterior / scale:.3g} {unit}; {result.iterations} iterations, "
               f"{result.seconds:.2f} s")
    if not result.converged:
        click.echo("  identification did not converge: nothing identified, the residuals "
                   "are the nominal machine's (set-up fitted)")
    elif result.names or result.setup_names:
        click.echo("  identified (value ± std):")
    for n in result.names:
        click.echo(f"    {n:10s} {with_std(payload['parameters'][n], payload['std'][n])} "
                   f"{payload['parameter_units'][n]}")
    for n in result.setup_names:
        click.echo(f"    {n:10s} {with_std(payload['setup'][n], payload['setup_std'][n])}")
    click.echo(f"  left at nominal: {len(result.unidentifiable)} (see --json or report.html)")
    if result.verdict is not None:
        for line in result.verdict.lines():
            click.echo("  " + line)
    if result.outliers:
        click.echo("  outliers: " + ", ".join(f"{lab} ({err / scale:.3g} {unit})"
                                              for lab, err, _ in result.outliers))
    if "files" in payload:
        click.echo(f"  → {payload['files'].get('report.html', '')}")
