"""A machine's one parameter vector (:class:`pkmkit.model.parameter_vector.ParameterVector`):
its nominal parameters, then its defects — ``machine.parameters()`` — and the machine rebuilt
from a changed vector — ``machine.with_parameters(vector)``.

**Nominal block**, in the scheme the machine is described in:

- a machine of a built-in kind (any family): the kind's named parameters, in declaration order;
  a vector parameter ``angles`` gives ``angles[0]``, ``angles[1]``, … (owner ``"machine"``);
- a rod-leg machine described leg by leg (or a rod machine carrying defects, whose geometry is no
  longer its kind's): the geometry of its defect level (equivalent legs of a translational
  machine, real rods of a full-pose one), named as the defects without their ``d`` —
  ``A<j>x`` … (base-side joint), ``B<j>x`` … (platform joint), ``L<j>`` (length), then per
  actuator ``u<k>x`` … (slide direction, normalised when rebuilt) or ``P<k>x`` …, ``w<k>x`` …
  (crank pivot and axis); planar machines have no z entries;
- a joint-chain machine described element by element: its elements' invariants
  ``I, J, K, A, B, C`` (and the spin ``S`` of fixed frames), suffixed by the element's label
  (:meth:`pkmkit.model.chains.JointChainModel.parameter_names`), read from the nominal frames.

**Defect block**: the machine's defects (:func:`pkmkit.geometric_errors.model.defect_set`
names, units and owners), absolute deviations from the nominal block
(:mod:`pkmkit.model.defect_rule`).

``with_parameters`` rebuilds the nominal machine from the nominal block (the kind's builder,
the legs' geometry, or the elements' invariants) and applies the defect block to it.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.model.defect_rule import (
    defect_index,
    defect_owners,
    defects,
    is_chain,
    nominal_kind,
    nominal_model,
)
from pkmkit.model.parameter_vector import ParameterIndex, ParameterVector

_AXES = "xyz"


def machine_parameters(machine) -> ParameterVector:
    """The parameter vector of ``machine`` (module docstring): nominal block, then defects."""
    names, units, owners, sources, values = _nominal_block(machine)
    index = defect_index(machine)
    nominal = ParameterIndex(tuple(names), tuple(units), ("nominal",) * len(names),
                             tuple(owners), tuple(sources))
    flaws = ParameterIndex(tuple(index.names), tuple(index.units), ("defect",) * len(index),
                           defect_owners(machine), tuple(index.names))
    return ParameterVector(np.concatenate([np.asarray(values, dtype=float), defects(machine)]),
                           nominal + flaws)


def machine_with_parameters(machine, vector: ParameterVector | Any):
    """``machine`` rebuilt from ``vector`` (a :class:`ParameterVector` with the machine's
    index, or its values ``(p,)``): the nominal machine from the nominal block, then the defect
    block applied (replacing any defects).

    Raises:
        InputError: a vector of another index or length.
        ParameterError: values the machine cannot be built from (the builder's message).
    """
    current = machine_parameters(machine)
    if isinstance(vector, ParameterVector):
        if vector.index.names != current.index.names:
            raise InputError("the parameter vector does not belong to this machine (its names "
                             "differ from machine.parameters()'s)")
        values = vector.values
    else:
        values = current.with_values(vector).values
    nominal_pos = current.index.select("nominal")
    defect_pos = current.index.select("defect")
    rebuilt = machine
    if not np.array_equal(values[nominal_pos], current.values[nominal_pos]):
        rebuilt = _rebuilt_nominal(machine, current.index.subset(nominal_pos),
                                   values[nominal_pos])
    return rebuilt.with_defects(values[defect_pos])


# ---------------------------------------------------------------------------- nominal blocks
def _nominal_block(machine):
    kind = nominal_kind(machine)
    if kind is not None:
        return _kind_block(*kind)
    if is_chain(machine):
        return _chain_block(machine.model)
    return _rod_block(nominal_model(machine))


def _kind_block(kind, params):
    names, units, owners, sources, values = [], [], [], [], []
    for spec in kind.parameters:
        value = np.asarray(params[spec.name], dtype=float).reshape(-1)
        single = spec.size is None
        for i, v in enumerate(value):
            names.append(spec.name if single else f"{spec.name}[{i}]")
            units.append(spec.si_unit)
            owners.append("machine")
            sources.append(spec.name)
            values.append(float(v))
    return names, units, owners, sources, values


def _rod_block(model):
    from pkmkit.model.rod_defects import CRANK, SLIDE, rod_geometry

    g = rod_geometry(model)
    space = 2 if model.planar else 3
    rows = []  # (name, unit, owner, source, value)
    for j in range(len(g["base"])):
        owner = f"rod {j + 1}" if g["level"] == "rods" else model.leg_names[j]
        where = f"rods.{j}" if g["level"] == "rods" else f"legs.{j}"
        rows += [(f"A{j + 1}{_AXES[c]}", "m", owner, f"{where}.base", g["base"][j, c])
                 for c in range(space)]
        rows += [(f"B{j + 1}{_AXES[c]}", "m", owner, f"{where}.platform", g["platform"][j, c])
                 for c in range(space)]
        rows.append((f"L{j + 1}", "m", owner, f"{where}.length", g["length"][j]))
    for k in range(model.n_actuators):
        leg = int(np.flatnonzero(model.leg_actuator == k)[0])
        owner = model.actuator_names[k]
        if model.actuator_kind[k] == CRANK:
            rows += [(f"P{k + 1}{_AXES[c]}", "m", owner, f"legs.{leg}.pivot",
                      g["pivot"][leg, c]) for c in range(3)]
            rows += [(f"w{k + 1}{_AXES[c]}", "1", owner, f"legs.{leg}.axis", g["axis"][leg, c])
                     for c in range(3)]
        elif model.actuator_kind[k] == SLIDE:
            rows += [(f"u{k + 1}{_AXES[c]}", "1", owner, f"legs.{leg}.axis", g["axis"][leg, c])
                     for c in range(space)]
    return tuple(list(col) for col in zip(*rows, strict=True))


def _chain_block(model):
    from pkmkit.model.chains import FIXED, invariant_frame

    names = model.parameter_names()
    units, owners, values = [], [], []
    for e, spec in enumerate(model.elements):
        frame = model.nominal_frames[e]
        units += ["1"] * 3 + ["m"] * 3
        values += [*frame[:3, 2], *frame[:3, 3]]
        if spec.type == FIXED:
            plain = invariant_frame(frame[:3, 2], frame[:3, 3])
            units.append("rad")
            values.append(float(np.arctan2(plain[:3, 1] @ frame[:3, 0],
                                           plain[:3, 0] @ frame[:3, 0])))
        count = 7 if spec.type == FIXED else 6
        owners += [f"element {spec.name}"] * count
    return list(names), units, owners, list(names), values


# ---------------------------------------------------------------------------- rebuilding
def _rebuilt_nominal(machine, index: ParameterIndex, values: np.ndarray):
    """The nominal machine (no defects) with the nominal block ``values``."""
    kind = nominal_kind(machine)
    if kind is not None:
        params: dict[str, Any] = {}
        for spec in kind[0].parameters:
            picked = [float(v) for v, s in zip(values, index.sources, strict=True)
                      if s == spec.name]
            params[spec.name] = picked[0] if spec.size is None else tuple(picked)
        if machine.kind is None:  # a rod machine with defects: its nominal machine first
            machine = machine.with_defects(np.zeros(len(defect_index(machine))))
        return machine.with_params(**params)
    if is_chain(machine):
        return replace(machine, model=_rebuilt_chain(machine.model, values))
    return replace(machine, model=_rebuilt_rods(nominal_model(machine), index, values))


def _rebuilt_rods(model, index: ParameterIndex, values: np.ndarray):
    from pkmkit.model.rod_defects import CRANK, rod_geometry, with_rod_geometry

    g = rod_geometry(model)
    by_name = dict(zip(index.names, values, strict=True))
    for j in range(len(g["base"])):
        for c in range(3):
            g["base"][j, c] = by_name.get(f"A{j + 1}{_AXES[c]}", g["base"][j, c])
            g["platform"][j, c] = by_name.get(f"B{j + 1}{_AXES[c]}", g["platform"][j, c])
        g["length"][j] = by_name[f"L{j + 1}"]
    for k in range(model.n_actuators):
        legs = model.leg_actuator == k
        first = int(np.flatnonzero(legs)[0])
        for c in range(3):
            g["pivot"][legs, c] = by_name.get(f"P{k + 1}{_AXES[c]}", g["pivot"][first, c])
        prefix = "w" if model.actuator_kind[k] == CRANK else "u"
        axis = np.array([by_name.get(f"{prefix}{k + 1}{_AXES[c]}", g["axis"][first, c])
                         for c in range(3)])
        norm = float(np.linalg.norm(axis))
        if norm > 0:  # struts have no axis
            g["axis"][legs] = axis / norm
    return with_rod_geometry(model, g["base"], g["platform"], g["length"], g["axis"],
                             g["pivot"])


def _element_spec(spec, frame: np.ndarray, values: np.ndarray):
    """The element ``spec`` with its invariants ``values`` (I, J, K, A, B, C[, S]); a joint
    given by a full rotation has that rotation tilted onto the new axis (``frame``: its
    current nominal frame)."""
    from pkmkit.model.chains import FIXED, minimal_rotation

    if spec.rotation is None or spec.type == FIXED:
        spin = float(values[6]) if spec.type == FIXED else spec.spin
        if not np.array_equal(values[:3], frame[:3, 2]):
            # the axis moves: keep the frame continuous (the current frame tilted by the
            # minimal rotation, as the defects and the element columns do), where (4.6) alone
            # would spin it by up to 180° when the axis leaves the previous z
            turn = 0.0
            if spec.type == FIXED:  # a changed spin S turns the frame on top
                turn = spin - _spin_about_axis(frame[:3, 2], frame[:3, :3])
            tilted = minimal_rotation(frame[:3, 2], values[:3] / np.linalg.norm(values[:3]))
            spin = _spin_about_axis(values[:3], tilted @ frame[:3, :3]) + turn
        return replace(spec, axis=tuple(values[:3]), point=tuple(values[3:6]), spin=spin,
                       rotation=None)
    z = values[:3] / np.linalg.norm(values[:3])
    rot = minimal_rotation(frame[:3, 2], z) @ frame[:3, :3]
    return replace(spec, rotation=rot, point=tuple(values[3:6]))


def _spin_about_axis(axis: np.ndarray, rotation: np.ndarray) -> float:
    """The spin (rad) that turns the (4.6) frame of ``axis`` into ``rotation`` ``(3, 3)``,
    whose z is that axis."""
    from pkmkit.model.chains import invariant_frame

    base = invariant_frame(axis, (0.0, 0.0, 0.0))[:3, :3]
    return float(np.arctan2(base[:, 1] @ rotation[:, 0], base[:, 0] @ rotation[:, 0]))


def element_frame(spec, frame: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The nominal frame ``(4, 4)`` of an element with invariants ``values`` (as
    :func:`machine_with_parameters` builds it; ``frame``: its current nominal frame)."""
    from pkmkit.model.chains import invariant_frame

    new = _element_spec(spec, frame, np.asarray(values, dtype=float))
    out = invariant_frame(new.axis, new.point, new.spin)
    if new.rotation is not None:
        out[:3, :3] = np.asarray(new.rotation, dtype=float)
    return out


def _rebuilt_chain(model, values: np.ndarray):
    from pkmkit.model.chains import FIXED, build_chain_model

    current = np.asarray(_chain_block(model)[4])
    specs, at = [], 0
    for e, spec in enumerate(model.elements):
        count = 7 if spec.type == FIXED else 6
        mine = values[at:at + count]
        unchanged = np.array_equal(mine, current[at:at + count])
        at += count
        specs.append(spec if unchanged else
                     _element_spec(spec, model.nominal_frames[e], np.asarray(mine)))
    names = [s.name for s in model.elements]
    return build_chain_model(specs, [[names[e] for e in leg] for leg in model.legs],
                             leg_names=model.leg_names, head=[names[e] for e in model.head],
                             characteristic_length=model.characteristic_length)
