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

For a machine carrying defects the composition differentiates at its current geometry (exact to
first order in its defects). Units: SI per SI unit of each parameter.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, PkmError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.model import _chain_sensitivity, tool_sensitivity
from pkmkit.model.parameter_vector import ParameterIndex

#: Relative step of the central differences of the direct model (joint-chain kinds).
STEP = 1e-6
#: Step of the central differences of the geometry builders (composition), SI units.
GEOMETRY_STEP = 1e-6
#: The method of a column whose machine cannot be built on one side of the step (a kind at
#: the edge of its domain, such as the parallel slides of the Biglide five-bar): NaN.
UNDEFINED = "undefined"


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
    cols = _nominal_columns(machine, vector, nominal, qb, sens) if nominal else {}
    for j, i in enumerate(chosen):
        if i in defect_pos:
            point[:, :, j] = sens.point[:, :, i - d_first]
            rotation[:, :, j] = sens.rotation[:, :, i - d_first]
            methods.append("analytic")
        else:
            point[:, :, j], rotation[:, :, j], how = cols[i]
            methods.append(how)
    actuator = _actuator_columns(machine, qb, sens.pose, point, rotation)
    return ParameterSensitivity(point, rotation, actuator, full.subset(chosen), tuple(methods),
                                qb)


# ---------------------------------------------------------------------------- nominal columns
def _nominal_columns(machine, vector, positions, q, sens) -> dict:
    from pkmkit.model.defect_rule import is_chain, nominal_kind

    if not is_chain(machine):
        g = _rod_geometry_derivative(machine, vector, positions)  # (d, k)
        pts = sens.point @ g
        rots = sens.rotation @ g
        return {i: (pts[:, :, j], rots[:, :, j], "composition" if np.isfinite(g[:, j]).all()
                    else UNDEFINED) for j, i in enumerate(positions)}
    if nominal_kind(machine) is None:
        return _chain_element_columns(machine, vector, positions, q)
    return {i: _chain_difference(machine, vector, i, q) for i in positions}


def _rod_geometry_derivative(machine, vector, positions) -> np.ndarray:
    """``(d, k)``: the first-order change of the defect level's geometry per unit nominal
    parameter, in the defect coordinates (central differences of the builder)."""
    from pkmkit.model.defect_rule import defect_index, nominal_model
    from pkmkit.model.rod_defects import rod_geometry

    index = defect_index(machine)
    model = nominal_model(machine)
    out = np.zeros((len(index), len(positions)))
    for j, i in enumerate(positions):
        name, h = vector.index.names[i], GEOMETRY_STEP
        try:
            g = [rod_geometry(nominal_model(machine.with_parameters(
                vector.replace({name: vector.values[i] + s * h})))) for s in (1.0, -1.0)]
        except PkmError:  # the builder refuses a side: not differentiable here
            out[:, j] = np.nan
            continue
        diff = {k: (g[0][k] - g[1][k]) / (2 * h) for k in ("base", "platform", "length",
                                                           "axis", "pivot")}
        for r, (kind, t, c) in enumerate(zip(index.kind, index.target, index.component,
                                             strict=True)):
            if kind in ("base", "platform"):
                out[r, j] = diff[kind][t, c]
            elif kind == "length":
                out[r, j] = diff["length"][t]
            elif kind in ("axis", "pivot"):
                leg = int(np.flatnonzero(model.leg_actuator == t)[0])
                out[r, j] = diff[kind][leg, c]
    return out


def _chain_element_columns(machine, vector, positions, q) -> dict:
    """Nominal invariants of an element-described chain: each moves one element frame by a
    twist (central differences of the frame alone), composed with the closure sensitivity."""
    from pkmkit.machines.parameter_vector import element_frame
    from pkmkit.model.chains import FIXED
    from pkmkit.solve.chains import with_column_twists
    from pkmkit.spatial.rotation import matrix_to_rotvec

    model = machine.model
    owners = vector.index.owners
    by_element = {f"element {s.name}": e for e, s in enumerate(model.elements)}
    first = {}
    for i, owner in enumerate(owners):
        first.setdefault(owner, i)
    elements, twists = [], []
    for i in positions:
        e = by_element[owners[i]]
        start = first[owners[i]]
        values = vector.values[start:start + (7 if model.elements[e].type == FIXED else 6)]
        h = GEOMETRY_STEP
        frames = []
        for s in (1.0, -1.0):
            moved = values.copy()
            moved[i - start] += s * h
            frames.append(element_frame(model.elements[e], model.nominal_frames[e], moved))
        rot, o = model.nominal_frames[e][:3, :3], model.nominal_frames[e][:3, 3]
        omega = (matrix_to_rotvec(frames[0][None, :3, :3] @ rot.T)[0]
                 - matrix_to_rotvec(frames[1][None, :3, :3] @ rot.T)[0]) / (2 * h)
        do = (frames[0][:3, 3] - frames[1][:3, 3]) / (2 * h)
        elements.append(e)
        twists.append(np.concatenate([do - np.cross(omega, o), omega]))
    columns = with_column_twists(model, np.array(elements), np.array(twists))
    sens = _chain_sensitivity(machine, q, None, columns)
    return {i: (sens.point[:, :, j], sens.rotation[:, :, j], "composition")
            for j, i in enumerate(positions)}


def _chain_difference(machine, vector, i, q):
    from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

    name = vector.index.names[i]
    h = STEP * max(1.0, abs(float(vector.values[i])))
    out = []
    try:
        for s in (1.0, -1.0):
            moved = machine.with_parameters(vector.replace({name: vector.values[i] + s * h}))
            out.append(moved.fk(q, full_output=True, strokes="ignore", check_singular=False))
    except PkmError:  # the builder refuses a side: not differentiable here
        nan = np.full((len(q), 3), np.nan)
        return nan, nan, UNDEFINED
    dp = (out[0].pose[:, :3] - out[1].pose[:, :3]) / (2 * h)
    r_plus, r_minus = (rotvec_to_matrix(r.tool_frame[:, 3:]) for r in out)
    omega = matrix_to_rotvec(r_plus @ np.swapaxes(r_minus, 1, 2)) / (2 * h)
    return dp, omega, "central-difference"


# ---------------------------------------------------------------------------- actuators
def _actuator_columns(machine, q, pose, point, rotation) -> np.ndarray:
    """``−J⁺ ∂x/∂p``: the actuator change that keeps the tool where it was."""
    if machine.family == "chain":
        jac = np.atleast_3d(machine.jacobian(q=q).J)
        axis = pose[:, 3:6] / np.linalg.norm(pose[:, 3:6], axis=1)[:, None]
        proj = np.zeros((len(q), 6, 6))
        proj[:, :3, :3] = np.eye(3)
        proj[:, 3:, 3:] = np.eye(3) - axis[:, :, None] * axis[:, None, :]
        moved = np.concatenate([point, rotation], axis=1)
        return -np.linalg.pinv(proj @ jac) @ (proj @ moved)
    x = np.atleast_2d(machine.fk(q, strokes="ignore"))
    j_inv = machine.jacobian(x, q=q).J_inv
    if machine.family == "full-pose":
        return -j_inv @ np.concatenate([point, rotation], axis=1)
    return -j_inv @ point[:, :machine.dims]
