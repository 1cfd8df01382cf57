"""The scalar parameters a design may vary, for any machine.

- a machine of a built-in kind: its named parameters, one scalar per parameter (``R``, ``L``) or
  per component of a vector parameter (``angles[1]``, ``B[0]``);
- a ``rod-legs`` machine (described leg by leg in its file): its leg fields, ``legs[i].length``,
  ``legs[i].base[k]``, ``legs[i].platform[k]``, ``legs[i].axis[k]``,
  ``legs[i].parallelogram_width``, ``legs[i].stroke[0|1]`` (see
  :func:`pkmkit.machines.registry.leg_parameters`).

Values are in SI units (m, rad). :func:`with_values` returns a new machine (machines are
immutable values): :meth:`Machine.with_params` for a kind, :func:`with_leg_values` for rod legs.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.machines.registry import leg_parameters, with_leg_values


@dataclass(frozen=True)
class ScalarParameter:
    """One variable scalar of a machine: its name, current value (SI) and quantity
    (``"length"``, m; ``"angle"``, rad; ``"number"``, dimensionless)."""

    name: str
    value: float
    quantity: str


def scalar_parameters(machine: Machine) -> dict[str, ScalarParameter]:
    """Every scalar that :func:`with_values` can change, by name (see the module docstring)."""
    out: dict[str, ScalarParameter] = {}
    if machine.kind is None:
        for name, (value, quantity) in leg_parameters(machine).items():
            out[name] = ScalarParameter(name, value, quantity)
        return out
    for spec in machine.kind.parameters:
        value = machine.params[spec.name]
        if spec.size is None:
            out[spec.name] = ScalarParameter(spec.name, float(value), spec.quantity)
        else:
            for i in range(spec.size):
                name = f"{spec.name}[{i}]"
                out[name] = ScalarParameter(name, float(value[i]), spec.quantity)
    return out


def check_names(machine: Machine, names: list[str]) -> dict[str, ScalarParameter]:
    """The parameters of ``names`` (validated: known to ``machine``, no duplicates).

    Raises:
        InputError: a duplicate name, an unknown one (the message lists the valid names), or a
            vector parameter without a component index.
    """
    table = scalar_parameters(machine)
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise InputError(f"design variable {name!r} is given twice")
        seen.add(name)
        if name in table:
            continue
        components = [n for n in table if n.startswith(f"{name}[")]
        if components:
            raise InputError(f"parameter {name!r} has {len(components)} components: vary them "
                             f"one by one, {components[0]} … {components[-1]}")
        raise InputError(f"unknown parameter {name!r} of {machine.id!r}; valid names: "
                         f"{', '.join(_summary(table))}")
    return {n: table[n] for n in names}


def _summary(table: Mapping[str, ScalarParameter]) -> list[str]:
    """Names with vector components collapsed (``angles[0..2]``)."""
    out: list[str] = []
    groups: dict[str, int] = {}
    for name in table:
        head, bracket, _ = name.rpartition("[")
        if bracket and name.endswith("]"):
            if head not in groups:
                out.append(head)
            groups[head] = groups.get(head, 0) + 1
        else:
            out.append(name)
    return [f"{n}[0..{groups[n] - 1}]" if n in groups else n for n in out]


def with_values(machine: Machine, values: Mapping[str, float]) -> Machine:
    """A new machine with the scalars ``values`` (name → SI value) changed.

    Raises:
        ParameterError: values that make an invalid machine.
        InputError: an unknown name.
    """
    if machine.kind is None:
        return with_leg_values(machine, values)
    check_names(machine, list(values))
    updates: dict[str, float | tuple[float, ...]] = {}
    for name, value in values.items():
        head, bracket, rest = name.partition("[")
        if not bracket:
            updates[name] = float(value)
            continue
        current = list(updates.get(head, machine.params[head]))
        current[int(rest[:-1])] = float(value)
        updates[head] = tuple(current)
    return machine.with_params(**updates)


def boundary_factor(quantity: str, length_scale: float) -> float:
    """SI value per boundary unit (lengths in the unit of ``length_scale`` m, areas in its
    square, angles in degrees, stiffnesses in N/µm)."""
    return {"length": length_scale, "area": length_scale**2, "angle": math.pi / 180.0,
            "stiffness": 1e6, "number": 1.0}[quantity]


def boundary_unit(quantity: str, length_unit: str) -> str:
    """Unit symbol of a quantity at the boundary (``""`` for a number)."""
    return {"length": length_unit, "area": f"{length_unit}^2", "angle": "deg",
            "stiffness": "N/µm", "number": ""}[quantity]
