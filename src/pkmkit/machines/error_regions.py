"""The machine protocol's regions for error analyses: in which coordinates a machine's
configurations are drawn, over which default box, and how a region point becomes actuator
values (:mod:`pkmkit.geometric_errors.configurations` asks the machine).

A **region** is a box ``(lower, upper)`` in the machine's *region coordinates*:

- rod legs on a translating platform (:class:`TranslationalRegions`): tool positions
  (``dims`` coordinates), default :meth:`default_box`;
- rod legs on a turning platform (:class:`FullPoseRegions`): x, y, z for fewer than six
  actuators (the orientation follows); position and rotation vector for six (three are
  accepted, the orientation then stays at home), with rotations of ± :data:`ROTATION_SPREAD`
  about home by default (identification needs the orientation to vary);
- joint chains (:class:`ChainRegions`): actuator coordinates (m, rad) — their tool pose is a
  point and an axis reached through a closed-loop inverse model, so the natural region is the
  actuators' box; default the strokes where finite, else home ± :data:`CHAIN_SPREAD`.

``machine.mechanism_configurations(n, seed=)`` draws configurations over the mechanism's range
with the strokes ignored (compatibility is a property of the mechanism): rod legs in their
default region, joint chains with their loop actuators over home ± :data:`CHAIN_SPREAD` and
their head actuators at home. :func:`draw_reachable` is the one draw loop (uniform or shifted
Halton points, unreachable ones replaced).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError

#: Default half-range around home of a joint-chain actuator without stroke: prismatic (m,
#: relative to |home|, at least 0.1 m) and revolute (rad).
CHAIN_SPREAD = {"P": 0.15, "R": np.radians(60.0)}
#: Default half-range of the rotation-vector components of a six-actuator machine (rad).
ROTATION_SPREAD = np.radians(10.0)

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


def draw_reachable(machine, lo: np.ndarray, hi: np.ndarray, n: int, *, seed: int | None = 0,
                   method: str = "random", within_strokes: bool = False
                   ) -> tuple[np.ndarray, np.ndarray, int]:
    """``(q (n, n_act), points (n, k), drawn)``: ``n`` reachable configurations drawn in the
    region box ``lo``, ``hi`` ``(k,)`` (uniformly at random, or a randomly shifted Halton
    sequence with ``method="halton"``), unreachable draws replaced by new ones — and, with
    ``within_strokes``, draws beyond the strokes (:func:`pkmkit.machines.strokes.
    stroke_excess`); ``drawn`` counts the points drawn.

    Raises:
        InputError: an unknown method, or fewer than n reachable points after 50 n draws.
    """
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
            q = machine.configurations_at(pts)
        ok = np.isfinite(q).all(axis=1)
        if within_strokes and ok.any():
            from pkmkit.machines.strokes import stroke_excess

            ok[ok] = ~stroke_excess(machine, q[ok]).out_of_stroke
        found_q.append(q[ok])
        found_p.append(pts[ok])
    return np.concatenate(found_q)[:n], np.concatenate(found_p)[:n], drawn


class _RodRegions:
    """What both rod-leg families share: a region in tool coordinates."""

    def region_sizes(self) -> tuple[int, ...]:
        """The numbers of region coordinates a region may bound (module docstring)."""
        return (len(self.region_names()),)

    def mechanism_configurations(self, n: int, *, seed: int | None = 0) -> np.ndarray:
        """``(n, n_act)`` configurations over the mechanism's range, strokes ignored: rod
        legs draw them in their default region (:func:`draw_reachable`).

        Raises:
            InputError: n < 1, too few reachable points in the default region.
        """
        if int(n) < 1:
            raise InputError(f"the number of configurations must be ≥ 1, got {n}")
        lo, hi = self.default_region()
        return draw_reachable(self, lo, hi, int(n), seed=seed)[0]


class TranslationalRegions(_RodRegions):
    """Regions of rod legs on a translating platform: tool positions."""

    def region_names(self) -> tuple[str, ...]:
        """Names of the region coordinates: the pose's."""
        return tuple(self.pose_names)

    def default_region(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower (dims,), upper (dims,))`` (m): the default box."""
        lo, hi = (np.asarray(v, dtype=float)[:3] for v in self.default_box())
        return lo, hi

    def configurations_at(self, points: Any) -> np.ndarray:
        """Actuator coordinates ``(N, n)`` of tool positions ``(N, dims)`` (NaN rows where
        unreachable)."""
        return np.atleast_2d(self.ik(np.atleast_2d(np.asarray(points, dtype=float))))


class FullPoseRegions(_RodRegions):
    """Regions of rod legs on a turning platform: positions, and rotation vectors when six
    actuators command them."""

    def region_names(self) -> tuple[str, ...]:
        """Names of the region coordinates: x, y, z (and the rotation vector's for six
        actuators)."""
        return tuple(self.pose_names[:6 if self.six_dof else 3])

    def region_sizes(self) -> tuple[int, ...]:
        """6 or 3 (the orientation at home) for six actuators, else 3."""
        return (6, 3) if self.six_dof else (3,)

    def default_region(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower, upper)``: the default box, with home ± :data:`ROTATION_SPREAD` rotations
        for six actuators (m, rad)."""
        lo, hi = (np.asarray(v, dtype=float)[:3] for v in self.default_box())
        if self.six_dof:
            rot = np.asarray(self.home_pose, dtype=float)[3:6]
            lo = np.concatenate([lo, rot - ROTATION_SPREAD])
            hi = np.concatenate([hi, rot + ROTATION_SPREAD])
        return lo, hi

    def configurations_at(self, points: Any) -> np.ndarray:
        """Actuator coordinates ``(N, n)`` of region points ``(N, 3)`` or ``(N, 6)`` (a
        six-actuator machine's orientation at home when only positions are given; NaN rows
        where unreachable)."""
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        if self.position_controlled and pts.shape[1] == 3:
            return np.atleast_2d(self.ik(pts))
        if pts.shape[1] == 3:
            pts = np.concatenate([pts, np.tile(self.home_pose[3:], (len(pts), 1))], axis=1)
        return np.atleast_2d(self.ik(pts))


class ChainRegions:
    """Regions of joint chains: their actuators' box."""

    def region_names(self) -> tuple[str, ...]:
        """Names of the region coordinates: the actuators'."""
        return tuple(self.actuator_names)

    def region_sizes(self) -> tuple[int, ...]:
        """One coordinate per actuator."""
        return (len(self.region_names()),)

    def default_region(self) -> tuple[np.ndarray, np.ndarray]:
        """``(lower (n,), upper (n,))`` (m, rad): the strokes where finite, else home ±
        :data:`CHAIN_SPREAD`."""
        model = self.model
        act = np.flatnonzero(model.actuated)
        home = self.home_q
        lo, hi = model.q_min[act].copy(), model.q_max[act].copy()
        for k, v in enumerate(act):
            half = self._spread(v, home[k])
            if not np.isfinite(lo[k]):
                lo[k] = home[k] - half
            if not np.isfinite(hi[k]):
                hi[k] = home[k] + half
        return lo, hi

    def _spread(self, variable: int, home: float) -> float:
        """Half-range of :data:`CHAIN_SPREAD` for joint variable ``variable`` at ``home``."""
        model = self.model
        element = int(np.flatnonzero(model.element_variable == variable)[0])
        if model.elements[element].type == "R":
            return CHAIN_SPREAD["R"]
        return max(CHAIN_SPREAD["P"] * abs(home), 0.1)

    def configurations_at(self, points: Any) -> np.ndarray:
        """The actuator coordinates themselves ``(N, n)``, NaN rows where the legs do not
        close."""
        q = np.atleast_2d(np.asarray(points, dtype=float)).copy()
        res = self.fk(q, full_output=True)
        q[~np.isfinite(res.pose).all(axis=1)] = np.nan
        return q

    def mechanism_configurations(self, n: int, *, seed: int | None = 0) -> np.ndarray:
        """``(n, n_act)`` configurations over the mechanism's range, strokes ignored: the loop
        actuators over home ± :data:`CHAIN_SPREAD`, the head actuators at home; only regular
        closures (status 0).

        Raises:
            InputError: too few closures around home.
        """
        model = self.model
        act = np.flatnonzero(model.actuated)
        home = self.home_q
        lo, hi = home.copy(), home.copy()
        for k, v in enumerate(act):
            if not model.loop_variables[v]:
                continue
            half = self._spread(v, home[k])
            lo[k], hi[k] = home[k] - half, home[k] + half
        moving = hi > lo
        region = (lo[moving], hi[moving])
        rng = np.random.default_rng(seed)
        found, drawn = [], 0
        while sum(len(f) for f in found) < n:
            if drawn > 50 * n:
                raise InputError(f"{self.id!r}: too few configurations close around home for "
                                 "a compatibility test; pass q explicitly")
            q = np.tile(home, (2 * n, 1))
            q[:, moving] = region[0] + rng.random((2 * n, int(moving.sum()))) * (region[1]
                                                                                - region[0])
            drawn += 2 * n
            res = self.fk(q, full_output=True)
            found.append(q[np.isfinite(res.pose).all(axis=1) & (res.status == 0)])
        return np.concatenate(found)[:n]
