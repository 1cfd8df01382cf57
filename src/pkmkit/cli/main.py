"""``pkmkit`` command line: machines, show, ik, fk, jacobian, analyze, map, workspace,
useful-workspace, demo.

Every command accepts ``--help``. Lengths are in metres unless ``--units mm``; angles in degrees.
Exit codes: 0 success; 1 an error (bad input, unreachable pose, malformed file: message on
stderr); 2 a usage error; 3 a batch run that completed but flagged some rows (see the ``status``
column of the output file).
"""

from __future__ import annotations

import sys
from pathlib import Path

import click
import numpy as np

from pkmkit import __version__
from pkmkit.errors import InputError, PkmError
from pkmkit.io.csv_io import read_table, write_table
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import machine as builtin_machine
from pkmkit.machines.registry import machines as builtin_ids
from pkmkit.model.parameters import length_scale
from pkmkit.status import Status, status_labels

from .analysis_cmds import register as register_analysis_commands
from .describe import describe_machine, print_description
from .design_cmds import register as register_design_commands
from .motion_cmds import register as register_motion_commands
from .options import (
    EXIT_PARTIAL,
    JSON_OPTION,
    SET_OPTION,
    UNITS_OPTION,
    emit_json,
    fmt,
    parse_vector,
    resolve_machine,
)


class PkmGroup(click.Group):
    """Turns pkmkit's typed errors into a one-line message and exit status 1."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except PkmError as exc:
            raise click.ClickException(str(exc)) from None


@click.group(cls=PkmGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="pkmkit")
def cli() -> None:
    """pkmkit: parallel kinematic machine tools — models, kinematics, Jacobians.

    MACHINE is a built-in id (see `pkmkit machines`) or a machine file (.toml, .yaml).
    """


def _batch_options(func):
    func = click.option("--output", "output", type=click.Path(dir_okay=False),
                        help="Output CSV file (batch mode).")(func)
    func = click.option("--input", "input_", type=click.Path(dir_okay=False),
                        help="Input CSV file, one row per case (batch mode).")(func)
    return func


def _read_batch(path: str, columns, scale: float) -> np.ndarray:
    """Batch input in SI units; unreadable cells become NaN rows, reported on stderr."""
    problems: list[str] = []
    table = read_table(path, columns, problems) * scale
    for message in problems:
        click.echo(f"warning: {message} (row flagged invalid-input)", err=True)
    return table


def _finish_batch(status: np.ndarray, output: str, note: str = "") -> None:
    bad = int((status != Status.OK).sum())
    click.echo(f"wrote {len(status)} rows to {output}; {bad} flagged{note}", err=True)
    if bad:
        labels = status_labels(status)
        counts = {lab: labels.count(lab) for lab in sorted(set(labels))}
        click.echo(f"statuses: {counts}", err=True)
        sys.exit(EXIT_PARTIAL)


def _require_batch_pair(single: str | None, input_: str | None, output: str | None,
                        flag: str) -> None:
    if input_ is None and single is None:
        raise click.UsageError(f"give {flag} or --input FILE.csv --output FILE.csv")
    if input_ is not None and single is not None:
        raise click.UsageError(f"{flag} and --input are exclusive")
    if input_ is not None and output is None:
        raise click.UsageError("--input needs --output FILE.csv")


def _parse_branches(text: str | None, m: Machine):
    if text is None:
        return None
    try:
        return [int(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"--branches expects comma-separated +1/-1 values, got {text!r}") from None


@cli.command("machines")
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
    for r in rows:
        click.echo(f"{r['id']:<{width}}  {r['kind']:<13} {r['dims']}-D  {r['name']}")


@cli.command()
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


@cli.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Platform position X,Y[,Z].")
@click.option("--branches", help="Inverse-model branch per leg, e.g. 1,1,-1 (default: working).")
@click.option("--q0", "q0_text", help="Initial actuator coordinates for --method numeric.")
@click.option("--method", type=click.Choice(["closed", "numeric"]), default="closed",
              show_default=True, help="Closed form or the least-squares engine.")
@_batch_options
@UNITS_OPTION
@JSON_OPTION
def ik(machine_name, assignments, pose, branches, q0_text, method, input_, output, units,
       as_json):
    """Inverse kinematics: actuator coordinates of a pose (or of every row of --input)."""
    _require_batch_pair(pose, input_, output, "--pose")
    m = resolve_machine(machine_name, assignments, units)
    scale = length_scale(units)
    br = _parse_branches(branches, m)
    if input_ is not None:
        x = _read_batch(input_, m.pose_names, scale)
        res = m.ik(x, method=method, branches=br, full_output=True)
        header = [*m.pose_names, *m.actuator_names, "mode", "status"]
        rows = [[*(x[k] / scale), *(res.q[k] / scale),
                 m.mode_label(res.mode[k]) if res.mode[k] else "", lab]
                for k, lab in enumerate(status_labels(res.status))]
        write_table(output, header, rows)
        _finish_batch(res.status, output)
        return
    x = parse_vector(pose, m.dims, "--pose", units)
    q0 = parse_vector(q0_text, m.n_actuators, "--q0", units) if q0_text else None
    res = m.ik(x, method=method, branches=br, q0=q0, full_output=True)
    mode = m.mode_label(int(res.mode))
    payload = {"machine": m.id, "units": units, "pose": x / scale, "q": res.q / scale,
               "actuators": list(m.actuator_names), "branches": res.branches,
               "mode": mode, "working_mode": int(res.mode) == m.working_mode,
               "method": method, "status": Status(int(res.status)).label}
    if as_json:
        emit_json(payload)
    else:
        click.echo(f"{m.name}: pose {fmt(x / scale)} {units}")
        for name, value in zip(m.actuator_names, res.q / scale, strict=True):
            click.echo(f"  {name} = {value:.9g} {units}")
        if int(res.mode) != m.working_mode:
            click.echo(f"  note: this configuration is in the {mode!r} assembly mode, not the "
                       f"working one ({m.mode_labels[0]!r}); fk returns it with --mode {mode}")


@cli.command()
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
@_batch_options
@UNITS_OPTION
@JSON_OPTION
def fk(machine_name, assignments, q_text, all_modes, mode, x0_text, method, input_, output,
       units, as_json):
    """Direct kinematics: platform pose of actuator coordinates (or of every row of --input)."""
    _require_batch_pair(q_text, input_, output, "--q")
    m = resolve_machine(machine_name, assignments, units)
    scale = length_scale(units)
    if input_ is not None:
        q = _read_batch(input_, m.actuator_names, scale)
        _fk_batch(m, q, all_modes, mode, method, output, scale)
        return
    q = parse_vector(q_text, m.n_actuators, "--q", units)
    x0 = parse_vector(x0_text, m.dims, "--x0", units) if x0_text else None
    res = m.fk(q, mode=mode, method=method, x0=x0, full_output=True)
    payload = {"machine": m.id, "units": units, "q": q / scale, "pose": res.pose / scale,
               "mode": res.mode_label, "mode_sign": res.mode, "branches": res.branches,
               "method": method, "status": Status(int(res.status)).label}
    if all_modes:
        modes = m.fk_all(q)
        payload["poses"] = [modes.poses[k] / scale for k in range(2) if modes.valid[k]]
        payload["modes"] = [modes.labels[k] for k in range(2) if modes.valid[k]]
    if as_json:
        emit_json(payload)
        return
    click.echo(f"{m.name}: q {fmt(q / scale)} {units}")
    click.echo(f"  pose {fmt(res.pose / scale, 9)} {units}  (mode {res.mode_label})")
    if all_modes:
        for label, p in zip(payload["modes"], payload["poses"], strict=True):
            click.echo(f"  mode {label}: {fmt(p, 9)} {units}")


def _fk_batch(m: Machine, q, all_modes, mode, method, output, scale) -> None:
    if all_modes:
        modes = m.fk_all(q)
        header = ["row", *m.actuator_names, "mode", *m.pose_names, "status"]
        rows = []
        for k in range(q.shape[0]):
            found = [c for c in range(2) if modes.valid[k, c]]
            for c in found or [None]:
                pose = modes.poses[k, c] / scale if c is not None else [np.nan] * m.dims
                label = modes.labels[c] if c is not None else ""
                rows.append([k, *(q[k] / scale), label, *pose,
                             Status(int(modes.status[k])).label])
        write_table(output, header, rows)
        _finish_batch(modes.status, output)
        return
    res = m.fk(q, mode=mode, method=method, full_output=True)
    header = [*m.actuator_names, *m.pose_names, "mode", "status"]
    rows = [[*(q[k] / scale), *(res.pose[k] / scale),
             res.mode_label if res.status[k] == Status.OK else "", lab]
            for k, lab in enumerate(status_labels(res.status))]
    write_table(output, header, rows)
    _finish_batch(res.status, output)


@cli.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Platform position X,Y[,Z].")
@click.option("--tol", type=float, default=1e-6, show_default=True,
              help="Threshold on the singularity measures.")
@_batch_options
@UNITS_OPTION
@JSON_OPTION
def jacobian(machine_name, assignments, pose, tol, input_, output, units, as_json):
    """Velocity model at a pose: A, B, J, transmission factors, conditioning, singularity."""
    _require_batch_pair(pose, input_, output, "--pose")
    if not tol > 0:
        raise click.BadParameter("must be > 0", param_hint="--tol")
    m = resolve_machine(machine_name, assignments, units)
    scale = length_scale(units)
    if input_ is not None:
        x = _read_batch(input_, m.pose_names, scale)
        inv = m.ik(x, full_output=True)
        jac = m.jacobian(x, q=inv.q, tol=tol)
        n, d = m.n_actuators, m.dims
        header = [*m.pose_names, *m.actuator_names, *[f"sv{i + 1}" for i in range(n)],
                  "condition", "det_A", "det_B",
                  *[f"J{i + 1}{j + 1}" for i in range(d) for j in range(n)], "status"]
        labels = [lab if ok else Status(int(st)).label for lab, ok, st in
                  zip(jac.status, inv.status == Status.OK, inv.status, strict=True)]
        rows = [[*(x[k] / scale), *(jac.q[k] / scale), *jac.singular_values[k],
                 jac.condition[k], jac.det_A[k] / scale**n, jac.det_B[k] / scale**n,
                 *jac.J[k].ravel(), lab] for k, lab in enumerate(labels)]
        write_table(output, header, rows)
        singular = int(((jac.singularity != 0) & (inv.status == Status.OK)).sum())
        _finish_batch(inv.status, output, f" (and {singular} singular rows computed)")
        return
    x = parse_vector(pose, m.dims, "--pose", units)
    jac = m.jacobian(x, tol=tol)
    n = m.n_actuators
    payload = {
        "machine": m.id, "units": units, "pose": x / scale, "q": jac.q / scale,
        "A": jac.A / scale, "B": jac.B / scale, "J": jac.J, "J_inv": jac.J_inv,
        "singular_values": jac.singular_values, "condition": jac.condition,
        "det_A": jac.det_A / scale**n, "det_B": jac.det_B / scale**n,
        "parallel_measure": jac.parallel_measure, "serial_measure": jac.serial_measure,
        "status": jac.status, "tolerance": jac.tolerance,
    }
    if as_json:
        emit_json(payload)
        return
    click.echo(f"{m.name}: pose {fmt(x / scale)} {units}, q {fmt(jac.q / scale)} {units}")
    for key in ("A", "B", "J"):
        click.echo(f"  {key} =")
        for row in np.atleast_2d(payload[key]):
            click.echo("    " + "  ".join(f"{v:12.6g}" for v in row))
    click.echo(f"  transmission factors (singular values of J): {fmt(jac.singular_values)}")
    click.echo(f"  condition number: {fmt(jac.condition)}   status: {jac.status}"
               f" (tolerance {tol:g})")


@cli.command()
@click.option("--out", "out_dir", default="pkmkit-demo", show_default=True,
              type=click.Path(file_okay=False), help="Directory for the JSON and PNG files.")
@click.option("--quick", is_flag=True,
              help="Coarser grids, no refinement of the inscribed cubes and a shorter Pareto "
                   "search: every study runs, faster, with less refined numbers and figures.")
def demo(out_dir: str, quick: bool) -> None:
    """Kinematic summary and analysis of every built-in machine (text, JSON and figures)."""
    from .demo import run_demo

    try:
        run_demo(Path(out_dir), quick=quick)
    except OSError as exc:
        raise click.ClickException(f"cannot write into {out_dir}: {exc.strerror or exc}") from None


register_analysis_commands(cli)
register_design_commands(cli)
register_motion_commands(cli)


def main() -> None:
    """Console-script entry point."""
    cli(prog_name="pkmkit")


if __name__ == "__main__":  # pragma: no cover
    main()
