"""Deflection of the tool point along a machining move: the weight of the moving parts and the
tool force (constant or against time), per program block.

The deflection at each pose is :func:`pkmkit.stiffness.loads.load_deflection` (quasi-static:
inertia forces are left out). Its largest norm over the move is found over continuous time
(:func:`pkmkit.motion.extrema.continuous_extrema`, between output samples too); the figures per
block (a G-code line, or a segment of a generated path) are over the output samples of that
block.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.masses import MassProperties
from pkmkit.dynamics.wrench import WrenchSeries
from pkmkit.exceptions import InputError
from pkmkit.motion.extrema import DEFAULT_RTOL, continuous_extrema
from pkmkit.motion.timelaw import Trajectory
from pkmkit.stiffness.data import StiffnessData
from pkmkit.stiffness.loads import load_deflection


@dataclass(frozen=True)
class PathDeflection:
    """Tool-point deflection along a move (N output samples, d = 2 or 3), SI units.

    Attributes:
        t: ``(N,)`` s. total, gravity, force: ``(N, d)`` m (their sum; the weight of the
            moving parts; the tool force).
        peak: the largest norm over continuous time: ``{"value" (m), "t" (s), "pose" (d,) m,
            "line", "block", "segment"}``.
        gravity_peak, force_peak: largest norm of each part over the output samples, m.
        blocks: per block (in path order), ``{"segment", "line", "block", "max" (m), "t" (s)}``
            over its output samples.
        converged: the continuous search converged (to ``rtol`` of the norm's range).
    """

    t: np.ndarray
    total: np.ndarray
    gravity: np.ndarray
    force: np.ndarray
    peak: dict[str, Any]
    gravity_peak: float
    force_peak: float
    blocks: tuple[dict[str, Any], ...]
    converged: bool


def _force_at(force: Any, times: np.ndarray) -> np.ndarray | None:
    if force is None:
        return None
    if isinstance(force, WrenchSeries):
        return force.at(times)
    f = np.asarray(force, dtype=float).reshape(-1)
    if f.size not in (3, 6):
        raise InputError(f"the tool force must be FX,FY,FZ (N), got {f.size} numbers")
    return np.broadcast_to(f[:3], (len(times), 3))


def path_deflection(machine: Any, trajectory: Trajectory, masses: MassProperties | None, *,
                    force: Any = None, data: StiffnessData | None = None,
                    rtol: float = DEFAULT_RTOL) -> PathDeflection:
    """Tool-point deflection along ``trajectory`` under the weight of ``masses`` and ``force``
    (``(3,)`` N, a :class:`~pkmkit.dynamics.wrench.WrenchSeries`, or None).

    Raises:
        InputError: a pose of the move where the machine has no stiffness (singular), and the
            refusals of :func:`~pkmkit.stiffness.loads.load_deflection`.
    """
    t = np.asarray(trajectory.t, dtype=float)
    d = machine.dims
    sampled = load_deflection(machine, trajectory.x[:, :d], masses,
                              force=_force_at(force, t), data=data)
    bad = ~np.isfinite(sampled.total).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputError(f"no stiffness at t = {t[k]:.6g} s, pose "
                         f"{np.round(trajectory.x[k, :d], 9).tolist()} m: the move crosses a "
                         "singular configuration")

    def evaluate(times: np.ndarray) -> dict[str, np.ndarray]:
        x = trajectory.at(times).x[:, :d]
        r = load_deflection(machine, x, masses, force=_force_at(force, times), data=data)
        return {"norm": np.linalg.norm(r.total, axis=1)[:, None]}

    breakpoints = trajectory.breakpoints()
    if isinstance(force, WrenchSeries):
        inside = force.t[(force.t > 0) & (force.t < trajectory.duration)]
        breakpoints = np.union1d(breakpoints, inside)
    extrema = continuous_extrema(evaluate, breakpoints, rtol=rtol)
    t_peak = float(extrema.t_high["norm"][0])
    at_peak = trajectory.at(np.array([t_peak]))
    norms = np.linalg.norm(sampled.total, axis=1)
    if norms.max() > extrema.high["norm"][0]:  # the samples themselves (rounding)
        k = int(np.argmax(norms))
        t_peak, at_peak = float(t[k]), trajectory.at(t[k:k + 1])
    segment = int(at_peak.segment[0])
    peak = {"value": float(max(extrema.high["norm"][0], norms.max())), "t": t_peak,
            "pose": at_peak.x[0, :d], **_source(trajectory, segment)}
    blocks = []
    seg = np.asarray(trajectory.segment)
    for s in np.unique(seg):
        rows = np.flatnonzero(seg == s)
        k = rows[int(np.argmax(norms[rows]))]
        blocks.append({**_source(trajectory, int(s)), "max": float(norms[k]), "t": float(t[k])})
    return PathDeflection(
        t=t, total=sampled.total, gravity=sampled.gravity, force=sampled.force, peak=peak,
        gravity_peak=float(np.linalg.norm(sampled.gravity, axis=1).max()),
        force_peak=float(np.linalg.norm(sampled.force, axis=1).max()),
        blocks=tuple(blocks), converged=bool(extrema.converged))


def _source(trajectory: Trajectory, segment: int) -> dict[str, Any]:
    path = trajectory.path
    return {"segment": segment, "line": int(path.source[segment]) if path.source else 0,
            "block": path.blocks[segment] if path.blocks else ""}
