"""Mass properties of a rod-leg machine, and the masses file.

A masses file (TOML) gives, in SI units unless ``units = "mm"`` (lengths only)::

    [masses]
    carriage = 8.0            # kg, moving part of each actuator (one value or one per actuator)
    rod = 1.31                # kg per rod (one value or one per rod; a strut's cylinder) ...
    rod_diameter = 0.040      # ... or computed from a section and a density:
    rod_inner_diameter = 0.0  # (hollow rods)
    rod_density = 7700        # kg/m³
    platform = 15.0           # kg, platform with spindle and tool
    platform_com = [0, 0, -0.05]      # m, platform frame (not needed for actuator forces)
    gravity = [0, 0, -9.81]   # m/s²
    piston = 2.0              # strut legs only: kg of the piston (platform side), and the
    cylinder_length = 0.6     # lengths of the two tubes (default 0.6 × the strut length at
    piston_length = 0.6       # q = 0 each); the cylinder hangs from the base joint

    [wrench]                  # optional constant cutting wrench at the tool point
    force = [0, 0, 100]       # N
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, MachineFileError, UnsupportedOperationError
from pkmkit.machines.machine import Machine
from pkmkit.model.machine_file import parse_toml
from pkmkit.model.parameters import MAX_LENGTH, is_plain_number, length_scale
from pkmkit.model.rods import STRUT
from pkmkit.model.text_files import number_problem, read_text
from pkmkit.numerics.magnitudes import (
    MAX_DENSITY,
    MAX_FORCE,
    MAX_GRAVITY,
    MAX_INERTIA,
    MAX_MASS,
)


@dataclass(frozen=True)
class MassProperties:
    """Masses of a machine's moving bodies (SI units).

    Attributes:
        carriage_mass: ``(n,)`` kg.
        rod_mass: ``(m,)`` kg, one per rod (uniform cylinders).
        rod_radius: ``(m,)`` m (0: slender rods).
        platform_mass: kg.
        platform_com: ``(3,)`` m, platform frame.
        platform_inertia: ``(3, 3)`` kg·m² about the centre of mass.
        gravity: ``(3,)`` m/s².
        piston_mass: ``(m,)`` kg, strut legs only (0 for slide rods): the part of the strut
            hinged at the platform joint; ``rod_mass`` is then the cylinder, hinged at the base.
        cylinder_length, piston_length: ``(m,)`` m, strut legs only: lengths of the two uniform
            tubes (centre of mass at mid-length, measured from their own joint).
    """

    carriage_mass: np.ndarray
    rod_mass: np.ndarray
    rod_radius: np.ndarray
    platform_mass: float
    platform_com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    platform_inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))
    piston_mass: np.ndarray | None = None
    cylinder_length: np.ndarray | None = None
    piston_length: np.ndarray | None = None

    def strut_parts(self, m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(piston_mass, cylinder_length, piston_length)``, each ``(m,)`` (zeros if unset)."""
        return tuple(np.zeros(m) if a is None else a
                     for a in (self.piston_mass, self.cylinder_length, self.piston_length))

    def check(self, machine: Machine) -> None:
        """Raise :class:`InputError` if the sizes do not fit ``machine``, a mass is negative or
        strut data is given for slide rods (or missing for struts with mass)."""
        n, m = machine.n_actuators, machine.model.n_rods
        if self.carriage_mass.shape != (n,):
            raise InputError(f"{n} carriage masses needed, got {self.carriage_mass.shape}")
        if self.rod_mass.shape != (m,) or self.rod_radius.shape != (m,):
            raise InputError(f"{m} rod masses and radii needed")
        parts = self.strut_parts(m)
        if any(a.shape != (m,) for a in parts):
            raise InputError(f"{m} piston masses and tube lengths needed")
        values = np.concatenate([self.carriage_mass, self.rod_mass, self.rod_radius,
                                 [self.platform_mass], *parts])
        if not np.isfinite(values).all() or (values < 0).any():
            raise InputError("masses, radii and lengths must be finite and >= 0")
        piston, cylinder_length, piston_length = parts
        for what, arr, limit, unit in (
                ("carriage mass", self.carriage_mass, MAX_MASS, "kg"),
                ("rod mass", self.rod_mass, MAX_MASS, "kg"),
                ("piston mass", piston, MAX_MASS, "kg"),
                ("platform mass", np.array([self.platform_mass]), MAX_MASS, "kg"),
                ("rod radius", self.rod_radius, MAX_LENGTH, "m"),
                ("cylinder length", cylinder_length, MAX_LENGTH, "m"),
                ("piston length", piston_length, MAX_LENGTH, "m"),
                ("platform_com component", np.asarray(self.platform_com), MAX_LENGTH, "m"),
                ("platform_inertia entry", np.ravel(self.platform_inertia), MAX_INERTIA,
                 "kg·m²"),
                ("gravity component", np.asarray(self.gravity), MAX_GRAVITY, "m/s²")):
            refuse_beyond(what, np.asarray(arr, dtype=float), limit, unit)
        strut = machine.model.rod_kind == STRUT
        if (piston[~strut] > 0).any():
            raise InputError("piston masses apply to strut legs only")
        for mass, length, what in ((self.rod_mass, cylinder_length, "cylinder"),
                                   (piston, piston_length, "piston")):
            if (strut & (mass > 0) & (length <= 0)).any():
                raise InputError(f"a strut with a {what} mass needs a {what} length > 0")

    @property
    def total_mass(self) -> float:
        piston = 0.0 if self.piston_mass is None else float(self.piston_mass.sum())
        return float(self.carriage_mass.sum() + self.rod_mass.sum() + self.platform_mass
                     + piston)


def refuse_beyond(what: str, values: np.ndarray, limit: float, unit: str) -> None:
    """An :class:`InputError` naming the first of ``values`` (``(k,)``, SI) that is not finite or
    is beyond ``limit`` in magnitude: ``"rod mass 2 = 1e+308 kg is beyond 1e+06 kg …"``."""
    values = np.ravel(np.asarray(values, dtype=float))
    big = np.flatnonzero(~(np.abs(values) <= limit))
    if big.size:
        k = int(big[0])
        which = f" {k + 1}" if values.size > 1 else ""
        if not math.isfinite(values[k]):
            raise InputError(f"{what}{which} must be a finite number, got {values[k]:g}")
        raise InputError(f"{what}{which} = {values[k]:g} {unit} is beyond {limit:g} {unit}, the "
                         "largest pkmkit accepts: check the units")


#: Default length of a strut's cylinder and of its piston, as a fraction of the strut's length at
#: q = 0 (the two tubes overlap in the middle).
STRUT_TUBE_FRACTION = 0.6


def strut_tube_lengths(machine: Machine, cylinder_length: Any = None,
                       piston_length: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Cylinder and piston lengths ``(m,)`` (m) of the strut rods (0 for slide rods); None gives
    :data:`STRUT_TUBE_FRACTION` of each strut's length at q = 0."""
    model = machine.model
    strut = model.rod_kind == STRUT
    out = []
    for value, what in ((cylinder_length, "cylinder_length"), (piston_length, "piston_length")):
        if value is None:
            arr = STRUT_TUBE_FRACTION * model.rod_length
        elif not is_plain_number(value):
            raise InputError(f"{what} must be numbers, got {value!r}")
        elif np.ndim(value) == 0:
            arr = np.full(model.n_rods, float(value))
        elif np.shape(value) == (model.n_rods,):
            arr = np.asarray(value, dtype=float)
        else:
            raise InputError(f"{what} needs 1 or {model.n_rods} values")
        out.append(np.where(strut, arr, 0.0))
    return out[0], out[1]


def rod_section_mass(machine: Machine, diameter: float, density: float,
                     inner_diameter: float = 0.0, *, cylinder_length: Any = None,
                     piston_length: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Masses of the machine's rods for a circular (hollow) section of outer diameter D and inner
    diameter d, and their equivalent radius: a tube's transverse inertia about its centre is
    m(ℓ²/12 + (D² + d²)/16), the solid-cylinder formula m(ℓ²/12 + ρ²/4) with ρ = √((D² + d²)/4).

    Returns:
        ``(rod_mass, rod_radius, piston_mass)``, each ``(m,)`` (kg, m, kg): for a slide rod the
        whole rod (piston 0); for a strut its cylinder and its piston, tubes of the lengths of
        :func:`strut_tube_lengths`.
    """
    if not (diameter > 0 and density > 0 and 0 <= inner_diameter < diameter):
        raise InputError("rod section: need diameter > 0, density > 0, 0 <= inner < diameter")
    refuse_beyond("rod_diameter", np.array([diameter]), MAX_LENGTH, "m")
    refuse_beyond("rod_density", np.array([density]), MAX_DENSITY, "kg/m³")
    model = machine.model
    area = math.pi / 4 * (diameter**2 - inner_diameter**2)
    cylinder, piston = strut_tube_lengths(machine, cylinder_length, piston_length)
    strut = model.rod_kind == STRUT
    mass = density * area * np.where(strut, cylinder, model.rod_length)
    radius = np.full(model.n_rods, math.sqrt((diameter**2 + inner_diameter**2) / 4))
    return mass, radius, density * area * piston


def _scalar(value: Any, what: str) -> float:
    if not is_plain_number(value) or np.ndim(value) != 0:
        raise InputError(f"{what} must be one number, got {value!r}")
    return float(value)


def _inertia(value: Any) -> np.ndarray:
    if value is None:
        return np.zeros((3, 3))
    if not is_plain_number(value) or np.shape(value) not in ((3, 3), (9,)):
        raise InputError(f"platform_inertia must be a 3 × 3 matrix (kg·m²), got {value!r}")
    inertia = np.asarray(value, dtype=float).reshape(3, 3)
    if not np.isfinite(inertia).all():
        raise InputError(f"platform_inertia must be finite, got {inertia.ravel().tolist()}")
    refuse_beyond("platform_inertia entry", inertia, MAX_INERTIA, "kg·m²")
    if not np.allclose(inertia, inertia.T):
        raise InputError("platform_inertia must be symmetric")
    return inertia


def mass_properties(machine: Machine, *, carriage: Any = 0.0, rod: Any = 0.0,
                    rod_radius: Any = 0.0, platform: float = 0.0, platform_com: Any = None,
                    platform_inertia: Any = None, gravity: Any = (0.0, 0.0, -9.81),
                    piston: Any = 0.0, cylinder_length: Any = None, piston_length: Any = None
                    ) -> MassProperties:
    """Build and check :class:`MassProperties`, broadcasting scalars (SI units).

    For strut legs, ``rod`` is the cylinder (hinged at the base joint) and ``piston`` the part
    hinged at the platform joint; their tube lengths default to :func:`strut_tube_lengths`.
    Values given for slide rods in ``piston`` must be 0.

    Raises:
        UnsupportedOperationError: a joint-chain machine (its members are links, not rods).
    """
    if machine.elastic_members != "rods":
        raise UnsupportedOperationError(
            "a rod-leg mass model", machine.id, "joint-chain",
            "pkmkit's masses (carriages, rods, platform) describe rod-leg machines; a "
            "joint-chain machine's members are links")
    n, m = machine.n_actuators, machine.model.n_rods

    def vec(value: Any, size: int, what: str) -> np.ndarray:
        if not is_plain_number(value):
            raise InputError(f"{what} must be numbers, got {value!r}")
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 0:
            return np.full(size, float(arr))
        if arr.shape != (size,):
            raise InputError(f"{what} needs 1 or {size} values, got {arr.shape[0]}")
        return arr.copy()

    props = MassProperties(
        carriage_mass=vec(carriage, n, "carriage"), rod_mass=vec(rod, m, "rod"),
        rod_radius=vec(rod_radius, m, "rod_radius"),
        platform_mass=_scalar(platform, "platform"),
        platform_com=np.zeros(3) if platform_com is None else vec(platform_com, 3,
                                                                  "platform_com"),
        platform_inertia=_inertia(platform_inertia),
        gravity=vec(gravity, 3, "gravity"),
    )
    cyl_len, pis_len = strut_tube_lengths(machine, cylinder_length, piston_length)
    pis = vec(piston, m, "piston")
    if np.ndim(piston) == 0:  # one value: the piston of every strut
        pis = np.where(machine.model.rod_kind == STRUT, pis, 0.0)
    props = dataclasses.replace(props, piston_mass=pis, cylinder_length=cyl_len,
                                piston_length=pis_len)
    props.check(machine)
    return props


_KEYS = {"carriage", "rod", "rod_diameter", "rod_inner_diameter", "rod_density", "rod_radius",
         "platform", "platform_com", "platform_inertia", "gravity", "units", "piston",
         "cylinder_length", "piston_length"}


#: Bounds of the [masses] keys that are not lengths (checked with their file line).
_BOUNDS = (("carriage", MAX_MASS, "kg"), ("rod", MAX_MASS, "kg"), ("piston", MAX_MASS, "kg"),
           ("platform", MAX_MASS, "kg"), ("rod_density", MAX_DENSITY, "kg/m³"),
           ("gravity", MAX_GRAVITY, "m/s²"), ("platform_inertia", MAX_INERTIA, "kg·m²"))
#: The [masses] keys that are lengths (in the file's ``units``).
_LENGTH_KEYS = ("rod_diameter", "rod_inner_diameter", "rod_radius", "platform_com",
                "cylinder_length", "piston_length")


def load_masses(path: str | Path, machine: Machine) -> tuple[MassProperties, np.ndarray | None]:
    """Read a masses file (see the module docstring): ``(mass properties, wrench or None)``.

    Raises:
        InputError: unreadable or binary file, syntax error, a number that overflows or
            underflows to 0 (with its line), unknown keys, negative masses, sizes that do not
            fit.
    """
    def error(message: str, line: int | None) -> InputError:
        return InputError(f"{path}:{line}: {message}" if line else f"{path}: {message}")

    text = read_text(path, error)
    try:
        data, lines = parse_toml(text, str(path))
    except MachineFileError as exc:
        raise InputError(str(exc)) from None
    rows = text.splitlines()
    for key_path, line in sorted(lines.items(), key=lambda item: item[1]):
        if len(key_path) == 2 and 0 < line <= len(rows):
            problem = number_problem(rows[line - 1].split("#", 1)[0].partition("=")[2])
            if problem:
                raise error(f"{key_path[1]}: {problem}", line)
    unknown = set(data) - {"masses", "wrench"}
    if unknown or "masses" not in data:
        raise InputError(f"{path}: expected a [masses] table (and optionally [wrench]); found "
                         f"{', '.join(sorted(data)) or 'nothing'}")
    table = data["masses"]
    bad = set(table) - _KEYS
    if bad:
        raise InputError(f"{path}: unknown key(s) {', '.join(sorted(bad))} in [masses]; valid: "
                         f"{', '.join(sorted(_KEYS))}")
    try:
        scale = length_scale(table.get("units", "m"))
    except Exception as exc:  # ParameterError
        raise InputError(f"{path}: {exc}") from None
    unit_name = table.get("units", "m")
    bounds = (*_BOUNDS, *((key, MAX_LENGTH / scale, unit_name) for key in _LENGTH_KEYS))
    for key, limit, unit in bounds:
        if key in table and is_plain_number(table[key]):
            try:
                values = np.asarray(table[key], dtype=float)
            except ValueError:  # ragged: refused below with the shape it should have
                continue
            try:
                refuse_beyond(key, values, limit, unit)
            except InputError as exc:
                raise error(str(exc), lines.get(("masses", key))) from None
    try:
        rod, radius = table.get("rod", 0.0), table.get("rod_radius", 0.0)
        piston = table.get("piston", 0.0)
        tubes = {key: (None if key not in table
                       else np.asarray(table[key], dtype=float) * scale)
                 for key in ("cylinder_length", "piston_length")}
        if "rod_diameter" in table:
            if "rod" in table or "piston" in table:
                raise InputError("give either 'rod' (and 'piston') masses or 'rod_diameter' "
                                 "with 'rod_density'")
            rod, radius, piston = rod_section_mass(
                machine, float(table["rod_diameter"]) * scale,
                float(table.get("rod_density", 7700.0)),
                float(table.get("rod_inner_diameter", 0.0)) * scale, **tubes)
        else:
            radius = np.asarray(radius, dtype=float) * scale
        props = mass_properties(
            machine, carriage=table.get("carriage", 0.0), rod=rod, rod_radius=radius,
            platform=table.get("platform", 0.0),
            platform_com=(None if "platform_com" not in table
                          else np.asarray(table["platform_com"], dtype=float) * scale),
            platform_inertia=table.get("platform_inertia"),
            gravity=table.get("gravity", (0.0, 0.0, -9.81)), piston=piston, **tubes)
    except (InputError, TypeError, ValueError) as exc:
        raise InputError(f"{path}: {exc}") from None
    wrench = None
    if "wrench" in data:
        w = data["wrench"]
        extra = set(w) - {"force", "moment"}
        if extra:
            raise InputError(f"{path}: unknown key(s) {', '.join(sorted(extra))} in [wrench]")
        wrench = np.concatenate([np.asarray(w.get("force", [0, 0, 0]), dtype=float),
                                 np.asarray(w.get("moment", [0, 0, 0]), dtype=float)])
        if wrench.shape != (6,) or not np.isfinite(wrench).all():
            raise InputError(f"{path}: [wrench] force and moment need 3 finite numbers each")
        for key, part, unit in (("force", wrench[:3], "N"), ("moment", wrench[3:], "N·m")):
            try:
                refuse_beyond(f"[wrench] {key} component", part, MAX_FORCE, unit)
            except InputError as exc:
                raise error(str(exc), lines.get(("wrench", key))) from None
    return props, wrench
