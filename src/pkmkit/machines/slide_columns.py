"""Positions that differ only along a common slide axis (issue 22 §3).

When every rod of a machine hangs from a slide and all the slides run along one axis ``d``
(the Verne-type module: three vertical slides), the rods' closure is unchanged by moving the
platform by ``t d`` and every carriage by ``t``: a solution ``(q, R)`` at position ``p`` gives
``(q + t, R)`` at ``p + t d``, and the engine's first-order start moves the same way (its
home Jacobian maps a common slide rate to the translation ``d``). A batch of positions then
needs one inverse per line parallel to ``d`` — a grid over x-y-z one per x-y column — and
the others follow by the shift. :func:`slide_columns` finds those lines exactly (positions
whose component across ``d`` is the same to the bit); rows that are not finite, beyond
:data:`~pkmkit.machines.common.MAX_COORDINATE` or farther than :data:`LINE_SPAN` machine
lengths from the origin keep their own row (far out the rounding of a shift exceeds the
solve's tolerances: a lone solve refuses a position 10⁵ m up the Verne module's slides, so the
batch must too).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.machines.common import MAX_COORDINATE, _valid_rows
from pkmkit.model.rods import SLIDE

#: Rows with a coordinate beyond this many machine lengths (1 + the longest rod, m) keep their
#: own solve (the Verne module's lone solves converge to 10⁴ m along its slides, not 10⁵).
LINE_SPAN = 100.0


@dataclass(frozen=True)
class SlideColumns:
    """Rows of a batch grouped by the line parallel to the common slide axis they lie on.

    Attributes:
        rows: ``(K,)`` the row solved for each line (its first row), then each row that is not
            a valid position.
        of: ``(N,)`` for each row, the index into ``rows`` of the row it follows.
        shift: ``(N,)`` how far each row lies from that row along the axis, in actuator units
            (m): its actuators are that row's plus ``shift`` (0 for the rows solved).
    """

    rows: np.ndarray
    of: np.ndarray
    shift: np.ndarray

    def spread(self, record: Any) -> Any:
        """A view of ``record`` (a velocity model or criteria rates computed at :attr:`rows`)
        whose array fields, read lazily (a lazy record computes only what is read), are
        given at every row of the batch; None fields stay None."""
        return _Spread(record, self.of)


class _Spread:
    """Fields of a record computed at the rows solved, taken at every row (on first read)."""

    def __init__(self, record: Any, of: np.ndarray) -> None:
        self._record = record
        self._of = of

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        value = getattr(self._record, name)
        out = None if value is None else np.asarray(value)[self._of]
        setattr(self, name, out)
        return out


def common_slide_axis(model) -> np.ndarray | None:
    """``(3,)`` the axis every rod's slide runs along (the same for all, to the bit), when every
    rod hangs from a slide and every actuator drives one; else None."""
    axis = np.asarray(model.rod_axis, dtype=float)
    if (axis.shape[0] == 0 or not np.all(model.rod_kind == SLIDE)
            or not np.array_equal(axis, np.broadcast_to(axis[0], axis.shape))
            or np.unique(model.rod_actuator).size != model.n_actuators
            or not np.all(np.isfinite(axis[0])) or not np.any(axis[0])):
        return None
    return axis[0].copy()


def _lines(across: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(first, inverse, shared)`` of the equal rows of ``across (N, 3)`` (finite) as np.unique's
    ``return_index`` and ``return_inverse`` give them — each group's first row, each row's group
    — up to the order of the groups, and the rows that may share theirs (the others are their
    group's first); None when no two rows are equal. Equal rows hash alike
    (their float bits, −0.0 made +0.0 first): only the rows whose hash repeats (a few in a
    table of random positions, rounded or not; every row of a grid) go through np.unique's
    row-wise sort (≈ 1.4 s per 10⁶ rows); a collision only sends a row there."""
    bits = np.ascontiguousarray(across + 0.0).view(np.uint64)  # −0.0 + 0.0 = +0.0
    mixed = bits[:, 0] * np.uint64(0x9E3779B97F4A7C15)
    mixed ^= bits[:, 1] * np.uint64(0xC2B2AE3D27D4EB4F)
    mixed ^= bits[:, 2] * np.uint64(0x165667B19E3779F9)
    ranked = np.sort(mixed)  # ≈ 3× cheaper than argsort: most tables stop here
    if not (ranked[1:] == ranked[:-1]).any():
        return None
    order = np.argsort(mixed)
    same = mixed[order[1:]] == mixed[order[:-1]]
    if not same.any():
        return None
    shared = np.zeros(across.shape[0], dtype=bool)
    shared[order[1:][same]] = True
    shared[order[:-1][same]] = True
    some = np.flatnonzero(shared)  # increasing: np.unique's first is the group's first row
    _, first, inverse = np.unique(across[some], axis=0, return_index=True, return_inverse=True)
    if first.size == some.size:
        return None  # collisions only
    alone = np.flatnonzero(~shared)
    groups = np.empty(across.shape[0], dtype=np.intp)
    groups[alone] = np.arange(alone.size)
    groups[some] = alone.size + inverse.reshape(-1)
    return np.concatenate([alone, some[first]]), groups, some


def slide_columns(model, positions: np.ndarray) -> SlideColumns | None:
    """The lines parallel to the common slide axis of ``model`` through ``positions (N, 3)``
    (:class:`SlideColumns`; rows not finite or beyond :data:`LINE_SPAN` machine lengths on
    their own), or None when the model has no common axis or no two rows share a line
    (nothing to spare)."""
    d = common_slide_axis(model)
    if d is None or positions.shape[0] < 2:
        return None
    span = LINE_SPAN * (1.0 + float(np.max(model.rod_length)))
    with np.errstate(invalid="ignore"):
        # one reduction over the whole batch when every row is within the span (a table's
        # rows): a reduction along the short last axis costs ≈ 25× more (issue 22 §5)
        if np.abs(positions).max() <= min(span, MAX_COORDINATE):
            valid = np.ones(positions.shape[0], dtype=bool)
        else:
            valid = _valid_rows(positions)
            for j in range(positions.shape[1]):
                valid &= np.abs(positions[:, j]) <= span
    good = np.flatnonzero(valid)
    inside = positions if good.size == positions.shape[0] else positions[good]
    along = inside @ d / (d @ d)  # carriage travel to each row's foot, m
    across = np.empty_like(inside)
    for j in range(3):  # column by column: the bits of inside − along[:, None] · d
        np.multiply(along, d[j], out=across[:, j])
        np.subtract(inside[:, j], across[:, j], out=across[:, j])
    lines = _lines(across)
    if lines is None:
        return None
    first, inverse, some = lines
    bad = np.flatnonzero(~valid)
    of = np.empty(positions.shape[0], dtype=np.intp)
    of[good] = inverse.reshape(-1)
    of[bad] = first.size + np.arange(bad.size)
    shift = np.zeros(positions.shape[0])
    some = good[some]  # the other rows are their line's first: no shift
    shift[some] = (positions[some] - positions[good[first]][of[some]]) @ d / (d @ d)
    return SlideColumns(rows=np.concatenate([good[first], bad]), of=of, shift=shift)
