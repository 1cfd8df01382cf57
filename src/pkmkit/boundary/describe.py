"""JSON-ready description of a machine (``pkmkit show``, the demo's summaries), lengths in a
unit and angles in degrees; :mod:`pkmkit.cli.describe` prints it."""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

import numpy as np

from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import length_scale
from pkmkit.model.rods import CRANK, LEG_KINDS, STRUT

from .coordinates import actuator_scales, actuator_units, pose_columns, pose_to_cli

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
    return _DESCRIBERS[m.family](m, units)


def describe_rod_machine(m: Machine, units: str = "m") -> dict[str, Any]:
    """JSON-ready description of a rod-leg machine (translational or full-pose; lengths in
    ``units``, angles in degrees): parameters, legs, home, assembly modes, mobility."""
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
        **_FAMILY_FIELDS.get(m.family, _no_fields)(m, scale),
    }


def _no_fields(m, scale: float) -> dict[str, Any]:
    return {}


def _characteristic_length(m, scale: float) -> dict[str, Any]:
    """A full-pose machine's characteristic length (homogenised Jacobian)."""
    return {"characteristic_length": m.characteristic_length / scale,
            "characteristic_length_given": m.length_given}


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


#: The description of each family (one dispatch table).
_DESCRIBERS = {"translational": describe_rod_machine, "full-pose": describe_rod_machine,
               "chain": describe_chain_machine}
#: Fields only one family has.
_FAMILY_FIELDS = {"full-pose": _characteristic_length}
