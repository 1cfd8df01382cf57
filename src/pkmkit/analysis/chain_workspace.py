"""Scalar indices of a joint-chain machine (Tripteor X7, TriMule, crank–slider) at tool points
and a tool axis.

Its workspace criteria go through the machine protocol like every machine's
(:func:`pkmkit.analysis.criteria.evaluate_poses`): for a pose ``(x, y, z, i, j, k)`` (tool
point, unit tool axis), ``reachable`` — the numerical inverse model (from home) closes every
loop and puts the tool there; ``strokes`` — every joint of that solution, actuators **and
passive joints** (the leg joints' angular ranges bound a joint-chain machine's workspace as much
as its slides), lies in its range; ``bounds`` / ``condition`` — on the singular values of the
homogenised Jacobian (angular rows times the model's characteristic length) and their ratio;
``mode`` — the closure's Jacobian keeps its home rank and is not singular
(``machine.in_working_mode``): no parallel singularity. The indices are those of its
homogenised Jacobian (:data:`CHAIN_INDICES`).
"""

from __future__ import annotations

import numpy as np

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
