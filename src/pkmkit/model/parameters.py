"""Named, documented machine parameters with units.

A machine kind declares its parameters as :class:`ParameterSpec` values. Values are stored in SI
units (metres, radians). At the boundaries (machine files, the command line) lengths may be
given in another unit (``"m"``, ``"mm"`` or ``"in"``) and angles are given in degrees;
conversion happens only there, through :meth:`ParameterSpec.from_boundary` and
:meth:`ParameterSpec.to_boundary`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from pkmkit.exceptions import ParameterError, UnknownParameterError

#: Length units accepted at the boundaries, as metres per unit.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3, "in": 0.0254}
#: Largest admissible magnitude of a length parameter, m (beyond it squares overflow and the
#: number is certainly a unit mistake).
MAX_LENGTH = 1e6


def is_plain_number(value: Any) -> bool:
    """True for real numbers and (nested) sequences of them — not booleans or strings, which
    NumPy would silently convert."""
    if isinstance(value, bool | np.bool_ | str | bytes):
        return False
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iuf"
    if isinstance(value, list | tuple):
        return all(is_plain_number(v) for v in value)
    return isinstance(value, int | float | np.integer | np.floating)

def plain_floats(value: Any) -> np.ndarray | None:
    """``value`` (plain numbers, :func:`is_plain_number`) as a float array, or None when it is
    not plain numbers, is ragged, or holds an integer too large for a double (a 400-digit
    literal in a file: NumPy raises ``OverflowError`` or keeps it as an object)."""
    if not is_plain_number(value):
        return None
    try:
        return np.asarray(value, dtype=float)
    except (OverflowError, ValueError):
        return None


Quantity = Literal["length", "angle", "number"]


def length_scale(unit: str) -> float:
    """Metres per ``unit``; raises :class:`ParameterError` for an unknown unit."""
    try:
        return LENGTH_UNITS[unit]
    except (KeyError, TypeError):
        raise ParameterError(
            f"unknown length unit {unit!r}; valid units: {', '.join(LENGTH_UNITS)}"
        ) from None


@dataclass(frozen=True)
class ParameterSpec:
    """Declaration of one machine parameter.

    Attributes:
        name: identifier used in the API, files and ``--set NAME=VALUE``.
        quantity: ``"length"`` (m inside), ``"angle"`` (rad inside, degrees at the boundary) or
            ``"number"`` (dimensionless).
        default: default value in SI units (a float, or a tuple for vectors).
        doc: one-line description.
        size: ``None`` for a scalar, else the vector length.
        positive: the value (each component) must be > 0.
    """

    name: str
    quantity: Quantity
    default: float | tuple[float, ...]
    doc: str
    size: int | None = None
    positive: bool = False

    @property
    def si_unit(self) -> str:
        """SI unit symbol of the stored value."""
        return {"length": "m", "angle": "rad", "number": "1"}[self.quantity]

    def boundary_unit(self, length_unit: str = "m") -> str:
        """Unit symbol used at the boundary (files, CLI) for ``length_unit``."""
        return {"length": length_unit, "angle": "deg", "number": "1"}[self.quantity]

    def _scale(self, length_unit: str) -> float:
        if self.quantity == "length":
            return length_scale(length_unit)
        if self.quantity == "angle":
            return math.pi / 180.0
        return 1.0

    def _error(self, machine: str, problem: str) -> ParameterError:
        return ParameterError(f"parameter {self.name!r} of {machine!r} {problem}", self.name)

    def validate(self, value: Any, machine: str) -> float | tuple[float, ...]:
        """Check an SI value (shape, finiteness, sign) and return it as float or tuple."""
        if not is_plain_number(value):
            raise self._error(machine, f"must be numeric, got {value!r}")
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise self._error(machine, f"must be numeric, got {value!r}") from None
        expected = () if self.size is None else (self.size,)
        if arr.shape != expected:
            what = "a scalar" if self.size is None else f"a vector of {self.size} values"
            raise self._error(machine, f"must be {what}, got shape {arr.shape}")
        if not np.isfinite(arr).all():
            raise self._error(machine, "must be finite")
        if self.positive and (arr <= 0).any():
            raise self._error(machine, f"must be > 0, got {value}")
        if self.quantity == "length" and (np.abs(arr) > MAX_LENGTH).any():
            raise self._error(machine, f"is a length beyond {MAX_LENGTH:g} m ({value}); check "
                              "the units")
        if self.quantity == "angle" and (np.abs(arr) > 2 * math.pi + 1e-12).any():
            raise self._error(
                machine,
                f"is an angle in radians in the Python API and must lie in [-2π, 2π]; got "
                f"{value} (degrees are only used in machine files and on the command line)",
            )
        return float(arr) if self.size is None else tuple(float(v) for v in arr)

    def from_boundary(self, value: Any, length_unit: str, machine: str) -> Any:
        """Convert a boundary value (file or CLI units) to a validated SI value."""
        if not is_plain_number(value):
            raise self._error(machine, f"must be numeric, got {value!r}")
        try:
            raw = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise self._error(machine, f"must be numeric, got {value!r}") from None
        if self.quantity == "angle" and (np.abs(raw) > 360.0).any():
            raise self._error(machine, f"is an angle in degrees within [-360, 360]; got {value}")
        return self.validate(raw * self._scale(length_unit), machine)

    def to_boundary(self, value: Any, length_unit: str = "m") -> float | list[float]:
        """Convert an SI value to boundary units (for display and export)."""
        arr = np.asarray(value, dtype=float) / self._scale(length_unit)
        return float(arr) if arr.ndim == 0 else [float(v) for v in arr]

    def parse_text(self, text: str, length_unit: str, machine: str) -> Any:
        """Parse a command-line value (``"0.7"`` or ``"0,120,240"``) into a validated SI value."""
        parts = [p.strip() for p in text.split(",")]
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            raise ParameterError(
                f"parameter {self.name!r}: cannot read {text!r} as comma-separated numbers",
                self.name,
            ) from None
        value: Any = numbers[0] if (self.size is None and len(numbers) == 1) else numbers
        return self.from_boundary(value, length_unit, machine)


def resolve_parameters(
    specs: tuple[ParameterSpec, ...], overrides: Mapping[str, Any], machine: str
) -> dict[str, Any]:
    """Defaults of ``specs`` updated with validated SI ``overrides``.

    Raises:
        UnknownParameterError: an override name is not declared (the message lists the names).
        ParameterError: an override has the wrong shape, is non-finite or out of its domain.
    """
    by_name = {s.name: s for s in specs}
    values = {s.name: s.default for s in specs}
    for name, value in overrides.items():
        if name not in by_name:
            raise UnknownParameterError(name, machine, by_name)
        values[name] = by_name[name].validate(value, machine)
    return values
