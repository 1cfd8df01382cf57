"""The record of a joint-chain machine's inverse model (:meth:`JointChainMachine.ik
<pkmkit.machines.joint_chain.JointChainMachine.ik>` with ``full_output``): its
:class:`~pkmkit.machines.chain_results.ChainInverseResult` assembled from the engine's solution,
with the direct model at that solution for the per-row messages."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from pkmkit.exceptions import StrokeWarning
from pkmkit.machines.chain_results import ChainInverseResult, single_row
from pkmkit.machines.strokes import signed_excess
from pkmkit.status import Status


def inverse_record(machine: Any, res: Any, status: np.ndarray, q: np.ndarray,
                   lengths: np.ndarray, strokes: str, bad: np.ndarray,
                   single: bool) -> ChainInverseResult:
    """The :class:`ChainInverseResult` of ``machine``'s inverse model of N rows: the engine's
    result ``res`` (``u (N, 6 + n_var)``), ``status (N,)``, actuators ``q (N, n)`` (NaN where
    not OK), tool lengths ``lengths (N,)`` (m), the ``strokes`` mode and the rows ``bad (N,)``
    with a joint beyond its stroke; one row's record for a ``single`` call."""
    n = q.shape[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        # the direct model at q starts from the closure the inverse found (it converges
        # at once, on that assembly)
        start = np.concatenate([res.u[:, :6], res.u[:, 6:][:, machine.passive_variables]],
                               axis=1)
        direct = machine.fk(q if not single else q[0], tool_length=lengths if not single else
                            lengths[0], start=start if not single else start[0],
                            full_output=True, strokes=strokes,
                            check_singular=False) if np.isfinite(q).any() else None
    pose = np.full((n, 6), np.nan) if direct is None else np.atleast_2d(direct.pose)
    act = machine._actuated
    out = ChainInverseResult(
        q=q, status=status, branches=None, shortfall=None, method="numeric",
        mode=np.zeros(n, dtype=int), iterations=res.iterations, residual=res.residual,
        pose=pose, out_of_stroke=inverse_out_of_stroke(strokes, bad, direct),
        stroke_excess=signed_excess(q, machine.model.q_min[act], machine.model.q_max[act]),
        direct=direct, solution=np.where((res.status == Status.OK)[:, None], res.u, np.nan))
    return single_row(out) if single else out


def inverse_out_of_stroke(strokes: str, bad: np.ndarray, direct) -> np.ndarray | None:
    """``(N,)`` rows of an inverse model with a joint beyond its stroke: with ``"flag"``
    the direct model's check at the solution (actuators and passive joints), with
    ``"refuse"`` the rows refused; None with ``"ignore"``."""
    if strokes == "ignore":
        return None
    if strokes == "refuse" or direct is None:
        return bad
    return np.atleast_1d(np.asarray(direct.out_of_stroke, dtype=bool))
