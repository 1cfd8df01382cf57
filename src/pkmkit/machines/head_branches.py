"""The branch rule of a head with two branches: an A/C head whose turn ``a`` and tilt ``c``
put the tool axis in the same direction at ``(a, c)`` and ``(a ± π, −c)`` (the TriMule 600's
Q4, Q5). From a start, the inverse model may reach either; the rule makes it one:

    **the branch whose turn joint is nearest the start's** (wrapped to (−π, π]; the branch the
    solver reached is kept unless the other one is strictly nearer).

Along a path (a start at the previous configuration) it keeps the branch followed; from home
(turn 0) it takes |a| ≤ π/2. It matters most near the tool axis along the turn axis (c = 0,
the "vertical" tool axis at home), where the turn leaves the axis unchanged and a solver's
first steps pick a branch by the tool point alone. The generated LinuxCNC module applies the
same rule (:mod:`pkmkit.export.linuxcnc_chain_c`), so both give the same joints there.

The other branch is solved only where it could be nearer: where the solution's turn is more
than π/2 − :data:`FLIP_MARGIN` from the start's (the TriMule's two branches differ in turn by
π to within 0.053 rad over its strokes, measured on 4000 configurations: the flipped branch is
then farther). The common case — a start on the branch, along a path — costs one solve.

A kind declares its head's pair by name (``MachineKind.head_flip = ("Q4", "Q5")``); machines
without one (every other kind, element-by-element machine files) take no second solve.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pkmkit.status import Status

#: Margin (rad) below π/2 within which a solution's turn keeps its branch without solving the
#: other (module docstring).
FLIP_MARGIN = float(np.radians(15.0))


def head_flip_variables(kind, variables: tuple[str, ...]) -> tuple[int, int] | None:
    """``(turn, tilt)`` variable indices of the kind's two-branch head, or None."""
    names = getattr(kind, "head_flip", None)
    if not names:
        return None
    return variables.index(names[0]), variables.index(names[1])


def wrapped(angle: np.ndarray) -> np.ndarray:
    """``angle`` (rad) wrapped to (−π, π]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def nearest_head_branch(solve: Callable, targets: np.ndarray, lengths: np.ndarray, res,
                        reference: np.ndarray, flip: tuple[int, int],
                        inside: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                        tilt_centre: float = 0.0, turn_reach: float = np.inf,
                        mirror_start: Callable | None = None):
    """Apply the rule to an inverse result ``res`` (a
    :class:`~pkmkit.solve.least_squares.SolveResult` whose ``u (N, 6 + V)`` holds the platform
    then every joint variable): the rows solved exactly whose turn is more than π/2 −
    :data:`FLIP_MARGIN` from ``reference`` are solved again by ``solve(targets, u0, lengths)``
    from their solution with the head flipped (turn + π, tilt mirrored about ``tilt_centre``:
    the tilt's value where the two branches meet, 0 on the TriMule), and the flipped
    solution replaces theirs where it is exact and its turn is strictly nearer ``reference
    (N,)`` (rad; the start's turn) — or, given ``inside(u, rows) -> (len(rows),) bool`` (every
    joint of the solutions ``u`` of those rows within its stroke), where it alone is within
    the strokes (also solved where the kept one is beyond a stroke; the generated LinuxCNC
    module does the same). ``res`` is updated in place (the re-solved rows' iterations added)
    and returned.

    ``turn_reach`` (rad): the farthest the turn's stroke reaches from ``reference``. Below
    π/2 a row within π/2 − FLIP_MARGIN of the reference has its mirror's turn at least π/2 +
    FLIP_MARGIN away (to within the FLIP_MARGIN the rule already allows between a turn + π and
    the mirror's), so beyond the turn's stroke and farther than the row's own: the mirror
    cannot be chosen and is not solved (the Tripteor's Q4, ±15°: every row beyond a stroke
    had its mirror solved before, for nothing).

    ``mirror_start(targets, lengths, u) -> (k, 6 + V)`` (the re-solved rows' targets, tool
    lengths and solutions): the mirror's solve starts from its rows where they are finite —
    a closed-form start on the other branch
    (:func:`~pkmkit.machines.chain_starts.closed_starts`) — instead of the flipped solution."""
    turn, tilt = 6 + flip[0], 6 + flip[1]
    with np.errstate(invalid="ignore"):
        far = np.abs(wrapped(res.u[:, turn] - reference)) > np.pi / 2 - FLIP_MARGIN
    rows = np.flatnonzero((res.status == Status.OK) & np.isfinite(reference))
    if inside is not None and turn_reach >= np.pi / 2:  # far from the start, or beyond a stroke
        rows = rows[far[rows] | ~inside(res.u[rows], rows)]
    else:
        rows = rows[far[rows]]
    if not rows.size:
        return res
    u0 = res.u[rows].copy()
    u0[:, turn] += np.pi
    u0[:, tilt] = 2.0 * tilt_centre - u0[:, tilt]
    if mirror_start is not None and (closed := mirror_start(targets[rows], lengths[rows],
                                                              res.u[rows])) is not None:
        exact = np.isfinite(closed).all(axis=1)
        u0[exact] = closed[exact]
    other = solve(targets[rows], u0, lengths[rows])
    ref = reference[rows]
    with np.errstate(invalid="ignore"):
        closer = np.abs(wrapped(other.u[:, turn] - ref)) < np.abs(wrapped(res.u[rows, turn] - ref))
    if inside is not None:
        kept, flipped = inside(res.u[rows], rows), inside(other.u, rows)
        closer = (flipped & ~kept) | ((flipped == kept) & closer)
    nearer = (other.status == Status.OK) & closer
    take = rows[nearer]
    res.iterations[rows] += other.iterations
    for name in ("u", "status", "residual", "rank"):
        getattr(res, name)[take] = getattr(other, name)[nearer]
    return res
