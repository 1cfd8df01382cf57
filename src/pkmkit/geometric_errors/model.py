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
  residual instead of a motion).

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


@dataclass(frozen=True)
class ToolSensitivity:
    """First-order effect of every defect on the tool at N configurations.

    Attributes:
        point: ``(N, 3, d)`` tool point displacement per unit defect (m per SI unit).
        rotation: ``(N, 3, d)`` tool frame rotation vector per unit defect (rad per SI unit).
        pose: ``(N, 6)`` the nominal tool pose (point and rotation vector, or axis for joint
            chains) at which it was taken.
        closure_defect: ``(N, r, d)`` or None — for a hyperstatic closure, the part of each
            defect's closure residual that no motion can absorb (the incompatible part,
            projected on the left null space), in m per unit.
    """

    point: np.ndarray
    rotation: np.ndarray
    pose: np.ndarray
    closure_defect: np.ndarray | None = None

    def stacked(self, rows: str = "point") -> np.ndarray:
        """``(N·r, d)`` rows of the point (``"point"``) or point and rotation (``"pose"``)."""
        if rows == "point":
            return self.point.reshape(-1, self.point.shape[2])
        return np.concatenate([self.point, self.rotation], axis=1).reshape(
            -1, self.point.shape[2])


@single_blas
def tool_sensitivity(machine, q: Any, *, tool_length: Any = None) -> ToolSensitivity:
    """Analytic first-order effect of every defect on the tool point and rotation at
    actuator coordinates ``q`` ``(n,)`` or ``(N, n)`` (see the module docstring).

    Raises:
        InputError: mis-shaped q, or configurations where the direct model fails.
    """
    family = machine.family
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.shape[1] != machine.n_actuators:
        raise InputError(f"q must have {machine.n_actuators} components per row, got "
                         f"{qb.shape[1]}")
    if family == "chain":
        return _chain_sensitivity(machine, qb, tool_length)
    return _rod_sensitivity(machine, qb, family)


@dataclass(frozen=True)
class ClosureLinearisation:
    """The closure of a machine linearised at N configurations: ``C_U dU + C_δ dδ = 0``.

    Attributes:
        unknowns: ``(N, r, u)`` ∂(closure residual)/∂(unknowns): the platform pose increments
            (translation, then rotation for full-pose and joint-chain machines) and, for joint
            chains, the passive joints; rows in m (rod residuals, chain translation rows, chain
            rotation rows × the characteristic length).
        defects: ``(N, r, d)`` ∂(closure residual)/∂(defects) (m per SI unit of the defect).
        pose: ``(N, 6)`` the nominal tool pose (see :class:`ToolSensitivity`).
    """

    unknowns: np.ndarray
    defects: np.ndarray
    pose: np.ndarray


@single_blas
def closure_linearisation(machine, q: Any, *, tool_length: Any = None) -> ClosureLinearisation:
    """The machine's closure linearised in its unknowns and its defects at actuator
    coordinates ``q`` ``(n,)`` or ``(N, n)`` — what compatibility (left null space of
    ``C_U``) and sensitivity (``dU = −C_U⁺ C_δ``) are built on. Rod residuals are
    ``|p + R b − a(q)| − ℓ`` per rod of the defect level; joint-chain residuals are the legs'
    closures on the platform (:mod:`pkmkit.solve.chains`).

    Raises:
        InputError: mis-shaped q, or configurations where the direct model fails.
    """
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.ndim != 2 or qb.shape[1] != machine.n_actuators:
        raise InputError(f"q must have {machine.n_actuators} components per row, got "
                         f"{qb.shape[-1]}")
    family = machine.family
    if family == "chain":
        lin = _chain_linearisation(machine, qb, tool_length)
        return ClosureLinearisation(lin["cu"], lin["cd"], lin["direct"].pose)
    _, unknowns, cols, pose = _rod_linearisation(machine, qb, family)
    return ClosureLinearisation(unknowns, cols, pose)


def _rod_linearisation(machine, q: np.ndarray, family: str):
    """(fk poses, ∂r/∂(platform) with unit rod rows, ∂r/∂δ, tool pose (N, 6))."""
    from pkmkit.solve.rod_closure import defect_columns
    from pkmkit.spatial.rotation import rotvec_to_matrix

    index = _rod_index(machine)
    x = np.atleast_2d(machine.fk(q))
    if not np.isfinite(x).all():
        bad = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
        raise InputError(f"configuration {bad}: the direct model has no assembly at q = "
                         f"{q[bad].tolist()}")
    n = q.shape[0]
    if family == "full-pose":
        rot = rotvec_to_matrix(x[:, 3:6])
        _, cols = defect_columns(machine.model, index, x[:, :3], rot, q)
        from pkmkit.machines.full_pose_forms import FullPoseForms

        a, _ = FullPoseForms(machine.model).jacobians(x, q)
        a_unit = a / np.linalg.norm(a[:, :, :3], axis=2)[:, :, None]
        return x, a_unit, cols, x
    dims = machine.dims
    position = np.zeros((n, 3))
    position[:, :dims] = x
    _, cols = defect_columns(machine.model, index, position, None, q)
    a = machine.jacobian(x, q=q).A  # rows p − c_i (N, n, dims)
    a_unit = a / np.linalg.norm(a, axis=2)[:, :, None]
    return x, a_unit, cols, np.concatenate([position, np.zeros((n, 3))], axis=1)


def _rod_sensitivity(machine, q: np.ndarray, family: str) -> ToolSensitivity:
    x, a_unit, cols, pose = _rod_linearisation(machine, q, family)
    n, d = q.shape[0], cols.shape[2]
    if family == "full-pose":
        motion = -np.linalg.pinv(a_unit) @ cols  # (N, 6, d)
        return ToolSensitivity(point=motion[:, :3], rotation=motion[:, 3:], pose=x)
    dims = machine.dims
    motion = -np.linalg.solve(a_unit, cols)  # (N, dims, d)
    point = np.zeros((n, 3, d))
    point[:, :dims] = motion
    return ToolSensitivity(point=point, rotation=np.zeros((n, 3, d)), pose=pose)


def _chain_linearisation(machine, q: np.ndarray, tool_length: Any, columns=None) -> dict:
    """(``columns``: a model with the machine's frames whose defect columns to use instead,
    :func:`pkmkit.solve.chains.with_column_twists`.)"""
    from pkmkit.solve.chains import closure
    from pkmkit.spatial.rotation import rotvec_to_matrix

    model = machine.model
    direct = machine.fk(q, tool_length=tool_length, full_output=True)
    if not np.isfinite(direct.pose).all():
        bad = int(np.flatnonzero(~np.isfinite(direct.pose).all(axis=1))[0])
        raise InputError(f"configuration {bad}: the legs do not close at q = {q[bad].tolist()}")
    n = q.shape[0]
    values = np.tile(model.home, (n, 1))
    act = np.flatnonzero(model.actuated)
    passive = np.flatnonzero(~model.actuated & model.loop_variables)
    values[:, act] = q
    values[:, passive] = direct.passive
    rot = rotvec_to_matrix(direct.platform[:, 3:]).transpose(1, 2, 0)
    p_x = direct.platform[:, :3].T
    c = closure(columns if columns is not None else model, rot, p_x, values.T, defects=True)
    cu = np.concatenate([c.platform, c.variables[:, passive]], axis=1).transpose(2, 0, 1)
    cd = c.defects.transpose(2, 0, 1)
    return {"direct": direct, "cu": cu, "cd": cd, "values": values, "rot": rot, "p_x": p_x}


def _chain_sensitivity(machine, q: np.ndarray, tool_length: Any, columns=None
                       ) -> ToolSensitivity:
    from pkmkit.solve.chains import tool_frame
    from pkmkit.spatial.rotation import skew

    lin = _chain_linearisation(machine, q, tool_length, columns)
    direct, cu, cd = lin["direct"], lin["cu"], lin["cd"]
    rot, p_x, values = lin["rot"], lin["p_x"], lin["values"]
    n = q.shape[0]
    pinv = np.linalg.pinv(cu, rcond=1e-9)
    du = -pinv @ cd  # (N, 6 + n_p, d)
    # the part of C_δ no motion absorbs: (I − C_U C_U⁺) C_δ
    incompatible = cd + cu @ du
    tool = tool_frame(columns if columns is not None else machine.model, rot, p_x, values.T,
                      defects=True)
    plat = np.zeros((n, 6, 6))
    plat[:, :3, :3] = np.eye(3)
    plat[:, 3:, 3:] = np.eye(3)
    plat[:, :3, 3:] = skew(p_x.T)
    twist = plat @ du[:, :6, :] + tool.defect_twists.transpose(2, 0, 1)
    point = direct.pose[:, :3]
    dp = twist[:, :3] + np.cross(twist[:, 3:].transpose(0, 2, 1), point[:, None, :]
                                 ).transpose(0, 2, 1)
    return ToolSensitivity(point=dp, rotation=twist[:, 3:], pose=direct.pose,
                           closure_defect=incompatible)
