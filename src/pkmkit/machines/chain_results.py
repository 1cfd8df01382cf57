"""Result records of joint-chain machines, as the protocol's records of every family: the direct
model's :class:`ChainDirectResult` is a :class:`~pkmkit.machines.results.DirectResult`, the
inverse model's :class:`ChainInverseResult` an :class:`~pkmkit.machines.results.InverseResult`
(that still unpacks, with a :class:`DeprecationWarning`, as the former tuple ``(q, direct)``)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.machines.results import DirectResult, InverseResult


@dataclass(frozen=True, kw_only=True)
class ChainDirectResult(DirectResult):
    """Direct model of a joint-chain machine at N actuator vectors.

    Attributes:
        pose: ``(N, 6)`` tool point (m) and unit tool axis (NaN rows where it failed).
        tool_frame: ``(N, 6)`` tool frame origin (m) and rotation vector (rad).
        platform: ``(N, 6)`` platform frame (the legs' common end) position and rotation vector.
        passive: ``(N, n_p)`` passive joint values (rad or m), in :attr:`passive_names` order.
        passive_names: names of the passive joints.
        closure_residual: ``(N,)`` largest closure residual (m; rotation rows × L): ~1e-15 for a
            compatible geometry, the least-squares misfit for an incompatible one.
        status: ``(N,)`` status codes (OK, or NO_ASSEMBLY when the closure failed, or
            INCONSISTENT when it converged to a non-zero residual: incompatible defects;
            OUT_OF_STROKE, SINGULAR: see :meth:`JointChainMachine.fk`).
        iterations: ``(N,)`` engine iterations.
        out_of_stroke: ``(N,)`` bool, a joint (actuator given or passive joint found) lies
            outside its stroke.
        messages: one sentence per row saying what is wrong (``""`` for a good row): which
            leg misses the platform and by how much, which joint is beyond its stroke.
        mode, mode_label, branches, method: as for every :class:`DirectResult`: a joint-chain
            machine's direct model is solved by the engine (``"numeric"``) from a start in the
            working mode (``mode`` 0: no sign of det A names it), without leg branches (None).
    """

    pose: np.ndarray
    status: np.ndarray
    tool_frame: np.ndarray
    platform: np.ndarray
    passive: np.ndarray
    passive_names: tuple[str, ...]
    closure_residual: np.ndarray
    iterations: np.ndarray
    out_of_stroke: np.ndarray | None = None
    messages: tuple[str, ...] | str = ()
    mode: np.ndarray | None = None
    mode_label: str = "working"
    branches: np.ndarray | None = None
    method: str = "numeric"


@dataclass(frozen=True, kw_only=True)
class ChainInverseResult(InverseResult):
    """Inverse model of a joint-chain machine at N tool points and axes.

    Attributes:
        q, status, iterations, residual, out_of_stroke, stroke_excess: as for every
            :class:`InverseResult` (``out_of_stroke`` counts the passive joints too; None when
            the strokes were ignored).
        pose: ``(N, 6)`` the tool point and axis reached (NaN where it failed).
        direct: the direct model at ``q`` (:class:`ChainDirectResult`: platform, passive
            joints, messages), None when no row was solved; a batch's record computes it when
            first read (:mod:`pkmkit.machines.chain_inverse_record`).
        solution: ``(N, 6 + n_var)`` the engine's complete solution — platform position,
            rotation vector, every joint variable in the model's order (NaN where it failed):
            the ``start`` of a next inverse model nearby (continuation).
        branches, shortfall, mode: no leg branches, shortfalls or sign of det A for a joint
            chain: ``(0,)``, ``(N, 0)`` and zeros.
        closure: ``(N, 6 + n_p)`` the closure the inverse model found with ``q`` — platform
            position, rotation vector, passive joints (NaN where not solved; None when no row
            was) — read by :attr:`closure_start`; None in a record built without it (then
            :attr:`closure_start` reads ``direct``).
    """

    direct: ChainDirectResult | None = None
    solution: np.ndarray | None = None
    closure: np.ndarray | None = None

    @property
    def closure_start(self) -> np.ndarray | None:
        """``(N, 6 + n_p)`` the closure found with ``q`` — platform position (m), rotation
        vector (rad), passive joints — as the ``start`` of the velocity model or of ``fk`` at
        ``q`` (NaN rows start from home); None when no row was solved. The inverse's own
        closure: the direct model at ``q`` from it converges at once on the same values."""
        if self.closure is not None:
            return np.atleast_2d(self.closure)
        if self.direct is None:
            return None
        return np.concatenate([np.atleast_2d(self.direct.platform),
                               np.atleast_2d(self.direct.passive)], axis=1)

    def _as_tuple(self) -> tuple[Any, Any]:
        warnings.warn("a joint-chain machine's ik(full_output=True) returns a "
                      "ChainInverseResult: read .q and .direct rather than unpacking a tuple",
                      DeprecationWarning, stacklevel=3)
        return (self.q, self.direct)

    def __iter__(self):
        """Deprecated: unpack as the former tuple ``(q, direct)``."""
        return iter(self._as_tuple())

    def __getitem__(self, index: int):
        """Deprecated: index as the former tuple ``(q, direct)``."""
        return self._as_tuple()[index]


def single_row(result: Any) -> Any:
    """The record of a single-row call: every array field loses its leading axis."""
    fields = {k: (v[0] if isinstance(v, np.ndarray) else v) for k, v in result.__dict__.items()}
    if "messages" in fields and isinstance(fields["messages"], tuple) and fields["messages"]:
        fields["messages"] = fields["messages"][0]
    return type(result)(**fields)
