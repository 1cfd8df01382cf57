"""One meaning of ``fk``'s warm start on every family (issue 19): ``x0`` is a *pose* — rows of
what ``fk`` returns — from which the direct model starts. A rod machine's closure unknowns are
its platform pose, so ``x0`` starts it; a joint chain's are its platform pose **and** passive
joints, which a tool pose (point and axis) does not give: a joint chain takes them as
``start`` (``6 + n_passive`` values per row: platform position, rotation vector, passive joints
— a previous :class:`~pkmkit.machines.chain_results.ChainDirectResult`'s ``platform`` and
``passive`` side by side) and refuses a pose ``x0`` with
:class:`~pkmkit.exceptions.UnsupportedOperationError`. Its former ``x0`` of ``6 + n_passive``
values still works for one release, with a :class:`DeprecationWarning`.

**The head's branch** (issue 22 §3). A two-axis head (the Tripteor's and the TriMule's Q4, Q5)
reaches a tool pose on two branches, ``(Q4 + π, −Q5)`` with the platform moved accordingly
(the Tripteor's ``−Q5 − 2.7°`` or so: its platform tilts). Which one the engine ends on
depends on its start: from home mostly the branch whose Q4 is nearer home's, but not always
(next to the wrist singularity — the tool axis along Q4's, where Q4 turns the tool about
itself — and wherever Q4 is near ±90°, adjacent grid points from home split between the
branches); from a neighbouring point's solution (continuation) whichever branch the
neighbour was on (137 of 4,096 points of the Tripteor's default box at home's tool axis
differed), which moved the transmission factors. The rule stated: **the inverse model from
its default start (no** ``q0`` **) reports the branch whose first wrist actuator (Q4) is
nearer its home value**, unless only the other one has every joint within its stroke
(:meth:`ChainWarmStart._nearest_branch`: a solution farther than a quarter turn less
:data:`~pkmkit.machines.head_branches.FLIP_MARGIN` from home, or beyond a stroke, has its
mirror solved from ``(Q4 + π, 2·Q5_home − Q5)``; the one
within the strokes is kept, else the nearer), whatever the start — home or a neighbour —
so a grid solved by continuation and the same grid solved from home agree point by point.
Right at the singularity Q4 is undetermined and the mirror may not come out nearer (then
either is reported): continuation does not start from a neighbour within
:data:`WRIST_SINGULAR_ANGLE` of it (:meth:`ChainWarmStart.continues_from`), those points start
from home. With ``q0`` the caller chooses the branch and nothing is changed.

**The legs' assembly modes** (issue 22 §3, fourth pass). A neighbour's start may also reach
another assembly of the legs than the start from home: on the TriMule, a slide of the opposite
sign (the leg through its base joint the other way), or a universal joint's other
parametrisation of a leg's line (ψ + π, π − θ) with the platform elsewhere. The mode
signature of a closure (:meth:`ChainWarmStart.in_home_modes`): every leg slide has its home
value's sign and every revolute leg joint lies within a quarter turn of its home value. A row
solved from a warm start whose closure is not in the home modes is solved again from home
(its answer is then the start from home's, whatever mode that reaches), so a warm start is
kept only where it is in home's modes; on the grids checked (tests/analysis/
test_continuation_modes.py) the start from home, wherever it ends in those modes, gives the
same closure, so continuation gives the start from home's answer point by point there — and
where the start from home ends in another mode (or fails) while the neighbour's start stays
in home's, continuation reports the mode containing home.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, UnsupportedOperationError
from pkmkit.machines.chain_starts import closed_starts
from pkmkit.machines.head_branches import nearest_head_branch
from pkmkit.status import Status

#: A neighbour's solution whose tool axis lies within this angle (rad) of its head's first
#: revolute axis (the wrist singularity) is not used as a continuation start.
WRIST_SINGULAR_ANGLE = np.radians(5.0)


class ChainWarmStart:
    """The joint chains' ``start`` and their deprecated ``x0``."""

    def _closure_start(self, x0: Any, start: Any) -> tuple[Any, str]:
        """``(warm start or None, the keyword it came by)`` of :meth:`fk`.

        Raises:
            InputError: both given. UnsupportedOperationError: a pose ``x0`` (width 6 where
                the closure needs ``6 + n_passive``).
        """
        if x0 is None:
            return start, "start"
        if start is not None:
            raise InputError("give the closure's warm start as start= alone (x0 is its "
                             "deprecated name)")
        width = np.shape(x0)[-1] if np.ndim(x0) else 1
        unknowns = 6 + len(self.passive_names)
        if width == self.dims and width != unknowns:
            raise UnsupportedOperationError(
                "fk from a warm-start pose x0", self.id, self.family,
                "its closure's unknowns are the platform pose and the passive joints, which a "
                f"tool pose does not give: pass those {unknowns} values per row as start= "
                "(a previous direct result's platform and passive)")
        warnings.warn("x0 of a joint chain's fk is deprecated: pass the platform pose and "
                      "passive joints as start= (x0 is a warm-start pose on every machine)",
                      DeprecationWarning, stacklevel=3)
        return x0, "x0"

    def _inverse_starts(self, start: Any, u_home: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(u0 (N, 6 + n_var), started (N,))`` of the inverse model: the rows of ``start``
        (platform position, rotation vector, every joint variable in the model's order — a
        previous inverse result's ``solution``) where they are finite, ``u_home`` (home, or the
        ``q0`` given) elsewhere; ``started`` marks the rows taken from ``start``.

        Raises:
            InputError: ``start`` not ``(6 + n_var,)`` or one such row per target.
        """
        if start is None:
            return u_home, np.zeros(len(u_home), dtype=bool)
        from pkmkit.machines.common import _rows_like

        u0 = _rows_like(start, u_home.shape[1], "start", len(u_home)).copy()
        started = np.isfinite(u0).all(axis=1)
        u0[~started] = u_home[~started]
        return u0, started

    def _solve_inverse_from(self, solve: Any, targets: np.ndarray, u0: np.ndarray,
                            u_home: np.ndarray, started: np.ndarray,
                            lengths: np.ndarray, warm: np.ndarray | None = None) -> Any:
        """``solve(targets, u0, lengths)`` (the engine's inverse), then the rows started from a
        warm start that did not converge, or converged outside the legs' home assembly modes
        (:meth:`in_home_modes`), solved again from ``u_home``: a warm start may only speed a
        row up, never lose one the start from home reaches nor move it to another assembly
        of the legs (a retried row reports the retry's iterations and is no longer marked in
        ``started``, updated in place). Rows ``warm (N,)`` — a caller's start, with the
        default branch (no ``q0``) — are solved again as :meth:`_solve_from_closed` says (the
        kind's closed-form start first), the others from ``u_home``."""
        res = solve(targets, u0, lengths)
        with np.errstate(invalid="ignore"):
            retry = np.flatnonzero(started & ((res.status != Status.OK)
                                              | ~self.in_home_modes(res.u)))
        if retry.size:
            started[retry] = False  # these rows now hold the start from home's answer
            again = self._solve_from_closed(solve, targets[retry], lengths[retry],
                                            u_home[retry], warm is not None and warm[retry])
            for name in ("u", "status", "residual", "iterations", "rank"):
                getattr(res, name)[retry] = getattr(again, name)
        return res

    def _solve_from_closed(self, solve: Any, targets: np.ndarray, lengths: np.ndarray,
                           u_home: np.ndarray, closed: Any = True) -> Any:
        """The rows solved again (session 33): from the kind's closed-form start
        (:func:`~pkmkit.machines.chain_starts.closed_starts`) on the rows ``closed`` (True:
        every row; False where the row's own start was that one already) where it answers,
        kept where it converges within the legs' home modes, and from ``u_home`` elsewhere —
        what the default start gives a row, so a warm start that fails or leaves the modes
        ends on the default start's answer, not on home's (which may leave the modes where
        the closed start's does not). The iterations reported are the last solve's."""
        u0 = u_home.copy()
        from_closed = np.zeros(len(u0), dtype=bool)
        starts = closed_starts(self, targets, lengths)
        if starts is not None:
            from_closed = np.isfinite(starts).all(axis=1) & closed
            u0[from_closed] = starts[from_closed]
        res = solve(targets, u0, lengths)
        if from_closed.any():
            with np.errstate(invalid="ignore"):
                home = np.flatnonzero(from_closed & ((res.status != Status.OK)
                                                     | ~self.in_home_modes(res.u)))
            if home.size:
                again = solve(targets[home], u_home[home], lengths[home])
                for name in ("u", "status", "residual", "iterations", "rank"):
                    getattr(res, name)[home] = getattr(again, name)
        return res

    def in_home_modes(self, u: np.ndarray) -> np.ndarray:
        """``(N,)`` bool: the closures ``u (N, 6 + n_var)`` (platform, every joint variable)
        are in the legs' home assembly modes — every leg slide with its home value's sign
        (slides at 0 at home not judged) and every revolute leg joint within a quarter turn
        of its home value (module docstring: the mode signature). NaN rows are False."""
        return self.mode_signature(u).all(axis=1)

    def mode_signature(self, u: np.ndarray) -> np.ndarray:
        """``(N, k)`` bool: the legs' assembly-mode signature of the closures ``u (N, 6 +
        n_var)`` — per leg slide away from 0 at home, whether it has its home value's sign;
        per revolute leg joint, whether it lies within a quarter turn of its home value. Two
        closures with equal rows are in the same modes; all True is home's. NaN: False."""
        home = self._home["values"]
        slides, turns = self.leg_joints_by_type()
        values = np.asarray(u, dtype=float)[:, 6:]
        with np.errstate(invalid="ignore"):
            same_side = values[:, slides] * np.sign(home[slides]) > 0
            near = np.cos(values[:, turns] - home[turns]) > 0
        return np.concatenate([same_side, near], axis=1)

    def leg_joints_by_type(self) -> tuple[np.ndarray, np.ndarray]:
        """``(slides, turns)``: variable indices of the legs' prismatic joints away from 0 at
        home, and of their revolute joints (each shared joint once); cached."""
        cached = self.__dict__.get("_leg_joints_cache")
        if cached is not None:
            return cached
        model = self.model
        home = self._home["values"]
        kinds = {int(model.element_variable[e]): model.elements[e].type
                 for leg in model.legs for e in leg if model.element_variable[e] >= 0}
        slides = np.array(sorted(v for v, k in kinds.items() if k == "P" and home[v] != 0),
                          dtype=int)
        turns = np.array(sorted(v for v, k in kinds.items() if k == "R"), dtype=int)
        object.__setattr__(self, "_leg_joints_cache", (slides, turns))
        return slides, turns

    def continuation_starts(self, points: np.ndarray, start: np.ndarray) -> np.ndarray:
        """The starts of a grid's continuation at tool poses ``points (N, 6)`` (the machine's
        tool length): the kind's closed-form start of the inverse model wherever it answers
        (:func:`~pkmkit.machines.chain_starts.closed_starts`: the solution itself, 0
        iterations, where a neighbour's solution took 2.9 on the Tripteor X7's and 3.0 on the
        TriMule 600's default workspaces), the neighbours' ``start (N, 6 + n_var)`` elsewhere
        (issue 22 §3, session 35). The same answers: a row's start is the one its default
        start would be, or the neighbour's as before."""
        x = np.atleast_2d(np.asarray(points, dtype=float))
        with np.errstate(invalid="ignore", divide="ignore"):
            targets = np.concatenate([x[:, :3], x[:, 3:] / np.linalg.norm(x[:, 3:], axis=1,
                                                                         keepdims=True)], axis=1)
        closed = closed_starts(self, targets, self._tool_lengths(None, len(x)))
        if closed is None:
            return start
        exact = np.isfinite(closed).all(axis=1)
        if not exact.any():
            return start
        out = np.array(start, dtype=float)
        out[exact] = closed[exact]
        return out

    def continues_from(self, solution: np.ndarray) -> np.ndarray:
        """``(N,)`` bool: rows of inverse solutions ``solution (N, 6 + n_var)`` (an inverse
        result's ``solution``) from which a neighbouring point may start — finite, and (on a
        machine whose head has two revolute actuators) with the tool axis farther than
        :data:`WRIST_SINGULAR_ANGLE` from the axis of the head's first revolute actuator
        (module docstring)."""
        from pkmkit.solve.chains import chain_pose, rotvec_matrices

        solution = np.atleast_2d(np.asarray(solution, dtype=float))
        ok = np.isfinite(solution).all(axis=1)
        model = self.model
        wrist = [i for i, e in enumerate(model.head) if model.elements[e].type == "R"
                 and model.element_variable[e] >= 0
                 and model.actuated[model.element_variable[e]]]
        if len(wrist) < 2 or not ok.any():
            return ok
        u = solution[ok].T
        start = (rotvec_matrices(u[3:6]), u[:3])
        values = u[6:]
        first = chain_pose(model, tuple(model.head[:wrist[0] + 1]), values, start=start)
        tool = chain_pose(model, tuple(model.head), values, start=start)
        sine = np.linalg.norm(np.cross(first.R[:, 2].T, tool.R[:, 2].T), axis=1)
        ok[ok] = sine > np.sin(WRIST_SINGULAR_ANGLE)
        return ok

    def _nearest_branch(self, solve: Any, targets: np.ndarray, res: Any,
                        lengths: np.ndarray, started: np.ndarray | None = None,
                        u_home: np.ndarray | None = None,
                        warm: np.ndarray | None = None) -> None:
        """The head's branch of the default start (module docstring):
        :func:`~pkmkit.machines.head_branches.nearest_head_branch` on the wrist pair with home
        as the reference, the strokes judged around home; ``res`` updated in place. Rows
        ``started (N,)`` from a warm start whose branch's closure then leaves the legs' home
        modes (the mirror solve may move the legs) are solved again from ``u_home`` with the
        rule: the start from home's answer."""
        pair = self.wrist_pair()
        if pair is None:
            return
        home = self._home["values"]
        turn = pair[0]
        reach = max(abs(self.model.q_min[turn] - home[turn]),
                    abs(self.model.q_max[turn] - home[turn]))

        tilt = 6 + pair[1]

        def mirror(t: np.ndarray, tool: np.ndarray, u: np.ndarray) -> np.ndarray | None:
            # the kind's closed form on the other branch (the tilt's other side)
            return closed_starts(self, t, tool,
                                 np.where(np.sin(u[:, tilt] - home[pair[1]]) < 0, 1.0, -1.0))

        def rule(result: Any, t: np.ndarray, tool: np.ndarray) -> None:
            nearest_head_branch(solve, t, tool, result, np.full(len(result.status),
                                home[turn]), pair, lambda u, rows: self._within_strokes(u),
                                home[pair[1]], turn_reach=reach, mirror_start=mirror)

        rule(res, targets, lengths)
        if started is None:
            return
        with np.errstate(invalid="ignore"):
            again = np.flatnonzero(started & (res.status == Status.OK)
                                   & ~self.in_home_modes(res.u))
        if again.size:  # a caller's start (warm): the closed-form start first
            other = self._solve_from_closed(solve, targets[again], lengths[again],
                                            u_home[again], warm is not None and warm[again])
            rule(other, targets[again], lengths[again])
            for name in ("u", "status", "residual", "iterations", "rank"):
                getattr(res, name)[again] = getattr(other, name)

    def _within_strokes(self, u: np.ndarray, around: np.ndarray | None = None) -> np.ndarray:
        """``(N,)`` bool: every joint (actuators, revolute ones on the turn nearest home — or
        nearest ``around (N, n_var)``, a start's joint values — and the legs' passive joints)
        of the solutions ``u (N, 6 + n_var)`` within its stroke."""
        from pkmkit.machines.strokes import signed_excess

        model = self.model
        values = u[:, 6:].copy()
        turn = [int(v) for v in self._actuated if self.element_of(int(v)).type == "R"]
        home = self._home["values"][turn] if around is None else around[:, turn]
        with np.errstate(invalid="ignore"):
            values[:, turn] = home + np.angle(np.exp(1j * (values[:, turn] - home)))
            joints = np.flatnonzero(model.loop_variables | model.actuated)
            excess = signed_excess(values[:, joints], model.q_min[joints], model.q_max[joints])
        return ~(excess != 0).any(axis=1)

    def wrist_pair(self) -> tuple[int, int] | None:
        """``(Q4, Q5)``: the variables of the head's first two revolute actuators, or None."""
        model = self.model
        wrist = [int(model.element_variable[e]) for e in model.head
                 if model.elements[e].type == "R" and model.element_variable[e] >= 0
                 and model.actuated[model.element_variable[e]]]
        return (wrist[0], wrist[1]) if len(wrist) >= 2 else None
