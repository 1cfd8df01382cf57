"""Configurations for error analyses: actuator coordinates spread over a region of a machine's
workspace, reachable with the nominal geometry.

A **region** is a box ``(lower, upper)`` in the machine's *region coordinates*, which each
family defines (``machine.region_names()``, ``machine.default_region()``,
``machine.configurations_at(points)``: :mod:`pkmkit.machines.error_regions`):

- rod machines: tool positions (``dims`` coordinates for a translational machine; x, y, z for a
  full-pose machine with fewer than six actuators, whose orientation follows); for a
  six-actuator machine position and rotation vector (six coordinates; three are accepted, the
  orientation then stays at home); default :meth:`default_box`, with rotations of ±
  :data:`ROTATION_SPREAD` about home for a six-actuator machine (identification needs the
  orientation to vary);
- joint-chain machines: actuator coordinates (m, rad) — their tool pose is a point and an axis
  reached through a closed-loop inverse model, so the natural region is the actuators' box;
  default the actuators' strokes where finite, else home ± :data:`CHAIN_SPREAD`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.error_regions import CHAIN_SPREAD, ROTATION_SPREAD, draw_reachable, halton
from pkmkit.numerics.magnitudes import MAX_CONFIGURATIONS, check_count

__all__ = ["CHAIN_SPREAD", "ROTATION_SPREAD", "Configurations", "check_region",
           "configurations_at", "default_region", "halton", "region_names",
           "sample_configurations"]


@dataclass(frozen=True)
class Configurations:
    """Reachable configurations of a region.

    Attributes:
        q: ``(N, n)`` actuator coordinates (m, rad).
        points: ``(N, k)`` the region coordinates they were drawn at (tool positions, or the
            actuator coordinates themselves for joint chains).
        region: ``(lower (k,), upper (k,))`` the box.
        names: names of the region coordinates.
        drawn: how many points were drawn to find the N reachable ones.
    """

    q: np.ndarray
    points: np.ndarray
    region: tuple[np.ndarray, np.ndarray]
    names: tuple[str, ...]
    drawn: int


def region_names(machine) -> tuple[str, ...]:
    """Names of the region coordinates of ``machine`` (module docstring)."""
    return machine.region_names()


def default_region(machine) -> tuple[np.ndarray, np.ndarray]:
    """The default region (module docstring)."""
    return machine.default_region()


def check_region(machine, region: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` validated against the machine's region coordinates.

    Accepts ``None`` (default), a pair of vectors or a flat ``(lo1, hi1, lo2, hi2, …)``.

    Raises:
        InputError: wrong number of bounds, non-finite values, lower ≥ upper.
    """
    if region is None:
        return default_region(machine)
    names = region_names(machine)
    if isinstance(region, tuple | list) and len(region) == 2 and np.ndim(region[0]) == 1:
        lo, hi = (np.asarray(v, dtype=float) for v in region)
    else:
        flat = np.asarray(region, dtype=float).reshape(-1)
        if flat.size % 2:
            raise InputError(f"a region needs pairs MIN,MAX; got {flat.size} values")
        lo, hi = flat[0::2], flat[1::2]
    if lo.shape != hi.shape or lo.size not in machine.region_sizes():
        raise InputError(f"the region of {machine.id!r} needs MIN,MAX for each of "
                         f"{', '.join(names)} ({len(names)} pairs), got {lo.size}")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise InputError("region bounds must be finite")
    bad = np.flatnonzero(~(lo < hi))
    if bad.size:
        k = int(bad[0])
        label = names[k] if k < len(names) else f"coordinate {k + 1}"
        raise InputError(f"region: {label} has MIN = {lo[k]:g} not below MAX = {hi[k]:g}")
    return lo, hi


def configurations_at(machine, points: np.ndarray) -> np.ndarray:
    """Actuator coordinates ``(N, n)`` of region points ``(N, k)`` with the nominal geometry
    (NaN rows where unreachable)."""
    return machine.configurations_at(points)


def sample_configurations(machine, n: int, *, region: Any = None, seed: int | None = 0,
                          method: str = "random", within_strokes: bool = False
                          ) -> Configurations:
    """``n`` reachable configurations drawn in ``region`` (uniformly at random, or a randomly
    shifted Halton sequence with ``method="halton"``, which covers the box more evenly);
    unreachable draws are replaced by new ones — and, with ``within_strokes``, draws whose
    actuators or passive joints are beyond their strokes
    (:func:`pkmkit.machines.strokes.stroke_excess`).

    Raises:
        InputError: n < 1, a bad region, or fewer than n reachable points after 50 n draws.
    """
    n = check_count(n, "the number of configurations", MAX_CONFIGURATIONS)
    lo, hi = check_region(machine, region)
    q, pts, drawn = draw_reachable(machine, lo, hi, n, seed=seed, method=method,
                                   within_strokes=within_strokes)
    names = region_names(machine)[:pts.shape[1]]
    return Configurations(q=q, points=pts, region=(lo, hi), names=names, drawn=drawn)
