"""What a machine's controller commands for tool-point targets, and the compensation of a nominal
controller by an identified machine.

A controller holds a geometric model (the nominal machine) and turns each target of the tool
into actuator coordinates with that model's inverse model: :func:`commanded_q`. The real machine
then puts its tool where *its* geometry sends it: ``FGM_real(IGM_nominal(X))``, not X.
**Compensation** (:func:`corrected_targets`) gives the nominal controller, for each wanted target
X, the target X' whose nominal command is the real machine's command for X:
``IGM_nominal(X') = IGM_identified(X)``, i.e. ``X' = FGM_nominal(IGM_identified(X))``.

Targets are tool points ``(N, 3)`` (m); for a joint-chain machine (5-axis head) tool point and
unit tool axis ``(N, 6)`` — a point alone takes the machine's home tool axis; for a six-actuator
machine tool point and platform rotation vector ``(N, 6)`` (rad; a point alone takes the home
orientation). Tool points follow
:func:`pkmkit.calibration.models.tool_state` (``tool_length`` along the tool axis; below the
platform for rod machines).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.measurement_models import CHAIN_IK_TOL  # noqa: F401  (re-exported)


def target_width(machine) -> int:
    """Columns of a target: 6 for joint-chain machines (tool point and axis) and six-actuator
    machines (tool point and rotation vector of the platform), else 3 (tool point)."""
    return 6 if machine.dims == 6 and not machine.position_controlled else 3


def as_targets(machine, targets: Any) -> np.ndarray:
    """Targets ``(N, w)`` for ``machine``: points ``(N, 3)`` get the home tool axis of a
    joint-chain machine, the home orientation of a six-actuator machine."""
    x = np.atleast_2d(np.asarray(targets, dtype=float))
    width = target_width(machine)
    if x.shape[1] == 3 and width == 6:
        axis = machine.home_pose[3:]
        x = np.concatenate([x, np.tile(axis, (len(x), 1))], axis=1)
    if x.shape[1] != width:
        raise InputError(f"targets of {machine.id!r} need {width} columns, got {x.shape[1]}")
    return x


def commanded_q(machine, targets: Any, tool_length: Any = None, *, iterations: int = 20
                ) -> np.ndarray:
    """Actuator coordinates ``(N, n)`` that ``machine``'s model gives for tool targets (its
    inverse model with the tool offset, :meth:`tool_inverse` of
    :mod:`pkmkit.machines.measurement_models`); NaN rows out of reach.

    For a position-controlled full-pose machine (its platform tilts with its position) the
    tool offset depends on the tilt: the platform position is found by fixed-point iteration
    (at most ``iterations`` passes; the tilt changes by micro-radians per millimetre). A
    joint-chain machine accepts least-squares closures up to :data:`CHAIN_IK_TOL`.
    """
    x = as_targets(machine, targets)
    tl = None if tool_length is None else np.broadcast_to(
        np.asarray(tool_length, dtype=float), (len(x),)).copy()
    with np.errstate(invalid="ignore"):
        return machine.tool_inverse(x, tl, iterations=iterations)


def reached(machine, q: Any, tool_length: Any = None) -> np.ndarray:
    """Tool targets ``(N, w)`` that ``machine`` reaches at ``q`` (tool point, and tool axis for
    a joint-chain machine, platform rotation vector for a six-actuator machine); NaN rows where
    it does not assemble."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = len(q)
    tl = None if tool_length is None else np.broadcast_to(np.asarray(tool_length, dtype=float),
                                                          (n,)).copy()
    ok = np.isfinite(q).all(axis=1)
    out = np.full((n, target_width(machine)), np.nan)
    if not ok.any():
        return out
    out[ok] = machine.tool_targets(q[ok], None if tl is None else tl[ok])
    return out


def corrected_targets(nominal, identified, targets: Any, tool_length: Any = None) -> np.ndarray:
    """Targets for the nominal controller that make the identified machine reach ``targets``:
    ``FGM_nominal(IGM_identified(X))`` ``(N, w)`` (NaN where the identified machine cannot reach
    a target)."""
    q = commanded_q(identified, targets, tool_length)
    return reached(nominal, q, tool_length)


def executed(real, controller, targets: Any, tool_length: Any = None) -> np.ndarray:
    """Where ``real`` puts its tool when ``controller``'s model commands ``targets``."""
    return reached(real, commanded_q(controller, targets, tool_length), tool_length)
