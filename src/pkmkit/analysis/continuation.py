"""The inverse model of a chunk of grid points by continuation (issue 22 §3): on a machine whose
numerical inverse starts from any complete solution (``machine.inverse_continues``: a joint
chain's platform, passive joints and actuators), the chunk is solved slab by slab, each slab
from the solution of the one before — point ``i`` of a C-order grid starts from point
``i − slab``, its neighbour one step back along the first axis — instead of every point from
home. A point whose neighbour failed starts from home, and so does again a point that does
not converge from its neighbour (:meth:`~pkmkit.machines.joint_chain.JointChainMachine.ik`),
so continuation loses no point the start from home reaches; revolute actuators stay on the
turn nearest home. A neighbour next to a joint-chain head's wrist singularity, where the
head's two branches meet, is not a start (``machine.continues_from``,
:mod:`pkmkit.machines.warm_starts`): the grid reports the branch the start from home reaches.
A point whose continued closure leaves the legs' home assembly modes (a slide of the opposite
sign, a revolute leg joint beyond a quarter turn of home: ``machine.in_home_modes``) is solved
again from home, so the grid gives the start from home's answer wherever that is in home's
modes (tests/analysis/test_continuation_modes.py). On by default
(:attr:`~pkmkit.analysis.criteria.Criteria.continuation`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import StrokeWarning
from pkmkit.progress import tracked


@dataclass(frozen=True)
class ContinuedInverse:
    """What the criteria read of the inverse model of a chunk solved slab by slab.

    Attributes:
        q: ``(M, n)`` actuator coordinates (NaN where not reached).
        status: ``(M,)`` Status codes.
        out_of_stroke: ``(M,)`` bool, a joint (actuator or passive) beyond its stroke.
        closure_start: ``(M, 6 + n_p)`` platform and passive joints found (the velocity model's
            start).
        iterations: ``(M,)`` the engine's iterations per point.
        solution: ``(M, 6 + n_var)`` platform and every joint variable found (NaN where not
            reached).
        pose: None (the points are complete poses).
    """

    q: np.ndarray
    status: np.ndarray
    out_of_stroke: np.ndarray
    closure_start: np.ndarray
    iterations: np.ndarray
    solution: np.ndarray
    pose: None = None


def inverse_of_chunk(machine: Any, points: np.ndarray, slab: int | None) -> Any:
    """The inverse model (``full_output``, strokes flagged) at ``points (M, dims)``: at once,
    or — with ``slab`` (points per slab of the grid they come from, C order) on a machine
    whose inverse continues — slab by slab from the neighbouring slab's solution."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        if not (slab and machine.inverse_continues and len(points) > slab):
            return machine.ik(points, full_output=True)
        parts, start = [], None
        slabs = range(0, len(points), slab)
        for k in tracked(slabs, total=len(slabs), unit="slab",
                         label=f"{machine.id}: inverse model of {len(points):,} poses"):
            piece = points[k:k + slab]
            if start is not None:  # the kind's closed start first (continuation_starts)
                start = machine.continuation_starts(piece, start[:len(piece)])
            inv = (machine.ik(piece, full_output=True) if start is None else
                   machine.ik(piece, full_output=True, start=start))
            parts.append(inv)
            start = np.where(machine.continues_from(inv.solution)[:, None], inv.solution,
                             np.nan)
    width = 6 + len(machine.passive_names)
    return ContinuedInverse(
        q=np.concatenate([np.atleast_2d(p.q) for p in parts]),
        status=np.concatenate([p.status for p in parts]),
        out_of_stroke=np.concatenate([np.asarray(p.out_of_stroke, dtype=bool)
                                      for p in parts]),
        closure_start=np.concatenate([np.full((len(p.q), width), np.nan)
                                      if p.closure_start is None else p.closure_start
                                      for p in parts]),
        iterations=np.concatenate([p.iterations for p in parts]),
        solution=np.concatenate([p.solution for p in parts]))
