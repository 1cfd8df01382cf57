"""Machine library: kinds, built-in presets (shipped machine files) and machines from files.

Every built-in machine is a machine file in ``pkmkit/machines/data/`` — the same format users
write — so presets and user files go through one loader. A file either names a built-in *kind*
and gives its ``[parameters]``, or has ``kind = "rod-legs"`` and describes its legs one by one::

    [machine]
    kind = "linear-delta"          # or "orthoglide", "five-bar", "rod-legs", "joint-chain"
    name = "My Delta"
    units = "mm"                   # lengths in this file; angles are always in degrees
    [parameters]
    R = 700
    angles = [0, 120, 240]
    [poses]                        # optional named sample poses
    low = [0, 0, 400]

See ``docs/machine-files.md`` for the ``rod-legs`` format. A ``rod-legs`` machine has no named
parameters; :func:`leg_parameters` lists its leg fields as scalar values (``legs[0].length``,
``legs[2].base[0]``, ...) and :func:`with_leg_values` returns a new machine with some of them
changed (the design layer varies them like parameters).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import MachineFileError, ParameterError, UnknownMachineError
from pkmkit.machines import (
    crank_slider,
    delta_robot,
    five_bar,
    gough_stewart,
    linear_delta,
    orthoglide,
    trimule,
    tripteor,
    verne,
)
from pkmkit.machines.build import build_machine
from pkmkit.machines.built_machines import built
from pkmkit.machines.chain_file import JOINT_CHAIN, chain_machine_from_document
from pkmkit.machines.machine import Machine, MachineKind
from pkmkit.model.machine_file import (
    MachineDocument,
    parse_machine_document,
    read_machine_document,
    read_machine_text,
)
from pkmkit.model.parameters import (
    MAX_LENGTH,
    is_plain_number,
    length_scale,
    resolve_parameters,
)
from pkmkit.model.rods import LegSpec, build_rod_model, leg_specs

#: Built-in machine kinds by name.
KINDS: dict[str, MachineKind] = {k.KIND.kind: k.KIND for k in (
    orthoglide, linear_delta, five_bar, delta_robot, gough_stewart, verne, tripteor,
    crank_slider, trimule)}
ROD_LEGS = "rod-legs"
#: Short ids naming a kind's reference preset.
ALIASES = {"linear-delta": "linear-delta-ch3", "five-bar": "five-bar-isotropic"}

_MACHINE_KEYS = {"kind", "id", "name", "description", "source", "units", "dims", "home",
                 "mode_names", "characteristic_length"}
_TOP_KEYS = {"machine", "parameters", "legs", "poses", "defects", "stiffness"}
_LEG_KEYS = {"name", "actuator", "type", "base", "axis", "platform", "length", "branch",
             "parallelogram", "stroke", "pivot", "actuator_stiffness"}


def _data_dir():
    here = Path(__file__).parent / "data"
    if here.is_dir():  # an ordinary install: importlib.resources (≈ 10–20 ms of imports: its
        return here  # tempfile, random) only for a packaging without files (a zip)
    from importlib import resources

    return resources.files("pkmkit.machines") / "data"


@cache
def _preset_paths() -> dict[str, str]:
    paths = {}
    for entry in sorted(_data_dir().iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".toml"):
            paths[entry.name[: -len(".toml")]] = str(entry)
    return paths


def machines() -> list[str]:
    """Ids of every built-in machine (presets and their short aliases), sorted."""
    return sorted([*_preset_paths(), *ALIASES])


def preset_path(machine_id: str) -> str:
    """Path of the machine file of a built-in preset (aliases resolved)."""
    try:
        return _preset_paths()[ALIASES.get(machine_id, machine_id)]
    except (KeyError, TypeError):  # TypeError: not a string (a list, a dict...)
        raise UnknownMachineError(machine_id, machines()) from None


def machine(machine_id: str, **params: Any) -> Machine:
    """A built-in machine by id, with parameter overrides in SI units (m, rad).

    Raises:
        UnknownMachineError: the id is not a preset (the message lists the valid ids).
        UnknownParameterError, ParameterError: bad overrides.
    """
    return load(preset_path(machine_id), _overrides=params, _id=machine_id)


def load(path: str | Path, *, _overrides: Mapping[str, Any] | None = None,
         _id: str | None = None) -> Machine:
    """A machine from a TOML or YAML machine file.

    Each call returns a new machine; loading a file whose text was loaded before (the same
    path, id and engine) copies the machine built then instead of building it again
    (:mod:`pkmkit.machines.built_machines`).

    Raises:
        MachineFileError: unreadable or malformed file, with the offending line when known.
    """
    if _overrides:
        doc = read_machine_document(path)
        return machine_from_document(doc, overrides=_overrides, machine_id=_id)
    text = read_machine_text(path)
    return built((str(path), text, _id), lambda: machine_from_document(
        parse_machine_document(path, text), machine_id=_id))


def _table(doc: MachineDocument, key: str, required: bool) -> dict[str, Any]:
    if key not in doc.data:
        if required:
            raise doc.error(f"missing [{key}] table")
        return {}
    value = doc.data[key]
    if value is None:
        if required:
            raise doc.error(f"the [{key}] table is empty", (key,))
        return {}
    if not isinstance(value, dict):
        raise doc.error(f"[{key}] must be a table of key = value entries", (key,))
    return value


def _check_keys(doc: MachineDocument, found: Mapping[str, Any], allowed: set[str],
                where: tuple, what: str) -> None:
    for key in found:
        if key not in allowed:
            raise doc.error(
                f"unknown key {key!r} in {what}; valid keys: {', '.join(sorted(allowed))}",
                (*where, key),
            )


def machine_from_document(
    doc: MachineDocument,
    *,
    overrides: Mapping[str, Any] | None = None,
    machine_id: str | None = None,
) -> Machine:
    """Build a machine from a parsed machine file (see the module docstring).

    Args:
        doc: parsed file.
        overrides: parameter values in SI units replacing the file's (built-in kinds only).
        machine_id: id to give the machine (default: ``[machine] id`` or the file name).
    """
    table = doc.data.get("machine")
    if isinstance(table, dict) and table.get("kind") == JOINT_CHAIN:
        return chain_machine_from_document(doc, machine_id=machine_id, overrides=overrides)
    _check_keys(doc, doc.data, _TOP_KEYS, (), "the file")
    head = _table(doc, "machine", required=True)
    _check_keys(doc, head, _MACHINE_KEYS, ("machine",), "[machine]")
    kind_name = head.get("kind")
    valid_kinds = [*sorted(KINDS), ROD_LEGS, JOINT_CHAIN]
    if kind_name not in valid_kinds:
        raise doc.error(
            f"[machine] kind must be one of {', '.join(valid_kinds)}; got {kind_name!r}",
            ("machine", "kind"),
        )
    units = head.get("units", "m")
    for key in ("units", "name", "description", "source", "id"):
        if key in head and not isinstance(head[key], str):
            raise doc.error(f"[machine] {key} must be a string, got {head[key]!r}",
                            ("machine", key))
    try:
        scale = length_scale(units)
    except ParameterError as exc:
        raise doc.error(str(exc), ("machine", "units")) from None
    ident = machine_id or str(head.get("id", Path(doc.path).stem))
    text = {k: str(head.get(k, "")) for k in ("name", "description", "source")}
    poses = _poses(doc, scale)
    try:
        if kind_name == ROD_LEGS:
            built = _rod_legs_machine(doc, head, scale, ident, text)
        else:
            built = _kind_machine(doc, KINDS[kind_name], units, ident, text)
    except MachineFileError:
        raise
    except ParameterError as exc:
        raise doc.error(str(exc), _parameter_path(kind_name, exc.parameter)) from None
    if poses:
        built = _with_poses(doc, built, poses)
    if "characteristic_length" in head:
        built = _with_length(doc, built, head["characteristic_length"], scale)
    if overrides:  # errors here concern the caller's values, not the file
        built = built.with_params(**overrides)
    if "defects" in doc.data:  # a calibrated (or simulated) machine: docs/machine-files.md
        built = _with_defects_table(doc, built, scale)
    return built


def _with_length(doc: MachineDocument, machine: Machine, value: Any, scale: float) -> Machine:
    """``[machine] characteristic_length`` (file units) of a full-pose machine."""
    where = ("machine", "characteristic_length")
    if not hasattr(machine, "with_characteristic_length"):
        raise doc.error("[machine] characteristic_length applies to full-pose machines (dims = "
                        "6); a joint-chain machine takes it as a parameter", where)
    try:
        return machine.with_characteristic_length(_number(value, "[machine] "
                                                          "characteristic_length", scale))
    except ParameterError as exc:
        raise doc.error(str(exc), where) from None


def _with_defects_table(doc: MachineDocument, machine: Machine, scale: float) -> Machine:
    from pkmkit.model.defect_rule import with_defects
    from pkmkit.model.defects_table import defects_from_table

    table = _table(doc, "defects", required=False)
    try:
        return with_defects(machine, defects_from_table(machine, table, scale))
    except ParameterError as exc:
        raise doc.error(str(exc), ("defects", exc.parameter) if exc.parameter else ("defects",)
                        ) from None


def _parameter_path(kind_name: str, parameter: str | None) -> tuple:
    if parameter is None:
        return ("machine",)
    if kind_name == ROD_LEGS:
        return tuple(int(p) if p.isdigit() else p for p in parameter.split("."))
    return ("parameters", parameter)


def _kind_machine(doc, kind: MachineKind, units: str, ident: str, text: dict) -> Machine:
    table = _table(doc, "parameters", required=False)
    specs = {s.name: s for s in kind.parameters}
    values = {}
    for name, raw in table.items():
        if name not in specs:
            raise doc.error(
                f"unknown parameter {name!r} for kind {kind.kind!r}; valid parameters: "
                f"{', '.join(sorted(specs))}",
                ("parameters", name),
            )
        values[name] = specs[name].from_boundary(raw, units, ident)
    params = resolve_parameters(kind.parameters, values, ident)
    return build_machine(kind, params, id=ident, **text)


def _vector(value: Any, size: int, what: str, scale: float = 1.0) -> np.ndarray:
    if not is_plain_number(value):
        raise ParameterError(f"{what} must be {size} numbers, got {value!r}", what)
    try:
        arr = np.asarray(value, dtype=float)
    except OverflowError:  # an integer beyond the float range
        raise ParameterError(f"{what} must be {size} finite numbers, got {value!r}",
                             what) from None
    if arr.shape != (size,) or not np.isfinite(arr).all():
        raise ParameterError(f"{what} must be {size} finite numbers, got {value!r}", what)
    _bounded(arr * scale, what)
    return arr * scale


def _bounded(si: Any, what: str) -> None:
    """Refuse magnitudes beyond MAX_LENGTH (m, rad, direction components): a unit mistake,
    whose squares overflow in the closures (issue 18 §7)."""
    if (np.abs(si) > MAX_LENGTH).any():
        raise ParameterError(f"{what}: magnitude beyond {MAX_LENGTH:g} (m, rad or direction "
                             "components): check the units", what)


def _number(value: Any, what: str, scale: float = 1.0) -> float:
    try:
        finite = is_plain_number(value) and np.ndim(value) == 0 and np.isfinite(float(value))
    except OverflowError:
        finite = False
    if not finite:
        raise ParameterError(f"{what} must be a finite number, got {value!r}", what)
    _bounded(float(value) * scale, what)
    return float(value) * scale


def _rod_legs_machine(doc, head: Mapping[str, Any], scale: float, ident: str,
                      text: dict) -> Machine:
    dims = head.get("dims", 3)
    if isinstance(dims, bool) or dims not in (2, 3, 6) or not isinstance(dims, int):
        raise doc.error(f"[machine] dims must be the integer 2, 3 or 6, got {dims!r}",
                        ("machine", "dims"))
    legs_raw = doc.data.get("legs")
    if not isinstance(legs_raw, list) or not legs_raw:
        raise doc.error("a rod-legs machine needs [[legs]] entries", ("legs",))
    space = 3 if dims == 6 else dims  # coordinates of points and directions
    legs = []
    actuators: list[str] = []
    for i, raw in enumerate(legs_raw):
        legs.append(_file_leg(doc, i, raw, dims, scale, actuators))
    home = _vector(head.get("home", [0.0] * dims), dims, "machine.home")
    home[:space] *= scale  # a full pose's rotation vector stays in radians
    mode_names = _mode_names(head)
    model = build_rod_model(
        legs, dims=dims, actuator_names=actuators, home_pose=home,
        mode_names=(mode_names[0], mode_names[1]),
    )
    cls: type = Machine
    if model.full_pose:
        from pkmkit.machines.full_pose import FullPoseMachine

        cls = FullPoseMachine
    return cls(id=ident, name=text["name"] or ident, kind=None, params={}, model=model,
               description=text["description"], source=text["source"])


def _mode_names(head: Mapping[str, Any]) -> list[str]:
    """``[machine] mode_names``: two different non-empty names (default det(A)<0, det(A)>0)."""
    mode_names = head.get("mode_names", ["det(A)<0", "det(A)>0"])
    if not (isinstance(mode_names, list) and len(mode_names) == 2
            and all(isinstance(n, str) and n for n in mode_names)
            and mode_names[0] != mode_names[1]):
        raise ParameterError("[machine] mode_names must be a list of two different names",
                             "machine.mode_names")
    return mode_names


def _padder(space: int):
    """Points and directions of a planar file (2 numbers) padded with z = 0."""
    def pad(v: np.ndarray) -> np.ndarray:
        return np.append(v, 0.0) if space == 2 else v
    return pad


def _leg_actuator(i: int, raw: dict, dims: int, actuators: list[str]) -> int:
    """The index of leg ``i``'s actuator, appended to ``actuators`` when new."""
    where = f"legs.{i}"
    actuator = raw.get("actuator", f"q{i + 1}")
    if not isinstance(actuator, str) or not actuator:
        raise ParameterError(f"{where}.actuator must be a name, got {actuator!r}",
                             f"{where}.actuator")
    if actuator in actuators and dims != 6:
        raise ParameterError(
            f"{where}: actuator {actuator!r} already drives another leg (only full-pose "
            "machines, dims = 6, may hang several legs on one actuator)", f"{where}.actuator")
    if actuator not in actuators:
        actuators.append(actuator)
    return actuators.index(actuator)


def _leg_parallelogram(where: str, raw: dict, space: int, scale: float):
    """``(width m, direction or None)`` of a leg's ``parallelogram`` table."""
    para = raw.get("parallelogram", {})
    if not isinstance(para, dict) or set(para) - {"width", "direction"}:
        raise ParameterError(
            f"{where}.parallelogram must be a table with 'width' and 'direction'",
            f"{where}.parallelogram",
        )
    width = _number(para.get("width", 0.0), f"{where}.parallelogram.width", scale)
    direction = None
    if width > 0:
        if "direction" not in para:
            raise ParameterError(f"{where}.parallelogram needs a 'direction'",
                                 f"{where}.parallelogram")
        direction = _padder(space)(_vector(para["direction"], space,
                                           f"{where}.parallelogram.direction"))
    return width, direction


def _file_leg(doc, i: int, raw: Any, dims: int, scale: float,
              actuators: list[str]) -> LegSpec:
    """``[[legs]]`` entry ``i`` of a rod-legs file as a :class:`LegSpec` (SI; crank strokes
    read in degrees); its actuator is added to ``actuators`` when new."""
    where = f"legs.{i}"
    space = 3 if dims == 6 else dims
    pad = _padder(space)
    if not isinstance(raw, dict):
        raise doc.error(f"legs entry {i} must be a table", ("legs", i))
    _check_keys(doc, raw, _LEG_KEYS, ("legs", i), f"legs entry {i}")
    for key in ("base", "platform", "length"):
        if key not in raw:
            raise ParameterError(f"{where} needs {key!r}", f"{where}")
    kind = raw.get("type", "slide")
    if kind not in ("slide", "strut", "crank"):
        raise ParameterError(
            f"{where}.type must be 'slide', 'strut' or 'crank', got {kind!r}", f"{where}.type")
    actuator = _leg_actuator(i, raw, dims, actuators)
    axis = pivot = None
    if kind in ("slide", "crank"):
        if "axis" not in raw:
            raise ParameterError(f"{where}: a {kind} leg needs 'axis'", where)
        axis = pad(_vector(raw["axis"], space, f"{where}.axis"))
    if kind == "crank":
        if "pivot" not in raw:
            raise ParameterError(f"{where}: a crank leg needs 'pivot' (a point of its "
                                 "rotation axis)", where)
        pivot = pad(_vector(raw["pivot"], space, f"{where}.pivot", scale))
    width, direction = _leg_parallelogram(where, raw, space, scale)
    branch = raw.get("branch", 1)
    if isinstance(branch, bool) or branch not in (1, -1):
        raise ParameterError(f"{where}.branch must be 1 or -1, got {branch!r}",
                             f"{where}.branch")
    stroke_scale = np.pi / 180.0 if kind == "crank" else scale  # crank strokes in degrees
    stroke = (_vector(raw["stroke"], 2, f"{where}.stroke", stroke_scale) if "stroke" in raw
              else (-np.inf, np.inf))
    return LegSpec(
        name=str(raw.get("name", f"leg {i + 1}")),
        actuator=actuator,
        kind=kind,
        base=pad(_vector(raw["base"], space, f"{where}.base", scale)),
        platform=pad(_vector(raw["platform"], space, f"{where}.platform", scale)),
        length=_number(raw["length"], f"{where}.length", scale),
        axis=axis,
        branch=int(branch),
        parallelogram_width=width,
        parallelogram_direction=direction,
        stroke=tuple(stroke),
        pivot=pivot,
    )

def _poses(doc: MachineDocument, scale: float) -> dict[str, np.ndarray]:
    table = _table(doc, "poses", required=False)
    out = {}
    for name, value in table.items():
        try:
            out[name] = _vector(value, len(value) if isinstance(value, list) else -1,
                                f"poses.{name}", scale)
            if len(out[name]) == 6:  # a full pose: the rotation vector is in radians
                out[name][3:] /= scale
        except ParameterError as exc:
            raise doc.error(str(exc), ("poses", name)) from None
    return out


def _with_poses(doc: MachineDocument, machine: Machine,
                poses: dict[str, np.ndarray]) -> Machine:
    widths = {machine.dims}
    if getattr(machine, "position_controlled", False):
        widths.add(3)  # a position: the machine's orientation follows from it
    for name, pose in poses.items():
        if pose.shape[0] not in widths:
            raise doc.error(f"pose {name!r} must have {' or '.join(map(str, sorted(widths)))} "
                            "coordinates", ("poses", name))
    return replace(machine, extra_poses={**machine.extra_poses, **poses})


# ------------------------------------------------------------------ leg fields of rod-legs machines
#: Leg fields of a ``rod-legs`` machine that :func:`leg_parameters` exposes, with their quantity
#: (vector fields have one scalar per pose coordinate).
LEG_FIELDS = {"length": "length", "base": "length", "platform": "length", "axis": "number",
              "parallelogram_width": "length", "stroke": "length"}
_LEG_NAME = re.compile(r"legs\[(\d+)\]\.([a-z_]+)(?:\[(\d+)\])?")


def _leg_specs(m: Machine) -> list[LegSpec]:
    """The leg descriptions a ``rod-legs`` machine was built from (SI, 3-D vectors)."""
    return leg_specs(m.model)


def leg_parameters(m: Machine) -> dict[str, tuple[float, str]]:
    """The leg fields of a ``rod-legs`` machine as scalars: ``{name: (SI value, quantity)}``.

    Names: ``legs[i].length``, ``legs[i].base[k]``, ``legs[i].platform[k]`` (k < dims),
    ``legs[i].axis[k]`` (slides only; the axis is normalised when the machine is built),
    ``legs[i].parallelogram_width`` (parallelogram legs only) and ``legs[i].stroke[0|1]``
    (limited strokes only); legs are numbered from 0 in file order. Quantities are
    ``"length"`` (m) or ``"number"``.

    Raises:
        ParameterError: ``m`` is a machine of a built-in kind (use its named parameters).
    """
    if m.kind is not None:
        raise ParameterError(f"machine {m.id!r} has named parameters; leg fields are only "
                             "exposed for rod-legs machines")
    out: dict[str, tuple[float, str]] = {}
    for i, leg in enumerate(_leg_specs(m)):
        out[f"legs[{i}].length"] = (float(leg.length), "length")
        for field in ("base", "platform", "axis"):
            if field == "axis" and leg.axis is None:
                continue
            for k in range(m.dims):
                out[f"legs[{i}].{field}[{k}]"] = (float(getattr(leg, field)[k]),
                                                  LEG_FIELDS[field])
        if leg.parallelogram_width > 0:
            out[f"legs[{i}].parallelogram_width"] = (leg.parallelogram_width, "length")
        for k, v in enumerate(leg.stroke):
            if np.isfinite(v):
                out[f"legs[{i}].stroke[{k}]"] = (float(v), "length")
    return out


def with_leg_values(m: Machine, values: Mapping[str, float]) -> Machine:
    """A new ``rod-legs`` machine with some leg fields changed (names and SI units as in
    :func:`leg_parameters`); ``m`` itself is not modified.

    Raises:
        ParameterError: an unknown name, or values that make an invalid machine (the message
            names the leg and the field).
    """
    valid = leg_parameters(m)
    legs = _leg_specs(m)
    changes: dict[int, dict[str, Any]] = {}
    for name, value in values.items():
        match = _LEG_NAME.fullmatch(name)
        if name not in valid or match is None:
            raise ParameterError(f"unknown leg field {name!r} of {m.id!r}; valid names: "
                                 f"{', '.join(valid)}", name)
        i, field = int(match.group(1)), match.group(2)
        index = None if match.group(3) is None else int(match.group(3))
        leg = changes.setdefault(i, {})
        if index is None:
            leg[field] = float(value)
        else:
            current = list(leg.get(field, getattr(legs[i], field)))
            current[index] = float(value)
            leg[field] = tuple(current)
    legs = [replace(leg, **changes.get(i, {})) for i, leg in enumerate(legs)]
    model = build_rod_model(legs, dims=m.dims, actuator_names=m.actuator_names,
                            home_pose=m.model.home_pose, mode_names=m.model.mode_names,
                            pose_names=m.pose_names)
    return replace(m, model=model)
