"""The elastic data of a machine file (validated, with the line of each error).

A machine file (any family) may carry a ``[stiffness]`` table — always SI for stiffness and
moduli, file units for section dimensions::

    [stiffness]
    actuator_stiffness = 1.2e8            # N/m or N·m/rad: one value, or one per actuator
    rod_section = "circle:12"             # rods of rod-leg machines: circle:D, tube:D,d, rect:b,h
    rod_material = [210e9, 81e9]          # E, G in Pa (default steel)
    link_section = "tube:80,60"           # links of joint-chain machines
    link_material = [70e9, 26e9]
    [stiffness.links]                     # a section for one link, by its distal element
    phi1 = "tube:100,80"

and a ``rod-legs`` file may give ``actuator_stiffness`` per leg instead (legs sharing an
actuator must agree). Values missing from the file take :func:`default_data`'s.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.model.machine_file import MachineDocument, read_machine_document
from pkmkit.model.parameters import length_scale
from pkmkit.stiffness.beam import Material, parse_section
from pkmkit.stiffness.data import STIFFNESS_RANGE, StiffnessData, default_data

_KEYS = {"actuator_stiffness", "rod_section", "rod_material", "link_section", "link_material",
         "links"}


def file_data(path: str, machine: Any) -> StiffnessData:
    """The elastic data of ``machine`` as its file ``path`` gives them (defaults elsewhere).

    Raises:
        MachineFileError: an unknown key, a stiffness that is not finite and > 0, a wrong count,
            a bad section or material, naming the line.
    """
    doc = read_machine_document(path)
    data = default_data(machine)
    head = doc.data.get("machine") or {}
    scale = length_scale(head.get("units", "m")) if isinstance(head, dict) else 1.0
    notes = [n for n in data.notes]
    changes: dict[str, Any] = {}
    per_leg = _per_leg(doc, machine)
    if per_leg is not None:
        changes["actuator_stiffness"] = per_leg
        notes = [n for n in notes if "actuators" not in n] + ["actuator stiffness per leg "
                                                               "(machine file)"]
    table = doc.data.get("stiffness")
    if table is None:
        return replace(data, **changes, notes=tuple(notes))
    if not isinstance(table, dict):
        raise doc.error("[stiffness] must be a table of key = value entries", ("stiffness",))
    for key in table:
        if key not in _KEYS:
            raise doc.error(f"unknown key {key!r} in [stiffness]; valid keys: "
                            f"{', '.join(sorted(_KEYS))}", ("stiffness", key))
    where = ("stiffness", "actuator_stiffness")
    if "actuator_stiffness" in table:
        if per_leg is not None:
            raise doc.error("actuator_stiffness is given per leg and in [stiffness]: give it "
                            "once", where)
        raw = table["actuator_stiffness"]
        values = raw if isinstance(raw, list) else [raw] * machine.n_actuators
        if len(values) != machine.n_actuators:
            raise doc.error(f"[stiffness] actuator_stiffness needs 1 or {machine.n_actuators} "
                            f"values, got {len(values)}", where)
        changes["actuator_stiffness"] = _stiffness(doc, values, where)
        notes = [n for n in notes if "actuators" not in n] + ["actuator stiffness (machine "
                                                               "file)"]
    for key, word in (("rod_section", "rods"), ("link_section", "links")):
        if key in table:
            changes[key] = _section(doc, table[key], scale, ("stiffness", key))
            notes = [n for n in notes if not n.startswith(word)]
            notes.append(f"{word} {changes[key].label} (machine file)")
    for key in ("rod_material", "link_material"):
        if key in table:
            changes[key] = _material(doc, table[key], ("stiffness", key))
    if "links" in table:
        links = table["links"]
        if not isinstance(links, dict):
            raise doc.error("[stiffness.links] must map element names to sections",
                            ("stiffness", "links"))
        names = (set(machine.model.element_names()) if machine.elastic_members == "links"
                 else set())
        sections = {}
        for name, text in links.items():
            path = ("stiffness", "links", name)
            if name not in names:
                raise doc.error(f"[stiffness.links] {name!r} is not an element of this machine",
                                path)
            sections[name] = _section(doc, text, scale, path)
        changes["link_sections"] = sections
        notes.append(f"sections of {', '.join(sections)} (machine file)")
    return replace(data, **changes, notes=tuple(notes))


def _stiffness(doc: MachineDocument, values: list, where: tuple) -> np.ndarray:
    out = []
    for i, v in enumerate(values):
        ok = isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v > 0
        if not ok:
            raise doc.error(f"actuator_stiffness[{i}] must be a finite stiffness > 0 (N/m or "
                            f"N·m/rad), got {v!r}", where)
        if not STIFFNESS_RANGE[0] <= v <= STIFFNESS_RANGE[1]:
            raise doc.error(f"actuator_stiffness[{i}] = {v:g} is outside [{STIFFNESS_RANGE[0]:g}"
                            f", {STIFFNESS_RANGE[1]:g}] (N/m or N·m/rad): check the units", where)
        out.append(float(v))
    return np.array(out)


def _per_leg(doc: MachineDocument, machine: Any) -> np.ndarray | None:
    legs = doc.data.get("legs")
    if not isinstance(legs, list) or not any(isinstance(leg, dict) and "actuator_stiffness"
                                             in leg for leg in legs):
        return None
    model = machine.model
    values: dict[int, float] = {}
    for i, leg in enumerate(legs):
        where = ("legs", i, "actuator_stiffness")
        if "actuator_stiffness" not in leg:
            raise doc.error(f"legs entry {i} has no actuator_stiffness (give it for every leg "
                            "or in [stiffness])", ("legs", i))
        value = _stiffness(doc, [leg["actuator_stiffness"]], where)[0]
        act = int(model.leg_actuator[i])
        if act in values and values[act] != value:
            raise doc.error(f"legs entry {i}: actuator {model.actuator_names[act]} already has "
                            f"actuator_stiffness {values[act]:g}", where)
        values[act] = value
    return np.array([values[a] for a in range(machine.n_actuators)])


def _section(doc: MachineDocument, text: Any, scale: float, where: tuple):
    if not isinstance(text, str):
        raise doc.error(f"a section is text such as \"circle:40\", got {text!r}", where)
    try:
        return parse_section(text, scale)
    except ParameterError as exc:
        raise doc.error(str(exc), where) from None


def _material(doc: MachineDocument, value: Any, where: tuple) -> Material:
    if not (isinstance(value, list) and len(value) == 2):
        raise doc.error(f"a material is [E, G] in Pa, got {value!r}", where)
    try:
        return Material(*value)
    except (ParameterError, TypeError) as exc:
        raise doc.error(str(exc), where) from None


def machine_data(name: str, machine: Any) -> StiffnessData:
    """The elastic data of a machine named on the command line: its file's for a machine
    file, the built-in defaults otherwise."""
    from pathlib import Path

    from pkmkit.model.machine_file import SUFFIXES

    if Path(name).suffix.lower() in SUFFIXES:
        return file_data(name, machine)
    return default_data(machine)
