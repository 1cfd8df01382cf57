"""Shared command-line plumbing: resolving machines, parsing vectors, converting units."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click
import numpy as np

from pkmkit.exceptions import InputError, ParameterError, UnknownParameterError
from pkmkit.io.json_io import to_jsonable
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import load, machine, preset_path
from pkmkit.model.machine_file import SUFFIXES
from pkmkit.model.parameters import LENGTH_UNITS, length_scale
from pkmkit.spatial.rotation import DEFAULT_CONVENTION

from .limits import check_tool_length
from .unit_text import MACHINE_KEY, UNITS_KEY, remember


def _remember_units(ctx: click.Context, param: click.Parameter, value: str) -> str:
    ctx.meta[UNITS_KEY] = value  # error messages in these units (cli.unit_text)
    return value


UNITS_OPTION = click.option(
    "--units",
    type=click.Choice(sorted(LENGTH_UNITS)),
    default="m",
    show_default=True,
    is_eager=True,  # read first: other options' checks state their values in these units
    callback=_remember_units,
    help="Length unit of every value on the command line and in the output "
    "(angles are always in degrees).",
)
SET_OPTION = click.option(
    "--set",
    "assignments",
    multiple=True,
    metavar="NAME=VALUE",
    help="Override a machine parameter (repeatable); vectors comma-separated, e.g. "
    "--set A=0,0 --set angles=90,210,330.",
)
JSON_OPTION = click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
ANGLES_OPTION = click.option(
    "--angles", "convention", default=DEFAULT_CONVENTION, show_default=True,
    help="Angle convention of 6-DOF poses (A,B,C in degrees): xyz = fixed axes x, y, z "
         "(R = Rz(C) Ry(B) Rx(A)); upper case for moving axes (ZYX, ZYZ, ...), or rpy, ypr, "
         "euler-zyz, ...")
TOOL_LENGTH_OPTION = click.option(
    "--tool-length", type=float, default=None, callback=check_tool_length,
    help="Tool length along the tool axis (joint-chain machines), in --units; default the "
         "machine's.")

#: Exit status when the command ran but some rows or samples were flagged (bad batch rows,
#: exceeded actuator limits): the output is written and usable.
EXIT_PARTIAL = 3


def is_machine_file(name: str) -> bool:
    """True if ``name`` designates a machine file rather than a built-in id."""
    return Path(name).suffix.lower() in SUFFIXES


def resolve_machine(name: str, assignments: Sequence[str], units: str) -> Machine:
    """A machine from a built-in id or a machine-file path, with ``--set`` overrides given in
    CLI units (lengths in ``units``, angles in degrees)."""
    base = load(name) if is_machine_file(name) else machine(name)
    remember(MACHINE_KEY, base)
    if is_machine_file(name):
        refuse_giant(base, name)
    if not assignments:
        return base
    if base.kind is None:
        raise ParameterError(
            f"machine {base.id!r} is described leg by leg; --set is not available, edit the file"
        )
    specs = {s.name: s for s in base.kind.parameters}
    overrides: dict[str, Any] = {}
    for text in assignments:
        key, sep, value = text.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ParameterError(f"--set expects NAME=VALUE, got {text!r}")
        if key not in specs:
            raise UnknownParameterError(key, base.id, specs)
        overrides[key] = specs[key].parse_text(value, units, base.id)
    built = base.with_params(**overrides)
    remember(MACHINE_KEY, built)
    return built


#: A machine whose home tool point or length actuators lie farther than this (m) from its
#: origin is a file in millimetres read as metres: machine tools are metres across.
MAX_MACHINE_SIZE = 100.0


def refuse_giant(m: Machine, name: str) -> None:
    """A :class:`ParameterError` when machine file ``name`` builds a machine hundreds of metres
    across (lengths in mm with no ``units = "mm"``: consistent, so nothing else notices)."""
    q = np.asarray(m.home_q, dtype=float)
    lengths = np.asarray(m.actuator_quantities) == "length"
    size = max(float(np.abs(np.asarray(m.home_pose, dtype=float)[:3]).max()),
               float(np.abs(q[lengths]).max()) if lengths.any() else 0.0)
    if size > MAX_MACHINE_SIZE:
        raise ParameterError(
            f"{name}: at its home the machine reaches {size:.4g} m from its origin, beyond "
            f"{MAX_MACHINE_SIZE:g} m: are its lengths in mm without `units = \"mm\"` in the "
            "file? (a machine file without units is read in metres)")


def machine_document_path(name: str) -> str:
    """Path of the machine file behind ``name`` (a preset id or a file)."""
    return name if is_machine_file(name) else preset_path(name)


def parse_vector(text: str, size: int, what: str, units: str) -> np.ndarray:
    """Comma-separated positions in CLI units → SI array ``(size,)``; each finite and within
    the plausible range of a position (:func:`check_each`)."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{what}: cannot read {text!r} as comma-separated numbers") from None
    if len(values) != size:
        raise InputError(f"{what} needs {size} comma-separated values, got {len(values)}")
    scale = length_scale(units)
    check_each(what, values, [scale] * size, [units] * size,
               labels="XYZ"[:size] if size <= 3 else None)
    return np.asarray(values) * scale


def check_each(option: str, values: Sequence[float], scales: Sequence[float],
               units: Sequence[str], *, labels: Sequence[str] | None = None,
               kind: str = "offset") -> None:
    """Every coordinate of a tuple option (``values`` in the option's units, ``scales`` SI per
    unit, ``units`` their names: a length unit or ``"deg"``) finite and within the plausible
    range of ``kind`` (lengths; :data:`~pkmkit.numerics.magnitudes.PLAUSIBLE`) or of an angle,
    else :class:`InputError` naming the option, the coordinate (``labels``), the value and the
    range in the option's unit."""
    from pkmkit.numerics.magnitudes import check_plausible

    for k, (v, scale, unit) in enumerate(zip(values, scales, units, strict=True)):
        name = f"{option} {labels[k]}" if labels is not None else option
        check_plausible(name, v, "angle" if unit == "deg" else kind, scale=scale, unit=unit)


def emit_json(payload: dict) -> None:
    """Print ``payload`` as indented JSON (NaN/inf as null)."""
    click.echo(json.dumps(to_jsonable(payload), indent=2))


def fmt(values: Any, digits: int = 6) -> str:
    """Compact text of a number or vector (rounding noise below 1e-12 shown as 0)."""
    arr = np.asarray(values, dtype=float)
    arr = np.where(np.abs(arr) < 1e-12, 0.0, arr)
    if arr.ndim == 0:
        return f"{float(arr):.{digits}g}"
    return "[" + ", ".join(f"{v:.{digits}g}" for v in arr.ravel()) + "]"
