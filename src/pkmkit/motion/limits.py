"""Every limit along a path: for every actuator and every kind of limit, every excursion.

:func:`path_limit_violations` compares a continuous motion (its :class:`~pkmkit.motion.extrema.
Extrema`, which can evaluate any quantity at any time) with the limits and returns, for each
(kind, actuator) pair that is exceeded at least once: the worst excess over the whole run, the
number of excursions and the time span of each (:func:`pkmkit.motion.extrema.all_excursions`),
and the program line and block text where each one peaks and starts.

Kinds (:data:`LIMIT_KINDS`): ``stroke`` (the machine's actuator ranges, ``q``), ``speed``
(``qd``), ``accel`` (``qdd``), ``force`` (``force``) and ``passive`` (passive-joint ranges, for
machines whose motion evaluates them: the rod machines that ``pkmkit path`` follows expose no
passive-joint ranges, so that kind is not checked for them). The stroke ranges are read by
:func:`actuator_strokes`, the one place to switch to the shared stroke check.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.strokes import signed_excess, stroke_limits
from pkmkit.motion.extrema import Extrema, Span, all_excursions
from pkmkit.motion.timelaw import Trajectory

#: Kinds of limits, in report order.
LIMIT_KINDS = ("stroke", "speed", "accel", "force", "passive")
#: Quantity of :attr:`Extrema` each kind compares.
QUANTITY = {"stroke": "q", "speed": "qd", "accel": "qdd", "force": "force",
            "passive": "passive"}


def actuator_strokes(machine) -> tuple[np.ndarray, np.ndarray]:
    """``(n,)`` lower and upper actuator strokes of ``machine`` (m or rad; ±inf where none):
    :func:`pkmkit.machines.strokes.stroke_limits`, the one place strokes are read."""
    return stroke_limits(machine)


def stroke_excess(machine, q: np.ndarray) -> np.ndarray:
    """``(N, n)`` how far each actuator value of ``q (N, n)`` lies outside its stroke (0 inside,
    and where q is NaN), by the one stroke check (:mod:`pkmkit.machines.strokes`)."""
    lo, hi = stroke_limits(machine)
    return np.abs(signed_excess(np.atleast_2d(np.asarray(q, dtype=float)), lo, hi))


@dataclass(frozen=True)
class Excursion:
    """One excursion (a :class:`~pkmkit.motion.extrema.Span`) with the program blocks where it
    starts and peaks (line 0 and empty text for paths not read from a program)."""

    span: Span
    line: int
    block: str
    start_line: int
    start_block: str


@dataclass(frozen=True)
class LimitViolation:
    """One limit of one actuator (or passive joint) exceeded along the path.

    Attributes:
        kind: one of :data:`LIMIT_KINDS`.
        joint: the actuator's (or passive joint's) name.
        lower, upper: the limit (SI units; −upper..upper for speeds, accelerations, forces).
        excursions: every excursion, in time order.
    """

    kind: str
    joint: str
    lower: float
    upper: float
    excursions: tuple[Excursion, ...] = field(default=())

    @property
    def worst(self) -> Excursion:
        """The excursion with the largest excess."""
        return max(self.excursions, key=lambda e: e.span.excess)

    def as_dict(self, trajectory: Trajectory, dims: int) -> dict[str, Any]:
        """JSON-ready (SI units): the worst excess, when, where (pose, line, block), the
        count and every span."""
        w = self.worst
        pose = trajectory.at(np.array([w.span.t_peak])).x[0, :dims]
        return {"limit": self.kind, "actuator": self.joint, "lower": self.lower,
                "upper": self.upper, "excess": w.span.excess, "value": w.span.value,
                "t_peak": w.span.t_peak, "t": self.excursions[0].span.start,
                "line": w.line, "block": w.block, "pose": pose,
                "excursions": len(self.excursions),
                "spans": [{"start": e.span.start, "end": e.span.end, "t_peak": e.span.t_peak,
                           "value": e.span.value, "excess": e.span.excess, "line": e.line,
                           "block": e.block, "start_line": e.start_line,
                           "start_block": e.start_block} for e in self.excursions]}


def _positive(limit: Any, kind: str, n: int) -> np.ndarray:
    lim = np.broadcast_to(np.asarray(limit, dtype=float), (n,))
    if not (np.isfinite(lim).all() and (lim > 0).all()):
        raise InputError(f"{kind} limits must be > 0, got {limit}")
    return lim


def limit_bounds(machine, limits) -> list[tuple[str, str, np.ndarray, np.ndarray]]:
    """``[(kind, quantity, lower (n,), upper (n,))]`` for every checked limit of
    :class:`~pkmkit.motion.joints.Limits` (strokes from :func:`actuator_strokes`)."""
    n = machine.n_actuators
    out = []
    if limits.strokes:
        lo, hi = actuator_strokes(machine)
        out.append(("stroke", "q", lo, hi))
    for kind, value in (("speed", limits.speed), ("accel", limits.accel),
                        ("force", limits.force)):
        if value is not None:
            lim = _positive(value, kind, n)
            out.append((kind, QUANTITY[kind], -lim, lim))
    return out


def _block_at(trajectory: Trajectory, times: np.ndarray) -> list[tuple[int, str]]:
    path = trajectory.path
    seg = trajectory.at(times).segment
    lines = [int(path.source[k]) if path.source else 0 for k in seg]
    texts = [path.blocks[k] if path.blocks else "" for k in seg]
    return list(zip(lines, texts, strict=True))


def path_limit_violations(machine, trajectory: Trajectory, extrema: Extrema, limits, *,
                          passive: tuple[list[str], np.ndarray, np.ndarray] | None = None
                          ) -> list[LimitViolation]:
    """Every limit exceeded along the continuous motion (module docstring).

    Args:
        machine: the machine (actuator names, strokes).
        trajectory: the tool trajectory (for the program blocks).
        extrema: the motion's extrema (:func:`pkmkit.motion.extrema.continuous_extrema`) with
            the quantities ``q``, ``qd``, ``qdd``, ``force`` (and ``passive`` when given).
        limits: a :class:`~pkmkit.motion.joints.Limits`.
        passive: ``(names, lower (p,), upper (p,))`` ranges of the passive joints, for a motion
            whose extrema include them.

    Returns:
        violations ordered by kind (:data:`LIMIT_KINDS`) then actuator; empty when every
        checked limit holds.
    """
    checks = [(kind, name, lo, hi, list(machine.actuator_names))
              for kind, name, lo, hi in limit_bounds(machine, limits)
              if name in extrema.high]
    if passive is not None and "passive" in extrema.high:
        names, lo, hi = passive
        checks.append(("passive", "passive", np.asarray(lo, float), np.asarray(hi, float),
                       list(names)))
    out = []
    for kind, name, lo, hi, joints in checks:
        for a, joint in enumerate(joints):
            spans = all_excursions(extrema, name, a, float(lo[a]), float(hi[a]))
            if not spans:
                continue
            times = np.array([t for s in spans for t in (s.t_peak, s.start)])
            blocks = _block_at(trajectory, times)
            excursions = tuple(Excursion(span=s, line=blocks[2 * i][0], block=blocks[2 * i][1],
                                         start_line=blocks[2 * i + 1][0],
                                         start_block=blocks[2 * i + 1][1])
                               for i, s in enumerate(spans))
            out.append(LimitViolation(kind=kind, joint=joint, lower=float(lo[a]),
                                      upper=float(hi[a]), excursions=excursions))
    return out
