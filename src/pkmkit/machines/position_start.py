"""The start of the paired position inverse (issue 22 §5): a table of the rotation the rods
impose, as a function of the position across the common slide axis.

When every rod hangs from a slide and the slides share one axis ``e`` (the Verne-type module),
moving the platform along ``e`` moves every carriage by the same amount and leaves the rods'
directions, hence the platform's rotation, unchanged: the rotation is a function of the
position's two coordinates ``(u, v)`` in a plane across ``e`` alone. That function has no
closed form worth the name here (two parallelogram legs and a trapezoid: each pair of rods adds
a quartic), but it is smooth, so the table holds it piecewise: a square of ``CELLS × CELLS``
cells of side ``2 SPAN ℓ / CELLS`` (ℓ the longest rod) about the home position, in each cell a
polynomial of total degree ``DEGREE`` in the cell's local coordinates fitted by least squares
to the paired Newton solve's answers at ``(NODES + 1)²`` equispaced nodes (the unit
quaternion's vector part, ``w ≥ 0``). Over the Verne module's ±0.3 m square the fit is within
≈ 3e-10 of the converged rotation, so the Newton solve started there stops after one step
(≤ PAIRED_STEP) where the first-order start took three
(``tests/machines/test_position_start.py``). A cell with a node beyond reach is NaN: its rows,
and those outside the square, start from the first order as before.

:func:`start_table` builds the table once per machine (≈ 4,000 paired solves, a few
milliseconds); :func:`pack` is the layout ``opts[10:]`` of the position kernels carries.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pkmkit.machines.slide_columns import common_slide_axis

#: Cells per side of the table's square.
CELLS = 8
#: Node intervals per cell side (the fit's nodes: (NODES + 1)² per cell, shared at the edges).
NODES = 8
#: Total degree of each cell's polynomial ((DEGREE + 1)(DEGREE + 2)/2 terms per component).
DEGREE = 7
#: Half the square's side in lengths of the longest rod.
SPAN = 0.3
#: Values before the coefficients in the packed table (the kernels' START_HEADER).
HEADER = 13


def plane_axes(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(u, v)`` across ``axis (3,)``, ``(u, v, axis)`` right-handed: ``u``
    from the coordinate axis least aligned with it (x, y for a vertical axis)."""
    e = axis / np.linalg.norm(axis)
    pick = np.eye(3)[int(np.argmin(np.abs(e)))]
    u = pick - (pick @ e) * e
    u /= np.linalg.norm(u)
    return u, np.cross(e, u)


def exponents(degree: int) -> list[tuple[int, int]]:
    """The terms ``a^i b^j`` of total degree ≤ ``degree`` in the table's order (i, then j)."""
    return [(i, j) for i in range(degree + 1) for j in range(degree + 1 - i)]


def quaternion_vectors(rotvec: np.ndarray) -> np.ndarray:
    """``(N, 3)`` the vector part of the unit quaternion (``w ≥ 0``) of rotation vectors
    ``(N, 3)`` of angle below π."""
    angle = np.linalg.norm(rotvec, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        scale = np.where(angle > 1e-8, np.sin(0.5 * angle) / angle, 0.5 - angle**2 / 48.0)
    return rotvec * scale[:, None]


def start_table(model, home: np.ndarray,
                solve: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]) -> np.ndarray | None:
    """The packed start table (:func:`pack`) of ``model`` about ``home (3,)``, the position the
    square is centred on, with ``solve(points (N, 3))`` → ``(rotation vectors (N, 3),
    answered (N,))`` the paired solve from the first-order start; None without a common slide
    axis."""
    axis = common_slide_axis(model)
    if axis is None:
        return None
    u_axis, v_axis = plane_axes(axis)
    half = SPAN * float(np.max(model.rod_length))
    side = 2.0 * half / CELLS
    grid = -half + np.arange(CELLS * NODES + 1) * (side / NODES)
    gu, gv = np.meshgrid(grid, grid, indexing="ij")
    points = home + gu.reshape(-1, 1) * u_axis + gv.reshape(-1, 1) * v_axis
    rotvec, answered = solve(points)
    values = quaternion_vectors(rotvec)
    values[~answered] = np.nan
    values = values.reshape(grid.size, grid.size, 3)
    local = np.arange(NODES + 1) / NODES - 0.5
    la, lb = np.meshgrid(local, local, indexing="ij")
    design = np.stack([la.ravel() ** i * lb.ravel() ** j for i, j in exponents(DEGREE)], axis=1)
    fit = np.linalg.pinv(design)  # (terms, nodes)
    at = np.arange(CELLS)[:, None] * NODES + np.arange(NODES + 1)[None]
    cells = values[at[:, None, :, None], at[None, :, None, :]].reshape(CELLS, CELLS, -1, 3)
    coef = np.einsum("tn,abnc->abtc", fit, cells)  # NaN where a node was left
    return pack(home, u_axis, v_axis, side, -half, coef)


def pack(origin: np.ndarray, u_axis: np.ndarray, v_axis: np.ndarray, side: float,
         corner: float, coef: np.ndarray) -> np.ndarray:
    """The table as the kernels read it: ``[cells, degree, side, corner, origin (3), u (3),
    v (3)]`` then ``coef (cells, cells, terms, 3)`` row-major."""
    cells, terms = coef.shape[0], coef.shape[2]
    degree = round((float(np.sqrt(8 * terms + 1)) - 3) / 2)
    header = np.concatenate([[cells, degree, side, corner], origin, u_axis, v_axis])
    return np.ascontiguousarray(np.concatenate([header, coef.reshape(-1)]), dtype=float)
