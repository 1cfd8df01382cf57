"""Mass properties of a rod-leg machine, and the masses file.

A masses file (TOML) gives, in SI units unless ``units = "mm"`` (lengths only)::

    [masses]
    carriage = 8.0            # kg, moving part of each actuator (one value or one per actuator)
    rod = 1.31                # kg per rod (one value or one per rod) ...
    rod_diameter = 0.040      # ... or computed from a section and a density:
    rod_inner_diameter = 0.0  # (hollow rods)
    rod_density = 7700        # kg/m³
    platform = 15.0           # kg, platform with spindle and tool
    platform_com = [0, 0, -0.05]      # m, platform frame (not needed for actuator forces)
    gravity = [0, 0, -9.81]   # m/s²

    [wrench]                  # optional constant cutting wrench at the tool point
    force = [0, 0, 100]       # N
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pkmkit.errors import InputError
from pkmkit.machines.machine import Machine
from pkmkit.model.parameters import is_plain_number, length_scale


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
    """

    carriage_mass: np.ndarray
    rod_mass: np.ndarray
    rod_radius: np.ndarray
    platform_mass: float
    platform_com: np.ndarray = field(default_factory=lambda: np.zeros(3))
    platform_inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.81]))

    def check(self, machine: Machine) -> None:
        """Raise :class:`InputError` if the sizes do not fit ``machine`` or a mass is negative."""
        n, m = machine.n_actuators, machine.model.n_rods
        if self.carriage_mass.shape != (n,):
            raise InputError(f"{n} carriage masses needed, got {self.carriage_mass.shape}")
        if self.rod_mass.shape != (m,) or self.rod_radius.shape != (m,):
            raise InputError(f"{m} rod masses and radii needed")
        values = np.concatenate([self.carriage_mass, self.rod_mass, self.rod_radius,
                                 [self.platform_mass]])
        if not np.isfinite(values).all() or (values < 0).any():
            raise InputError("masses and radii must be finite and >= 0")
        if not np.isfinite(self.gravity).all():
            raise InputError("gravity must be finite")

    @property
    def total_mass(self) -> float:
        return float(self.carriage_mass.sum() + self.rod_mass.sum() + self.platform_mass)


def rod_section_mass(machine: Machine, diameter: float, density: float,
                     inner_diameter: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Masses ``(m,)`` (kg) and equivalent radii ``(m,)`` (m) of the machine's rods for a circular
    (hollow) section of outer diameter D and inner diameter d: a tube's transverse inertia about
    its centre is m(ℓ²/12 + (D² + d²)/16), the solid-cylinder formula m(ℓ²/12 + ρ²/4) with
    ρ = √((D² + d²)/4)."""
    if not (diameter > 0 and density > 0 and 0 <= inner_diameter < diameter):
        raise InputError("rod section: need diameter > 0, density > 0, 0 <= inner < diameter")
    area = math.pi / 4 * (diameter**2 - inner_diameter**2)
    mass = density * area * machine.model.rod_length
    radius = np.full(machine.model.n_rods, math.sqrt((diameter**2 + inner_diameter**2) / 4))
    return mass, radius


def mass_properties(machine: Machine, *, carriage: Any = 0.0, rod: Any = 0.0,
                    rod_radius: Any = 0.0, platform: float = 0.0, platform_com: Any = None,
                    platform_inertia: Any = None, gravity: Any = (0.0, 0.0, -9.81)
                    ) -> MassProperties:
    """Build and check :class:`MassProperties`, broadcasting scalars."""
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
        platform_mass=float(vec(platform, 1, "platform")[0]),
        platform_com=np.zeros(3) if platform_com is None else vec(platform_com, 3,
                                                                  "platform_com"),
        platform_inertia=(np.zeros((3, 3)) if platform_inertia is None
                          else np.asarray(platform_inertia, dtype=float).reshape(3, 3)),
        gravity=vec(gravity, 3, "gravity"),
    )
    props.check(machine)
    return props


_KEYS = {"carriage", "rod", "rod_diameter", "rod_inner_diameter", "rod_density", "rod_radius",
         "platform", "platform_com", "platform_inertia", "gravity", "units"}


def load_masses(path: str | Path, machine: Machine) -> tuple[MassProperties, np.ndarray | None]:
    """Read a masses file (see the module docstring): ``(mass properties, wrench or None)``.

    Raises:
        InputError: unreadable file, unknown keys, negative masses, sizes that do not fit.
    """
    try:
        data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read file: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{path}: TOML syntax error: {exc}") from None
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
    try:
        rod, radius = table.get("rod", 0.0), table.get("rod_radius", 0.0)
        if "rod_diameter" in table:
            if "rod" in table:
                raise InputError("give either 'rod' (mass) or 'rod_diameter' with 'rod_density'")
            rod, radius = rod_section_mass(
                machine, float(table["rod_diameter"]) * scale,
                float(table.get("rod_density", 7700.0)),
                float(table.get("rod_inner_diameter", 0.0)) * scale)
        else:
            radius = np.asarray(radius, dtype=float) * scale
        props = mass_properties(
            machine, carriage=table.get("carriage", 0.0), rod=rod, rod_radius=radius,
            platform=table.get("platform", 0.0),
            platform_com=(None if "platform_com" not in table
                          else np.asarray(table["platform_com"], dtype=float) * scale),
            platform_inertia=table.get("platform_inertia"),
            gravity=table.get("gravity", (0.0, 0.0, -9.81)))
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
    return props, wrench
