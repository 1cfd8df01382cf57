"""``fk`` and ``jacobian`` for full-pose (6-DOF) and joint-chain machines, and the pose fields
every family's reports share.

The translational machines' ``fk`` and ``jacobian`` live in :mod:`pkmkit.cli.main`, which
dispatches here for the other families (one table per command); ``ik`` is one code path for
every family (:mod:`pkmkit.cli.ik_cmd`). Coordinates on the command line follow
:mod:`pkmkit.boundary.coordinates`.
"""

from __future__ import annotations

from typing import Any

import click
import numpy as np

from pkmkit.boundary.coordinates import (
    actuator_scales,
    actuator_units,
    parse_actuators,
    parse_numbers,
    parse_pose,
    pose_columns,
    pose_from_cli,
    pose_to_cli,
)
from pkmkit.model.parameters import length_scale
from pkmkit.status import Status

from .batch import run_batch
from .columns import named, status_column
from .options import emit_json, fmt
from .stroke_flags import BatchFlags, add_to_payload, finish_single, hint, single_check


def pose_payload(m, pose: np.ndarray, units: str, convention: str) -> dict[str, Any]:
    """JSON fields of a full pose ``(6,)`` (position, rotation vector; SI): position, angles
    in the convention, rotation vector."""
    if m.pose_orientation != "rotvec":
        # a frame of a joint-chain machine (tool frame, platform): position and rotation
        # vector, whereas its CLI pose rows are a tool point and axis
        from pkmkit.spatial.poses import pose_to_angles

        position, angles = pose_to_angles(np.asarray(pose, dtype=float), convention,
                                          degrees=True)
        return {"position": np.ravel(position) / length_scale(units),
                "angles": np.ravel(angles), "convention": convention,
                "rotation_vector": np.asarray(pose)[3:]}
    cli = pose_to_cli(pose, m, units, convention)[0]
    return {"position": cli[:3], "angles": cli[3:], "convention": convention,
            "rotation_vector": np.asarray(pose)[3:]}


def pose_line(m, pose: np.ndarray, units: str, convention: str) -> str:
    cli = pose_to_cli(pose, m, units, convention)[0]
    return (f"position {fmt(cli[:3], 9)} {units}, angles ({convention}) {fmt(cli[3:], 9)} deg, "
            f"rotation vector {fmt(np.asarray(pose)[3:], 9)} rad")


def _passive_units(m, units: str) -> str:
    """``"deg"``, ``units`` or ``"deg or <units>"``: the units of the passive joints shown."""
    types = {next(el for el in m.model.elements if el.name == name).type
             for name in m.passive_names}
    found = [u for t, u in (("R", "deg"), ("P", units)) if t in types]
    return " or ".join(found) or "deg"


def passive_by_name(m, passive: np.ndarray, units: str) -> dict[str, float]:
    """Passive joint values in CLI units (degrees for revolutes, ``units`` for prismatic
    joints) by name."""
    out = {}
    for i, name in enumerate(m.passive_names):
        e = next(el for el in m.model.elements if el.name == name)
        value = float(passive[i])
        out[name] = float(np.degrees(value)) if e.type == "R" else value / length_scale(units)
    return out


# ------------------------------------------------------------------------------------- fk
def fk_full_pose(m, q_text, all_modes, x0_text, input_, output, chunk_rows, units, convention,
                 tool_length, as_json) -> None:
    """Direct model of a full-pose machine (single q or batch; every real mode with --all)."""
    scales = actuator_scales(m, units)
    if input_ is not None:
        _fk_full_pose_batch(m, all_modes, input_, output, chunk_rows, units, convention)
        return
    q = parse_actuators(q_text, m, units)
    payload: dict[str, Any] = {"machine": m.id, "units": units, "q": q / scales,
                               "actuators": list(m.actuator_names)}
    x0 = None
    if x0_text:
        x0 = pose_from_cli(parse_numbers(x0_text, "--x0", (6,)), m, units, convention)[0]
    check = single_check(m, q, units)
    res = _fk_or_stroke(m, q, units, check, x0=x0, full_output=True)
    payload.update({"pose": pose_payload(m, res.pose, units, convention),
                    "mode_sign": int(res.mode), "status": Status(int(res.status)).label})
    if all_modes:
        modes = m.fk_all(q)
        payload["poses"] = [pose_payload(m, modes.poses[k], units, convention)
                            for k in range(int(modes.count))]
        payload["modes"] = modes.labels
        payload["mode_signs"] = modes.mode_sign[:int(modes.count)]
        payload["all_modes_status"] = Status(int(modes.status)).label
        payload["finite_solutions"] = int(modes.n_finite)
    add_to_payload(payload, check, units)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(f"{m.name}: q {fmt(q / scales, 9)}")
    click.echo(f"  pose {pose_line(m, res.pose, units, convention)}")
    if all_modes:
        complete = {"ok": "complete", "no-assembly": "complete"}.get(
            payload["all_modes_status"], f"not certified complete: {payload['all_modes_status']}")
        click.echo(f"  {int(modes.count)} real assembly modes of {payload['finite_solutions']} "
                   f"finite complex solutions ({complete}):")
        for label, p in zip(payload["modes"], payload["poses"], strict=True):
            click.echo(f"    {label:<8} {fmt(p['position'], 6)} {units}, angles "
                       f"{fmt(p['angles'], 6)} deg")
    finish_single(check, units)


def _fk_full_pose_batch(m, all_modes, input_, output, chunk_rows, units, convention) -> None:
    scales = actuator_scales(m, units)
    columns = pose_columns(m)
    flags = BatchFlags(m, units)

    def compute(values, chunk):
        q = values * scales
        if all_modes:
            modes = m.fk_all(q)
            rows, cols = np.nonzero(modes.valid)
            poses = pose_to_cli(modes.poses[rows, cols], m, units, convention) if len(
                rows) else np.zeros((0, 6))
            from pkmkit.io.table import Labels

            labels = Labels(np.asarray([1 if c == modes.working[r] else 2
                                        for r, c in zip(rows, cols, strict=True)],
                                       dtype=np.int32), ["", "working", "other"])
            status = flags(q, modes.status, chunk)
            return {"row": chunk.first_row + rows, **named(m.actuator_names, values[rows]),
                    "mode": labels, **named(columns, poses),
                    "status": status_column(status[rows])
                    }, status, rows
        res = m.fk(q, full_output=True, strokes="ignore")
        status = flags(q, res.status, chunk)
        poses = pose_to_cli(res.pose, m, units, convention)
        return {**named(m.actuator_names, values), **named(columns, poses),
                "status": status_column(status)}, status

    run_batch(input_, output, list(m.actuator_names), compute, chunk_rows=chunk_rows,
              units=units, column_units=actuator_units(m, units))


def fk_chain(m, q_text, all_modes, x0_text, input_, output, chunk_rows, units, convention,
             tool_length, as_json) -> None:
    """Direct model of a joint-chain machine: tool point and axis, tool frame, platform,
    passive joints, closure residual (single q or batch)."""
    scales = actuator_scales(m, units)
    lengths = None if tool_length is None else tool_length * length_scale(units)
    if input_ is not None:
        _fk_chain_batch(m, lengths, input_, output, chunk_rows, units, convention)
        return
    q = parse_actuators(q_text, m, units)
    payload: dict[str, Any] = {"machine": m.id, "units": units, "q": q / scales,
                               "actuators": list(m.actuator_names)}
    if x0_text:
        raise click.UsageError("--x0 is not available for joint-chain machines")
    # the stroke check of a chain needs its passive joints: judged after the closure
    res = _fk_or_stroke(m, q, units, None, tool_length=lengths, full_output=True, x0=None)
    check = single_check(m, q, units, res.passive)
    frame = res.tool_frame
    payload.update({
        "pose": res.pose[:3] / length_scale(units), "tool_axis": res.pose[3:],
        "tool_frame": pose_payload(m, frame, units, convention),
        "platform": pose_payload(m, res.platform, units, convention),
        "passive": passive_by_name(m, res.passive, units),
        "closure_residual": float(res.closure_residual) / length_scale(units),
        "status": Status(int(res.status)).label})
    add_to_payload(payload, check, units)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(f"{m.name}: q " + ", ".join(
        f"{v:.9g} {u}" for v, u in zip(q / scales, actuator_units(m, units), strict=True)))
    click.echo(f"  tool point {fmt(payload['pose'], 9)} {units}, tool axis "
               f"{fmt(payload['tool_axis'], 9)}")
    click.echo(f"  passive joints ({_passive_units(m, units)}): " + ", ".join(
        f"{k} = {v:.6g}" for k, v in payload["passive"].items()))
    click.echo(f"  closure residual {payload['closure_residual']:.3g} {units} "
               f"({payload['status']})")
    finish_single(check, units)


def _fk_chain_batch(m, lengths, input_, output, chunk_rows, units, convention) -> None:
    scales = actuator_scales(m, units)
    columns = pose_columns(m)
    flags = BatchFlags(m, units)

    def compute(values, chunk):
        q = values * scales
        res = m.fk(q, tool_length=lengths, full_output=True, strokes="ignore")
        status = flags(q, res.status, chunk, res.passive)
        poses = pose_to_cli(res.pose, m, units, convention)
        extra = {**named([f"passive_{n}" for n in m.passive_names],
                         _passive_matrix(m, res.passive, units)),
                 "closure_residual": res.closure_residual / length_scale(units)}
        return {**named(m.actuator_names, values), **named(columns, poses), **extra,
                "status": status_column(status)}, status

    run_batch(input_, output, list(m.actuator_names), compute, chunk_rows=chunk_rows,
              units=units, column_units=actuator_units(m, units))


def _fk_or_stroke(m, q: np.ndarray, units: str, check, **options: Any):
    """``m.fk(q, strokes="ignore", **options)``; an error of a q beyond the strokes (``check``,
    None when not judged first) also says by how much and hints at ``--units mm``."""
    from pkmkit.exceptions import InputError, PkmError

    try:
        return m.fk(q, strokes="ignore", **options)
    except PkmError as exc:
        if check is not None and check.out_of_stroke[0]:
            raise InputError(f"{exc}; out of stroke: {check.message(0, units)}"
                             f"{hint(check, 0, units)}") from None
        raise


def _passive_matrix(m, passive: np.ndarray, units: str) -> np.ndarray:
    """Passive joint values ``(N, n_p)`` in CLI units: degrees for revolutes, ``units`` for
    prismatic joints."""
    out = np.array(passive, dtype=float)
    for i, name in enumerate(m.passive_names):
        if next(el for el in m.model.elements if el.name == name).type == "R":
            out[:, i] = np.degrees(out[:, i])
        else:
            out[:, i] = out[:, i] / length_scale(units)
    return out


# ------------------------------------------------------------------------------- jacobian
def jacobian_full_pose(m, pose, q_text, tol, units, convention, as_json) -> None:
    """Velocity model of a full-pose machine at one pose."""
    scales = actuator_scales(m, units)
    if pose is None:
        raise click.UsageError("give --pose")
    x = pose_from_cli(parse_pose(pose, m, "--pose", units), m, units, convention)[0]
    jac = m.jacobian(x, q=m.ik(x, strokes="ignore"), tol=tol)
    check = single_check(m, jac.q, units)
    payload = {"machine": m.id, "units": units, "q": jac.q / scales,
               "J": jac.J / _row_scales(units)[:, None] * scales[None, :],
               "J_homogeneous_singular_values": jac.singular_values,
               "condition": jac.condition,
               "translation_singular_values": jac.translation_singular_values,
               "rotation_singular_values": jac.rotation_singular_values,
               "characteristic_length": jac.characteristic_length / length_scale(units),
               "parallel_measure": jac.parallel_measure,
               "serial_measure": jac.serial_measure, "status": jac.status}
    last = (f"  translation factors {fmt(payload['translation_singular_values'])}, "
            f"rotation factors {fmt(payload['rotation_singular_values'])} rad per unit; "
            f"status: {payload['status']} (tolerance {tol:g})")
    _report_jacobian(m, payload, check, units, as_json, last)


def jacobian_chain(m, pose, q_text, tol, units, convention, as_json) -> None:
    """Velocity model of a joint-chain machine at actuator values (given, or those of a tool
    point and axis)."""
    scales = actuator_scales(m, units)
    if q_text is None and pose is None:
        raise click.UsageError("give --q Q1,...,Qn or --pose X,Y,Z,I,J,K")
    q = (parse_actuators(q_text, m, units) if q_text is not None else
         m.ik(pose_from_cli(parse_pose(pose, m, "--pose", units), m, units, convention)[0],
              strokes="ignore"))
    jac = m.jacobian(q=q)
    check = single_check(m, q, units)
    payload = {"machine": m.id, "units": units, "q": q / scales,
               "J": jac.J / _row_scales(units)[:, None] * scales[None, :],
               "singular_values": jac.singular_values, "condition": jac.condition,
               "closure_rank": int(jac.closure_rank), "expected_rank": jac.expected_rank,
               "characteristic_length": m.model.characteristic_length / length_scale(units)}
    last = (f"  closure rank {payload['closure_rank']} (at home "
            f"{payload['expected_rank']})")
    _report_jacobian(m, payload, check, units, as_json, last)


def _report_jacobian(m, payload: dict[str, Any], check, units: str, as_json: bool,
                     last: str) -> None:
    """JSON or text of a 6-row Jacobian's report (``last``: the family's closing line)."""
    add_to_payload(payload, check, units, set_status=False)
    if as_json:
        emit_json(payload)
        finish_single(check, units)
        return
    click.echo(f"{m.name}: q {fmt(payload['q'], 9)}")
    click.echo(f"  J (rows: velocity in {units}/s, angular velocity in deg/s, per unit "
               f"actuator rate in {'/'.join(sorted(set(actuator_units(m, units))))}/s) =")
    for row in payload["J"]:
        click.echo("    " + "  ".join(f"{v:12.6g}" for v in row))
    sv = payload.get("J_homogeneous_singular_values", payload.get("singular_values"))
    click.echo(f"  singular values of the homogenised J (L = "
               f"{payload['characteristic_length']:.6g} {units}): {fmt(sv)}")
    click.echo(f"  condition number: {float(payload['condition']):.6g}")
    click.echo(last)
    finish_single(check, units)


def _row_scales(units: str) -> np.ndarray:
    """SI value of one CLI unit of the twist rows: length, length, length, deg ×3."""
    length = length_scale(units)
    return np.array([length, length, length, np.pi / 180, np.pi / 180, np.pi / 180])
