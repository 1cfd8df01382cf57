"""What the kinematics commands say about configurations outside the strokes.

Every command judges its configurations with :func:`pkmkit.machines.strokes.stroke_excess` (the
one definition of *out of stroke*):

- a single pose or q prints its values, then ``out of stroke: <joint (leg) = value, excess
  beyond its stroke [lo, hi]>`` on standard error (in ``--units``, degrees for angles; with a
  hint when the values are orders of magnitude beyond the strokes) and exits with status 3; its
  JSON has ``"status": "out-of-stroke"`` and an ``out_of_stroke`` list (joint, leg, value,
  signed excess, stroke, unit);
- a batch keeps the rows' values, labels them ``out-of-stroke`` in the status column, names the
  joint and the excess of the first rows on standard error and exits with status 3, as for the
  other flagged rows.
"""

from __future__ import annotations

import sys
from typing import Any

import click
import numpy as np

from pkmkit.machines.strokes import StrokeCheck, magnitude_hint, stroke_excess
from pkmkit.status import Status

#: Out-of-stroke rows of a batch named on standard error before they are only counted.
MAX_MESSAGES = 20


def hint(check: StrokeCheck, row: int, units: str) -> str:
    """A ``--units mm`` hint when the worst joint of ``row`` is a length orders of magnitude
    beyond its stroke (read in metres)."""
    k = check.first(row)
    if k < 0 or check.quantities[k] != "length":
        return ""
    return magnitude_hint(float(check.excess[row, k]), float(check.lower[k]),
                          float(check.upper[k]), units)


def single_check(m, q: np.ndarray, units: str, passive: Any = None) -> StrokeCheck | None:
    """The check of one configuration ``q (n,)`` (None when q is not finite)."""
    q = np.asarray(q, dtype=float)
    if not np.isfinite(q).all():
        return None
    pas = None if passive is None else np.atleast_2d(np.asarray(passive, dtype=float))
    return stroke_excess(m, q[None], pas)


def add_to_payload(payload: dict[str, Any], check: StrokeCheck | None, units: str,
                   set_status: bool = True) -> None:
    """The ``out_of_stroke`` details when the row is out of stroke, and ``status`` →
    ``out-of-stroke`` unless ``set_status`` is False (a Jacobian's status is its singularity
    class, kept)."""
    if check is not None and check.out_of_stroke[0]:
        if set_status:
            payload["status"] = Status.OUT_OF_STROKE.label
        payload["out_of_stroke"] = check.details(0, units)


def finish_single(check: StrokeCheck | None, units: str) -> None:
    """After a single configuration's output: the message and exit status 3 if it is out of
    stroke."""
    if check is None or not check.out_of_stroke[0]:
        return
    click.echo(f"out of stroke: {check.message(0, units)}{hint(check, 0, units)}", err=True)
    sys.exit(3)


class BatchFlags:
    """Flags the out-of-stroke rows of a batch, chunk after chunk."""

    def __init__(self, m, units: str) -> None:
        self.m = m
        self.units = units
        self.shown = 0
        self.hidden = 0

    def __call__(self, q: np.ndarray, status: np.ndarray, chunk: Any,
                 passive: Any = None) -> np.ndarray:
        """``status (N,)`` with OUT_OF_STROKE where an OK row of ``q (N, n)`` (m, rad) is out of
        stroke; names the joints of the first rows on standard error."""
        status = np.array(status, dtype=np.int64, copy=True)
        ok = status == Status.OK
        # column-major, as the excess is computed column by column (C-ordered rows made it
        # stride over every row: ≈ 0.1 s per 5·10⁵ six-actuator rows); the same values
        rows = np.empty(np.shape(q), order="F")
        np.copyto(rows, q)
        if not ok.all():
            rows[~ok] = np.nan
        pas = None
        if passive is not None:
            pas = np.where(ok[:, None], np.atleast_2d(np.asarray(passive, dtype=float)), np.nan)
        check = stroke_excess(self.m, rows, pas)
        bad = check.out_of_stroke & ok
        status[bad] = Status.OUT_OF_STROKE
        first = int(getattr(chunk, "first_row", 0))
        real = len(chunk) if hasattr(chunk, "__len__") else len(status)
        for i in np.flatnonzero(bad):
            if i >= real:  # the copy of a one-row chunk (see batch._compute_rows)
                continue
            if self.shown < MAX_MESSAGES:
                click.echo(f"warning: row {first + i}: out of stroke: "
                           f"{check.message(int(i), self.units)}{hint(check, int(i), self.units)}",
                           err=True)
                self.shown += 1
            else:
                self.hidden += 1
        return status
