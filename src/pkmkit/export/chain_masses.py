"""Masses of a joint-chain machine's bodies for its MuJoCo model (``pkmkit export MACHINE --to
mjcf --masses FILE``): pkmkit's dynamics model has no masses of joint chains
(:func:`pkmkit.dynamics.masses.mass_properties` refuses them), so a machine's real masses come
from a file, body by body::

    [masses]
    units = "mm"                # lengths (com) in this file; inertias always kg·m²
    gravity = [0, 0, -9.81]     # m/s² (default)

    [bodies.platform]           # the platform body (pkmkit's platform frame)
    mass = 50.0                 # kg
    com = [0, 0, -40]           # centre of mass in the body's frame (default its origin)
    inertia = [2.1, 2.1, 3.4]   # kg·m² about the centre of mass, body frame: the diagonal,
                                # or a 3 × 3 matrix (default: a solid sphere of 20 mm)
    [bodies.Q1]                 # the body an element carries, by the element's name
    mass = 31.5
    com = [0, 0, 350]

A body is the link an element of pkmkit's chains carries (``<name>_body`` in the model, placed
by the element's frame; ``platform`` the platform frame), as in :func:`pkmkit.export.
urdf_chains.chain_tree`. Bodies the file leaves out get a :data:`PLACEHOLDER_KG` kg
placeholder sphere (MuJoCo needs a mass on every moving body), and the model file names them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pkmkit.dynamics.masses import refuse_beyond
from pkmkit.exceptions import InputError, MachineFileError
from pkmkit.model.machine_file import parse_toml
from pkmkit.model.parameters import MAX_LENGTH, is_plain_number, length_scale
from pkmkit.model.text_files import read_text
from pkmkit.numerics.magnitudes import MAX_GRAVITY, MAX_INERTIA, MAX_MASS

#: Mass (kg) and sphere radius (m) of a body the file leaves out, and of a default inertia.
PLACEHOLDER_KG = 0.01
SPHERE_RADIUS = 0.02


@dataclass(frozen=True)
class BodyMass:
    """One body's mass (kg), centre of mass ``com (3,)`` (m, body frame) and inertia
    ``(3, 3)`` (kg·m², about the centre of mass, body frame)."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray


@dataclass(frozen=True)
class ChainBodyMasses:
    """The bodies' masses of a joint-chain machine, read from ``source``.

    Attributes:
        bodies: body name (an element's name, or ``platform``) → :class:`BodyMass`.
        gravity: ``(3,)`` m/s².
        source: the file they come from.
    """

    bodies: dict[str, BodyMass]
    gravity: np.ndarray
    source: str

    def body(self, name: str) -> BodyMass:
        """A body's mass, or the placeholder sphere where the file gives none."""
        return self.bodies.get(name) or sphere(PLACEHOLDER_KG)

    def note(self, names: list[str], short: bool = False) -> str:
        """What the model file (or, ``short``, the command) says of its masses (``names``:
        every body of the model)."""
        missing = [n for n in names if n not in self.bodies]
        total = sum(b.mass for b in self.bodies.values())
        text = (f"masses from {Path(self.source).name} ({len(self.bodies)} bodies, "
                f"{total:.6g} kg)")
        if missing and short:
            text += (f"; {len(missing)} other bodies {PLACEHOLDER_KG:g} kg placeholders, "
                     "named in the file")
        elif missing:
            text += (f"; {', '.join(missing)}: {PLACEHOLDER_KG:g} kg placeholder spheres "
                     "(not in the file)")
        return text


def sphere(mass: float) -> BodyMass:
    """A solid sphere of :data:`SPHERE_RADIUS` at the body's origin."""
    return BodyMass(mass, np.zeros(3), np.eye(3) * 0.4 * mass * SPHERE_RADIUS**2)


def body_names(machine) -> list[str]:
    """The bodies a masses file may name: ``platform`` and every element."""
    return ["platform", *(e.name for e in machine.model.elements)]


def _vector(value, what: str) -> np.ndarray:
    if not is_plain_number(value) or np.shape(value) != (3,):
        raise InputError(f"{what} must be 3 numbers, got {value!r}")
    return np.asarray(value, dtype=float)


def _inertia(value, mass: float, what: str) -> np.ndarray:
    """``(3, 3)`` from a diagonal or a matrix; symmetric, positive semi-definite and obeying
    the triangle inequality of principal moments (as MuJoCo requires)."""
    if value is None:
        return sphere(mass).inertia
    if not is_plain_number(value) or np.shape(value) not in ((3,), (3, 3)):
        raise InputError(f"{what}: inertia must be 3 numbers (the diagonal) or a 3 × 3 matrix "
                         f"(kg·m²), got {value!r}")
    arr = np.asarray(value, dtype=float)
    inertia = np.diag(arr) if arr.shape == (3,) else arr
    refuse_beyond(f"{what}: inertia entry", inertia, MAX_INERTIA, "kg·m²")
    if not np.allclose(inertia, inertia.T):
        raise InputError(f"{what}: inertia must be symmetric")
    moments = np.linalg.eigvalsh(inertia)
    scale = max(float(moments.max()), 1e-300)
    if moments.min() < -1e-12 * scale or (
            moments[0] + moments[1] < moments[2] * (1 - 1e-12)):
        raise InputError(f"{what}: inertia principal moments {moments.tolist()} kg·m² are not "
                         "those of a body (each must be >= 0 and at most the sum of the other "
                         "two)")
    return inertia


def load_chain_masses(path: str | Path, machine) -> ChainBodyMasses:
    """Read a joint-chain masses file (module docstring).

    Raises:
        InputError: unreadable file, syntax error, unknown tables or keys, a body the machine
            does not have (with the valid names), negative or absurd values (with the line).
    """
    def error(message: str, line: int | None = None) -> InputError:
        return InputError(f"{path}:{line}: {message}" if line else f"{path}: {message}")

    text = read_text(path, error)
    try:
        data, lines = parse_toml(text, str(path))
    except MachineFileError as exc:
        raise InputError(str(exc)) from None
    extra = set(data) - {"masses", "bodies"}
    if extra or "bodies" not in data:
        raise error("a joint-chain masses file has a [bodies.NAME] table per body (and an "
                    f"optional [masses]); found {', '.join(sorted(data)) or 'nothing'}")
    head = data.get("masses", {})
    bad = set(head) - {"units", "gravity"}
    if bad:
        raise error(f"unknown key(s) {', '.join(sorted(bad))} in [masses]; valid: gravity, "
                    "units")
    try:
        scale = length_scale(head.get("units", "m"))
    except Exception as exc:  # ParameterError
        raise error(str(exc)) from None
    try:
        gravity = _vector(head.get("gravity", [0.0, 0.0, -9.81]), "gravity")
        refuse_beyond("gravity component", gravity, MAX_GRAVITY, "m/s²")
    except InputError as exc:
        raise error(str(exc.args[0]), lines.get(("masses", "gravity"))) from None
    valid = body_names(machine)
    bodies = {}
    for name, table in data["bodies"].items():
        line = lines.get(("bodies", name)) or lines.get(("bodies", name, "mass"))
        if name not in valid:
            raise error(f"machine {machine.id!r} has no body {name!r}; its bodies: "
                        f"{', '.join(valid)}", line)
        if not isinstance(table, dict) or set(table) - {"mass", "com", "inertia"} or (
                "mass" not in table):
            raise error(f"[bodies.{name}] needs mass (kg) and may give com and inertia", line)
        mass = table["mass"]
        if not is_plain_number(mass) or np.ndim(mass) != 0 or not 0 < float(mass):
            raise error(f"[bodies.{name}] mass must be one number > 0 (kg), got {mass!r}", line)
        key = "mass"
        try:
            refuse_beyond(f"[bodies.{name}] mass", np.array([float(mass)]), MAX_MASS, "kg")
            key = "com"
            com = _vector(table.get("com", [0.0, 0.0, 0.0]), f"[bodies.{name}] com")
            com = com * scale
            refuse_beyond(f"[bodies.{name}] com component", com, MAX_LENGTH, "m")
            key = "inertia"
            inertia = _inertia(table.get("inertia"), float(mass), f"[bodies.{name}]")
        except InputError as exc:
            raise error(str(exc.args[0]), lines.get(("bodies", name, key), line)) from None
        bodies[name] = BodyMass(float(mass), com, inertia)
    return ChainBodyMasses(bodies, gravity, str(path))


def read_masses(path: str | Path, machine):
    """The masses file ``path`` for ``machine``'s MJCF or URDF: a joint-chain machine's bodies
    (:func:`load_chain_masses`), a rod-leg machine's carriages (a crank's arm), rods and
    platform (:func:`pkmkit.dynamics.masses.load_masses`).

    Raises:
        InputError: the file does not fit the machine (with its line).
    """
    from pkmkit.export.base import machine_family

    if machine_family(machine) == "chain":  # the formats' own table: chains vs rod legs
        return load_chain_masses(path, machine)
    from pkmkit.dynamics.masses import load_masses

    return load_masses(path, machine)[0]
