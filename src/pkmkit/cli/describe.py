"""Text and JSON description of a machine (``pkmkit show``)."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

import click
import numpy as np

from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale
from pkmkit.model.rods import SLIDE

from .options import fmt


def describe_machine(m: Machine, units: str = "m") -> dict[str, Any]:
    """JSON-ready description of ``m`` with lengths in ``units`` and angles in degrees."""
    scale = length_scale(units)
    model = m.model
    parameters = []
    if m.kind is not None:
        for spec in m.kind.parameters:
            parameters.append({
                "name": spec.name,
                "value": spec.to_boundary(m.params[spec.name], units),
                "unit": spec.boundary_unit(units),
                "doc": spec.doc,
            })
    legs = []
    for i in range(model.n_legs):
        slide = model.leg_kind[i] == SLIDE
        legs.append({
            "name": model.leg_names[i],
            "actuator": model.actuator_names[model.leg_actuator[i]],
            "type": "slide" if slide else "strut",
            "base": model.leg_base[i] / scale,
            "axis": model.leg_axis[i] if slide else None,
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
        "home": {"pose": m.home_pose / scale, "q": m.home_q / scale},
        "assembly_modes": {"working": m.mode_labels[0], "other": m.mode_labels[1],
                           "working_det_A_sign": m.working_mode},
        "reference_poses": {k: v / scale for k, v in m.reference_poses().items()},
        "mobility": {
            "grubler": mobility["grubler"].as_dict(),
            "instantaneous": asdict(mobility["instantaneous"]),
        },
        "warnings": warnings,
    }


def print_description(info: dict[str, Any]) -> None:
    """Human-readable form of :func:`describe_machine`'s output."""
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
        click.echo(
            f"  {leg['name']} ({leg['type']} {leg['actuator']}): base {fmt(leg['base'])}{axis} "
            f"platform {fmt(leg['platform'])} length {fmt(leg['length'])} {u} "
            f"branch {leg['branch']:+d}, {leg['rods']} rod(s)"
        )
    home = info["home"]
    click.echo(f"home: pose {fmt(home['pose'])} {u}, {', '.join(info['actuators'])} = "
               f"{fmt(home['q'])} {u}")
    modes = info["assembly_modes"]
    click.echo(f"assembly modes: working {modes['working']!r}, other {modes['other']!r}")
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
    poses = np.array(list(info["reference_poses"].values()))
    click.echo(f"reference poses ({u}): " + "; ".join(
        f"{k} {fmt(v)}" for k, v in zip(info["reference_poses"], poses, strict=True)))
