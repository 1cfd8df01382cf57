"""``pkmkit errors``, ``identifiability`` and ``select-poses``: geometric error analyses.

Units at this boundary: lengths in ``--units``, angles in degrees (actuator angles, angle-like
defect sizes and tolerances), orientation components dimensionless. Region coordinates are
the tool position for rod machines and the actuator coordinates for joint-chain machines.
"""

from __future__ import annotations

import math
from pathlib import Path

import click
import numpy as np

from pkmkit.boundary.coordinates import actuator_scales, actuator_units
from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.measurements import MEASURES
from pkmkit.model.parameters import MAX_LENGTH, length_scale

from .limits import MAX_SAMPLED, check_count, check_tool_length
from .options import (
    JSON_OPTION,
    SET_OPTION,
    UNITS_OPTION,
    check_each,
    emit_json,
    fmt,
    resolve_machine,
)

DEG = math.pi / 180.0


def _region_scales(machine, units: str) -> np.ndarray:
    from pkmkit.geometric_errors.configurations import region_names

    if tuple(region_names(machine)) == tuple(machine.actuator_names):  # of actuator values
        return actuator_scales(machine, units)
    n = len(region_names(machine))
    return np.array([length_scale(units)] * 3 + [DEG] * (n - 3))


def _region_units(machine, units: str) -> list[str]:
    """The CLI unit of each region coordinate (as :func:`_region_scales`)."""
    from pkmkit.geometric_errors.configurations import region_names

    if tuple(region_names(machine)) == tuple(machine.actuator_names):
        return actuator_units(machine, units)
    return [units] * 3 + ["deg"] * (len(region_names(machine)) - 3)


def _numbers(text: str, what: str) -> np.ndarray:
    try:
        values = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if not np.isfinite(values).all():
        raise InputError(f"{what}: every value must be finite, got {text!r}")
    return values


def _region(machine, text: str | None, units: str):
    """``--region MIN,MAX,...`` in CLI units → SI (lower, upper) or None."""
    if text is None:
        return None
    values = _numbers(text, "--region")
    from pkmkit.geometric_errors.configurations import check_region, region_names

    names = region_names(machine)
    if values.size != 2 * len(names) and not (len(names) == 6 and values.size == 6):
        raise InputError(f"--region needs MIN,MAX for each of {', '.join(names)} "
                         f"({2 * len(names)} values), got {values.size}")
    k = values.size // 2
    scales = _region_scales(machine, units)[:k]
    check_each("--region", values, np.repeat(scales, 2),
               np.repeat(_region_units(machine, units)[:k], 2),
               labels=[f"{name} {end}" for name in names[:k] for end in ("MIN", "MAX")])
    bad = np.flatnonzero(~(values[0::2] < values[1::2]))
    if bad.size:
        i = int(bad[0])
        raise InputError(f"--region {names[i]}: MIN {values[2 * i]:g} is not below MAX "
                         f"{values[2 * i + 1]:g}")
    return check_region(machine, (values[0::2] * scales, values[1::2] * scales))


def _selection(parameters: str | None, exclude: str | None, kinds: str | None) -> dict:
    return {"parameters": parameters, "exclude": exclude, "kinds": kinds}


def _read_poses(machine, path: str, units: str) -> np.ndarray:
    """Actuator coordinates from a CSV file (columns named as the machine's actuators, CLI
    units); bad rows are reported and left out."""
    from pkmkit.io.csv_io import read_table

    problems: list[str] = []
    stated = ["deg" if k == "angle" else units for k in machine.actuator_quantities]
    table = read_table(path, machine.actuator_names, problems, units=stated) * actuator_scales(
        machine, units)
    for message in problems:
        click.echo(f"warning: {message} (row left out)", err=True)
    good = np.isfinite(table).all(axis=1)
    if not good.any():
        raise InputError(f"{path}: no usable row of actuator coordinates "
                         f"({', '.join(machine.actuator_names)})")
    return table[good]


def _reachable(machine, q: np.ndarray, what: str) -> np.ndarray:
    from pkmkit.geometric_errors.measurements import measure

    with np.errstate(invalid="ignore"):
        points = measure(machine, "point", q)
    ok = np.isfinite(points).all(axis=1)
    for k in np.flatnonzero(~ok)[:10]:
        click.echo(f"warning: {what} row {int(k) + 1}: the machine does not assemble at "
                   f"these actuator coordinates (row left out)", err=True)
    if not ok.any():
        raise InputError(f"{what}: the machine assembles at none of the configurations")
    return q[ok]


#: Most configurations a study samples (--poses N, --candidates N): a billion hung for hours.
MAX_STUDY_POSES = 100_000
#: Smallest relative rank tolerance: below a few ulps of double precision every singular value
#: passes and rank-deficient problems are reported full-rank (rank 30 of 30 at κ = 1.8e18).
MIN_RTOL = 1e-14


def check_rtol(rtol: float | None) -> float | None:
    """``--rtol`` in [:data:`MIN_RTOL`, 1) (None: the analysis's default)."""
    if rtol is not None and not MIN_RTOL <= rtol < 1:
        raise InputError(f"--rtol {rtol:g} is outside [{MIN_RTOL:g}, 1): below, rounding "
                         "errors of double precision pass for independent directions")
    return rtol


def _poses(machine, poses: str, units: str, region, seed: int) -> np.ndarray:
    """``--poses FILE|N``."""
    from pkmkit.geometric_errors.configurations import sample_configurations

    if poses.strip().isdigit():
        n = int(poses)
        if n < 1:
            raise InputError("--poses N needs N ≥ 1")
        check_count(n, MAX_STUDY_POSES, "configurations to sample (--poses/--candidates N)",
                    "give fewer (a few hundred poses identify what a study can)")
        return sample_configurations(machine, n, region=region, seed=seed, method="halton").q
    if not Path(poses).exists():
        raise InputError(f"--poses: {poses!r} is neither a number of poses nor an existing file")
    return _reachable(machine, _read_poses(machine, poses, units), poses)


def _setup(machine, measure: str, pivot: str | None, tool_length: float | None,
           units: str) -> dict:
    setup: dict = {}
    if pivot is not None:
        values = _numbers(pivot, "--pivot")
        if values.size != 3:
            raise InputError("--pivot needs X,Y,Z")
        if (np.abs(values * length_scale(units)) > MAX_LENGTH).any():
            raise InputError(f"--pivot {pivot}: beyond {MAX_LENGTH:g} m from the origin, check "
                             "the units")
        setup["pivot"] = values * length_scale(units)
    if tool_length is not None:
        setup["tool_length"] = tool_length * length_scale(units)
    return setup


def _length_out(values, units: str):
    return np.asarray(values, dtype=float) / length_scale(units)


SELECTION_OPTIONS = [
    click.option("--parameters", help="Defects to analyse: names, owners or patterns, "
                 "comma-separated (e.g. 'dA*,dL1'); default all."),
    click.option("--exclude", help="Defects to leave out (held at zero): names, owners or "
                 "patterns, comma-separated."),
    click.option("--kinds", help="Only these kinds of defects, comma-separated (e.g. "
                 "orientation,position; base,length)."),
]


def _selection_options(func):
    for option in reversed(SELECTION_OPTIONS):
        func = option(func)
    return func


@click.command("errors")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--compatibility", is_flag=True,
              help="Hyperstatic compatibility: defects forced to zero, remaining "
              "conditions, compatible subspace.")
@click.option("--orientation-only", is_flag=True,
              help="Compatibility of the orientation defects only (positions at zero, as "
              "the thesis).")
@click.option("--thesis", is_flag=True,
              help="Hold the first joint of the first leg nominal (the thesis's D_ICS^L11).")
@click.option("--configurations", type=click.IntRange(2, 2000), default=40,
              show_default=True, help="Configurations of the compatibility test.")
@click.option("--rtol", type=float, default=None,
              help="Relative rank tolerance (default 1e-8 compatibility).")
@click.option("--sensitivity", is_flag=True,
              help="Largest tool displacement per defect over --region.")
@click.option("--region", metavar="MIN,MAX,...",
              help="Region: tool x,y[,z] ranges (rod machines; a six-actuator machine "
              "also rx,ry,rz rotation-vector ranges in degrees) or actuator ranges "
              "(joint-chain machines), in --units and degrees.")
@click.option("--points", type=click.IntRange(1, 100000), default=200, show_default=True,
              help="Configurations drawn in the region (sensitivity).")
@click.option("--length-size", type=float, default=None,
              help="Size of length defects, in --units (default 10 µm).")
@click.option("--angle-size", type=float, default=None,
              help="Size of angle-like defects in degrees (direction components take the "
              "angle in radians); default 10 µm over the characteristic length.")
@click.option("--exact", is_flag=True, help="Sensitivity: also on the exact model.")
@click.option("--tolerance", "tolerance_file", type=click.Path(dir_okay=False),
              help="Tolerance file (TOML/YAML) for a tolerance analysis over --region.")
@click.option("--monte-carlo", "n_samples", type=click.IntRange(1, 10_000_000),
              default=None, help="Monte Carlo samples per configuration (tolerance).")
@click.option("--resolution", type=click.IntRange(2, 201), default=15, show_default=True,
              help="Accuracy-map points per side (tolerance).")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--out", "out_dir", type=click.Path(file_okay=False),
              help="Directory for figures and CSV tables.")
@_selection_options
@UNITS_OPTION
@SET_OPTION
@JSON_OPTION
def errors_cmd(machine_name, compatibility, orientation_only, thesis, configurations,
               rtol, sensitivity, region, points, length_size, angle_size, exact,
               tolerance_file, n_samples, resolution, seed, out_dir, parameters,
               exclude, kinds, units, assignments, as_json):
    """Geometric error analyses of MACHINE: its defect set (default), hyperstatic
    compatibility, sensitivity, tolerance analysis.

    JSON: the compatibility's keys at the top level (forced_zero, conditions,
    compatible_dimension, …); the sensitivity and tolerance results under "sensitivity"
    and "tolerance"."""
    m = resolve_machine(machine_name, assignments, units)
    out = Path(out_dir) if out_dir else None
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    sel = _selection(parameters, exclude, kinds)
    payload: dict = {"machine": m.id}
    if n_samples is not None and tolerance_file is None:
        raise click.UsageError("--monte-carlo needs --tolerance FILE")
    if rtol is not None and not compatibility:
        raise click.UsageError("--rtol is the rank tolerance of --compatibility")
    check_rtol(rtol)
    if n_samples is not None:
        check_count(n_samples * resolution ** 2, MAX_SAMPLED,
                    f"sampled machines ({n_samples} --monte-carlo samples at each of "
                    f"{resolution}² map points)", "lower --monte-carlo or --resolution")
    if not (compatibility or sensitivity or tolerance_file):
        payload["defects"] = _defect_rows(m)
        if as_json:
            emit_json(payload)
            return
        click.echo(f"{m.name}: {len(payload['defects'])} defects")
        for row in payload["defects"]:
            click.echo(f"  {row['name']:<8} {row['unit']:<4} {row['kind']:<12} "
                       f"{row['owner']}")
        return
    if compatibility:  # its keys at the top level ("forced_zero", "conditions", …)
        payload.update(_compatibility(m, sel, orientation_only, thesis, configurations,
                                      rtol, seed, as_json))
    region_si = _region(m, region, units)
    if sensitivity:
        payload["sensitivity"] = _sensitivity(m, sel, region_si, points, length_size,
                                              angle_size, exact, units, seed, out, as_json)
    if tolerance_file:
        payload["tolerance"] = _tolerance(m, tolerance_file, n_samples or 200, region_si,
                                          resolution, units, seed, out, as_json)
    if as_json:
        emit_json(payload)


@click.command("identifiability")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--measure", "kind", type=click.Choice(MEASURES), required=True,
              help="Measurement type.")
@click.option("--poses", required=True, metavar="FILE|N",
              help="CSV of actuator coordinates (columns named as the actuators, --units "
              "and degrees) or a number of configurations drawn in --region.")
@click.option("--region", metavar="MIN,MAX,...", help="Region for --poses N.")
@click.option("--pivot", metavar="X,Y,Z", help="Ball-bar pivot (default 0.1 L below the "
              "mean tool point).")
@click.option("--tool-length", type=float, help="Tool length (joint-chain machines).",
              callback=check_tool_length)
@click.option("--scaling", type=click.Choice(["length", "norm", "none"]), default="length",
              show_default=True, help="Column scaling of the identification Jacobian.")
@click.option("--rtol", type=float, default=1e-9, show_default=True,
              help="Relative rank tolerance.")
@click.option("--compatible", is_flag=True,
              help="Restrict the loop defects to their hyperstatic compatible subspace "
              "(each basis vector named after its free defect).")
@click.option("--seed", type=int, default=0, show_default=True)
@_selection_options
@UNITS_OPTION
@SET_OPTION
@JSON_OPTION
def identifiability_cmd(machine_name, kind, poses, region, pivot, tool_length, scaling,
                        rtol, compatible, seed, parameters, exclude, kinds, units,
                        assignments, as_json):
    """Which defects KIND measurements at the poses can identify: rank, base parameters,
    combinations, gauges, observability indices."""
    from pkmkit.geometric_errors.identifiability import identifiability

    check_rtol(rtol)
    m = resolve_machine(machine_name, assignments, units)
    q = _poses(m, poses, units, _region(m, region, units), seed)
    result = identifiability(m, kind, q, _setup(m, kind, pivot, tool_length, units),
                             scaling=scaling, rtol=rtol, compatible=compatible,
                             **_selection(parameters, exclude, kinds))
    summary = result.summary()
    if as_json:
        emit_json(summary)
        return
    click.echo(f"{m.name}: {kind} measurements at {result.n_poses} poses "
               f"({result.n_measurements} readings)")
    click.echo(f"  rank {result.rank} of {result.n_parameters} parameters "
               f"(QR: {result.rank_qr}); condition of the base parameters "
               f"{result.condition:.4g} ({scaling} scaling)")
    click.echo(f"  unidentifiable: {', '.join(result.unidentifiable) or '-'}")
    for group in result.together:
        click.echo(f"  seen only together: {', '.join(group)}")
    # coefficients in the units of the boundary: lengths in --units, angles in degrees
    unit_value = {n: length_scale(units) if u == "m" else DEG if u == "rad" else 1.0
                  for n, u in zip(result.names, result.jacobian.units, strict=True)}
    combos = [c.in_units(unit_value).text() for c in result.combinations
              if len(c.terms) > 1]
    if combos:
        click.echo("  identifiable combinations:")
        for text in combos:
            click.echo(f"    {text}")
    click.echo("  indices: " + ", ".join(f"{k} = {v:.4g}" for k, v in
                                         summary["indices"].items()))


@click.command("select-poses")
@click.argument("machine_name", metavar="MACHINE")
@click.option("--measure", "kind", type=click.Choice(MEASURES), required=True)
@click.option("--n", "n_poses", type=click.IntRange(1, 100000), required=True,
              help="Poses to choose.")
@click.option("--index", type=click.Choice(["O1", "O2", "O3", "O4", "O5"]), default="O1",
              show_default=True, help="Observability index to maximise.")
@click.option("--candidates", metavar="FILE|N", default=None,
              help="Candidate configurations (CSV) or a number drawn in --region "
              "(default max(20 n, 200)).")
@click.option("--region", metavar="MIN,MAX,...")
@click.option("--pivot", metavar="X,Y,Z")
@click.option("--tool-length", type=float, callback=check_tool_length)
@click.option("--out", "out_file", type=click.Path(dir_okay=False), required=True,
              help="CSV of the chosen actuator coordinates.")
@click.option("--seed", type=int, default=0, show_default=True)
@_selection_options
@UNITS_OPTION
@SET_OPTION
@JSON_OPTION
def select_poses_cmd(machine_name, kind, n_poses, index, candidates, region, pivot,
                     tool_length, out_file, seed, parameters, exclude, kinds, units,
                     assignments, as_json):
    """Choose N poses maximising an observability index; writes their actuator
    coordinates and reports the gain over random poses."""
    from pkmkit.geometric_errors.pose_selection import select_poses
    from pkmkit.io.csv_io import write_table

    m = resolve_machine(machine_name, assignments, units)
    region_si = _region(m, region, units)
    cand = None
    if candidates is not None:
        cand = _poses(m, candidates, units, region_si, seed)
    result = select_poses(m, kind, n_poses, candidates=cand, region=region_si,
                          setup=_setup(m, kind, pivot, tool_length, units), index=index,
                          seed=seed, **_selection(parameters, exclude, kinds))
    scales = actuator_scales(m, units)
    write_table(out_file, m.actuator_names, (result.q / scales).tolist(), units=units)
    summary = result.summary()
    summary["out"] = out_file
    if as_json:
        emit_json(summary)
        return
    click.echo(f"{m.name}: {n_poses} poses of {result.n_candidates} candidates for {kind} "
               f"measurements, {len(result.base)} identifiable combinations")
    click.echo(f"  {index} = {result.value:.4g}; random choices: median "
               f"{summary['random_median']:.4g}, best {summary['random_best']:.4g} "
               f"({summary['n_random']} draws); gain {result.gain:.3g}x")
    click.echo(f"  condition {result.indices['condition']:.4g}; wrote {out_file}")
    if result.beyond_strokes:
        click.echo(f"  {result.beyond_strokes} candidates beyond the strokes left out")


def _defect_rows(m) -> list[dict]:
    from pkmkit.geometric_errors.model import defect_set

    ds = defect_set(m)
    return [{"name": n, "unit": u, "kind": k, "owner": o}
            for n, u, k, o in zip(ds.names, ds.units, ds.kinds, ds.owners, strict=True)]


def _compatibility(m, sel, orientation_only, thesis, configurations, rtol, seed, as_json):
    from pkmkit.geometric_errors.compatibility import RTOL, compatibility

    check_rtol(rtol)
    result = compatibility(m, orientation_only=orientation_only, reference_nominal=thesis,
                           n_configurations=configurations, seed=seed,
                           rtol=rtol if rtol is not None else RTOL, **sel)
    summary = result.summary()
    if not as_json:
        click.echo(f"{m.name}: compatibility of {len(result.names)} defects over "
                   f"{result.configurations} configurations (hyperstatism {result.hyperstatism})")
        click.echo(f"  forced to zero ({len(result.forced_zero)}): "
                   f"{', '.join(result.forced_zero) or '-'}")
        click.echo(f"  other conditions ({len(result.conditions)}):")
        for c in result.conditions:
            click.echo(f"    {c.text()}")
        click.echo(f"  compatible subspace: dimension {result.compatible_dimension} of "
                   f"{len(result.names)}")
        gap = summary["singular_value_gap"]
        if not result.conditions and result.compatible_dimension == len(result.names):
            click.echo("  no closure constrains the defects (hyperstatism 0): every defect is "
                       "compatible")
            return summary
        click.echo(f"  singular values at the rank: {gap['kept']:.3g} kept, "
                   f"{gap['dropped']:.3g} dropped (ratio {gap['ratio']:.3g}"
                   f"{'' if gap['clear'] else ', NOT a clear gap'})")
    return summary


#: Defect sizes a first-order sensitivity means something for: lengths from 1 nm to a tenth of
#: the machine's size, angles from 1e-7° to 10° (beyond, 1e300 gave inf displacements and
#: 1e-300 an exact model that rounds them to 0, with exit status 0).
LENGTH_SIZE_RANGE = (1e-9, 0.1)  # m, fraction of the machine's size
ANGLE_SIZE_RANGE = (1e-7, 10.0)  # degrees


def _check_defect_sizes(m, length_size: float | None, angle_size: float | None,
                        units: str) -> None:
    """Refuse --length-size / --angle-size outside :data:`LENGTH_SIZE_RANGE` /
    :data:`ANGLE_SIZE_RANGE` (values in ``units`` and degrees)."""
    scale = length_scale(units)
    if length_size is not None:
        lo, hi = LENGTH_SIZE_RANGE[0], LENGTH_SIZE_RANGE[1] * m.length_scale
        if not lo <= length_size * scale <= hi:
            raise InputError(f"--length-size {length_size:g} {units} is outside "
                             f"[{lo / scale:g}, {hi / scale:.4g}] {units} (1 nm to a tenth of "
                             "the machine's size): a first-order sensitivity needs small "
                             "defects that the exact model still resolves")
    if angle_size is not None and not ANGLE_SIZE_RANGE[0] <= angle_size <= ANGLE_SIZE_RANGE[1]:
        raise InputError(f"--angle-size {angle_size:g}° is outside [{ANGLE_SIZE_RANGE[0]:g}, "
                         f"{ANGLE_SIZE_RANGE[1]:g}]°: a first-order sensitivity needs small "
                         "defects that the exact model still resolves")


def _sensitivity(m, sel, region, points, length_size, angle_size, exact, units, seed, out,
                 as_json):
    from pkmkit.geometric_errors.sensitivity import LENGTH_SIZE, sensitivity_analysis

    size = LENGTH_SIZE if length_size is None else length_size * length_scale(units)
    angle = None if angle_size is None else angle_size * DEG
    _check_defect_sizes(m, length_size, angle_size, units)
    table = sensitivity_analysis(m, region=region, n_points=points, length_size=size,
                                 angle_size=angle, exact=exact, seed=seed, **sel)
    rows = table.rows()
    scale = length_scale(units)
    for row in rows:
        for key in ("max_dx", "max_dy", "max_dz", "max_displacement", "exact_max_displacement"):
            if key in row:
                row[key] /= scale
        row["max_rotation_deg"] = row.pop("max_rotation") / DEG
    if out is not None:
        from pkmkit.io.csv_io import write_table
        from pkmkit.plot.error_figures import plot_sensitivity

        keys = ["name", "unit", "kind", "owner", "size", "max_dx", "max_dy", "max_dz",
                "max_displacement", "max_rotation_deg"]
        write_table(out / "sensitivity.csv", keys, [[r[k] for k in keys] for r in rows],
                    units=units)
        plot_sensitivity(table, out / "sensitivity.png", unit="um")
    if not as_json:
        click.echo(f"{m.name}: largest tool displacement over {len(table.q)} configurations "
                   f"({units}), most influential first")
        click.echo(f"  {'defect':<8} {'size (SI)':>10} {'|dx|':>10} {'|dy|':>10} {'|dz|':>10} "
                   f"{'|d|':>10}" + (f" {'exact':>10}" if exact else ""))
        for row in rows:
            line = (f"  {row['name']:<8} {row['size']:>10.3g} {row['max_dx']:>10.4g} "
                    f"{row['max_dy']:>10.4g} {row['max_dz']:>10.4g} "
                    f"{row['max_displacement']:>10.4g}")
            if exact:
                line += f" {row['exact_max_displacement']:>10.4g}"
            click.echo(line)
    return {"units": units, "configurations": len(table.q), "rows": rows}


def _tolerance(m, path, n_samples, region, resolution, units, seed, out, as_json):
    from pkmkit.geometric_errors.tolerance import accuracy_map, read_tolerances

    tol = read_tolerances(path, m)
    if not tol.active():
        raise InputError(f"{path}: every tolerance is zero; nothing to analyse")
    amap = accuracy_map(m, tol, n_samples=n_samples, resolution=resolution, region=region,
                        seed=seed)
    mc = amap.result
    scale = length_scale(units)
    overall = {f"p{k:g}": v / scale for k, v in mc.overall.items()}
    fo_map = np.nanmax(amap.rms)
    payload = {"units": units, "tolerances": path, "distribution": tol.distribution,
               "active_defects": list(tol.active()), "samples_per_point": n_samples,
               "points": int(np.isfinite(amap.exact).sum()),
               "percentile_level": amap.level,
               "exact_percentile_max": float(np.nanmax(amap.exact)) / scale,
               "exact_percentile_min": float(np.nanmin(amap.exact)) / scale,
               "first_order_percentile_max": float(np.nanmax(amap.first_order)) / scale,
               "first_order_rms_max": float(fo_map) / scale,
               "nonlinearity": mc.nonlinearity / scale,
               "failed_pairs": mc.failed, "overall_exact": overall,
               "overall_first_order": {f"p{k:g}": v / scale
                                       for k, v in mc.linear_overall.items()},
               "evaluations_per_second": mc.rate, "map_axes": list(amap.axes)}
    if out is not None:
        from pkmkit.plot.error_figures import plot_accuracy_map

        plot_accuracy_map(amap, out / "accuracy-map.png", unit="µm" if units == "m" else units,
                          position_unit=units)
        payload["figure"] = str(out / "accuracy-map.png")
    if not as_json:
        click.echo(f"{m.name}: tolerance analysis ({tol.distribution}, "
                   f"{len(tol.active())} defects with a tolerance), {payload['points']} points "
                   f"× {n_samples} samples, exact model")
        click.echo(f"  {amap.level:g}th percentile of |error| over the map: "
                   f"{fmt(payload['exact_percentile_min'])} … "
                   f"{fmt(payload['exact_percentile_max'])} {units} (first order: max "
                   f"{fmt(payload['first_order_percentile_max'])})")
        click.echo("  over every point and sample: " + ", ".join(
            f"{k.replace('p100', 'max')} {fmt(v)}" for k, v in overall.items()) + f" {units}")
        click.echo(f"  largest |exact − first order| {fmt(payload['nonlinearity'])} {units}; "
                   f"{mc.failed} pairs did not assemble; "
                   f"{mc.rate / 1e6:.3g} M evaluations/s")
        if out is not None:
            click.echo(f"  wrote {payload['figure']}")
    return payload


def register(cli: click.Group) -> None:
    """Add this module's commands to ``cli``."""
    for command in (errors_cmd, identifiability_cmd, select_poses_cmd):
        cli.add_command(command, command.name)
