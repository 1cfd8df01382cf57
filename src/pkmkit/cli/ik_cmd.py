"""``pkmkit ik``: one code path for every machine family.

Parse the pose (:mod:`pkmkit.boundary.coordinates`), solve with
:func:`pkmkit.boundary.kinematics.inverse`, judge the strokes (:mod:`.stroke_flags`), write.
Only what is shown differs by family — the fields of a single pose's report and its text — and
that is the one dispatch table :data:`FACES`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import click
import numpy as np

from pkmkit.boundary.coordinates import (
    actuator_scales,
    actuator_units,
    parse_actuators,
    parse_pose,
    pose_columns,
    pose_from_cli,
    pose_to_cli,
    pose_units,
)
from pkmkit.boundary.kinematics import InverseRows, inverse, inverse_options
from pkmkit.exceptions import InputError
from pkmkit.model.parameters import length_scale
from pkmkit.spatial.rotation import resolve_convention
from pkmkit.status import Status

from .batch import ChunkBuffers, batch_options, run_batch
from .columns import mode_column, named, require_batch_pair, status_column
from .options import (
    ANGLES_OPTION,
    JSON_OPTION,
    SET_OPTION,
    TOOL_LENGTH_OPTION,
    UNITS_OPTION,
    emit_json,
    fmt,
    resolve_machine,
)
from .pose_cmds import passive_by_name, pose_line, pose_payload
from .stroke_flags import BatchFlags, add_to_payload, finish_single, single_check


class Pose(NamedTuple):
    """One pose as given (CLI units) and in SI."""

    values: np.ndarray
    x: np.ndarray


@click.command()
@click.argument("machine_name", metavar="MACHINE")
@SET_OPTION
@click.option("--pose", help="Pose: X,Y[,Z] (translational machines), X,Y,Z,A,B,C (6-DOF; "
                             "X,Y,Z for a Verne-type module), X,Y,Z,I,J,K (tool point and axis "
                             "of a joint-chain machine).")
@click.option("--branches", help="Inverse-model branch per leg, e.g. 1,1,-1 (default: working).")
@click.option("--q0", "q0_text", help="Initial actuator coordinates for --method numeric.")
@click.option("--method", type=click.Choice(["closed", "numeric"]), default="closed",
              show_default=True, help="Closed form or the least-squares engine.")
@batch_options
@ANGLES_OPTION
@TOOL_LENGTH_OPTION
@UNITS_OPTION
@JSON_OPTION
def ik(machine_name, assignments, pose, branches, q0_text, method, input_, output, chunk_rows,
       convention, tool_length, units, as_json):
    """Inverse kinematics: actuator coordinates of a pose (or of every row of --input).

    Batch input columns: the pose, named x,y (planar machines) or x,y,z, in --units. Output
    columns: x,y[,z], the actuators (q1,q2[,q3]; `pkmkit show` names them), mode (the
    assembly mode of the solution) and status (ok, unreachable, invalid-input, ...).
    """
    require_batch_pair(pose, input_, output, "--pose")
    m = resolve_machine(machine_name, assignments, units)
    convention = resolve_convention(convention)
    options = inverse_options(
        m, method=None if method == "closed" else method, branches=parse_branches(branches),
        q0=parse_actuators(q0_text, m, units, "--q0") if q0_text else None,
        tool_length=None if tool_length is None else tool_length * length_scale(units))
    face = FACES[m.family]
    if input_ is not None:
        _batch(m, face, options, input_, output, chunk_rows, units, convention)
        return
    values = parse_pose(pose, m, "--pose", units)
    given = Pose(values, pose_from_cli(values, m, units, convention)[0])
    sol = inverse(m, given.x, **options)
    passive = None if sol.passive is None else sol.passive[0]
    check = single_check(m, sol.q[0], units, passive)
    payload = {"machine": m.id, "units": units, **face.payload(m, given, sol, units, convention,
                                                              method)}
    add_to_payload(payload, check, units)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(face.header(m, given, payload, units, convention))
    for name, value, unit in zip(m.actuator_names, sol.q[0] / actuator_scales(m, units),
                                 actuator_units(m, units), strict=True):
        click.echo(f"  {name} = {value:.9g} {unit}")
    for line in face.footer(m, sol, payload, units):
        click.echo(line)
    finish_single(check, units)


def parse_branches(text: str | None) -> list[int] | None:
    """``--branches 1,-1,1`` → ``[1, -1, 1]`` (None if not given)."""
    if text is None:
        return None
    try:
        return [int(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"--branches expects comma-separated +1/-1 values, got {text!r}") from None


def _batch(m, face: Face, options: dict[str, Any], input_: str, output: str,
           chunk_rows: int | None, units: str, convention: str) -> None:
    """Every row of ``input_``: the pose, the actuators, [A, B, C of a position-controlled
    machine given positions], [the assembly mode], the status."""
    columns = ["x", "y", "z"] if m.position_controlled else pose_columns(m)
    scales = actuator_scales(m, units)
    flags = BatchFlags(m, units)
    buffers = ChunkBuffers()  # q and the actuator columns: the same memory every chunk

    def compute(values, chunk):
        rows, n = len(values), m.n_actuators
        sol = inverse(m, pose_from_cli(values, m, units, convention),
                      out=buffers.take("q", rows, n), mode=face.mode_column, **options)
        status = flags(sol.q, sol.status, chunk, sol.passive)
        actuators = np.divide(sol.q, scales, out=buffers.take("columns", rows, n, "F"))
        out = {**named(columns, values), **named(m.actuator_names, actuators)}
        if sol.pose is not None:
            found = pose_to_cli(sol.pose, m, units, convention)
            out.update(named(["A", "B", "C"], found[:, 3:]))
        if face.mode_column:
            out["mode"] = mode_column(m, sol.mode)
        return {**out, "status": status_column(status)}, status

    run_batch(input_, output, columns, compute, chunk_rows=chunk_rows, units=units,
              column_units=pose_units(m, units, len(columns)))


# --- what each family shows of one pose ------------------------------------------------------
def _rod_payload(m, given: Pose, sol: InverseRows, units: str, convention: str,
                 method: str) -> dict[str, Any]:
    mode = int(sol.mode[0])
    return {"pose": given.x / length_scale(units), "q": sol.q[0] / actuator_scales(m, units),
            "actuators": list(m.actuator_names), "actuator_units": actuator_units(m, units),
            "branches": sol.branches, "mode": m.mode_label(mode),
            "working_mode": mode == m.working_mode, "method": method,
            "status": Status(int(sol.status[0])).label}


def _rod_header(m, given: Pose, payload: dict, units: str, convention: str) -> str:
    return f"{m.name}: pose {fmt(payload['pose'])} {units}"


def _rod_footer(m, sol: InverseRows, payload: dict, units: str) -> list[str]:
    if int(sol.mode[0]) == m.working_mode:
        return []
    mode = payload["mode"]
    return [f"  note: this configuration is in the {mode!r} assembly mode, not the working one "
            f"({m.mode_labels[0]!r}); fk returns it with --mode {mode}"]


def _full_pose_payload(m, given: Pose, sol: InverseRows, units: str, convention: str,
                       method: str) -> dict[str, Any]:
    full = given.x if sol.pose is None else sol.pose[0]
    payload = {"actuators": list(m.actuator_names), "actuator_units": actuator_units(m, units),
               "q": sol.q[0] / actuator_scales(m, units),
               "status": Status(int(sol.status[0])).label,
               "pose": pose_payload(m, full, units, convention)}
    if sol.pose is not None:  # a position alone: the orientation the rods impose
        from pkmkit.spatial.rotation import rotvec_to_matrix

        # the tilt of the platform's z axis (analysis.orientation's), from the pose just found:
        # importing pkmkit.analysis (its workspaces import scipy.ndimage) costs ≈ 0.25 s
        axis_z = rotvec_to_matrix(full[None, 3:])[0, :, 2]
        payload["tilt"] = float(np.degrees(np.arccos(np.clip(axis_z[2], -1.0, 1.0))))
    return payload


def _full_pose_header(m, given: Pose, payload: dict, units: str, convention: str) -> str:
    if "tilt" not in payload:
        return f"{m.name}: pose {pose_line(m, given.x, units, convention)}"
    found = payload["pose"]
    return (f"{m.name}: position {fmt(given.values, 9)} {units}\n"
            f"  orientation the rods impose: angles ({convention}) {fmt(found['angles'], 9)} "
            f"deg, rotation vector {fmt(found['rotation_vector'], 9)} rad; tilt "
            f"{payload['tilt']:.6g} deg")


def _chain_payload(m, given: Pose, sol: InverseRows, units: str, convention: str,
                   method: str) -> dict[str, Any]:
    return {"actuators": list(m.actuator_names), "actuator_units": actuator_units(m, units),
            "pose": given.values[:3], "tool_axis": given.x[3:],
            "q": sol.q[0] / actuator_scales(m, units),
            "passive": passive_by_name(m, sol.passive[0], units), "status": "ok"}


def _chain_header(m, given: Pose, payload: dict, units: str, convention: str) -> str:
    return (f"{m.name}: tool point {fmt(given.values[:3], 9)} {units}, tool axis "
            f"{fmt(given.x[3:], 9)}")


def _chain_footer(m, sol: InverseRows, payload: dict, units: str) -> list[str]:
    return ["  passive joints: " + ", ".join(f"{k} = {v:.6g}" for k, v in
                                             payload["passive"].items()) + f" (deg or {units})"]


def _no_footer(m, sol: InverseRows, payload: dict, units: str) -> list[str]:
    return []


class Face(NamedTuple):
    """What ``ik`` shows of a family: the single pose's report fields (after ``machine`` and
    ``units``), its text before and after the actuator lines, and whether batch output has a
    ``mode`` column."""

    payload: Any
    header: Any
    footer: Any
    mode_column: bool


#: The one family dispatch table of ``pkmkit ik``.
FACES = {
    "translational": Face(_rod_payload, _rod_header, _rod_footer, True),
    "full-pose": Face(_full_pose_payload, _full_pose_header, _no_footer, False),
    "chain": Face(_chain_payload, _chain_header, _chain_footer, False),
}
