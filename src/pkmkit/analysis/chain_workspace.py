"""Workspace criteria of a joint-chain machine (Tripteor X7, TriMule, crank–slider) at tool
points and a tool axis.

A joint-chain machine has no closed-form inverse model and its velocity model comes from the
linearised closure, so :func:`pkmkit.analysis.workspace.evaluate_poses` hands its poses here.
The masks mean, for a pose ``(x, y, z, i, j, k)`` (tool point, unit tool axis):

- ``reachable`` — the numerical inverse model (from home) closes every loop and puts the tool
  there;
- ``strokes`` — every joint of that solution, actuators **and passive joints** (the leg joints'
  angular ranges bound a joint-chain machine's workspace as much as its slides), lies in its
  range;
- ``bounds`` / ``condition`` — on the singular values of the homogenised Jacobian (angular rows
  times the model's characteristic length) and their ratio;
- ``mode`` — the closure's Jacobian keeps its home rank and is not singular
  (:data:`pkmkit.machines.joint_chain.SINGULAR_TOL`): no parallel singularity.
"""

from __future__ import annotations

import warnings

import numpy as np

from pkmkit.analysis.evaluation import PoseEvaluation
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines.strokes import signed_excess
from pkmkit.status import Status


def evaluate_chain_poses(machine, points: np.ndarray, criteria):
    """:class:`~pkmkit.analysis.evaluation.PoseEvaluation` of a joint-chain machine at poses
    ``points (M, 6)`` (tool point in m, tool axis).

    ``criteria.q_limits`` (limits of the actuators alone) replace the actuator strokes when
    given; the passive joints keep their ranges."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    m, n = len(points), machine.n_actuators
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        inverse = machine.ik(points, full_output=True, strokes="flag")
    q, direct = np.atleast_2d(inverse.q), inverse.direct
    reachable = np.isfinite(q).all(axis=1)
    if criteria.strokes and criteria.q_limits is None and direct is not None:
        strokes = reachable & ~np.asarray(direct.out_of_stroke, dtype=bool)
    elif criteria.strokes:
        lo, hi = criteria.limits(machine)
        with np.errstate(invalid="ignore"):
            strokes = reachable & ~(signed_excess(q, lo, hi) != 0).any(axis=1)
    else:
        strokes = reachable.copy()
    factors = np.full((m, min(6, n)), np.nan)
    condition = np.full(m, np.nan)
    regular = np.zeros(m, dtype=bool)
    if reachable.any():
        jac = machine.jacobian(q=q[reachable])
        factors[reachable] = jac.singular_values
        condition[reachable] = jac.condition
        regular[reachable] = ((np.asarray(jac.status) == Status.OK)
                              & (jac.closure_rank == jac.expected_rank))
    with np.errstate(invalid="ignore"):
        bounds = reachable.copy() if criteria.bounds is None else (
            reachable & criteria.within_bounds(factors))
        kappa = reachable.copy() if criteria.kappa_max is None else (
            reachable & (condition <= criteria.kappa_max))
    masks = {"reachable": reachable, "strokes": strokes, "bounds": bounds,
             "condition": kappa, "mode": reachable & regular}
    return PoseEvaluation(q=q, factors=factors, condition=condition, masks=masks)


#: Indices of :data:`pkmkit.analysis.indices.SCALAR_INDICES` a joint-chain machine has (from
#: the singular values of its homogenised Jacobian).
CHAIN_INDICES = ("lambda_min", "lambda_max", "condition", "inverse_condition", "force_min",
                 "force_max", "manipulability")


def chain_index_values(machine, points: np.ndarray, name: str) -> np.ndarray:
    """``(M,)`` index ``name`` of a joint-chain machine at poses ``points (M, 6)``: NaN where
    the inverse model finds no assembly or the closure is singular.

    Raises:
        InputError: an index a joint-chain machine does not define (the distances to
            singularities are those of rod machines' A and B matrices).
    """
    from pkmkit.exceptions import InputError

    if name not in CHAIN_INDICES:
        raise InputError(f"index {name!r} is not defined for a joint-chain machine; its "
                         f"indices: {', '.join(CHAIN_INDICES)}")
    points = np.atleast_2d(np.asarray(points, dtype=float))
    q = machine.ik(points)
    out = np.full(len(points), np.nan)
    ok = np.isfinite(q).all(axis=1)
    if not ok.any():
        return out
    jac = machine.jacobian(q=q[ok])
    sv = jac.singular_values
    with np.errstate(divide="ignore", invalid="ignore"):
        values = {"lambda_min": sv[:, -1], "lambda_max": sv[:, 0], "condition": jac.condition,
                  "inverse_condition": 1.0 / jac.condition, "force_min": 1.0 / sv[:, 0],
                  "force_max": 1.0 / sv[:, -1], "manipulability": np.prod(sv, axis=1)}[name]
    out[ok] = values
    return out
