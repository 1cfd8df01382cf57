"""The tool as a measurement sees it, per family: the machine-side half of the calibration's
measurement models (:mod:`pkmkit.calibration.models`, :mod:`pkmkit.calibration.controller`,
:mod:`pkmkit.calibration.simulate`), so that those ask the machine instead of testing its family.

Every machine answers with the same keywords and meanings:

- ``tool_length`` (m): a tool of that length along the tool axis; the measured point is its tip.
  A joint chain's tool axis is its tool frame's z axis (the length enters its closure: ``fk``,
  ``ik`` and the defect sensitivities take it); a rod machine's is the platform's −z axis (a
  spindle below the platform: the tip is ``tool_length`` below the platform point, along the
  platform's rotated −z for a full-pose machine). None: the machine's own ``tool_length``
  (0 for rod machines) for joint chains, no tool for rod machines.
- ``start``: a warm start of the direct model's closure, the ``start`` of a previous
  :class:`ToolFrames` at the same actuator values (joint chains: platform pose and passive
  joints); rod machines' direct models are closed forms and return None, and refuse a start
  with :class:`~pkmkit.exceptions.UnsupportedOperationError`.

Methods (every family): :meth:`tool_frames` (tip and rotation at actuator values),
:meth:`tool_frames_linearised` (the same with their defect derivatives, from the defect
sensitivity), :meth:`tool_inverse` (actuator values that put the tip at targets),
:meth:`tool_targets` (the targets a machine reaches at actuator values),
:meth:`measurement_configurations` (the default region of simulated measurements) and
:attr:`default_tool_lengths`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from pkmkit.exceptions import InputError, UnsupportedOperationError
from pkmkit.spatial.rotation import compose_rotvec, matrix_to_rotvec, rotvec_to_matrix

#: Largest residual (m) of a joint-chain machine's inverse model accepted as reached.
CHAIN_IK_TOL = 1e-6
#: Seed 002's two tool lengths (m): a joint-chain machine's default measurement tools.
SEED_TOOLS = (0.169889, 0.110006)
#: Orientation range of random full poses about the home orientation (rad, per axis).
TILT = np.radians(5.0)


@dataclass(frozen=True)
class ToolFrames:
    """The tool at N configurations: tip ``point (N, 3)`` (m), ``rotation (N, 3, 3)`` (or
    None), their defect Jacobians ``dpoint``, ``drotation`` ``(N, 3, d)`` (m or rad per SI unit
    of each defect; None without them) and ``start``, a warm start of the direct model's
    closure at the same actuator values (None for closed forms). NaN rows: no assembly."""

    point: np.ndarray
    rotation: np.ndarray | None
    dpoint: np.ndarray | None
    drotation: np.ndarray | None
    start: np.ndarray | None = None


def within_strokes(machine, q: np.ndarray) -> np.ndarray:
    """``(N,)`` rows that assemble with every actuator and passive joint within its stroke
    (:func:`pkmkit.machines.strokes.stroke_excess`; non-finite rows are not within)."""
    from pkmkit.machines.strokes import stroke_excess

    q = np.atleast_2d(np.asarray(q, dtype=float))
    finite = np.isfinite(q).all(axis=1)
    out = np.zeros(len(q), dtype=bool)
    if finite.any():
        check = stroke_excess(machine, q[finite])
        assembled = np.isfinite(check.values).all(axis=1)
        out[finite] = assembled & ~check.out_of_stroke
    return out


def _lengths(tool_length: Any, n: int) -> np.ndarray:
    return np.zeros(n) if tool_length is None else np.asarray(tool_length, dtype=float)


class RodMeasurement:
    """Rod machines (translational and full-pose): the tool below the platform."""

    #: A rod machine carries no tool of its own (m).
    tool_length: ClassVar[float] = 0.0
    #: Tool lengths of simulated measurements by default: none (the platform point).
    default_tool_lengths: ClassVar[tuple[float, ...] | None] = None

    def _tip(self, x: np.ndarray, tl: np.ndarray, dpoint: np.ndarray | None,
             drot: np.ndarray | None, rotation: bool) -> ToolFrames:
        raise NotImplementedError

    def tool_frames(self, q: np.ndarray, tool_length: Any = None, *, rotation: bool = False,
                    start: Any = None, **engine_options: Any) -> ToolFrames:
        """The tool tip (and rotation) at actuator values ``q (N, n)`` (module docstring).
        ``engine_options`` tune a numeric closure; a rod machine's closed form takes none.

        Raises:
            UnsupportedOperationError: a ``start`` (a closed form has no closure to start).
            PkmError: as :meth:`fk`.
        """
        if start is not None:
            raise UnsupportedOperationError(
                "a direct-model start", self.id, self.family,
                "its direct model is a closed form: there is no closure to start")
        x = np.atleast_2d(self.fk(q))
        return self._tip(x, _lengths(tool_length, q.shape[0]), None, None, rotation)

    def tool_frames_linearised(self, q: np.ndarray, sensitivity: Any, tool_length: Any = None,
                               *, rotation: bool = False) -> ToolFrames:
        """:meth:`tool_frames` with the defect Jacobians, from ``sensitivity`` (the
        :class:`~pkmkit.geometric_errors.model.ToolSensitivity` at ``q`` with the same
        ``tool_length``)."""
        return self._tip(sensitivity.pose, _lengths(tool_length, q.shape[0]),
                         sensitivity.point.copy(), sensitivity.rotation, rotation)

    def tool_targets(self, q: np.ndarray, tool_length: Any = None) -> np.ndarray:
        """Targets ``(N, w)`` the machine reaches at assembling actuator values ``q (N, n)``:
        the tool tip, and the platform rotation vector of a six-actuator machine."""
        six = self.six_dof
        state = self.tool_frames(q, tool_length, rotation=six)
        if six:
            return np.concatenate([state.point, matrix_to_rotvec(state.rotation)], axis=1)
        return state.point

    def measurement_configurations(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` actuator vectors ``(n, n_act)`` whose tool points are uniform in the default
        box (a full-pose machine at its home orientation ± :data:`TILT` about each axis), kept
        where the inverse model and the strokes allow.

        Raises:
            InputError: fewer than ``n`` reachable configurations in 50 draws of ``4 n``.
        """
        lo, hi = self.default_box()
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        full = self.dims == 6 and not self.position_controlled
        out = []
        for _ in range(50):
            p = lo + (hi - lo) * rng.random((4 * n, len(lo)))
            if full:
                tilt = rng.uniform(-TILT, TILT, (len(p), 3))
                home = np.tile(self.home_pose[3:], (len(p), 1))
                with np.errstate(invalid="ignore"):
                    q = np.atleast_2d(self.ik(np.concatenate([p, compose_rotvec(tilt, home)],
                                                             axis=1)))
            else:
                pts = np.zeros((len(p), 3))
                pts[:, :p.shape[1]] = p
                with np.errstate(invalid="ignore"):
                    q = self.tool_inverse(pts)
            ok = np.isfinite(q).all(axis=1) & within_strokes(self, np.nan_to_num(q, nan=np.inf))
            out.extend(q[ok])
            if len(out) >= n:
                return np.array(out[:n])
        raise InputError(f"fewer than {n} reachable configurations in the default box of "
                         f"{self.id!r}")


class TranslationalMeasurement(RodMeasurement):
    """A translating platform: the tip ``tool_length`` below the platform point."""

    def _tip(self, x, tl, dpoint, drot, rotation) -> ToolFrames:
        n = x.shape[0]
        point = np.zeros((n, 3))
        dims = min(self.dims, 3)
        point[:, :dims] = x[:, :dims]
        point[:, 2] -= tl
        return ToolFrames(point, np.tile(np.eye(3), (n, 1, 1)) if rotation else None, dpoint,
                          drot)

    def tool_inverse(self, x: np.ndarray, tool_length: Any = None, *, iterations: int = 20
                     ) -> np.ndarray:
        """Actuator values ``(N, n)`` that put the tool tip at targets ``x (N, 3)`` (m; NaN
        rows out of reach): the platform point ``tool_length`` above each."""
        p = x.copy()
        p[:, 2] += _lengths(tool_length, len(x))
        return np.atleast_2d(self.ik(p[:, :self.dims]))


class FullPoseMeasurement(RodMeasurement):
    """A full-pose platform: the tip ``tool_length`` along the platform's rotated −z."""

    def _tip(self, x, tl, dpoint, drot, rotation) -> ToolFrames:
        rot = rotvec_to_matrix(np.nan_to_num(x[:, 3:6]))
        offset = -tl[:, None] * rot[:, :, 2]
        point = x[:, :3] + offset
        if dpoint is not None:
            dpoint = dpoint + np.cross(drot.transpose(0, 2, 1), offset[:, None, :]
                                       ).transpose(0, 2, 1)
        bad = ~np.isfinite(x).all(axis=1)
        point[bad] = np.nan
        rot[bad] = np.nan
        return ToolFrames(point, rot if rotation else None, dpoint, drot)

    def tool_inverse(self, x: np.ndarray, tool_length: Any = None, *, iterations: int = 20
                     ) -> np.ndarray:
        """Actuator values ``(N, n)`` that put the tool tip at targets ``x`` (m; NaN rows out of
        reach): tool points ``(N, 3)`` for a position-controlled machine — its platform tilts
        with its position, so the platform point is found by fixed-point iteration (at most
        ``iterations`` passes) — else tool point and platform rotation vector ``(N, 6)``."""
        tl = np.zeros(len(x)) if tool_length is None else np.broadcast_to(
            np.asarray(tool_length, dtype=float), (len(x),)).copy()
        if self.position_controlled:
            p = x.copy()
            if not np.any(tl):
                return np.atleast_2d(self.ik(p))
            for _ in range(iterations):
                inv = self.ik(p, full_output=True)
                rot = rotvec_to_matrix(np.nan_to_num(np.atleast_2d(inv.pose)[:, 3:]))
                new = x + tl[:, None] * rot[:, :, 2]
                converged = np.nanmax(np.abs(new - p), initial=0.0) < 1e-13
                p = new
                if converged:
                    break
            return np.atleast_2d(self.ik(p))
        rot = rotvec_to_matrix(x[:, 3:6])
        p = x[:, :3] + tl[:, None] * rot[:, :, 2]
        return np.atleast_2d(self.ik(np.concatenate([p, x[:, 3:6]], axis=1)))


def _frame_rotation(frame: np.ndarray) -> np.ndarray:
    """Rotations ``(N, 3, 3)`` of tool frames ``(N, 6)`` (position, rotation vector); NaN rows
    where the frame is not finite."""
    rot = rotvec_to_matrix(np.nan_to_num(frame[:, 3:]))
    rot[~np.isfinite(frame).all(axis=1)] = np.nan
    return rot


class ChainMeasurement:
    """Joint chains: the tool length enters the closure (``fk``, ``ik``, sensitivities)."""

    #: Seed 002's two tools: simulated measurements alternate them by default (m).
    default_tool_lengths: ClassVar[tuple[float, ...] | None] = SEED_TOOLS

    def _rotation(self, q: np.ndarray, tool_length: Any) -> np.ndarray:
        return _frame_rotation(self.fk(q, tool_length=tool_length, full_output=True).tool_frame)

    def tool_frames(self, q: np.ndarray, tool_length: Any = None, *, rotation: bool = False,
                    start: Any = None, **engine_options: Any) -> ToolFrames:
        """The tool tip (and the tool frame's rotation) at actuator values ``q (N, n)``, the
        closure solved from ``start`` (default home) with ``engine_options``; ``start`` of the
        result: platform pose and passive joints (None where a row did not assemble).

        Raises:
            PkmError: as :meth:`fk`.
        """
        direct = self.fk(q, tool_length=tool_length, start=start, full_output=True,
                         **engine_options)
        found = np.concatenate([direct.platform, direct.passive], axis=1)
        rot = _frame_rotation(direct.tool_frame) if rotation else None
        return ToolFrames(direct.pose[:, :3], rot, None, None,
                          found if np.isfinite(found).all() else None)

    def tool_frames_linearised(self, q: np.ndarray, sensitivity: Any, tool_length: Any = None,
                               *, rotation: bool = False) -> ToolFrames:
        """:meth:`tool_frames` with the defect Jacobians of ``sensitivity`` (taken with the
        same ``tool_length``)."""
        rot = self._rotation(q, tool_length) if rotation else None
        return ToolFrames(sensitivity.pose[:, :3], rot, sensitivity.point, sensitivity.rotation)

    def tool_inverse(self, x: np.ndarray, tool_length: Any = None, *, iterations: int = 20
                     ) -> np.ndarray:
        """Actuator values ``(N, n)`` that put the tool point and axis at ``x (N, 6)`` (NaN rows
        out of reach). A calibrated hyperstatic machine closes its legs in least squares
        (residuals of 1e-8 m for second-order incompatible defects): residuals up to
        :data:`CHAIN_IK_TOL` count as reached. ``iterations`` is unused (one solve)."""
        tl = None if tool_length is None else np.broadcast_to(
            np.asarray(tool_length, dtype=float), (len(x),)).copy()
        return np.atleast_2d(self.ik(x, tool_length=tl, residual_tol=CHAIN_IK_TOL))

    def tool_targets(self, q: np.ndarray, tool_length: Any = None) -> np.ndarray:
        """Tool point and axis ``(N, 6)`` the machine reaches at actuator values ``q``."""
        with np.errstate(invalid="ignore"):
            return np.atleast_2d(self.fk(q, tool_length=tool_length))

    def measurement_configurations(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` actuator vectors ``(n, n_act)`` by seed 002's protocol: half platform-only
        moves (the legs within their strokes, the head at zero) and half wrist-only moves (the
        legs at mid-stroke, the head within its strokes); rows that do not assemble or put a
        passive joint beyond its range are drawn again (their leg actuators).

        Raises:
            InputError: rows still out after 50 draws.
        """
        from pkmkit.machines.strokes import stroke_limits

        lo, hi = stroke_limits(self)
        lo = np.where(np.isfinite(lo), lo, self.home_q - 0.01)
        hi = np.where(np.isfinite(hi), hi, self.home_q + 0.01)
        loop = self.model.loop_variables[np.flatnonzero(self.model.actuated)]
        q = lo + (hi - lo) * rng.random((n, len(lo)))
        if (~loop).any() and n > 1:
            platform = np.arange(n) < (n + 1) // 2
            q[np.ix_(platform, ~loop)] = np.clip(0.0, lo[~loop], hi[~loop])
            q[np.ix_(~platform, loop)] = (lo[loop] + hi[loop]) / 2
        ok = within_strokes(self, q)
        for _ in range(50):
            if ok.all():
                break
            bad = np.flatnonzero(~ok)
            cols = loop if (~loop).any() and n > 1 else np.ones(len(lo), dtype=bool)
            redraw = lo + (hi - lo) * rng.random((len(bad), len(lo)))
            sub = q[bad]
            sub[:, cols] = redraw[:, cols]
            q[bad] = sub
            ok[bad] = within_strokes(self, q[bad])
        if not ok.all():
            raise InputError(f"{(~ok).sum()} configurations of the default region do not "
                             "assemble within the joint strokes")
        return q
