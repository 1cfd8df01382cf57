"""The one rule by which geometric defects are applied, for every machine family.

**Defects are absolute deviations from the nominal geometry.** A machine carries its nominal
model and its current defect vector δ; ``with_defects(machine, δ')`` gives the nominal machine
with δ' applied exactly, whatever δ it carried: applying the same defects twice is applying them
once (the rule of a calibrated machine file, whose ``[defects]`` table *is* the machine's
deviation from its kind). To add defects on top of a machine's own, say so:
``add_defects(machine, Δ)`` is ``with_defects(machine, defects(machine) + Δ)`` — what
identification and ``simulate-measurements`` mean, and what their written files hold (the
source's defects plus the new ones), so a written machine file reloads to exactly the machine
that was fitted.

- joint chains keep their nominal frames and defects in their model
  (:meth:`pkmkit.model.chains.JointChainModel.with_defects`);
- rod machines keep them in :attr:`pkmkit.model.rods.RodModel.nominal` and ``.defects``
  (:func:`pkmkit.model.rod_defects.apply_rod_defects` on the nominal model); a rod machine of a
  built-in kind keeps its id but loses its kind's named parameters once it carries defects (its
  geometry is no longer the kind's).

Every defect application in pkmkit goes through :func:`with_defects`:
``machine.with_defects``, :func:`pkmkit.geometric_errors.model.with_defects`, machine files'
``[defects]`` tables, identification, and the deprecated
:func:`pkmkit.model.defects_table.apply_defect_vector`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError


def is_chain(machine) -> bool:
    """True for a joint-chain machine: its model indexes its own defects (the model's declared
    ``owns_defect_index``)."""
    return machine.model.owns_defect_index


def nominal_model(machine):
    """The model of ``machine`` without defects (rod machines; a chain model keeps its nominal
    frames itself)."""
    model = machine.model
    if is_chain(machine):
        return model
    return model.nominal if model.nominal is not None else model


def defect_index(machine):
    """The defect index of ``machine`` (names, units, kinds): its chain model's, or the rod
    index of its nominal model."""
    if is_chain(machine):
        return machine.model.defect_index
    from pkmkit.model.rod_defects import rod_defect_index

    model = nominal_model(machine)
    cached = model.__dict__.get("_defect_index")
    if cached is None:
        cached = rod_defect_index(model)
        for value in vars(cached).values():  # kept on the model every load shares: read-only
            if isinstance(value, np.ndarray):
                value.setflags(write=False)
        object.__setattr__(model, "_defect_index", cached)
    return cached


def defect_owners(machine) -> tuple[str, ...]:
    """The element, rod, leg or actuator each defect belongs to (:func:`defect_index`
    order)."""
    index = defect_index(machine)
    if is_chain(machine):
        return tuple(machine.model.elements[e].name for e in index.element)
    model = nominal_model(machine)
    return tuple(f"rod {t + 1}" if index.level == "rods" else model.leg_names[t]
                 if k in ("base", "platform", "length") else model.actuator_names[t]
                 for k, t in zip(index.kind, index.target, strict=True))


def defects(machine) -> np.ndarray:
    """``(d,)`` the machine's current defects (SI, :func:`defect_index` order); zeros for a
    nominal machine. A copy."""
    if is_chain(machine):
        return np.array(machine.model.defects, dtype=float)
    current = machine.model.defects
    if current is None:
        return np.zeros(len(defect_index(machine)))
    return np.array(current, dtype=float)


def defect_vector(machine, values: Any) -> np.ndarray:
    """A full SI defect vector from a mapping name → value (absent names 0) or a vector.

    Raises:
        ParameterError: an unknown name, or a vector of the wrong length or not finite.
    """
    index = defect_index(machine)
    if isinstance(values, Mapping):
        out = np.zeros(len(index))
        for name, value in values.items():
            out[index.index(name)] = float(value)
        return out
    arr = np.asarray(values, dtype=float).reshape(-1)
    if arr.shape != (len(index),) or not np.isfinite(arr).all():
        raise ParameterError(f"defects must be {len(index)} finite values, got shape "
                             f"{arr.shape}")
    return arr


def with_defects(machine, values: Any):
    """``machine``'s nominal geometry with the defects ``values`` (mapping name → SI value,
    absent names 0, or a full vector) applied exactly, replacing any defects it carried (the
    module's rule). The original is unchanged; the same defects give the machine back.

    Raises:
        ParameterError: an unknown name, a mis-shaped vector, or defects too large to apply
            (an axis tilted beyond 90°, a non-positive rod length).
    """
    delta = defect_vector(machine, values)
    if np.array_equal(delta, defects(machine)):
        return machine
    if is_chain(machine):
        return replace(machine, model=machine.model.with_defects(delta))
    from pkmkit.model.rod_defects import apply_rod_defects

    nominal = nominal_model(machine)
    kind = nominal_kind(machine)
    if not np.any(delta):
        if kind is not None:  # the nominal machine of its kind, whole again
            return replace(machine, model=nominal, kind=kind[0], params=dict(kind[1]))
        return replace(machine, model=nominal)
    moved = apply_rod_defects(nominal, defect_index(machine), delta)
    frozen = np.array(delta, dtype=float)
    frozen.setflags(write=False)
    return replace(machine, model=replace(moved, nominal=nominal, defects=frozen,
                                          nominal_kind=kind), kind=None, params={})


def nominal_kind(machine) -> tuple | None:
    """``(kind, params)`` of the nominal machine of a built-in kind — the machine's own, or,
    for a rod machine carrying defects, those it had before them — else None."""
    if machine.kind is not None:
        return machine.kind, dict(machine.params)
    if is_chain(machine):
        return None
    return machine.model.nominal_kind


def add_defects(machine, increment: Any):
    """``machine`` with ``increment`` (mapping or full SI vector) added to its own defects:
    ``with_defects(machine, defects(machine) + increment)``."""
    return with_defects(machine, defects(machine) + defect_vector(machine, increment))
