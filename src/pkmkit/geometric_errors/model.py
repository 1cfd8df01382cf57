"""Geometric error models of any machine: its defect set, the exact machine with defects, and
the analytic first-order effect of every defect on the tool (the identification Jacobian's
core).

One interface for every family — the named defects come from the model layer
(:mod:`pkmkit.model.rod_defects` for rod machines, :mod:`pkmkit.model.chains` for joint
chains) — so that sensitivity, tolerance, compatibility, identifiability and calibration are
written once:

- :func:`defect_set` — names, units, kinds and owners of a machine's defects;
- :func:`with_defects` — the machine with defects applied exactly (a new immutable machine);
- :func:`tool_sensitivity` — ``∂(tool point, tool rotation)/∂(defects)`` at actuator
  coordinates q, through the closure: the actuators are held at q and the platform (and the
  passive joints) move so the legs still close. For rod machines ``dX = −A⁺ ∂r/∂δ`` with A the
  closure's Jacobian in the platform unknowns; for joint chains ``dU = −C_U⁺ C_δ`` (notes §3.9,
  §4.5: least squares for a hyperstatic closure, whose incompatible defect directions leave a
  residual instead of a motion). Each family linearises its own closure
  (``machine.tool_sensitivity``, ``machine.closure_linearisation``:
  :mod:`pkmkit.machines.defect_linearisation`, where :class:`ToolSensitivity` and
  :class:`ClosureLinearisation` are defined); the functions here are their faces.

Rotation rows are the small rotation vector of the tool frame (rad per unit defect); a
translational machine's platform does not rotate (zero rows). Units: defects in SI (m, rad or
dimensionless direction components), displacements in m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, ParameterError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.machines.defect_linearisation import ClosureLinearisation, ToolSensitivity


@dataclass(frozen=True)
class DefectSet:
    """The defects of a machine.

    Attributes:
        names: ``(d,)`` names (``"dK21"``, ``"dA3x"``, …).
        units: ``(d,)`` ``"m"``, ``"rad"`` or ``"1"`` (a direction component, ≈ rad).
        kinds: ``(d,)`` what each perturbs (``"orientation"``, ``"position"``, ``"spin"`` for
            joint chains; ``"base"``, ``"platform"``, ``"length"``, ``"axis"``, ``"pivot"``,
            ``"offset"`` for rods).
        owners: ``(d,)`` the element, rod or actuator each belongs to.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    kinds: tuple[str, ...]
    owners: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of a defect by name.

        Raises:
            ParameterError: an unknown name (with some valid ones).
        """
        try:
            return self.names.index(name)
        except ValueError:
            preview = ", ".join(self.names[:10]) + (", …" if len(self.names) > 10 else "")
            raise ParameterError(f"unknown defect {name!r}; this machine's defects are named "
                                 f"like {preview}", name) from None

    def vector(self, values: Any) -> np.ndarray:
        """A full defect vector from a mapping name → value (others 0) or a vector."""
        if isinstance(values, dict):
            out = np.zeros(len(self))
            for name, value in values.items():
                out[self.index(name)] = float(value)
            return out
        arr = np.asarray(values, dtype=float).reshape(-1)
        if arr.shape != (len(self),) or not np.isfinite(arr).all():
            raise InputError(f"defects must be {len(self)} finite values, got shape {arr.shape}")
        return arr


def defect_set(machine) -> DefectSet:
    """The defect set of ``machine`` (any family)."""
    from pkmkit.model.defect_rule import defect_index, defect_owners

    index = defect_index(machine)
    return DefectSet(index.names, index.units, tuple(index.kind), defect_owners(machine))


def _rod_index(machine):
    from pkmkit.model.defect_rule import defect_index

    return defect_index(machine)


def with_defects(machine, values: Any):
    """``machine``'s nominal geometry with the defects ``values`` (mapping name → SI value,
    or a full vector) applied exactly, **replacing** any it carried (the one rule,
    :mod:`pkmkit.model.defect_rule`): a new machine (the original is unchanged). Rod machines
    keep their identity but lose their kind's named parameters (their geometry is no longer the
    kind's); joint-chain machines solve their home closure again (in least squares if
    incompatible).

    Raises:
        ParameterError: an unknown name. InputError: a vector of the wrong length.
    """
    from pkmkit.model.defect_rule import with_defects as apply

    return apply(machine, defect_set(machine).vector(values))


@single_blas
def tool_sensitivity(machine, q: Any, *, tool_length: Any = None,
                     **closure: Any) -> ToolSensitivity:
    """Analytic first-order effect of every defect on the tool point and rotation at
    actuator coordinates ``q`` ``(n,)`` or ``(N, n)`` (see the module docstring): the
    machine's own linearisation, ``machine.tool_sensitivity``
    (:mod:`pkmkit.machines.defect_linearisation`); ``closure``: a joint chain's closure
    ``start`` and engine options (e.g. ``compiled=True``).

    Raises:
        InputError: mis-shaped q, or configurations where the direct model fails.
    """
    return machine.tool_sensitivity(q, tool_length=tool_length, **closure)


@single_blas
def closure_linearisation(machine, q: Any, *, tool_length: Any = None) -> ClosureLinearisation:
    """The machine's closure linearised in its unknowns and its defects at actuator
    coordinates ``q`` ``(n,)`` or ``(N, n)`` — what compatibility (left null space of
    ``C_U``) and sensitivity (``dU = −C_U⁺ C_δ``) are built on. Rod residuals are
    ``|p + R b − a(q)| − ℓ`` per rod of the defect level; joint-chain residuals are the legs'
    closures on the platform (:mod:`pkmkit.solve.chains`). The machine's own,
    ``machine.closure_linearisation`` (:mod:`pkmkit.machines.defect_linearisation`).

    Raises:
        InputError: mis-shaped q, or configurations where the direct model fails.
    """
    return machine.closure_linearisation(q, tool_length=tool_length)
