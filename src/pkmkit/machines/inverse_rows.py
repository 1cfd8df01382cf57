"""How a machine reads its own ``ik(full_output=True)`` into the fields every family shares
(:class:`pkmkit.boundary.kinematics.InverseRows`: ``q``, ``status``, ``mode``, ``branches``,
``pose``, ``passive``), so that the one ``pkmkit ik`` path asks the machine instead of looking
its family up.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.status import Status


class RodInverseRows:
    """Rod legs: an :class:`~pkmkit.machines.results.InverseResult` as it is."""

    def inverse_rows(self, result: Any, mode: bool = True) -> dict[str, Any]:
        """Rows ``(N, …)`` of ``result`` (one pose or many): q, status, mode (None unless
        ``mode``: a lazy record's modes are then never computed), branches and, for a
        position-controlled machine given positions, the full poses found."""
        pose = None if result.pose is None else np.atleast_2d(result.pose)
        return {"q": np.atleast_2d(result.q), "status": np.atleast_1d(result.status),
                "mode": np.atleast_1d(result.mode) if mode else None,
                "branches": result.branches, "pose": pose}


class ChainInverseRows:
    """Joint chains: a row is OK where q is finite; the passive joints of its direct model."""

    def inverse_rows(self, result: Any, mode: bool = True) -> dict[str, Any]:
        """Rows ``(N, …)`` of a :class:`~pkmkit.machines.chain_results.ChainInverseResult`:
        q, status (OK where q is finite, else UNREACHABLE) and the passive joints (NaN when no
        row was solved); a joint chain has no assembly mode (``mode`` is ignored)."""
        q = np.atleast_2d(result.q)
        status = np.where(np.isfinite(q).all(axis=1), Status.OK, Status.UNREACHABLE)
        direct = result.direct
        passive = (np.full((len(q), len(self.passive_names)), np.nan) if direct is None
                   else np.atleast_2d(direct.passive))
        return {"q": q, "status": status, "passive": passive}
