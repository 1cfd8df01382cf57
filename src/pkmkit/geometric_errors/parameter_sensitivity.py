"""First-order effect of every parameter of a machine's one vector (``machine.parameters()``:
nominal parameters and defects) on its tool and its actuators.

At actuator coordinates q (N configurations):

- ``point``, ``rotation`` — ``∂(tool point, tool rotation)/∂(parameters)`` with the actuators
  held at q (the direct model; as :class:`~pkmkit.geometric_errors.model.ToolSensitivity`);
- ``actuator`` — ``∂q/∂(parameters)`` with the tool held at its pose (the inverse model):
  ``−J⁺ ∂x/∂p`` with ``J`` the actuator-to-tool Jacobian (``A⁻¹B`` of rod machines, the
  joint-chain ``J`` with the rotation about the tool axis left free). Where the tool pose has
  more components than the machine has actuators (a 3-DOF Verne module, a planar chain) it is
  the least-squares change.

How each column is obtained (``method``):

- ``"analytic"`` — defects, every family (:func:`~pkmkit.geometric_errors.model.
  tool_sensitivity`: the closure linearised, exact derivatives);
- ``"composition"`` — nominal parameters of rod machines (a kind's ``base_radius``, a rod's
  ``L3``) and of joint chains described element by element (``I21``, ``A13``): the analytic
  closure sensitivity composed with the parameter's first-order change of the geometry — the
  rods' ends, lengths and axes in the defect coordinates, or the element frame's twist — that
  change obtained by central differences of the geometry builder alone (no closure solved;
  step :data:`GEOMETRY_STEP`), so the result is exact to ~1e-9 relative;
- ``"central-difference"`` — the named parameters of a joint-chain kind (the Tripteor's ``L``,
  which move many frames and the tool length): central differences of the direct model at q,
  step ``STEP · max(1, |p|)`` (:data:`STEP`, SI units), the machine rebuilt
  (``with_parameters``) on either side; rows where the direct model fails are NaN;
- ``"undefined"`` — the kind's builder refuses one side of the step (NaN column).

Each family computes its own columns (``machine.nominal_sensitivity``,
``machine.held_tool_actuators``: :mod:`pkmkit.machines.parameter_columns`, where the steps
:data:`STEP`, :data:`GEOMETRY_STEP` and :data:`UNDEFINED` are defined).

For a machine carrying defects the composition differentiates at its current geometry (exact to
first order in its defects). Units: SI per SI unit of each parameter.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.model import tool_sensitivity
from pkmkit.machines.parameter_columns import GEOMETRY_STEP, STEP, UNDEFINED
from pkmkit.model.parameter_vector import ParameterIndex

__all__ = ["GEOMETRY_STEP", "STEP", "UNDEFINED", "ParameterSensitivity",
           "parameter_sensitivity"]


@dataclass(frozen=True)
class ParameterSensitivity:
    """First-order effect of p parameters at N configurations (module docstring).

    Attributes:
        point: ``(N, 3, p)`` tool point displacement per unit parameter (m per SI unit).
        rotation: ``(N, 3, p)`` tool rotation vector per unit parameter (rad per SI unit).
        actuator: ``(N, n, p)`` actuator change at a held tool pose (m or rad per SI unit).
        index: the p parameters (a sub-index of ``machine.parameters().index``).
        method: ``(p,)`` ``"analytic"``, ``"composition"`` or ``"central-difference"``.
        q: ``(N, n)`` the actuator coordinates.
    """

    point: np.ndarray
    rotation: np.ndarray
    actuator: np.ndarray
    index: ParameterIndex
    method: tuple[str, ...]
    q: np.ndarray


@single_blas
def parameter_sensitivity(machine, q: Any, *, roles: tuple[str, ...] = ("nominal", "defect"),
                          names: tuple[str, ...] | None = None) -> ParameterSensitivity:
    """Effect of the machine's parameters (those of ``roles``, or the ``names`` given) on its
    tool and actuators at actuator coordinates ``q`` ``(n,)`` or ``(N, n)``.

    Raises:
        InputError: mis-shaped q, configurations where the direct model fails.
        ParameterError: an unknown parameter name.
    """
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.ndim != 2 or qb.shape[1] != machine.n_actuators or not np.isfinite(qb).all():
        raise InputError(f"q must be finite with {machine.n_actuators} components per row")
    vector = machine.parameters()
    full = vector.index
    if names is not None:
        chosen = np.array([full.position(n) for n in names], dtype=int)
    else:
        chosen = np.concatenate([full.select(r) for r in roles]).astype(int)
    defect_pos = set(full.select("defect").tolist())
    sens = tool_sensitivity(machine, qb)
    d_first = int(full.select("defect")[0]) if len(full.select("defect")) else 0
    n, p = qb.shape[0], len(chosen)
    point, rotation = np.zeros((n, 3, p)), np.zeros((n, 3, p))
    methods = []
    nominal = [i for i in chosen if i not in defect_pos]
    cols = machine.nominal_sensitivity(vector, nominal, qb, sens) if nominal else {}
    for j, i in enumerate(chosen):
        if i in defect_pos:
            point[:, :, j] = sens.point[:, :, i - d_first]
            rotation[:, :, j] = sens.rotation[:, :, i - d_first]
            methods.append("analytic")
        else:
            point[:, :, j], rotation[:, :, j], how = cols[i]
            methods.append(how)
    actuator = machine.held_tool_actuators(qb, sens.pose, point, rotation)
    return ParameterSensitivity(point, rotation, actuator, full.subset(chosen), tuple(methods),
                                qb)
