"""Machine files describing joint-chain machines element by element (``kind = "joint-chain"``).

The format follows the thesis's invariants (seed 002, Table 4.2): every element — a revolute
(R) or prismatic (P) joint, or a fixed frame (F) — is placed in the frame of the element before it
by its axis ``(I, J, K)`` and a point ``(A, B, C)``; legs are ordered element lists from the base
to the platform frame (an element may be named in several legs: a shared joint), the head an
element list from the platform frame to the tool frame::

    [machine]
    kind = "joint-chain"
    units = "mm"                   # lengths; angles are in degrees
    characteristic_length = 300    # rotation-residual scale of the closures (default 0.5 m)
    tool_length = 0                # default tool length along the tool frame's z

    [[elements]]
    name = "theta1"                # the joint variable's name
    type = "R"                     # R, P or F
    axis = [0, -1, 0]              # (I, J, K) in the previous frame
    point = [0, 0, 0]              # (A, B, C), file units
    actuated = true
    home = 30                      # degrees (R) or length (P): the home configuration
    stroke = [-180, 180]

    [[legs]]
    name = "crank and rod"
    elements = ["theta1", "theta2", "theta3", "R3_RF"]

    [head]                         # optional
    elements = ["Q4", "Q5", "tool"]

    [poses]                        # optional: actuator vectors (degrees, file units)
    crank-90 = [90]

    [defects]                      # optional: dI…, dS… (degrees), da… (file units)
    dK4 = 0.001

Everything is checked on load, and every error names the file line: unknown keys or joint types,
axes of zero length, bad numbers, legs naming unknown elements, elements used by nothing, no
actuated joint, actuated joints that do not match the mobility of the legs, and home joint
values where the legs do not close (the leg that misses the platform and by how much).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import MachineFileError, ParameterError
from pkmkit.machines.chain_checks import leg_misses, miss_message
from pkmkit.machines.joint_chain import RANK_RCOND, JointChainMachine
from pkmkit.model.chains import (
    ELEMENT_TYPES,
    FIXED,
    PRISMATIC,
    REVOLUTE,
    ElementSpec,
    JointChainModel,
    build_chain_model,
)
from pkmkit.model.machine_file import KeyPath, MachineDocument
from pkmkit.model.parameters import MAX_LENGTH, length_scale, plain_floats
from pkmkit.solve.chains import chain_pose, closure, solve_closure
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix
from pkmkit.status import Status

JOINT_CHAIN = "joint-chain"
TOP_KEYS = {"machine", "elements", "legs", "head", "poses", "defects", "stiffness"}
MACHINE_KEYS = {"kind", "id", "name", "description", "source", "units",
                "characteristic_length", "tool_length"}
ELEMENT_KEYS = {"name", "type", "axis", "point", "spin", "rotation", "label", "actuated",
                "home", "stroke", "display"}
LEG_KEYS = {"name", "elements"}
TYPE_NAMES = {REVOLUTE: "revolute", PRISMATIC: "prismatic", FIXED: "fixed frame"}
#: Default rotation-residual scale of the closures (m).
DEFAULT_CHARACTERISTIC_LENGTH = 0.5


class _Reader:
    """Typed access to the document's values, raising errors at their lines."""

    def __init__(self, doc: MachineDocument, scale: float):
        self.doc = doc
        self.scale = scale

    def fail(self, message: str, path: KeyPath) -> MachineFileError:
        return self.doc.error(message, path)

    def keys(self, table: Mapping[str, Any], allowed: set[str], path: KeyPath,
             what: str) -> None:
        for key in table:
            if key not in allowed:
                raise self.fail(f"unknown key {key!r} in {what}; valid keys: "
                                f"{', '.join(sorted(allowed))}", (*path, key))

    def table(self, key: str, required: bool) -> dict[str, Any]:
        value = self.doc.data.get(key)
        if value is None:
            if required:
                raise self.fail(f"missing [{key}] table", (key,))
            return {}
        if not isinstance(value, dict):
            raise self.fail(f"[{key}] must be a table of key = value entries", (key,))
        return value

    def bounded(self, si: np.ndarray, path: KeyPath, what: str) -> None:
        """Refuse magnitudes beyond :data:`MAX_LENGTH` (m, rad or direction components):
        a unit mistake, whose squares overflow in the closure."""
        if (np.abs(si) > MAX_LENGTH).any():
            raise self.fail(f"{what}: magnitude beyond {MAX_LENGTH:g} (m, rad or direction "
                            "components): check the units", path)

    def number(self, value: Any, path: KeyPath, what: str, scale: float = 1.0) -> float:
        number = plain_floats(value)
        if number is None or number.ndim != 0 or not np.isfinite(number):
            raise self.fail(f"{what} must be a finite number, got {_short(value)}", path)
        self.bounded(number * scale, path, what)
        return float(number) * scale

    def vector(self, value: Any, size: int, path: KeyPath, what: str,
               scale: float = 1.0) -> np.ndarray:
        arr = plain_floats(value)
        if arr is None or arr.shape != (size,):
            raise self.fail(f"{what} must be {size} numbers, got {_short(value)}", path)
        self.bounded(arr * scale, path, what)
        if not np.isfinite(arr).all():
            raise self.fail(f"{what} must be {size} finite numbers, got {value!r}", path)
        return arr * scale

    def text(self, value: Any, path: KeyPath, what: str) -> str:
        if not isinstance(value, str) or not value.strip():
            raise self.fail(f"{what} must be a non-empty string, got {value!r}", path)
        return value

    def names(self, value: Any, path: KeyPath, what: str) -> list[str]:
        if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
            raise self.fail(f"{what} must be a list of element names, got {value!r}", path)
        return value


def chain_machine_from_document(doc: MachineDocument, *, machine_id: str | None = None,
                                overrides: Mapping[str, Any] | None = None
                                ) -> JointChainMachine:
    """Build a :class:`JointChainMachine` from a parsed ``joint-chain`` machine file (module
    docstring).

    Raises:
        MachineFileError: anything wrong in the file, with its line.
        ParameterError: ``overrides`` given (such a machine has no named parameters).
    """
    reader = _Reader(doc, 1.0)
    reader.keys(doc.data, TOP_KEYS, (), "a joint-chain machine file")
    head = reader.table("machine", required=True)
    reader.keys(head, MACHINE_KEYS, ("machine",), "[machine]")
    for key in ("units", "name", "description", "source", "id"):
        if key in head:
            reader.text(head[key], ("machine", key), f"[machine] {key}")
    try:
        reader.scale = length_scale(head.get("units", "m"))
    except ParameterError as exc:
        raise reader.fail(str(exc), ("machine", "units")) from None
    ident = machine_id or str(head.get("id", Path(doc.path).stem))
    if overrides:
        raise ParameterError(f"machine {ident!r} is described element by element and has no "
                             "named parameters; edit its file")
    length = reader.number(head.get("characteristic_length",
                                    DEFAULT_CHARACTERISTIC_LENGTH / reader.scale),
                           ("machine", "characteristic_length"),
                           "[machine] characteristic_length", reader.scale)
    if length <= 0:
        raise reader.fail("[machine] characteristic_length must be > 0",
                          ("machine", "characteristic_length"))
    tool_length = reader.number(head.get("tool_length", 0.0), ("machine", "tool_length"),
                                "[machine] tool_length", reader.scale)
    specs = _elements(reader)
    by_name = {s.name: i for i, s in enumerate(specs)}
    leg_names, legs = _legs(reader, by_name)
    head_names = _head(reader, by_name)
    _check_usage(reader, specs, legs, head_names)
    try:
        model = build_chain_model(specs, legs, leg_names=leg_names, head=head_names,
                                  characteristic_length=length)
    except ParameterError as exc:
        raise reader.fail(str(exc), _where(exc.parameter, by_name, leg_names)) from None
    model = _with_defects(reader, model)
    _check_home_closes(reader, model)
    text = {k: str(head.get(k, "")) for k in ("name", "description", "source")}
    machine = JointChainMachine(id=ident, name=text["name"] or ident, kind=None, params={},
                                model=model, description=text["description"],
                                source=text["source"], tool_length=tool_length)
    _check_mobility(reader, machine, specs)
    poses = _poses(reader, machine)
    if poses:
        from dataclasses import replace

        machine = replace(machine, extra_poses=poses)
    return machine


def _where(parameter: str | None, by_name: Mapping[str, int], leg_names: list[str]) -> KeyPath:
    if parameter in by_name:
        return ("elements", by_name[parameter])
    if parameter in leg_names:
        return ("legs", leg_names.index(parameter))
    if parameter == "head":
        return ("head", "elements")
    return ("machine",)


def _elements(reader: _Reader) -> list[ElementSpec]:
    raw = reader.doc.data.get("elements")
    if not isinstance(raw, list) or not raw:
        raise reader.fail("a joint-chain machine needs [[elements]] entries (its joints and "
                          "fixed frames)", ("elements",))
    specs: list[ElementSpec] = []
    seen: dict[str, int] = {}
    for i, entry in enumerate(raw):
        path: KeyPath = ("elements", i)
        if not isinstance(entry, dict):
            raise reader.fail(f"elements entry {i} must be a table", path)
        reader.keys(entry, ELEMENT_KEYS, path, f"elements entry {i}")
        if "name" not in entry:
            raise reader.fail(f"elements entry {i} needs a name", path)
        name = reader.text(entry["name"], (*path, "name"), "an element's name")
        if name in seen:
            raise reader.fail(f"element {name!r} is defined twice (first as elements entry "
                              f"{seen[name]})", (*path, "name"))
        seen[name] = i
        specs.append(_element(reader, entry, path, name))
    return specs


def _element(reader: _Reader, entry: Mapping[str, Any], path: KeyPath, name: str
             ) -> ElementSpec:
    what = f"element {name!r}"
    kind = entry.get("type")
    if kind not in ELEMENT_TYPES:
        valid = ", ".join(f"{k} ({v})" for k, v in TYPE_NAMES.items())
        raise reader.fail(f"{what}: unknown joint type {kind!r}; valid types: {valid}",
                          (*path, "type"))
    fields: dict[str, Any] = {"name": name, "type": kind}
    if "rotation" in entry:
        fields["rotation"] = _element_rotation(reader, entry, path, what, kind)
    if "axis" in entry:
        axis = reader.vector(entry["axis"], 3, (*path, "axis"), f"{what}: axis")
        if not np.linalg.norm(axis) > 1e-12:
            raise reader.fail(f"{what}: the axis {entry['axis']!r} has zero length",
                              (*path, "axis"))
        fields["axis"] = tuple(axis / np.linalg.norm(axis))
    elif kind != FIXED:
        raise reader.fail(f"{what}: a joint needs an 'axis' (I, J, K)", path)
    if "point" in entry:
        fields["point"] = tuple(reader.vector(entry["point"], 3, (*path, "point"),
                                              f"{what}: point", reader.scale))
    if "spin" in entry:
        fields["spin"] = math.radians(reader.number(entry["spin"], (*path, "spin"),
                                                    f"{what}: spin"))
    for key in ("label", "display"):
        if key in entry:
            fields[key] = reader.text(entry[key], (*path, key), f"{what}: {key}")
    if "actuated" in entry:
        if not isinstance(entry["actuated"], bool):
            raise reader.fail(f"{what}: actuated must be true or false",
                              (*path, "actuated"))
        if entry["actuated"] and kind == FIXED:
            raise reader.fail(f"{what}: a fixed frame cannot be actuated", (*path, "actuated"))
        fields["actuated"] = entry["actuated"]
    fields.update(_element_range(reader, entry, path, what, kind))
    return ElementSpec(**fields)


def _element_rotation(reader: _Reader, entry: Mapping[str, Any], path: KeyPath, what: str,
                      kind: str) -> tuple:
    """A fixed frame's ``rotation``: 3 rows of 3 numbers forming a rotation matrix."""
    if kind != FIXED:
        raise reader.fail(f"{what}: 'rotation' places fixed frames (type F); a joint is "
                          "placed by its axis", (*path, "rotation"))
    if "axis" in entry or "spin" in entry:
        raise reader.fail(f"{what}: give either 'axis' (and 'spin') or 'rotation', not "
                          "both", (*path, "rotation"))
    rot = plain_floats(entry["rotation"])
    if rot is None or rot.shape != (3, 3):
        raise reader.fail(f"{what}: rotation must be 3 rows of 3 numbers",
                          (*path, "rotation"))
    # entries of a rotation lie in [-1, 1] (beyond, R^T R may overflow)
    if (not np.isfinite(rot).all() or np.abs(rot).max() > 1.0 + 1e-6
            or np.abs(rot.T @ rot - np.eye(3)).max() > 1e-6
            or np.linalg.det(rot) < 0):
        raise reader.fail(f"{what}: rotation must be a rotation matrix (orthonormal, "
                          "det +1)", (*path, "rotation"))
    return tuple(map(tuple, rot))


def _element_range(reader: _Reader, entry: Mapping[str, Any], path: KeyPath, what: str,
                   kind: str) -> dict[str, Any]:
    """A joint's ``home`` and ``stroke`` (degrees for revolute joints, the file's length
    unit for prismatic ones), the home within the stroke; a fixed frame has neither."""
    fields: dict[str, Any] = {}
    joint_scale = math.pi / 180.0 if kind == REVOLUTE else reader.scale
    for key in ("home", "stroke"):
        if key in entry and kind == FIXED:
            raise reader.fail(f"{what}: a fixed frame has no {key}", (*path, key))
    if "home" in entry:
        fields["home"] = reader.number(entry["home"], (*path, "home"), f"{what}: home",
                                       joint_scale)
    if "stroke" in entry:
        lo, hi = reader.vector(entry["stroke"], 2, (*path, "stroke"), f"{what}: stroke",
                               joint_scale)
        if not lo < hi:
            raise reader.fail(f"{what}: stroke must be [min, max] with min < max",
                              (*path, "stroke"))
        fields["stroke"] = (float(lo), float(hi))
        if "home" in fields and not lo <= fields["home"] <= hi:
            raise reader.fail(f"{what}: home {entry['home']} lies outside the stroke "
                              f"{entry['stroke']}", (*path, "home"))
    return fields


def _legs(reader: _Reader, by_name: Mapping[str, int]) -> tuple[list[str], list[list[str]]]:
    raw = reader.doc.data.get("legs")
    if not isinstance(raw, list) or not raw:
        raise reader.fail("a joint-chain machine needs [[legs]] entries (each a name and the "
                          "list of its elements from the base to the platform)", ("legs",))
    names, legs = [], []
    for i, entry in enumerate(raw):
        path: KeyPath = ("legs", i)
        if not isinstance(entry, dict):
            raise reader.fail(f"legs entry {i} must be a table", path)
        reader.keys(entry, LEG_KEYS, path, f"legs entry {i}")
        name = reader.text(entry.get("name", f"leg {i + 1}"), (*path, "name"), "a leg's name")
        if name in names:
            raise reader.fail(f"two legs are named {name!r}", (*path, "name"))
        if "elements" not in entry:
            raise reader.fail(f"{name} needs 'elements' (its elements from the base to the "
                              "platform)", path)
        chain = reader.names(entry["elements"], (*path, "elements"), f"{name}: elements")
        _check_chain(reader, chain, by_name, (*path, "elements"), name)
        names.append(name)
        legs.append(chain)
    return names, legs


def _check_chain(reader: _Reader, chain: list[str], by_name: Mapping[str, int], path: KeyPath,
                 what: str) -> None:
    if not chain:
        raise reader.fail(f"{what} has no element", path)
    for element in chain:
        if element not in by_name:
            raise reader.fail(f"{what} names an unknown element {element!r}; elements: "
                              f"{', '.join(by_name)}", path)
    repeated = sorted({e for e in chain if chain.count(e) > 1})
    if repeated:
        raise reader.fail(f"{what} names {', '.join(repeated)} twice", path)


def _head(reader: _Reader, by_name: Mapping[str, int]) -> list[str]:
    table = reader.table("head", required=False)
    if not table:
        return []
    reader.keys(table, {"elements"}, ("head",), "[head]")
    chain = reader.names(table.get("elements", []), ("head", "elements"), "[head] elements")
    if chain:
        _check_chain(reader, chain, by_name, ("head", "elements"), "the head")
    return chain


def _check_usage(reader: _Reader, specs: list[ElementSpec], legs: list[list[str]],
                 head: list[str]) -> None:
    used = {e for leg in legs for e in leg} | set(head)
    for i, spec in enumerate(specs):
        if spec.name not in used:
            raise reader.fail(f"element {spec.name!r} is used by no leg and not by the head",
                              ("elements", i))
    in_legs = {e for leg in legs for e in leg}
    for name in head:
        if name in in_legs:
            raise reader.fail(f"element {name!r} is in a leg and in the head; the head starts "
                              "at the platform frame", ("head", "elements"))
    if not any(s.actuated for s in specs):
        raise reader.fail("no element is actuated: mark the driven joints with "
                          "actuated = true", ("elements",))


def _with_defects(reader: _Reader, model: JointChainModel) -> JointChainModel:
    table = reader.table("defects", required=False)
    if not table:
        return model
    values = {}
    index = model.defect_index
    for name, raw in table.items():
        path: KeyPath = ("defects", name)
        try:
            i = index.index(name)
        except ParameterError as exc:
            raise reader.fail(str(exc), path) from None
        kind = index.kind[i]
        scale = (reader.scale if kind == "position" else
                 math.pi / 180.0 if kind == "spin" else 1.0)
        values[name] = reader.number(raw, path, f"defect {name}", scale)
    try:
        return model.with_defects(values)
    except ParameterError as exc:
        raise reader.fail(str(exc), ("defects",)) from None


def _check_home_closes(reader: _Reader, model: JointChainModel) -> None:
    """The legs must close at the home values (exactly; in least squares with defects)."""
    values = model.home.copy()
    passive = np.flatnonzero(~model.actuated & model.loop_variables)
    start = chain_pose(model, model.legs[0], values[:, None])
    u0 = np.concatenate([start.p[:, 0], matrix_to_rotvec(start.R[:, :, 0])[0],
                         values[passive]])[None]
    res = solve_closure(model, values[None], u0, unknown_variables=passive, compute_rank=False)
    status = int(res.status[0])
    if status == Status.OK or (status == Status.INCONSISTENT and model.defects.any()):
        return
    values[passive] = res.u[0, 6:]
    trans, rot = leg_misses(model, values[None], res.u[:, :6])
    leg, text = miss_message(model, trans[0], rot[0])
    raise reader.fail(
        f"the legs do not close at the home joint values: {text} (largest closure residual "
        f"{res.residual[0] / reader.scale:.4g} {_unit_name(reader.scale)}); check the "
        "geometry and the home values of the joints", ("legs", leg))


def _unit_name(scale: float) -> str:
    return "mm" if scale == 1e-3 else "m"


def _check_mobility(reader: _Reader, machine: JointChainMachine,
                    specs: list[ElementSpec]) -> None:
    """The actuated joints of the legs must match the legs' mobility and fix every passive
    joint and the platform (at home)."""
    model = machine.model
    loop_act = [i for i in np.flatnonzero(model.actuated) if model.loop_variables[i]]
    first = next(i for i, s in enumerate(specs) if s.actuated)
    where: KeyPath = ("elements", first, "actuated")
    mobility = machine.hyperstatism().mobility
    names = ", ".join(model.variables[i] for i in loop_act) or "none"
    if len(loop_act) != mobility:
        raise reader.fail(
            f"the legs have {mobility} degree(s) of freedom at home but {len(loop_act)} "
            f"actuated joint(s) ({names}): the direct model needs exactly one actuator per "
            "degree of freedom", where)
    passive = np.flatnonzero(~model.actuated & model.loop_variables)
    values = machine.home_values[:, None]
    platform = machine.home_platform
    rot = rotvec_to_matrix(platform[3:]).transpose(1, 2, 0)
    c = closure(model, rot, platform[:3, None], values)
    cu = np.concatenate([c.platform, c.variables[:, passive]], axis=1)[:, :, 0]
    sv = np.linalg.svd(cu, compute_uv=False)
    rank = int((sv > RANK_RCOND * sv[0]).sum())
    if rank < cu.shape[1]:
        raise reader.fail(
            f"the actuated joints ({names}) do not fix the legs at home: {cu.shape[1] - rank} "
            "combination(s) of the platform pose and passive joints stay free (actuate other "
            "joints, or move home away from a singularity)", where)


def _poses(reader: _Reader, machine: JointChainMachine) -> dict[str, np.ndarray]:
    table = reader.table("poses", required=False)
    scales = np.array([math.pi / 180.0 if kind == "angle" else reader.scale
                       for kind in machine.actuator_quantities])
    out = {}
    for name, value in table.items():
        arr = reader.vector(value, machine.n_actuators, ("poses", name),
                            f"pose {name!r} (one value per actuator: "
                            f"{', '.join(machine.actuator_names)})")
        out[name] = arr * scales
    return out


def _short(value: Any) -> str:
    """``repr(value)``, cut to 60 characters (a 400-digit literal in an error message)."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:57]}…"


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list | tuple | np.ndarray):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return repr(float(value))


def machine_file_text(machine: JointChainMachine, units: str = "m") -> str:
    """A ``joint-chain`` machine file (TOML text) describing ``machine`` element by element,
    with its defects, default tool length and reference configurations — e.g. to edit a
    built-in machine, or to save one with identified defects. ``load`` of the text gives the
    same kinematics (exactly with ``units="m"``; mm values are rounded by the conversion).
    """
    scale = length_scale(units)
    model = machine.model
    q = ["[machine]", f'kind = "{JOINT_CHAIN}"', f"name = {_toml_value(machine.name)}"]
    for key in ("description", "source"):
        if getattr(machine, key):
            q.append(f"{key} = {_toml_value(getattr(machine, key))}")
    q += [f'units = "{units}"',
          f"characteristic_length = {_toml_value(model.characteristic_length / scale)}",
          f"tool_length = {_toml_value(machine.tool_length / scale)}"]
    home = dict(zip(model.variables, machine.home_values, strict=True))
    for spec in model.elements:
        q += ["", "[[elements]]", f"name = {_toml_value(spec.name)}",
              f'type = "{spec.type}"']
        if spec.rotation is not None:
            q.append(f"rotation = {_toml_value(np.asarray(spec.rotation, dtype=float))}")
        else:
            q.append(f"axis = {_toml_value(spec.axis)}")
            if spec.spin:
                q.append(f"spin = {_toml_value(math.degrees(spec.spin))}")
        q.append(f"point = {_toml_value(np.asarray(spec.point, dtype=float) / scale)}")
        if spec.label is not None:
            q.append(f"label = {_toml_value(spec.label)}")
        if spec.display is not None:
            q.append(f"display = {_toml_value(spec.display)}")
        if spec.type == FIXED:
            continue
        joint_scale = math.pi / 180.0 if spec.type == REVOLUTE else scale
        if spec.actuated:
            q.append("actuated = true")
        q.append(f"home = {_toml_value(home[spec.name] / joint_scale)}")
        if np.isfinite(spec.stroke).all():
            q.append(f"stroke = {_toml_value(np.asarray(spec.stroke) / joint_scale)}")
    for name, leg in zip(model.leg_names, model.legs, strict=True):
        q += ["", "[[legs]]", f"name = {_toml_value(name)}",
              f"elements = {_toml_value([model.elements[e].name for e in leg])}"]
    if model.head:
        head = [model.elements[e].name for e in model.head]
        q += ["", "[head]", f"elements = {_toml_value(head)}"]
    poses = {k: v for k, v in machine.reference_poses().items() if k != "home"}
    if poses:
        scales = np.array([math.pi / 180.0 if kind == "angle" else scale
                           for kind in machine.actuator_quantities])
        q += ["", "[poses]"] + [f"{_toml_value(k)} = {_toml_value(np.asarray(v) / scales)}"
                                 for k, v in poses.items()]
    if model.defects.any():
        q += ["", "[defects]"]
        index = model.defect_index
        for i in np.flatnonzero(model.defects):
            kind = index.kind[i]
            unit = scale if kind == "position" else math.pi / 180.0 if kind == "spin" else 1.0
            q.append(f"{index.names[i]} = {_toml_value(model.defects[i] / unit)}")
    return "\n".join(q) + "\n"
