"""Text and JSON description of a machine (``pkmkit show``)."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

import click
import numpy as np

from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale
from pkmkit.model.rods import CRANK, LEG_KINDS, STRUT

from .coordinates import actuator_scales, actuator_units, pose_columns, pose_to_cli
from .options import fmt

_KIND_NAMES = {v: k for k, v in LEG_KINDS.items()}


def _parameters(m, units: str) -> list[dict[str, Any]]:
    out = []
    if m.kind is not None:
        for spec in m.kind.parameters:
            out.append({
                "name": spec.name,
                "value": spec.to_boundary(m.params[spec.name], units),
                "unit": spec.boundary_unit(units),
                "doc": spec.doc,
            })
    return out


def describe_machine(m: Machine, units: str = "m") -> dict[str, Any]:
    """JSON-ready description of ``m`` with lengths in ``units`` and angles in degrees."""
    if m.family == "chain":
        return describe_chain_machine(m, units)
    scale = length_scale(units)
    model = m.model
    parameters = _parameters(m, units)
    legs = []
    for i in range(model.n_legs):
        kind = int(model.leg_kind[i])
        legs.append({
            "name": model.leg_names[i],
            "actuator": model.actuator_names[model.leg_actuator[i]],
            "type": _KIND_NAMES[kind],
            "base": model.leg_base[i] / scale,
            "axis": model.leg_axis[i] if kind != STRUT else None,
            "pivot": model.leg_pivot[i] / scale if kind == CRANK else None,
            "platform": model.leg_platform[i] / scale,
            "length": model.leg_length[i] / scale,
            "branch": int(model.leg_branch[i]),
            "rods": int((model.rod_leg == i).sum()),
        })
    mobility = m.mobility()
    warnings = []
    freedom = mobility["instantaneous"].platform_freedom_locked
    if freedom:
        warnings.append(
            f"with the actuators locked the rods leave the platform {freedom} degree(s) of "
            "freedom (rotations): the translational model assumes joints that fix the "
            "orientation, which the rods alone do not"
        )
    return {
        "id": m.id,
        "name": m.name,
        "kind": m.kind.kind if m.kind is not None else "rod-legs",
        "description": m.description,
        "source": m.source,
        "dims": m.dims,
        "units": units,
        "pose_names": list(m.pose_names),
        "actuators": list(m.actuator_names),
        "parameters": parameters,
        "legs": legs,
        "pose_columns": pose_columns(m),
        "actuator_units": actuator_units(m, units),
        "home": {"pose": pose_to_cli(m.home_pose, m, units, "xyz")[0],
                 "q": m.home_q / actuator_scales(m, units)},
        "assembly_modes": {"working": m.mode_labels[0], "other": m.mode_labels[1],
                           "working_det_A_sign": m.working_mode},
        "reference_poses": {k: (pose_to_cli(v, m, units, "xyz")[0] if len(v) == m.dims
                                else v / scale) for k, v in m.reference_poses().items()},
        "mobility": {
            "grubler": mobility["grubler"].as_dict(),
            "instantaneous": asdict(mobility["instantaneous"]),
        },
        "warnings": warnings,
        "elastic_data": _elastic(m),
        **({"characteristic_length": m.characteristic_length / scale,
            "characteristic_length_given": m.length_given}
           if hasattr(m, "characteristic_length") else {}),
    }


def describe_chain_machine(m, units: str = "m") -> dict[str, Any]:
    """JSON-ready description of a joint-chain machine (lengths in ``units``, angles in
    degrees): elements with their invariants, legs, head, joints, hyperstatism, home."""
    scale = length_scale(units)
    model = m.model
    elements = []
    for e, spec in enumerate(model.elements):
        frame = model.frames[e]
        elements.append({"name": spec.name, "type": spec.type, "label": spec.label or spec.name,
                         "axis": frame[:3, 2], "point": frame[:3, 3] / scale,
                         "actuated": bool(spec.actuated)})
    names = model.element_names()
    count = m.hyperstatism()
    home_passive = dict(zip(m.passive_names, m.home_passive, strict=True))
    passive_out = {}
    for name, value in home_passive.items():
        kind = next(el.type for el in model.elements if el.name == name)
        passive_out[name] = float(np.degrees(value)) if kind == "R" else value / scale
    return {
        "id": m.id, "name": m.name, "kind": m.kind.kind if m.kind is not None else "joint-chain",
        "family": "joint-chain", "description": m.description, "source": m.source,
        "units": units, "pose_columns": pose_columns(m),
        "actuators": list(m.actuator_names), "actuator_units": actuator_units(m, units),
        "passive": list(m.passive_names), "parameters": _parameters(m, units),
        "elements": elements,
        "legs": {leg: [names[e] for e in chain] for leg, chain in
                 zip(model.leg_names, model.legs, strict=True)},
        "head": [names[e] for e in model.head],
        "tool_length": m.tool_length / scale,
        "characteristic_length": model.characteristic_length / scale,
        "defects": len(model.defect_index),
        "home": {"q": m.home_q / actuator_scales(m, units), "passive": passive_out,
                 "pose": pose_to_cli(m.home_pose, m, units, "xyz")[0]},
        "hyperstatism": asdict(count),
        "reference_configurations": {k: v / actuator_scales(m, units)
                                     for k, v in m.reference_poses().items()},
        "elastic_data": _elastic(m),
    }


def _elastic(m) -> dict[str, Any]:
    """The machine's elastic data for ``pkmkit stiffness`` (SI), saying what is assumed."""
    from pkmkit.stiffness import default_data

    data = default_data(m)
    return {"actuator_stiffness": data.actuator_stiffness, "notes": list(data.notes),
            "assumed": data.assumed}


def print_description(info: dict[str, Any]) -> None:
    """Human-readable form of :func:`describe_machine`'s output."""
    if info.get("family") == "joint-chain":
        _print_chain(info)
        return
    u = info["units"]
    click.echo(f"{info['id']}: {info['name']}  [{info['kind']}, {info['dims']}-D]")
    for key in ("description", "source"):
        if info[key]:
            click.echo(f"  {key}: {info[key]}")
    if info["parameters"]:
        click.echo("parameters:")
        for p in info["parameters"]:
            click.echo(f"  {p['name']:<20} = {fmt(p['value'])} {p['unit']:<4} {p['doc']}")
    click.echo("legs:")
    for leg in info["legs"]:
        axis = f" axis {fmt(leg['axis'])}" if leg["axis"] is not None else ""
        pivot = f" pivot {fmt(leg['pivot'])}" if leg.get("pivot") is not None else ""
        click.echo(
            f"  {leg['name']} ({leg['type']} {leg['actuator']}):{pivot} base "
            f"{fmt(leg['base'])}{axis} platform {fmt(leg['platform'])} length "
            f"{fmt(leg['length'])} {u} branch {leg['branch']:+d}, {leg['rods']} rod(s)"
        )
    home = info["home"]
    q_units = sorted(set(info["actuator_units"]))
    click.echo(f"home: pose ({', '.join(info['pose_columns'])}) {fmt(home['pose'])}, "
               f"{', '.join(info['actuators'])} = {fmt(home['q'])} {'/'.join(q_units)}")
    modes = info["assembly_modes"]
    click.echo(f"assembly modes: working {modes['working']!r}, other {modes['other']!r}")
    if "characteristic_length" in info:
        how = ("given" if info["characteristic_length_given"] else
               "default: the platform joints' mean radius")
        click.echo(f"characteristic length L = {fmt(info['characteristic_length'])} {u} "
                   f"({how}): J_h = diag(1, 1, 1, L, L, L) J")
    g, inst = info["mobility"]["grubler"], info["mobility"]["instantaneous"]
    joints = ", ".join(f"{n} {k}" for k, n in g["joints_by_type"].items())
    click.echo(
        f"mobility (Grübler): m = {g['motion_space']}({g['bodies']} - 1 - {g['joints']}) + "
        f"{g['joint_freedoms']} - {g['internal_mobilities']} = {g['mobility']}  "
        f"[{g['bodies']} bodies incl. base; joints: {joints}]"
    )
    click.echo(
        f"mobility (rank of the closure at home): {inst['mobility']}; "
        f"redundant constraints: {inst['redundant_constraints']}; platform freedom with "
        f"actuators locked: {inst['platform_freedom_locked']}"
    )
    for text in info["warnings"]:
        click.echo(f"warning: {text}")
    click.echo(f"reference poses ({u}, deg): " + "; ".join(
        f"{k} {fmt(v)}" for k, v in info["reference_poses"].items()))
    _print_elastic(info)


def _print_elastic(info: dict[str, Any]) -> None:
    click.echo("elastic data (pkmkit stiffness): " + "; ".join(info["elastic_data"]["notes"]))


def _print_chain(info: dict[str, Any]) -> None:
    u = info["units"]
    click.echo(f"{info['id']}: {info['name']}  [{info['kind']}, joint chains]")
    for key in ("description", "source"):
        if info[key]:
            click.echo(f"  {key}: {info[key]}")
    if info["parameters"]:
        click.echo("parameters:")
        for p in info["parameters"]:
            click.echo(f"  {p['name']:<22} = {fmt(p['value'])} {p['unit']:<4} {p['doc']}")
    click.echo(f"elements (axis I,J,K and point A,B,C in the previous frame, {u}):")
    for e in info["elements"]:
        act = " actuated" if e["actuated"] else ""
        click.echo(f"  {e['name']:<10} {e['type']}{act:<9} label {e['label']:<4} axis "
                   f"{fmt(e['axis'], 4)} point {fmt(e['point'], 6)}")
    for leg, chain in info["legs"].items():
        click.echo(f"{leg}: {' → '.join(chain)}")
    if info["head"]:
        click.echo(f"head: {' → '.join(info['head'])}; tool length {info['tool_length']:.6g} {u}")
    h = info["hyperstatism"]
    joints = ", ".join(f"{n} {k}" for k, n in h["joints_by_type"].items())
    click.echo(f"parallel part: {h['joints']} one-DOF joints ({joints}), {h['bodies']} bodies, "
               f"{h['loops']} loops; mobility {h['mobility']}; degree of hyperstatism "
               f"h = 6·{h['loops']} − {h['joints']} + {h['mobility']} = {h['hyperstatism']} "
               f"(rank test: {h['rank_hyperstatism']} redundant closure equations)")
    home = info["home"]
    click.echo(f"home: {', '.join(info['actuators'])} = {fmt(home['q'])} "
               f"({'/'.join(sorted(set(info['actuator_units'])))}); tool point and axis "
               f"{fmt(home['pose'])}")
    click.echo("  passive joints (deg or " + u + "): " + ", ".join(
        f"{k} = {v:.6g}" for k, v in home["passive"].items()))
    click.echo(f"defects: {info['defects']} (pkmkit errors {info['id']} lists them)")
    _print_elastic(info)
