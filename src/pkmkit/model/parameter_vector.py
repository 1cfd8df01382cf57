"""One parameter vector: a flat float array with an immutable index.

Every entry has a **name**, an SI **unit** (``"m"``, ``"rad"``, ``"1"``), a **role** —
``"nominal"`` (the geometry a machine is built from), ``"defect"`` (an absolute deviation from
it, :mod:`pkmkit.model.defect_rule`) or ``"set-up"`` (what a measurement adds: an instrument
frame, a pivot, a tool length) — an **owner** (``"machine"``, a leg, a rod, an actuator, a
joint-chain element, ``"frame"``) and its **source**: the name the entry has in its own scheme
(``"angles"`` component 1 of a kind's vector parameter, ``"legs.0.base"``, ``dA1x``, ``I21``,
``frame_rx``). The mapping from those schemes is tabled in ``docs/architecture.md``; a
machine's vector is ``machine.parameters()`` (:mod:`pkmkit.machines.parameter_vector`).

Units: SI inside; values are read-only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, ParameterError

#: The roles of a parameter.
ROLES = ("nominal", "defect", "set-up")
#: The SI units a parameter may have.
UNITS = ("m", "rad", "1")


@dataclass(frozen=True)
class ParameterIndex:
    """The immutable index of a parameter vector (all tuples of length p).

    Attributes:
        names: unique names (a kind's vector parameter ``angles`` gives ``angles[0]`` …).
        units: ``"m"``, ``"rad"`` or ``"1"`` (dimensionless: direction components).
        roles: one of :data:`ROLES` each.
        owners: what each belongs to (``"machine"``, ``"leg 2"``, ``"rod 3"``, ``"q1"``,
            ``"element psi1"``, ``"frame"``).
        sources: each entry's name in its own naming scheme.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    roles: tuple[str, ...]
    owners: tuple[str, ...]
    sources: tuple[str, ...]

    def __post_init__(self) -> None:
        n = len(self.names)
        if any(len(t) != n for t in (self.units, self.roles, self.owners, self.sources)):
            raise InputError("a parameter index needs as many units, roles, owners and sources "
                             "as names")
        if len(set(self.names)) != n:
            dup = sorted({x for x in self.names if self.names.count(x) > 1})
            raise ParameterError(f"parameter names must be unique; repeated: {', '.join(dup)}")
        bad = sorted(set(self.roles) - set(ROLES)) + sorted(set(self.units) - set(UNITS))
        if bad:
            raise InputError(f"unknown parameter roles or units: {', '.join(bad)}")
        object.__setattr__(self, "_position", {name: i for i, name in enumerate(self.names)})

    def __len__(self) -> int:
        return len(self.names)

    def position(self, name: str) -> int:
        """Position of a parameter by name.

        Raises:
            ParameterError: an unknown name (with some valid ones).
        """
        try:
            return self._position[name]
        except KeyError:
            preview = ", ".join(self.names[:10]) + (", …" if len(self.names) > 10 else "")
            raise ParameterError(f"unknown parameter {name!r}; parameters are named like "
                                 f"{preview}", name) from None

    def select(self, role: str) -> np.ndarray:
        """``(k,)`` positions of the parameters of ``role``."""
        if role not in ROLES:
            raise InputError(f"role must be one of {', '.join(ROLES)}, got {role!r}")
        return np.flatnonzero(np.array(self.roles) == role) if self.names else np.zeros(0, int)

    def subset(self, positions: Sequence[int]) -> ParameterIndex:
        """The index of the entries at ``positions`` (in that order)."""
        pos = [int(i) for i in positions]
        return ParameterIndex(*(tuple(t[i] for i in pos) for t in (
            self.names, self.units, self.roles, self.owners, self.sources)))

    def __add__(self, other: ParameterIndex) -> ParameterIndex:
        return ParameterIndex(self.names + other.names, self.units + other.units,
                              self.roles + other.roles, self.owners + other.owners,
                              self.sources + other.sources)


@dataclass(frozen=True, eq=False)
class ParameterVector:
    """Values ``(p,)`` (SI, read-only) with their :class:`ParameterIndex`.

    Raises (construction):
        InputError: values not p finite numbers.
    """

    values: np.ndarray
    index: ParameterIndex

    def __post_init__(self) -> None:
        values = np.array(self.values, dtype=float).reshape(-1)
        if values.shape != (len(self.index),) or not np.isfinite(values).all():
            raise InputError(f"a parameter vector needs {len(self.index)} finite values, got "
                             f"shape {np.shape(self.values)}")
        values.setflags(write=False)
        object.__setattr__(self, "values", values)

    def __len__(self) -> int:
        return len(self.index)

    def __getitem__(self, name: str) -> float:
        return float(self.values[self.index.position(name)])

    @property
    def names(self) -> tuple[str, ...]:
        """The parameter names."""
        return self.index.names

    def as_dict(self) -> dict[str, float]:
        """Name → SI value."""
        return dict(zip(self.index.names, self.values.tolist(), strict=True))

    def replace(self, changes: Mapping[str, Any] | None = None, **named: Any) -> ParameterVector:
        """A copy with some values changed (SI), by name.

        Raises:
            ParameterError: an unknown name.
        """
        values = self.values.copy()
        for name, value in {**(changes or {}), **named}.items():
            values[self.index.position(name)] = float(value)
        return ParameterVector(values, self.index)

    def with_values(self, values: Any) -> ParameterVector:
        """The same index with new values ``(p,)``."""
        return ParameterVector(np.asarray(values, dtype=float), self.index)

    def role(self, role: str) -> ParameterVector:
        """The sub-vector of one role."""
        pos = self.index.select(role)
        return ParameterVector(self.values[pos], self.index.subset(pos))

    def __add__(self, other: ParameterVector) -> ParameterVector:
        """Concatenation (a machine's vector and a measurement's set-up block)."""
        return ParameterVector(np.concatenate([self.values, other.values]),
                               self.index + other.index)


def parameter_block(names: Sequence[str], units: Sequence[str], values: Any, *, role: str,
                    owners: Sequence[str] | str, sources: Sequence[str] | None = None
                    ) -> ParameterVector:
    """A vector of one role (e.g. the set-up parameters of a calibration model:
    ``parameter_block(setup.names, setup.units, values, role="set-up", owners="frame")``)."""
    names = tuple(names)
    owner = (owners,) * len(names) if isinstance(owners, str) else tuple(owners)
    index = ParameterIndex(names, tuple(units), (role,) * len(names), owner,
                           tuple(sources) if sources is not None else names)
    return ParameterVector(np.asarray(values, dtype=float), index)
