"""Measurement models: what an instrument reads on a machine at actuator coordinates q, exactly
and to first order in the machine's defects (the rows of identification Jacobians).

Measurement types (``kind``), each a function of (machine with its defects, q, setup):

- ``"point"`` — the tool point (3 rows, m): laser tracker; a joint-chain machine's tool point
  depends on the tool length of each row (``setup["tool_length"]``, m);
- ``"pose"`` — tool point and tool-frame rotation (6 rows; rotation vector of the tool frame in
  the fixed frame, rad);
- ``"ballbar"`` — the distance from a fixed pivot (``setup["pivot"]``, ``(3,)`` or
  ``(N, 3)`` m) to the tool point (1 row, m);
- ``"height"`` — the z coordinate of the tool point (1 row, m): a height probe touching a plane;
- ``"part"`` — the actuator coordinates that put the tool point on measured points
  (``setup["points"]``, ``(N, 3)`` m) with the machine's geometry (n rows): seed 003's
  joint-space error of a machined part, compared with the commanded joints. Rod machines only
  (the orientation, if any, follows the rods).

:func:`measurement_jacobian` gives ``∂(reading)/∂(defects)`` analytically from
:func:`pkmkit.geometric_errors.model.tool_sensitivity` (and, for ``"part"``, the closure's
derivative in
q at a fixed tool point). The machine gives its tool readings (``machine.tool_readings``) and
says whether it has machined-part readings (``machine.measures_machined_parts``):
:mod:`pkmkit.machines.tool_readings`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, MeasurementError
from pkmkit.geometric_errors.blas_threads import single_blas
from pkmkit.geometric_errors.model import tool_sensitivity

MEASURES = ("point", "pose", "ballbar", "height", "part")
#: Rows of each measurement type (``None``: the number of actuators).
ROWS = {"point": 3, "pose": 6, "ballbar": 1, "height": 1, "part": None}


def _check_kind(machine, kind: str) -> None:
    if kind not in MEASURES:
        raise MeasurementError(f"unknown measurement type {kind!r}; valid types: "
                               f"{', '.join(MEASURES)}", kind)
    if kind == "part" and not machine.measures_machined_parts:
        raise MeasurementError("machined-part (joint-space) measurements are defined for rod "
                               "machines (seed 003); use point or pose measurements for a "
                               "joint-chain machine", kind)
    if kind == "pose" and machine.orientation_fixed:
        raise MeasurementError(f"{machine.id!r} only translates: a full-pose measurement has "
                               "nothing to measure in its orientation; use point measurements",
                               kind)


def measurement_rows(machine, kind: str) -> int:
    """Scalar readings per configuration for ``kind``."""
    _check_kind(machine, kind)
    rows = ROWS[kind]
    return machine.n_actuators if rows is None else rows


def _pivot(setup: dict, n: int) -> np.ndarray:
    if "pivot" not in setup:
        raise InputError("a ball-bar measurement needs setup['pivot'] (the fixed pivot, m)")
    pivot = np.broadcast_to(np.asarray(setup["pivot"], dtype=float), (n, 3))
    if not np.isfinite(pivot).all():
        raise InputError("the ball-bar pivot must be finite")
    return pivot


def measure(machine, kind: str, q: Any, setup: dict | None = None) -> np.ndarray:
    """Exact readings ``(N, r)`` of a measurement type at actuator coordinates q (module
    docstring); NaN rows where the machine cannot assemble."""
    _check_kind(machine, kind)
    setup = setup or {}
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    n = qb.shape[0]
    if kind == "part":
        return _part_joints(machine, setup)
    point, rotvec = machine.tool_readings(qb, tool_length=setup.get("tool_length"))
    if kind == "point":
        return point
    if kind == "pose":
        return np.concatenate([point, rotvec], axis=1)
    if kind == "height":
        return point[:, 2:3]
    return np.linalg.norm(point - _pivot(setup, n), axis=1, keepdims=True)


def _part_joints(machine, setup: dict) -> np.ndarray:
    if "points" not in setup:
        raise InputError("a machined-part measurement needs setup['points'] (measured tool "
                         "points, (N, 3) m)")
    return machine.part_actuators(_part_points(machine, setup))


def _part_points(machine, setup: dict) -> np.ndarray:
    """The measured points (positions; full poses for a six-actuator machine)."""
    points = np.atleast_2d(np.asarray(setup["points"], dtype=float))
    width = 6 if machine.six_dof else 3
    if points.shape[1] != width and not (width == 3 and points.shape[1] >= machine.dims):
        what = "full poses (N, 6)" if width == 6 else "points (N, 3)"
        raise InputError(f"machined-part measurements of {machine.id!r} need measured {what}")
    return points


@single_blas
def measurement_jacobian(machine, kind: str, q: Any, setup: dict | None = None) -> np.ndarray:
    """``∂(reading)/∂(defects)`` ``(N, r, d)`` at actuator coordinates q (module docstring)."""
    _check_kind(machine, kind)
    setup = setup or {}
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if kind == "part":
        return _part_jacobian(machine, setup)
    sens = tool_sensitivity(machine, qb, tool_length=setup.get("tool_length"))
    if kind == "point":
        return sens.point
    if kind == "pose":
        return np.concatenate([sens.point, sens.rotation], axis=1)
    if kind == "height":
        return sens.point[:, 2:3]
    point = sens.pose[:, :3]
    bar = point - _pivot(setup, qb.shape[0])
    unit = bar / np.linalg.norm(bar, axis=1, keepdims=True)
    return np.einsum("kc,kcd->kd", unit, sens.point)[:, None, :]


def _part_jacobian(machine, setup: dict) -> np.ndarray:
    """``∂q/∂δ`` at fixed tool points (the machine's ``part_sensitivity``)."""
    return machine.part_sensitivity(_part_points(machine, setup))
