"""Writing a sized machine (``pkmkit design --out``, ``pkmkit optimize --out``) as a machine
file that :func:`pkmkit.load` reads back.

The file is a machine of a built-in kind: a ``[machine]`` table (``kind``, ``name``,
``description``, ``source``, ``units``) and a ``[parameters]`` table with every parameter of the
kind in the file's units (lengths in ``units``, angles in degrees, numbers as they are), written
with ``repr`` so that nothing is lost but the unit conversion's rounding. Before anything is
written, the text is loaded back and compared with the machine: the same parameters (to
1e-12 relative), the same strokes and the same inverse kinematics at the given poses (to
:data:`IK_TOL` m); a mismatch raises :class:`~pkmkit.exceptions.ExportCheckError` and writes
nothing. Machines without a built-in kind (``rod-legs``, ``joint-chain`` files) are refused
with :class:`~pkmkit.exceptions.UnsupportedExportError`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import ExportCheckError, InputError, UnsupportedExportError
from pkmkit.io.atomic import check_output_file, write_text_atomic
from pkmkit.model.machine_file import MachineDocument, parse_toml
from pkmkit.model.parameters import length_scale

#: Largest difference (m, or rad for rotary actuators) between the actuator coordinates of the
#: machine and of the file read back, at every checked pose.
IK_TOL = 1e-12
_PARAM_RTOL = 1e-12
_FORMAT = "machine file"
#: A written value may differ from the machine's by this relative amount (a few units in the last
#: place) so that it reads as the shortest decimal.
_SHORT_RTOL = 1e-15


def _toml(value: Any) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list | tuple | np.ndarray):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(float(value))


def _factor(quantity: str, scale: float) -> float:
    """SI value per file unit."""
    return {"length": scale, "angle": math.pi / 180.0}.get(quantity, 1.0)


def _in_file_units(value: float, factor: float) -> float:
    """``value`` (SI) / ``factor`` as the shortest decimal that converts back to ``value``
    within :data:`_SHORT_RTOL` (``120.0`` rather than ``119.99999999999999`` degrees, ``700.0``
    rather than ``699.9999999999999`` mm), else the plain quotient."""
    plain = value / factor
    for digits in range(16):
        short = round(plain, digits)
        if math.isclose(short * factor, value, rel_tol=_SHORT_RTOL, abs_tol=0.0):
            return short
    return plain


def check_destination(path: str | Path) -> Path:
    """The destination of a sized machine file, checked before any computation.

    Raises:
        InputError: not a ``.toml`` name, or a file that cannot be created there.
    """
    if Path(path).suffix.lower() != ".toml":
        raise InputError(f"{path}: a sized machine is written as TOML; give a .toml file name")
    return check_output_file(path)


def sized_machine_text(machine: Any, units: str = "m", *, name: str | None = None,
                       source: str | None = None) -> str:
    """TOML machine file text for ``machine`` (a machine of a built-in kind), lengths in
    ``units``; ``name`` and ``source`` replace the machine's (``[machine] name``, ``source``).

    Raises:
        UnsupportedExportError: ``machine`` has no built-in kind (a ``rod-legs`` or
            ``joint-chain`` machine), or has defects.
    """
    kind = machine.kind
    if kind is None:
        raise UnsupportedExportError(_FORMAT, machine.id, "only machines of a built-in kind "
                                     "are written as a sized machine file (this one is "
                                     "described leg by leg or element by element, or has "
                                     "geometric defects)")
    defects = machine.model.defects
    if defects is not None and np.any(np.asarray(defects, dtype=float) != 0):
        raise UnsupportedExportError(_FORMAT, machine.id, "the machine has geometric defects")
    scale = length_scale(units)
    text = {"name": machine.name if name is None else name,
            "description": machine.description,
            "source": machine.source if source is None else source}
    lines = ["[machine]", f"kind = {_toml(kind.kind)}"]
    lines += [f"{key} = {_toml(value)}" for key, value in text.items() if value]
    lines += [f"units = {_toml(units)}", "", "[parameters]"]
    for spec in kind.parameters:
        factor = _factor(spec.quantity, scale)
        value = machine.params[spec.name]
        if spec.size is None:
            lines.append(f"{spec.name} = {_toml(_in_file_units(float(value), factor))}")
        else:
            shown = [_in_file_units(float(v), factor) for v in np.asarray(value, dtype=float)]
            lines.append(f"{spec.name} = {_toml(shown)}")
    return "\n".join(lines) + "\n"


def check_reproduces(machine: Any, loaded: Any, poses: np.ndarray) -> None:
    """Check that ``loaded`` (the file read back) is ``machine``: same kind and parameters
    (relative 1e-12), same strokes, and actuator coordinates at ``poses`` ``(N, dims)`` (SI)
    within :data:`IK_TOL`.

    Raises:
        ExportCheckError: the first difference found.
    """
    def fail(what: str) -> ExportCheckError:
        return ExportCheckError(f"the machine file written for {machine.id!r} does not "
                                f"reproduce the sized machine: {what}")

    if getattr(loaded, "kind", None) is not machine.kind:
        raise fail("another kind")
    for spec in machine.kind.parameters:
        a = np.asarray(machine.params[spec.name], dtype=float)
        b = np.asarray(loaded.params[spec.name], dtype=float)
        if a.shape != b.shape or not np.allclose(b, a, rtol=_PARAM_RTOL, atol=0.0):
            raise fail(f"parameter {spec.name} is {b.tolist()} instead of {a.tolist()}")
    for name in ("q_min", "q_max"):
        a = np.asarray(getattr(machine.model, name, np.nan), dtype=float)
        b = np.asarray(getattr(loaded.model, name, np.nan), dtype=float)
        if not np.allclose(b, a, rtol=_PARAM_RTOL, atol=IK_TOL, equal_nan=True):
            raise fail(f"strokes ({name}) {b.tolist()} instead of {a.tolist()}")
    x = np.atleast_2d(np.asarray(poses, dtype=float))
    qa = np.asarray(machine.ik(x, strokes="ignore"), dtype=float)
    qb = np.asarray(loaded.ik(x, strokes="ignore"), dtype=float)
    gap = np.abs(qb - qa)
    worst = np.nanmax(gap) if np.any(np.isfinite(gap)) else np.inf
    if not np.array_equal(np.isnan(qa), np.isnan(qb)) or worst > IK_TOL:
        raise fail(f"inverse kinematics differ by {worst:.3g} at the checked poses "
                   f"(tolerance {IK_TOL:g})")


def box_corners(center: Any, side: float) -> np.ndarray:
    """The ``2**d`` corners ``(2**d, d)`` of the square/cube of ``side`` centred at ``center``
    ``(d,)`` (any consistent length unit)."""
    c = np.asarray(center, dtype=float).reshape(-1)
    signs = np.array(np.meshgrid(*[[-0.5, 0.5]] * c.size, indexing="ij")).reshape(c.size, -1).T
    return c + side * signs


def load_text(text: str, path: str | Path) -> Any:
    """The machine that ``text`` (TOML) describes, as :func:`pkmkit.load` of ``path`` would
    build it (without touching the disk)."""
    from pkmkit.machines.registry import machine_from_document

    data, lines = parse_toml(text, str(path))
    return machine_from_document(MachineDocument(str(path), data, lines))


def write_sized_machine(path: str | Path, machine: Any, poses: np.ndarray, *,
                        units: str = "m", name: str | None = None,
                        source: str | None = None) -> str:
    """Write ``machine`` as a TOML machine file at ``path`` (atomically), after checking that
    the text loads back as the same machine (:func:`check_reproduces` at ``poses``, SI).

    Returns:
        The text written.

    Raises:
        InputError: ``path`` is not a ``.toml`` name or cannot be written (checked before
            anything else).
        UnsupportedExportError, ExportCheckError: see :func:`sized_machine_text` and
            :func:`check_reproduces`; nothing is written.
    """
    target = check_destination(path)
    text = sized_machine_text(machine, units, name=name, source=source)
    check_reproduces(machine, load_text(text, target), poses)
    write_text_atomic(target, text)
    return text
