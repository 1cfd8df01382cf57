"""Largest axis-aligned square/cube in a region, refined in all its unknowns (centre and side).

A grid gives the largest box of grid points
(:func:`pkmkit.analysis.workspace.largest_inscribed_box`): up to two grid steps short, and
centred on grid points. :func:`largest_box` takes it from there without a grid: the box is a
lattice of points ``c + h·u`` (``u`` on a fixed lattice of ``[-1, 1]^d``, edges and corners
included) that moves with its centre ``c`` and half-side ``h``; every point carries the signed
slack of the region's criteria (≥ 0 inside), and ``h`` is maximised subject to "every slack ≥ 0"
and "inside the bounds" by SLSQP, with the constraint gradients analytic where the caller
gives them (``slack_gradient``), else by finite differences along each axis (one evaluation of
the lattice per axis); ∂/∂h follows by the chain rule, Σᵢ uᵢ ∂/∂xᵢ.
The box slides and grows together, so a square held by a slanted boundary at one
corner and by another side elsewhere still reaches the optimum, where it touches the region at
the points that hold it in place.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

#: Relative tolerance of the refined side.
DEFAULT_RTOL = 1e-4

#: ``slack(points (K, dims)) -> (K,)``: ≥ 0 where a point satisfies the region's criteria.
Slack = Callable[[np.ndarray], np.ndarray]
#: ``slack_gradient(points (K, dims)) -> (slack (K,), gradient (K, d))`` along the box's axes.
SlackGradient = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
#: ``points_of(center (d,), half, offsets (K, d)) -> (K, dims)`` full points of the lattice.
PointsOf = Callable[[np.ndarray, float, np.ndarray], np.ndarray]


def lattice_offsets(d: int, samples: int) -> np.ndarray:
    """``(samples**d, d)`` points of ``[-1, 1]^d``, ``samples`` per edge (C order)."""
    axis = np.linspace(-1.0, 1.0, samples)
    return np.stack(np.meshgrid(*([axis] * d), indexing="ij"), axis=-1).reshape(-1, d)


def lattice_shell(d: int, samples: int) -> np.ndarray:
    """The points of :func:`lattice_offsets` on the faces of ``[-1, 1]^d`` (a coordinate
    ±1), in the same order: ``samples**d − (samples − 2)**d`` of them (3,458 of 15,625 for a
    cube of 25 per edge)."""
    offsets = lattice_offsets(d, samples)
    return offsets[(np.abs(offsets) == 1.0).any(axis=1)]


def largest_box(slack: Slack, points_of: PointsOf, center: np.ndarray, half: float,
                lower: np.ndarray, upper: np.ndarray, *, samples: int,
                rtol: float = DEFAULT_RTOL, max_iter: int = 100,
                slack_gradient: SlackGradient | None = None,
                offsets: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Largest box ``center ± half`` whose lattice satisfies ``slack ≥ 0``, from a start near
    it (see the module docstring).

    Args:
        slack: signed slack of the criteria at points.
        points_of: the lattice's points for a centre and a half-side.
        center, half: the start (e.g. the grid's box).
        lower, upper: ``(d,)`` bounds the box stays within.
        samples: lattice points per edge.
        rtol: relative tolerance of the half-side.
        max_iter: SLSQP iterations.
        slack_gradient: the slack at points with its gradient along the box's axes, in one
            evaluation (:func:`pkmkit.analysis.slack.slack_and_gradient`): one lattice per
            iterate instead of one per axis more; None: finite differences.
        offsets: the points of ``[-1, 1]^d`` constrained (``(K, d)``); default the whole
            lattice, :func:`lattice_offsets` ``(d, samples)``. :func:`lattice_shell` constrains
            its faces only: the same optimum wherever no interior point holds the box — the
            caller checks the interior at the optimum (as
            :func:`pkmkit.analysis.workspace.refine_box` does) and runs the whole lattice if
            one fails there.

    Returns:
        ``(center, half)``; the start if the optimiser does not improve on it.

    The largest square in the unit disc, from a small square off its centre (side √2):

    >>> import numpy as np
    >>> center, half = largest_box(lambda p: 1 - np.hypot(p[:, 0], p[:, 1]),
    ...                            lambda c, h, u: c + h * u, np.array([0.3, 0.2]), 0.1,
    ...                            np.full(2, -2.0), np.full(2, 2.0), samples=21)
    >>> round(2 * half, 6), [round(v, 6) + 0.0 for v in center.tolist()]
    (1.414214, [0.0, 0.0])
    """
    from scipy.optimize import minimize

    c0 = np.asarray(center, dtype=float)
    d = len(c0)
    scale = max(float(half), 1e-9 * max(1.0, float(np.max(np.abs(c0)))))
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    offsets = lattice_offsets(d, samples) if offsets is None else np.asarray(offsets, float)
    eps = 1e-7 * scale
    memo: dict[str, tuple[bytes, np.ndarray]] = {}

    def unpack(z: np.ndarray) -> tuple[np.ndarray, float]:
        return c0 + z[:d] * scale, float(z[d] * scale)

    def values(z: np.ndarray) -> np.ndarray:
        key = z.tobytes()
        if "v" not in memo or memo["v"][0] != key:
            c, h = unpack(z)
            if slack_gradient is None:
                memo["v"] = (key, slack(points_of(c, h, offsets)))
            else:
                value, grad = slack_gradient(points_of(c, h, offsets))
                memo["v"], memo["g"] = (key, value), (key, grad)
        return memo["v"][1]

    def gradient(z: np.ndarray) -> np.ndarray:
        key = z.tobytes()
        if slack_gradient is not None:
            values(z)
            return memo["g"][1]
        if "g" not in memo or memo["g"][0] != key:
            c, h = unpack(z)
            base = values(z)
            g = np.empty((len(offsets), d))
            for i in range(d):
                shifted = c.copy()
                shifted[i] += eps
                g[:, i] = (slack(points_of(shifted, h, offsets)) - base) / eps
            memo["g"] = (key, g)
        return memo["g"][1]

    def constraints(z: np.ndarray) -> np.ndarray:
        c, h = unpack(z)
        return np.concatenate([values(z), (c - h - lower) / scale, (upper - c - h) / scale])

    def constraints_jac(z: np.ndarray) -> np.ndarray:
        g = gradient(z)
        rows = np.column_stack([g * scale, (g * offsets).sum(axis=1) * scale])
        eye = np.eye(d)
        room_low = np.column_stack([eye, -np.ones(d)])
        room_high = np.column_stack([-eye, -np.ones(d)])
        return np.vstack([rows, room_low, room_high])

    z0 = np.concatenate([np.zeros(d), [half / scale]])
    objective = np.zeros(d + 1)
    objective[d] = -1.0
    result = minimize(lambda z: -z[d], z0, jac=lambda z: objective, method="SLSQP",
                      constraints=[{"type": "ineq", "fun": constraints,
                                    "jac": constraints_jac}],
                      options={"maxiter": max_iter, "ftol": 1e-3 * rtol})
    c, h = unpack(result.x)
    if not (np.isfinite(result.x).all() and h > half):
        return c0, float(half)
    return c, h
