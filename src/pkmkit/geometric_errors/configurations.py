"""Configurations for error analyses: actuator coordinates spread over a region of a machine's
workspace, reachable with the nominal geometry.

A **region** is a box ``(lower, upper)`` in the machine's *region coordinates*:

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

#: Default half-range around home of a joint-chain actuator without stroke: prismatic (m,
#: relative to |home|, at least 0.1 m) and revolute (rad).
CHAIN_SPREAD = {"P": 0.15, "R": np.radians(60.0)}
#: Default half-range of the rotation-vector components of a six-actuator machine (rad).
ROTATION_SPREAD = np.radians(10.0)


def _six_dof(machine) -> bool:
    return machine.family == "full-pose" and machine.n_actuators == 6


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
    if machine.family == "chain":
        return tuple(machine.actuator_names)
    if machine.family == "full-pose":
        return tuple(machine.pose_names[:6 if _six_dof(machine) else 3])
    return tuple(machine.pose_names)


def default_region(machine) -> tuple[np.ndarray, np.ndarray]:
    """The default region (module docstring)."""
    if machine.family == "chain":
        model = machine.model
        act = np.flatnonzero(model.actuated)
        home = machine.home_q
        lo, hi = model.q_min[act].copy(), model.q_max[act].copy()
        for k, v in enumerate(act):
            kind = "R" if _joint_type(model, v) == "R" else "P"
            half = CHAIN_SPREAD[kind] if kind == "R" else max(CHAIN_SPREAD["P"] * abs(home[k]),
                                                              0.1)
            if not np.isfinite(lo[k]):
                lo[k] = home[k] - half
            if not np.isfinite(hi[k]):
                hi[k] = home[k] + half
        return lo, hi
    lo, hi = (np.asarray(v, dtype=float)[:3] for v in machine.default_box())
    if _six_dof(machine):
        rot = np.asarray(machine.home_pose, dtype=float)[3:6]
        lo = np.concatenate([lo, rot - ROTATION_SPREAD])
        hi = np.concatenate([hi, rot + ROTATION_SPREAD])
    return lo, hi


def _joint_type(model, variable: int) -> str:
    element = int(np.flatnonzero(model.element_variable == variable)[0])
    return model.elements[element].type


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
    allowed = {len(names)}
    if _six_dof(machine):
        allowed.add(3)
    if lo.shape != hi.shape or lo.size not in allowed:
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
    family = machine.family
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    if family == "chain":
        q = pts.copy()
        res = machine.fk(q, full_output=True)
        q[~np.isfinite(res.pose).all(axis=1)] = np.nan
        return q
    if family == "full-pose":
        if machine.position_controlled and pts.shape[1] == 3:
            return np.atleast_2d(machine.ik(pts))
        if pts.shape[1] == 3:
            pts = np.concatenate([pts, np.tile(machine.home_pose[3:], (len(pts), 1))], axis=1)
        return np.atleast_2d(machine.ik(pts))
    return np.atleast_2d(machine.ik(pts))


_PRIMES = (2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37)


def halton(index: np.ndarray, dims: int) -> np.ndarray:
    """Points ``(k, dims)`` in [0, 1) of the Halton sequence at integer ``index`` (k,) ≥ 0
    (radical inverses in the first primes; skip 0 by passing index + 1)."""
    if dims > len(_PRIMES):
        raise InputError(f"Halton points in at most {len(_PRIMES)} dimensions")
    idx = np.asarray(index, dtype=np.int64) + 1
    out = np.zeros((idx.size, dims))
    for d in range(dims):
        base = _PRIMES[d]
        i = idx.copy()
        f = 1.0
        while np.any(i > 0):
            f /= base
            out[:, d] += f * (i % base)
            i //= base
    return out


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
    if int(n) < 1:
        raise InputError(f"the number of configurations must be ≥ 1, got {n}")
    n = int(n)
    lo, hi = check_region(machine, region)
    rng = np.random.default_rng(seed)
    if method not in ("random", "halton"):
        raise InputError(f"unknown sampling method {method!r}; use 'random' or 'halton'")
    shift = rng.random(lo.size)
    found_q, found_p, drawn = [], [], 0
    while sum(len(a) for a in found_q) < n:
        batch = max(2 * n, 16)
        if drawn > 50 * n:
            within = " within the strokes" if within_strokes else ""
            raise InputError(f"only {sum(len(a) for a in found_q)} of {drawn} points drawn in "
                             f"the region of {machine.id!r} are reachable{within}; choose a "
                             "region inside the workspace")
        if method == "halton":
            unit = (halton(drawn + np.arange(batch), lo.size) + shift) % 1.0
        else:
            unit = rng.random((batch, lo.size))
        pts = lo + unit * (hi - lo)
        drawn += batch
        with np.errstate(invalid="ignore"):
            q = configurations_at(machine, pts)
        ok = np.isfinite(q).all(axis=1)
        if within_strokes and ok.any():
            from pkmkit.machines.strokes import stroke_excess

            ok[ok] = ~stroke_excess(machine, q[ok]).out_of_stroke
        found_q.append(q[ok])
        found_p.append(pts[ok])
    q = np.concatenate(found_q)[:n]
    pts = np.concatenate(found_p)[:n]
    names = region_names(machine)[:pts.shape[1]]
    return Configurations(q=q, points=pts, region=(lo, hi), names=names, drawn=drawn)
