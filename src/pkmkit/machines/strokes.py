"""The one definition of *out of stroke*, used by every machine family and every command.

A joint value ``v`` with stroke ``[lo, hi]`` is **within its stroke** when
``lo − STROKE_TOL ≤ v ≤ hi + STROKE_TOL`` (``STROKE_TOL`` absorbs the rounding of a value placed
exactly at a stroke end; m or rad). Its **excess** is signed: ``v − hi > 0`` beyond the upper
end, ``v − lo < 0`` below the lower end, 0 within (and 0 for a NaN value: a row without a
configuration has nothing to be out of stroke). Unlimited strokes (±inf) are never exceeded.

The joints checked are the actuators of every family and, for joint-chain machines, the passive
joints of the legs, which have ranges (rod-leg models have no passive-joint ranges: their
spherical and universal joints are unlimited in the model).

:func:`stroke_excess` is the public entry: machine + actuator values → :class:`StrokeCheck`
(per row, per joint excess; which rows are out of stroke; a sentence per row naming the joint,
its leg and by how much, in the units asked for). The machine classes' ``ik`` / ``fk``
(``strokes="flag" | "refuse" | "ignore"``), the command line (status ``out-of-stroke``, exit
status 3) and pose selection all call it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np

#: Slack on a stroke end (m or rad): a value this close beyond it counts as within.
STROKE_TOL = 1e-12


def stroke_ends(lower: np.ndarray, upper: np.ndarray) -> tuple:
    """Per stroke ``(lower, upper, lower − STROKE_TOL, upper + STROKE_TOL)`` in Python floats:
    :func:`row_excess`'s ``strokes``."""
    return tuple((lo, hi, lo - STROKE_TOL, hi + STROKE_TOL)
                 for lo, hi in zip(np.asarray(lower, dtype=float).tolist(),
                                   np.asarray(upper, dtype=float).tolist(), strict=True))


def row_excess(values: list[float], strokes: tuple) -> np.ndarray:
    """:func:`signed_excess` of one row ``values`` (Python floats) over ``strokes``
    (:func:`stroke_ends`) — the same bits, without NumPy's per-column calls (≈ 30 µs of a
    joint chain's one-pose ``full_output`` call with ``strokes="ignore"``, session 35)."""
    out = []
    for v, (lo, hi, lo_tol, hi_tol) in zip(values, strokes, strict=True):
        e = v - hi if v > hi_tol else 0.0
        if v < lo_tol:
            e += v - lo
        out.append(e)
    return np.array(out)


def signed_excess(values: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Signed excess of ``values (N, k)`` over strokes ``lower, upper (k,)`` (module docstring):
    ``(N, k)`` in the values' unit, > 0 beyond the upper end, < 0 below the lower end, 0 within
    or where a value is NaN."""
    v = np.asarray(values, dtype=float)
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if v.ndim != 2 or lo.shape != (v.shape[1],) or hi.shape != lo.shape:
        with np.errstate(invalid="ignore"):
            above = np.where(v > hi + STROKE_TOL, v - hi, 0.0)
            below = np.where(v < lo - STROKE_TOL, v - lo, 0.0)
        return above + below
    # column by column: the batch's (N, k) arrays are often transposed views, and a (k,)
    # operand broadcast over them made NumPy loop k values at a time (25× slower). The same
    # values: above + below, where the excess beyond one end is added to +0.0 for the other.
    out = np.zeros(v.shape, order="F")
    with np.errstate(invalid="ignore"):
        for j in range(v.shape[1]):
            col, target = v[:, j], out[:, j]
            if hi[j] < np.inf:
                np.subtract(col, hi[j], out=target, where=col > hi[j] + STROKE_TOL)
            if lo[j] > -np.inf:
                below = col < lo[j] - STROKE_TOL
                if below.any():
                    target[below] += col[below] - lo[j]
    return out


@dataclass(frozen=True)
class StrokeCheck:
    """Joint values of N configurations against their strokes.

    Attributes:
        lower, upper: ``(k,)`` strokes (±inf when unlimited).
        values: ``(N, k)`` the joint values (m, rad).
        excess: ``(N, k)`` signed excess (m, rad; see :func:`signed_excess`).
        n_actuators: the first ``n_actuators`` joints are the actuators.
        joints: names of the k joints checked (the actuators, then passive joints with ranges).
        legs: the leg(s) each joint belongs to (``""`` when it is not in a leg: a head axis).
        quantities: ``"length"`` (m) or ``"angle"`` (rad) per joint.

    ``joints``, ``legs`` and ``quantities`` are built when first read (they only serve the
    messages), so that checking a pose stays cheap.
    """

    lower: np.ndarray
    upper: np.ndarray
    values: np.ndarray
    excess: np.ndarray
    n_actuators: int
    layout: Callable[[], tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]] = field(
        repr=False, compare=False)

    @cached_property
    def _names(self) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
        return self.layout()

    @property
    def joints(self) -> tuple[str, ...]:
        """Names of the joints checked."""
        return self._names[0]

    @property
    def legs(self) -> tuple[str, ...]:
        """The leg(s) of each joint checked."""
        return self._names[1]

    @property
    def quantities(self) -> tuple[str, ...]:
        """``"length"`` or ``"angle"`` per joint checked."""
        return self._names[2]

    @property
    def out_of_stroke(self) -> np.ndarray:
        """``(N,)`` bool: a joint of the row lies outside its stroke."""
        e = self.excess
        if e.ndim != 2 or not 0 < e.shape[1] <= 16:
            return (e != 0).any(axis=1)
        out = e[:, 0] != 0  # column by column (a reduction along a short axis is slow)
        for j in range(1, e.shape[1]):
            out |= e[:, j] != 0
        return out

    @property
    def actuator_excess(self) -> np.ndarray:
        """``(N, n)`` the actuators' signed excess (m, rad)."""
        return self.excess[:, :self.n_actuators]

    def first(self, row: int) -> int:
        """Index of the joint of ``row`` farthest beyond its stroke (relative to the stroke's
        span where finite), −1 when the row is within its strokes."""
        e = np.abs(self.excess[row])
        if not (e > 0).any():
            return -1
        span = self.upper - self.lower
        rel = np.where(np.isfinite(span) & (span > 0), e / np.where(np.isfinite(span), span, 1),
                       e)
        # ties (to rounding) go to the first joint: equal excesses name q1, not q4
        return int(np.flatnonzero(rel >= rel.max() * (1 - 1e-9))[0])

    def joint_text(self, row: int, k: int, units: str = "m") -> str:
        """``"q1 (leg 1) = 1830 mm, 730 mm beyond its stroke [650, 1100] mm"``."""
        scale, unit = _display(self.quantities[k], units)
        value = self.values[row, k] / scale
        over = self.excess[row, k] / scale
        side = "beyond" if over > 0 else "below"
        leg = f" ({self.legs[k]})" if self.legs[k] and self.legs[k] != self.joints[k] else ""
        return (f"{self.joints[k]}{leg} = {value:.6g} {unit}, {abs(over):.6g} {unit} {side} its "
                f"stroke [{self.lower[k] / scale:.6g}, {self.upper[k] / scale:.6g}] {unit}")

    def message(self, row: int, units: str = "m") -> str:
        """Every joint of ``row`` outside its stroke, the worst in full, then the others'
        excess (``""`` within strokes): ``"q1 (leg 1) = 578 mm, 122 mm below its stroke [700,
        2000] mm; also q2 (leg 2) 122 mm below"``."""
        bad = np.flatnonzero(self.excess[row] != 0)
        if bad.size == 0:
            return ""
        worst = self.first(row)
        text = self.joint_text(row, worst, units)
        others = []
        for k in (int(k) for k in bad if k != worst):
            scale, unit = _display(self.quantities[k], units)
            over = self.excess[row, k] / scale
            leg = f" ({self.legs[k]})" if self.legs[k] and self.legs[k] != self.joints[k] else ""
            others.append(f"{self.joints[k]}{leg} {abs(over):.6g} {unit} "
                          f"{'beyond' if over > 0 else 'below'}")
        return text + (f"; also {', '.join(others)}" if others else "")

    def messages(self, units: str = "m") -> list[str]:
        """One :meth:`message` per row."""
        return [self.message(i, units) for i in range(self.values.shape[0])]

    def details(self, row: int, units: str = "m") -> list[dict[str, Any]]:
        """JSON-ready list of the joints of ``row`` outside their strokes: joint, leg, value,
        excess (signed), stroke and unit, in ``units`` (degrees for angles)."""
        out = []
        for k in np.flatnonzero(self.excess[row] != 0):
            scale, unit = _display(self.quantities[k], units)
            out.append({"joint": self.joints[k], "leg": self.legs[k],
                        "value": float(self.values[row, k] / scale),
                        "excess": float(self.excess[row, k] / scale),
                        "stroke": [float(self.lower[k] / scale), float(self.upper[k] / scale)],
                        "unit": unit})
        return out

    def error(self, row: int, prefix: str = "", pose_index: int | None = None):
        """The :class:`~pkmkit.exceptions.OutOfStrokeError` of ``row`` (naming its worst joint)."""
        from pkmkit.exceptions import OutOfStrokeError

        k = self.first(row)
        return OutOfStrokeError(f"{prefix}{self.message(row)}", self.joints[k],
                                float(self.values[row, k]),
                                (float(self.lower[k]), float(self.upper[k])), pose_index)


def _display(quantity: str, units: str) -> tuple[float, str]:
    """SI value of one display unit and its name: degrees for angles, ``units`` for lengths."""
    if quantity == "angle":
        return np.pi / 180.0, "deg"
    return (1e-3, "mm") if units == "mm" else (1.0, "m")


def stroke_limits(machine) -> tuple[np.ndarray, np.ndarray]:
    """The actuators' strokes ``(lower (n,), upper (n,))`` (m, rad; ±inf when unlimited)."""
    model = machine.model
    if machine.family == "chain":
        act = np.flatnonzero(model.actuated)
        return np.asarray(model.q_min[act], dtype=float), np.asarray(model.q_max[act], dtype=float)
    return np.asarray(model.q_min, dtype=float), np.asarray(model.q_max, dtype=float)


def _rod_layout(model) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
    legs = []
    for k in range(model.n_actuators):
        names = [model.leg_names[i] for i in np.flatnonzero(model.leg_actuator == k)]
        legs.append(", ".join(names))
    return tuple(model.actuator_names), tuple(legs), tuple(model.actuator_quantities)


def _chain_layout(model, variables: np.ndarray):
    owner = {}
    for leg, chain in zip(model.leg_names, model.legs, strict=True):
        for e in chain:
            v = int(model.element_variable[e])
            if v >= 0:
                owner.setdefault(v, []).append(leg)
    quantities = []
    for v in variables:
        e = int(np.flatnonzero(model.element_variable == v)[0])
        quantities.append("angle" if model.elements[e].type == "R" else "length")
    return (tuple(model.variables[v] for v in variables),
            tuple(", ".join(owner.get(int(v), [])) for v in variables), tuple(quantities))


def stroke_excess(machine, q: Any, passive: Any = None) -> StrokeCheck:
    """How far each actuator (and passive joint with a range) of N configurations lies
    beyond its stroke.

    Args:
        machine: any pkmkit machine (rod-leg, full-pose or joint-chain).
        q: ``(n,)`` or ``(N, n)`` actuator values (m, rad); NaN rows are never out of stroke.
        passive: joint-chain machines only: ``(N, n_p)`` passive joint values (rad, m) in
            ``machine.passive_names`` order; default: found by the machine's direct model
            (rows without assembly are not checked for passive joints).

    Returns:
        :class:`StrokeCheck` with N rows.
    """
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    model = machine.model
    if machine.family != "chain":
        lo, hi = stroke_limits(machine)
        return StrokeCheck(lo, hi, qb, signed_excess(qb, lo, hi), qb.shape[1],
                           lambda: _rod_layout(model))
    act = np.flatnonzero(model.actuated)
    pas = np.asarray(machine.passive_variables, dtype=int)
    if passive is None:
        import warnings

        from pkmkit.exceptions import StrokeWarning

        finite = np.isfinite(qb).all(axis=1)
        passive = np.full((qb.shape[0], pas.size), np.nan)
        if finite.any():
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", StrokeWarning)
                res = machine.fk(qb[finite], full_output=True, strokes="ignore",
                                 check_singular=False)
            passive[finite] = np.atleast_2d(res.passive)
    pv = np.atleast_2d(np.asarray(passive, dtype=float))
    variables = np.concatenate([act, pas])
    values = np.concatenate([qb, pv], axis=1)
    lo = np.asarray(model.q_min[variables], dtype=float)
    hi = np.asarray(model.q_max[variables], dtype=float)
    return StrokeCheck(lo, hi, values, signed_excess(values, lo, hi), act.size,
                       lambda: _chain_layout(model, variables))


def magnitude_hint(excess: float, lower: float, upper: float, units: str = "m") -> str:
    """``" (did you mean --units mm?)"`` when a value lies orders of magnitude (≥ 100 ×
    the stroke's largest end) beyond a finite length stroke and the command read metres;
    ``""`` otherwise."""
    size = max(abs(lower), abs(upper))
    if units != "m" or not np.isfinite(size) or size == 0:
        return ""
    return " (did you mean --units mm?)" if abs(excess) >= 100 * size else ""


#: What the direct and inverse models do with configurations outside the strokes: ``"flag"``
#: (the default: batched results carry ``out_of_stroke`` and ``stroke_excess``, a single call
#: warns with :class:`~pkmkit.exceptions.StrokeWarning` naming the joint, its leg and the excess),
#: ``"refuse"`` (rows NaN with status OUT_OF_STROKE; a single call raises
#: :class:`~pkmkit.exceptions.OutOfStrokeError`) or ``"ignore"``.
STROKE_MODES = ("flag", "refuse", "ignore")


def check_mode(strokes: Any) -> str:
    """``strokes`` if it is one of :data:`STROKE_MODES`, else an :class:`InputError`."""
    if not isinstance(strokes, str) or strokes not in STROKE_MODES:
        from pkmkit.exceptions import InputError

        raise InputError(f"strokes must be one of {', '.join(STROKE_MODES)}, got {strokes!r}")
    return strokes


def judge_rows(machine, q: np.ndarray, status: np.ndarray, strokes: str, single: bool,
               what: str, full_output: bool, stacklevel: int = 3) -> StrokeCheck | None:
    """Apply ``strokes`` (:data:`STROKE_MODES`) to the rows ``q (N, n)`` whose ``status`` is OK
    (rod-leg and full-pose machines): with ``"refuse"`` their status becomes OUT_OF_STROKE (in
    place) and a single row raises; with ``"flag"`` a single row warns. ``what`` starts the
    message (``"pose [..]"``). Returns the check (None when nothing needed it)."""
    from pkmkit.status import Status

    if strokes == "ignore" or not (single or full_output or strokes == "refuse"):
        return None
    lo, hi = stroke_limits(machine)
    if not (np.isfinite(lo).any() or np.isfinite(hi).any()):
        return None
    if not full_output and not ((q > hi + STROKE_TOL) | (q < lo - STROKE_TOL)).any():
        return None  # the fast path of a pose within its strokes (NaN compares False)
    ok = status == Status.OK
    rows = q.copy(order="K") if ok.all() else np.where(ok[:, None], q, np.nan)
    check = stroke_excess(machine, rows)
    bad = check.out_of_stroke
    if strokes == "refuse":
        status[bad] = Status.OUT_OF_STROKE
        if single and bad[0]:
            raise check.error(0, f"{what}: ")
    elif single and bad[0]:
        import warnings

        from pkmkit.exceptions import StrokeWarning

        warnings.warn(f"{what}: out of stroke: {check.message(0)}", StrokeWarning,
                      stacklevel=stacklevel)
    return check


#: A home configuration this many times the stroke's largest end beyond it is a unit slip.
MAGNITUDE_FACTOR = 100.0


def refuse_absurd_home(machine, q_home: np.ndarray) -> None:
    """A :class:`~pkmkit.exceptions.ParameterError` when the home configuration ``q_home (n,)``
    puts a length actuator orders of magnitude (:data:`MAGNITUDE_FACTOR` × the stroke's
    largest end) beyond its stroke — lengths in mm read as metres (a machine file without
    ``units``, ``--set`` values in mm) —, naming the actuator and asking for the unit. A home
    only a little outside a stroke is the designer's business and loads."""
    check = stroke_excess(machine, np.asarray(q_home, dtype=float)[None])
    for k in np.flatnonzero(check.excess[0] != 0):
        if check.quantities[k] != "length":
            continue
        size = max(abs(check.lower[k]), abs(check.upper[k]))
        if np.isfinite(size) and size > 0 and abs(check.excess[0, k]) >= MAGNITUDE_FACTOR * size:
            from pkmkit.exceptions import ParameterError

            raise ParameterError(
                f"machine {machine.id!r}: at the home pose {check.joint_text(0, int(k))}, "
                f"{abs(check.excess[0, k]) / size:.3g} times its size: are some lengths in mm "
                "read as metres? (a machine file states `units = \"mm\"`; --set values follow "
                "--units: did you mean --units mm?)")
