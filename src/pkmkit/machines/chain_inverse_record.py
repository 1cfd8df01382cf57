"""The record of a joint-chain machine's inverse model (:meth:`JointChainMachine.ik
<pkmkit.machines.joint_chain.JointChainMachine.ik>` with ``full_output``): its
:class:`~pkmkit.machines.chain_results.ChainInverseResult` assembled from the engine's solution.

Everything a batch's record holds but its ``direct`` part comes from the inverse's own
solution: the stroke flags (``out_of_stroke``) are those of its joint values — actuators and
passive joints, the joints the direct model checks —, the closure (``closure_start``) is its
platform and passive joints, the pose reached is the tool at that closure. The direct model at
``q`` (``direct``: its per-row messages) is computed when first read (issue 22 §3: a workspace
study reads only the strokes mask and the closure; the direct model at every grid point cost it
3.6 s of 20 on the TriMule): started from the inverse's closure it converges there at once
(zero iterations, the same values to the bit), so its stroke flags, platform, passive joints
and pose are those given here (tests/machines/test_chain_inverse_record.py). A single row's
record computes it at once (its messages are read by the caller)."""

from __future__ import annotations

import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np

from pkmkit.exceptions import StrokeWarning
from pkmkit.machines.chain_results import ChainInverseResult, single_row
from pkmkit.machines.lazy_records import lazy_record_class
from pkmkit.machines.strokes import signed_excess
from pkmkit.status import Status

#: The batch record whose ``direct`` and ``pose`` are computed when first read.
LazyChainInverseResult = lazy_record_class(
    ChainInverseResult, "Lazy",
    lambda r: (f"{len(r.q)} poses, {r.q.shape[1]} actuators; the direct model at q computed "
               "when read"),
    "A joint chain's batched inverse record, its direct model computed when read (module doc).")


def _plain_record(fields: dict) -> ChainInverseResult:
    """The plain record of a pickled lazy one (its fields are keyword-only)."""
    return ChainInverseResult(**fields)


# pickled as the plain record, every field computed (by keyword: the record's fields are
# keyword-only, which lazy_record_class's positional rebuild does not take)
LazyChainInverseResult.__reduce__ = lambda self: (_plain_record, (
    {name: getattr(self, name) for name in ChainInverseResult.__dataclass_fields__},))


class _InverseEvaluation:
    """The fields of a lazy record not given at construction: ``direct`` (the direct model at
    ``q`` from the inverse's closure, strokes as the inverse's) and ``pose`` (the tool point and
    axis at that closure, NaN where not solved)."""

    def __init__(self, machine: Any, known: dict, q: np.ndarray, closure: np.ndarray,
                 values: np.ndarray, lengths: np.ndarray, strokes: str) -> None:
        self._machine, self._known = machine, known  # the record's known_fields()
        self._q, self._closure, self._values = q, closure, values
        self._lengths, self._strokes = lengths, strokes

    def field(self, name: str) -> Any:
        if name == "direct":
            return direct_at(self._machine, self._q, self._closure, self._lengths,
                             self._strokes, False)
        if name == "pose":
            direct = self._known.get("direct")
            if direct is not None:  # already read: its pose
                return np.atleast_2d(direct.pose)
            return tool_pose(self._machine, self._closure, self._values, self._lengths)
        raise AttributeError(name)  # pragma: no cover - every other field is given


def direct_at(machine: Any, q: np.ndarray, closure: np.ndarray, lengths: np.ndarray,
              strokes: str, single: bool):
    """The direct model (``full_output``) at ``q (N, n)`` started from the inverse's
    ``closure (N, 6 + n_p)`` (it converges at once, on that assembly), None where no ``q`` is
    finite."""
    if not np.isfinite(q).any():
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        return machine.fk(q if not single else q[0], tool_length=lengths if not single else
                          lengths[0], start=closure if not single else closure[0],
                          full_output=True, strokes=strokes, check_singular=False)


def tool_pose(machine: Any, closure: np.ndarray, values: np.ndarray,
              lengths: np.ndarray) -> np.ndarray:
    """``(N, 6)`` tool point (m) and axis at the closures ``closure (N, 6 + n_p)`` with the
    joint values ``values (N, n_var)`` (NaN rows where the closure is not finite): the direct
    model's own tool rows."""
    usable = np.isfinite(closure).all(axis=1)
    # the engine result's one field the tool rows read
    return machine.tool_rows(SimpleNamespace(u=closure), values, lengths, usable)[0]


def inverse_record(machine: Any, res: Any, status: np.ndarray, q: np.ndarray,
                   lengths: np.ndarray, strokes: str, bad: np.ndarray,
                   single: bool) -> ChainInverseResult:
    """The :class:`ChainInverseResult` of ``machine``'s inverse model of N rows: the engine's
    result ``res`` (``u (N, 6 + n_var)``), ``status (N,)``, actuators ``q (N, n)`` (NaN where
    not OK), tool lengths ``lengths (N,)`` (m), the ``strokes`` mode and the rows ``bad (N,)``
    with a joint (actuator or passive, of the inverse's joint values) beyond its stroke; one
    row's record for a ``single`` call, a batch's with ``direct`` computed when read."""
    n = q.shape[0]
    passive = machine.passive_variables
    solved = status == Status.OK
    closure = np.concatenate([res.u[:, :6], res.u[:, 6:][:, passive]], axis=1)
    closure[~solved] = np.nan
    act = machine.actuated_columns
    given = dict(
        q=q, status=status, branches=None, shortfall=None, method="numeric",
        mode=np.zeros(n, dtype=int), iterations=res.iterations, residual=res.residual,
        out_of_stroke=None if strokes == "ignore" else bad,
        stroke_excess=signed_excess(q, machine.model.q_min[act], machine.model.q_max[act]),
        solution=np.where((res.status == Status.OK)[:, None], res.u, np.nan),
        closure=closure if np.isfinite(q).any() else None)
    if single:
        direct = direct_at(machine, q, closure, lengths, strokes, True)
        pose = np.full((n, 6), np.nan) if direct is None else np.atleast_2d(direct.pose)
        return single_row(ChainInverseResult(pose=pose, direct=direct, **given))
    values = machine.full_values(q)
    values[:, passive] = closure[:, 6:]
    record = LazyChainInverseResult(None, **given)
    # copies: the caller may change the record's q or closure, or its tool lengths, before the
    # first read
    object.__setattr__(record, "_evaluation", _InverseEvaluation(
        machine, record.known_fields(), q.copy(), closure.copy(), values, lengths.copy(),
        strokes))
    return record
