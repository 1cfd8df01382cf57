"""``pkmkit machines``, ``show``, ``ik``, ``fk`` and ``jacobian``: the kinematics commands.

They are listed by :data:`pkmkit.cli.lazy.LAZY_COMMANDS` and imported when one of them runs (or
its ``--help`` is asked for), so ``pkmkit --help`` imports neither NumPy nor the machine library
(issue 22 §5). ``ik`` is one code path for every family (:mod:`pkmkit.cli.ik_cmd`); ``fk`` and
``jacobian`` of the other families are in :mod:`pkmkit.cli.pose_cmds`.
"""

from __future__ import annotations

import click
import numpy as np

from pkmkit.boundary.coordinates import actuator_scales, actuator_units, parse_actuators
from pkmkit.exceptions import InputError, PkmError
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import machine as builtin_machine
from pkmkit.machines.registry import machines as builtin_ids
from pkmkit.model.parameters import length_scale
from pkmkit.spatial.rotation import resolve_convention
from pkmkit.status import Status

from .batch import batch_options, run_batch, status_names
from .columns import named, require_batch_pair, status_column
from .describe import describe_machine, print_description
from .ik_cmd import ik
from .options import (
    ANGLES_OPTION,
    JSON_OPTION,
    SET_OPTION,
    TOOL_LENGTH_OPTION,
    UNITS_OPTION,
    emit_json,
    fmt,
    parse_vector,
    resolve_machine,
)
from .pose_cmds import fk_chain, fk_full_pose, jacobian_chain, jacobian_full_pose
from .stroke_flags import BatchFlags, add_to_payload, finish_single, hint, single_check


def register(cli: click.Group) -> None:
    """Add this module's commands to ``cli``."""
    for command in (machines_cmd, show, ik, fk, jacobian):
        cli.add_command(command, command.name)


@click.command("machines")
@JSON_OPTION
def machines_cmd(as_json: bool) -> None:
    """List the built-in machines."""
    rows = []
    for ident in builtin_ids():
        m = builtin_machine(ident)
        rows.append({"id": ident, "kind": m.kind.kind if m.kind else "rod-legs",
                     "name": m.name, "dims": m.dims, "actuators": list(m.actuator_names)})
    if as_json:
        emit_json({"machines": rows})
        return
    width = max(len(r["id"]) for r in rows)
    kind_width = max(len(r["kind"]) for r in rows)
    for r in rows:
        click.echo(f"{r['id']:<{width}}  {r['kind']:<{kind_width}}  {r['dims']}-D  {r['name']}")


@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@UNITS_OPTION
@JSON_OPTION
def show(machine_name: str, assignments, units: str, as_json: bool) -> None:
    """Describe a machine: parameters, legs, home configuration, assembly modes, mobility."""
    m = resolve_machine(machine_name, assignments, units)
    info = describe_machine(m, units)
    if as_json:
        emit_json(info)
    else:
        print_description(info)



@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--q", "q_text", help="Actuator coordinates Q1,Q2[,Q3].")
@click.option("--all", "all_modes", is_flag=True, help="Report every real assembly mode.")
@click.option("--mode", default="working", show_default=True,
              help="Assembly mode: working, other, a mode name (see `pkmkit show`), or the "
                   "sign of det A (1 or -1).")
@click.option("--x0", "x0_text", help="Initial pose for --method numeric.")
@click.option("--method", type=click.Choice(["closed", "numeric"]), default="closed",
              show_default=True, help="Closed form or the least-squares engine.")
@batch_options
@ANGLES_OPTION
@TOOL_LENGTH_OPTION
@UNITS_OPTION
@JSON_OPTION
def fk(machine_name, assignments, q_text, all_modes, mode, x0_text, method, input_, output,
       chunk_rows, convention, tool_length, units, as_json):
    """Direct kinematics: platform pose of actuator coordinates (or of every row of --input).

    Batch input columns: the actuators (q1,q2[,q3]; `pkmkit show` names them), in --units.
    Output columns: the actuators, x,y[,z], mode and status; with --all, one row per real
    assembly mode, led by `row`, the 0-based input row.
    """
    require_batch_pair(q_text, input_, output, "--q")
    m = resolve_machine(machine_name, assignments, units)
    other = _FK_OF_FAMILY.get(m.family)
    if other is not None:
        other(m, q_text, all_modes, x0_text, input_, output, chunk_rows, units,
              resolve_convention(convention), tool_length, as_json)
        return
    scale = length_scale(units)
    qs = actuator_scales(m, units)
    if input_ is not None:
        _fk_batch(m, all_modes, mode, method, input_, output, scale, chunk_rows, qs, units)
        return
    q = parse_actuators(q_text, m, units)
    x0 = parse_vector(x0_text, m.dims, "--x0", units) if x0_text else None
    check = single_check(m, q, units)
    try:
        res = m.fk(q, mode=mode, method=method, x0=x0, full_output=True, strokes="ignore")
    except PkmError as exc:  # no assembly: say first that q is beyond the strokes
        if check is not None and check.out_of_stroke[0]:
            raise InputError(f"{exc}; out of stroke: {check.message(0, units)}"
                             f"{hint(check, 0, units)}") from None
        raise
    payload = {"machine": m.id, "units": units, "q": q / qs, "pose": res.pose / scale,
               "mode": res.mode_label, "mode_sign": res.mode, "branches": res.branches,
               "method": method, "status": Status(int(res.status)).label}
    if all_modes:
        modes = m.fk_all(q)
        payload["poses"] = [modes.poses[k] / scale for k in range(2) if modes.valid[k]]
        payload["modes"] = [modes.labels[k] for k in range(2) if modes.valid[k]]
    add_to_payload(payload, check, units)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(f"{m.name}: q {fmt(q / qs)} {_units_text(m, units)}")
    click.echo(f"  pose {fmt(res.pose / scale, 9)} {units}  (mode {res.mode_label})")
    if all_modes:
        for label, p in zip(payload["modes"], payload["poses"], strict=True):
            click.echo(f"  mode {label}: {fmt(p, 9)} {units}")
    finish_single(check, units)


def _units_text(m, units: str) -> str:
    """The actuators' CLI unit, or units when they differ."""
    found = actuator_units(m, units)
    return found[0] if len(set(found)) == 1 else "(" + ", ".join(found) + ")"


def _fk_batch(m: Machine, all_modes, mode, method, input_, output, scale, chunk_rows,
              qs, units) -> None:
    from pkmkit.io.table import Labels

    flags = BatchFlags(m, units)
    if all_modes:
        def compute(values, chunk):
            modes = m.fk_all(values * qs)
            status = flags(values * qs, modes.status, chunk)
            valid = np.asarray(modes.valid)
            n = len(values)
            # one output row per real mode of each input row, one NaN row if it has none
            k_rows, c_rows = np.nonzero(valid)
            none = np.flatnonzero(~valid.any(axis=1))
            k_all = np.concatenate([k_rows, none])
            c_all = np.concatenate([c_rows, np.full(len(none), -1)])
            order = np.lexsort((c_all, k_all))
            k_all, c_all = k_all[order], c_all[order]
            pose = np.full((len(k_all), m.dims), np.nan)
            has = c_all >= 0
            pose[has] = modes.poses[k_all[has], c_all[has]] / scale
            labels = Labels(c_all + 1, ["", *modes.labels[:2]])
            return {"row": chunk.first_row + k_all, **named(m.actuator_names, values[k_all]),
                    "mode": labels, **named(m.pose_names, pose),
                    "status": status_column(status[k_all])
                    }, status[:n], k_all

        run_batch(input_, output, list(m.actuator_names), compute, chunk_rows=chunk_rows,
                  units=units, column_units=actuator_units(m, units))
        return

    def compute(values, chunk):
        res = m.fk(values * qs, mode=mode, method=method, full_output=True, strokes="ignore")
        ok = np.asarray(res.status) == Status.OK
        label = Labels(ok.astype(np.int32), ["", res.mode_label])
        status = flags(values * qs, res.status, chunk)
        return {**named(m.actuator_names, values), **named(m.pose_names, res.pose / scale),
                "mode": label, "status": status_column(status)}, status

    run_batch(input_, output, list(m.actuator_names), compute, chunk_rows=chunk_rows,
              units=units, column_units=actuator_units(m, units))


@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Pose (see `pkmkit ik --help`).")
@click.option("--q", "q_text", help="Actuator coordinates (joint-chain machines, instead of "
                                    "--pose).")
@click.option("--tol", type=float, default=1e-6, show_default=True,
              help="Threshold on the singularity measures (ratios in [0, 1]), in (0, 1).")
@batch_options
@ANGLES_OPTION
@UNITS_OPTION
@JSON_OPTION
def jacobian(machine_name, assignments, pose, q_text, tol, input_, output, chunk_rows,
             convention, units, as_json):
    """Velocity model at a pose: A, B, J, transmission factors, conditioning, singularity.

    Batch input columns: x,y[,z] in --units. Output columns: the pose, the actuators,
    sv1..svn (singular values of J), condition, det_A, det_B, J11..Jdn (row-major) and status
    (regular, serial, parallel, serial+parallel, or why the pose has no Jacobian).
    """
    if not 0 < tol < 1:  # the measures are ratios in [0, 1]: tol ≥ 1 calls every pose singular
        raise click.BadParameter(f"must lie in (0, 1), got {tol:g}: the singularity measures "
                                 "are ratios between 0 (singular) and 1", param_hint="--tol")
    m = resolve_machine(machine_name, assignments, units)
    other = _JACOBIAN_OF_FAMILY.get(m.family)
    if other is not None:
        if input_ is not None:
            raise click.UsageError("batch Jacobians are available for translational machines; "
                                   "give --pose (or --q)")
        other(m, pose, q_text, tol, units, resolve_convention(convention), as_json)
        return
    require_batch_pair(pose, input_, output, "--pose")
    if input_ is not None:
        _jacobian_batch(m, input_, output, chunk_rows, tol, units)
    else:
        _jacobian_single(m, pose, tol, units, as_json)


def _jacobian_batch(m, input_: str, output: str, chunk_rows: int, tol: float,
                    units: str) -> None:
    """``pkmkit jacobian --input --output`` of a translational machine."""
    from pkmkit.io.table import Labels
    from pkmkit.machines.results import Singularity

    scale = length_scale(units)
    qs = actuator_scales(m, units)
    n, d = m.n_actuators, m.dims
    singular = [0]
    sing_names = [Singularity(f).label for f in range(4)]
    flags = BatchFlags(m, units)

    def compute(values, chunk):
        x = values * scale
        inv = m.ik(x, full_output=True, strokes="ignore")
        jac = m.jacobian(x, q=inv.q, tol=tol)
        ok = np.asarray(inv.status) == Status.OK
        status = flags(inv.q, inv.status, chunk)
        codes = np.where(status == Status.OK, np.asarray(jac.singularity, dtype=np.int64),
                         len(sing_names) + status)
        singular[0] += int(((np.asarray(jac.singularity) != 0) & ok).sum())
        jay = np.asarray(jac.J).reshape(len(x), d * n)
        return {**named(m.pose_names, values), **named(m.actuator_names, jac.q / qs),
                **named([f"sv{i + 1}" for i in range(n)], jac.singular_values),
                "condition": jac.condition, "det_A": jac.det_A / scale**n,
                "det_B": jac.det_B / scale**n,
                **named([f"J{i + 1}{j + 1}" for i in range(d) for j in range(n)], jay),
                "status": Labels(codes, [*sing_names, *status_names()])}, status

    run_batch(input_, output, list(m.pose_names), compute, chunk_rows=chunk_rows,
              note=lambda: f" (and {singular[0]} singular rows computed)", units=units,
              column_units=[units] * m.dims)


def _jacobian_single(m, pose: str, tol: float, units: str, as_json: bool) -> None:
    """``pkmkit jacobian --pose`` of a translational machine: A, B, J and its measures."""
    scale = length_scale(units)
    qs = actuator_scales(m, units)
    x = parse_vector(pose, m.dims, "--pose", units)
    jac = m.jacobian(x, q=m.ik(x, strokes="ignore"), tol=tol)
    check = single_check(m, jac.q, units)
    n = m.n_actuators
    payload = {
        "machine": m.id, "units": units, "pose": x / scale, "q": jac.q / qs,
        "A": jac.A / scale, "B": jac.B / scale, "J": jac.J, "J_inv": jac.J_inv,
        "singular_values": jac.singular_values, "condition": jac.condition,
        "det_A": jac.det_A / scale**n, "det_B": jac.det_B / scale**n,
        "parallel_measure": jac.parallel_measure, "serial_measure": jac.serial_measure,
        "status": jac.status, "tolerance": jac.tolerance,
    }
    add_to_payload(payload, check, units, set_status=False)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(f"{m.name}: pose {fmt(x / scale)} {units}, q {fmt(jac.q / qs)} "
               f"{_units_text(m, units)}")
    for key in ("A", "B", "J"):
        click.echo(f"  {key} =")
        for row in np.atleast_2d(payload[key]):
            click.echo("    " + "  ".join(f"{v:12.6g}" for v in row))
    click.echo(f"  transmission factors (singular values of J): {fmt(jac.singular_values)}")
    click.echo(f"  condition number: {fmt(jac.condition)}   status: {jac.status}"
               f" (tolerance {tol:g})")
    finish_single(check, units)


#: ``fk`` and ``jacobian`` of the families other than translational (one table per command;
#: ``ik`` is one code path for every family, :mod:`pkmkit.cli.ik_cmd`).
_FK_OF_FAMILY = {"full-pose": fk_full_pose, "chain": fk_chain}
_JACOBIAN_OF_FAMILY = {"full-pose": jacobian_full_pose, "chain": jacobian_chain}
