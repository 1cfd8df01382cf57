"""``pkmkit register``: rigid registration of a measurement frame to the machine frame."""

from __future__ import annotations

import click
import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.numerics.magnitudes import check_plausible

from .calibration_options import CAL_UNITS_OPTION
from .options import JSON_OPTION, emit_json, fmt


@click.command("register")
@click.option("--measured", required=True, type=click.Path(dir_okay=False),
              help="CSV of points in the measurement frame: x, y, z (optional i, j, k "
                   "directions, id).")
@click.option("--nominal", required=True, type=click.Path(dir_okay=False),
              help="CSV of the same points in the machine frame (same order, or matched by an "
                   "id column).")
@click.option("--direction-weight", type=float,
              help="Lever arm at which a direction counts like a pair of points (length unit; "
                   "default: the RMS spread of the points).")
@click.option("--out", "out_file", type=click.Path(dir_okay=False),
              help="Write the transform as JSON (for calibrate/simulate-measurements --frame).")
@CAL_UNITS_OPTION
@JSON_OPTION
def register_cmd(measured, nominal, direction_weight, out_file, units, as_json):
    """Rigid registration of a measurement frame to the machine frame (≥ 3 points, optional
    direction vectors), with residuals."""
    from pkmkit.calibration.registration import register_points, save_registration
    from pkmkit.io.measurements import read_csv_table

    a = read_csv_table(measured, ("x", "y", "z"), ("i", "j", "k", "id"), units=units)
    b = read_csv_table(nominal, ("x", "y", "z"), ("i", "j", "k", "id"), units=units)
    if a.unit != b.unit and units is None:
        raise InputError(f"measurement units mismatch: {measured} is in {a.unit}, {nominal} in "
                         f"{b.unit}; convert one or give --units")
    unit = units or a.unit
    check_plausible("--direction-weight", direction_weight, "length",
                    scale=length_scale(unit), unit=unit)
    pa, pb = (np.column_stack([t.numbers[c] for c in "xyz"]) * t.scale for t in (a, b))
    order_b = np.arange(len(pb))
    if "id" in a.texts and "id" in b.texts:
        missing = [i for i in a.texts["id"] if i not in b.texts["id"]]
        if missing:
            raise InputError(f"{nominal}: no point with id {missing[0]!r} (from {measured})")
        order_b = np.array([b.texts["id"].index(i) for i in a.texts["id"]])
    elif len(pa) != len(pb):
        raise InputError(f"{measured} has {len(pa)} points and {nominal} {len(pb)}: give the "
                         "same points in the same order (or an id column in both)")
    pb = pb[order_b]
    dirs = [all(c in t.numbers for c in "ijk") for t in (a, b)]
    if dirs[0] != dirs[1]:
        raise InputError("give directions (i, j, k) in both files or in neither")
    if direction_weight is not None and not dirs[0]:
        raise click.UsageError("--direction-weight weighs directions: the files have none "
                               "(columns i, j, k)")
    da = db = None
    if dirs[0]:
        da = np.column_stack([a.numbers[c] for c in "ijk"])
        db = np.column_stack([b.numbers[c] for c in "ijk"])[order_b]
        keep = (np.linalg.norm(da, axis=1) > 0) & (np.linalg.norm(db, axis=1) > 0)
        da, db = (da[keep], db[keep]) if keep.any() else (None, None)
    reg = register_points(pa, pb, measured_directions=da, nominal_directions=db,
                          direction_weight=None if direction_weight is None
                          else direction_weight * length_scale(unit))
    if out_file:
        save_registration(out_file, reg, units=unit)
    scale = length_scale(unit)
    payload = {"units": unit, "points": len(pa), "directions": 0 if da is None else len(da),
               **reg.to_dict(scale), "out": out_file}
    if as_json:
        emit_json(payload)
        return
    click.echo(f"registration of {len(pa)} points" + (f" and {len(da)} directions"
                                                       if da is not None else "") +
               f" ({unit}, degrees): nominal = R · measured + t")
    for row in reg.rotation:
        click.echo("  R  " + "  ".join(f"{v:12.8f}" for v in row))
    click.echo(f"  t  {fmt(reg.translation / scale, 9)} {unit}")
    click.echo(f"  rotation vector {fmt(payload['rotation_vector_deg'], 7)} deg")
    for k, r in enumerate(np.linalg.norm(reg.point_residuals, axis=1) / scale):
        click.echo(f"  point {k + 1}: residual {r:.4g} {unit}")
    click.echo(f"  rms {reg.rms / scale:.4g} {unit}, max {reg.max / scale:.4g} {unit}")
    if reg.direction_residuals.size:
        click.echo("  direction residuals: " + ", ".join(
            f"{v:.3g}°" for v in np.degrees(reg.direction_residuals)))
    if out_file:
        click.echo(f"  → {out_file}")
