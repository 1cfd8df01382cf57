"""Regular grids over boxes and plane slices of a pose space (or of the actuator space).

A :class:`Grid` varies some coordinates (``free``) on a regular lattice with **the same step on
every free axis** — so that k × k grid points span a true square — and keeps the others fixed
(a slice ``z = 0.2`` of a 3-D workspace, for instance). Points are listed in C order over
``axes`` (``indexing="ij"``), so a mask of shape ``grid.shape`` maps to ``grid.points`` by
``mask.ravel()``.

**Measure.** Each grid point stands for the part of the box nearer to it than to any other point
(cells of one step centred on the points, the outer ones clipped to the box, the last one along
a shorter axis stretched to the box's upper bound): a fully feasible box therefore measures
exactly its area/volume, and a region with a curved boundary is estimated by the midpoint rule
(see :meth:`Grid.measure`).

**Size.** Grids are limited to :data:`MAX_GRID_POINTS` points: a workspace evaluation keeps
about 100 bytes per point (actuator coordinates, factors, masks) plus chunked temporaries, so the
limit keeps a 3-D study under about 1 GB (0.7 GB measured for the Orthoglide at 170³).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pkmkit.exceptions import InputError

#: Largest number of points of a grid (170³ ≈ 4.9e6 in 3-D; 2001² ≈ 4.0e6 in 2-D).
MAX_GRID_POINTS = 5_000_000


@dataclass(frozen=True)
class Grid:
    """Lattice of poses (or actuator vectors).

    Attributes:
        axes: coordinates along each free coordinate, one ``(n_k,)`` array per free axis.
        free: indices of the free coordinates in the full vector.
        base: ``(dims,)`` full vector holding the values of the fixed coordinates.
        step: common spacing of the free axes (units of the coordinates).
        names: names of all the coordinates (e.g. ``("x", "y", "z")``).
        upper: ``(len(free),)`` upper bounds of the box the grid covers (None: the last point
            of each axis). The lower bounds are the first points.
    """

    axes: tuple[np.ndarray, ...]
    free: tuple[int, ...]
    base: np.ndarray
    step: float
    names: tuple[str, ...]
    upper: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of points along each free axis."""
        return tuple(len(a) for a in self.axes)

    @property
    def size(self) -> int:
        """Number of grid points."""
        return int(np.prod(self.shape))

    @property
    def cell_measure(self) -> float:
        """Length, area or volume of an interior cell (step ** number of free axes)."""
        return self.step ** len(self.free)

    @property
    def lower_bounds(self) -> np.ndarray:
        """``(len(free),)`` lower bounds of the box (the first point of each axis)."""
        return np.array([a[0] for a in self.axes])

    @property
    def upper_bounds(self) -> np.ndarray:
        """``(len(free),)`` upper bounds of the box (``upper``, else the last points)."""
        if self.upper is not None:
            return np.asarray(self.upper, dtype=float)
        return np.array([a[-1] for a in self.axes])

    def axis_weights(self) -> tuple[np.ndarray, ...]:
        """Length of the cell of each point along each free axis, one ``(n_k,)`` array per
        axis: cell edges halfway between points, the outer edges at the box bounds. Each
        array sums to the box's extent along that axis."""
        out = []
        for axis, hi in zip(self.axes, self.upper_bounds, strict=True):
            edges = np.concatenate([[axis[0]], 0.5 * (axis[1:] + axis[:-1]),
                                    [max(float(hi), float(axis[-1]))]])
            out.append(np.diff(edges))
        return tuple(out)

    def measure(self, mask: np.ndarray) -> float:
        """Length/area/volume of the points of ``mask`` (shape ``shape``): the sum of their
        cells (:meth:`axis_weights`). Exact for a mask true everywhere (the box itself)."""
        mask = np.asarray(mask, bool)
        if mask.shape != self.shape:
            raise InputError(f"mask of shape {mask.shape} does not fit the grid {self.shape}")
        weights = self.axis_weights()
        total = mask.astype(float)
        for w in weights:  # contract one axis at a time (no full weight array)
            total = np.tensordot(total, w, axes=([0], [0]))
        return float(total)

    def weights(self) -> np.ndarray:
        """Cell measure of every point, shape ``shape`` (see :meth:`axis_weights`)."""
        out = np.ones(())
        for w in self.axis_weights():
            out = np.multiply.outer(out, w)
        return out

    @property
    def free_names(self) -> tuple[str, ...]:
        """Names of the free coordinates."""
        return tuple(self.names[k] for k in self.free)

    @property
    def points(self) -> np.ndarray:
        """All grid points ``(size, dims)``."""
        return self.points_between(0, self.size)

    def points_between(self, start: int, stop: int) -> np.ndarray:
        """Grid points ``start`` to ``stop − 1`` in C order, ``(stop − start, dims)`` (to
        evaluate a large grid in chunks without building every point at once)."""
        flat = np.arange(start, min(stop, self.size))
        out = np.tile(self.base, (flat.size, 1))
        for k, axis, index in zip(self.free, self.axes, np.unravel_index(flat, self.shape),
                                  strict=True):
            out[:, k] = axis[index]
        return out

    def point(self, index: Sequence[int]) -> np.ndarray:
        """Full coordinate vector of the grid point with multi-index ``index``."""
        out = self.base.copy()
        for k, axis, i in zip(self.free, self.axes, index, strict=True):
            out[k] = axis[i]
        return out

    def nearest_index(self, point: np.ndarray) -> tuple[int, ...] | None:
        """Multi-index of the grid point nearest to ``point`` (None when outside the grid)."""
        index = []
        for k, axis in zip(self.free, self.axes, strict=True):
            if not axis[0] - 0.5 * self.step <= point[k] <= axis[-1] + 0.5 * self.step:
                return None
            index.append(int(np.clip(np.rint((point[k] - axis[0]) / self.step), 0, len(axis) - 1)))
        return tuple(index)


def make_grid(lower: Sequence[float], upper: Sequence[float], *, free: Sequence[int],
              base: Sequence[float], names: Sequence[str], resolution: int = 101) -> Grid:
    """Grid over the box ``[lower, upper]`` of the free coordinates.

    Args:
        lower, upper: bounds of each free coordinate (same units as ``base``).
        free: indices of the free coordinates.
        base: full vector whose fixed coordinates are kept.
        names: names of all the coordinates.
        resolution: number of points along the *longest* side; the step is shared by all axes.

    Raises:
        InputError: bounds with lower ≥ upper, non-finite bounds or extent, resolution < 2,
            a step too small to separate the points at that magnitude, more than
            :data:`MAX_GRID_POINTS` points.
    """
    try:
        lo = np.asarray(lower, dtype=float).reshape(-1)
        hi = np.asarray(upper, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"the box bounds must be numbers, got {lower!r} and {upper!r}"
                         ) from None
    if isinstance(resolution, bool) or not isinstance(resolution, int | np.integer):
        raise InputError(f"resolution must be an integer, got {resolution!r}")
    if lo.shape != (len(free),) or hi.shape != (len(free),):
        raise InputError(f"the box needs {len(free)} lower and upper bounds")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise InputError("the box bounds must be finite")
    for name, a, b in zip((names[k] for k in free), lo, hi, strict=True):
        if not a < b:
            raise InputError(f"box bounds for {name}: lower {a:g} must be below upper {b:g}")
    if resolution < 2:
        raise InputError(f"resolution must be at least 2, got {resolution}")
    with np.errstate(over="ignore"):
        span = hi - lo
    if not np.isfinite(span).all():
        raise InputError(f"the box [{lo.tolist()}, {hi.tolist()}] is too large to grid (its "
                         "extent overflows)")
    step = float(span.max()) / (resolution - 1)
    magnitude = float(np.max(np.maximum(np.abs(lo), np.abs(hi))))
    if not step > 64 * np.spacing(magnitude):
        raise InputError(f"the box is too thin for its position: a step of {step:g} cannot "
                         f"separate points at coordinates of magnitude {magnitude:g}")
    counts = [int(np.floor(b / step + 1e-9)) + 1 for b in span]
    total = int(np.prod(counts, dtype=float))
    if total > MAX_GRID_POINTS:
        raise InputError(f"the grid would have {total:.3g} points, above the limit of "
                         f"{MAX_GRID_POINTS:.3g} (memory); lower the resolution")
    axes = tuple(a + step * np.arange(n) for a, n in zip(lo, counts, strict=True))
    return Grid(axes=axes, free=tuple(int(k) for k in free),
                base=np.asarray(base, dtype=float).copy(), step=step, names=tuple(names),
                upper=hi.copy())


@dataclass(frozen=True)
class PoseFrame:
    """The pose vector a machine's workspace grids run over, and which part of it may vary.

    Workspace grids vary the **position** and hold the orientation: a translational machine's
    pose is its position; a hexapod's grid points are ``(x, y, z, rx, ry, rz)`` with the
    rotation vector fixed (a constant-orientation workspace); a Verne-type module's are
    positions ``(x, y, z)`` (its rods impose the orientation); a joint-chain machine's are
    ``(x, y, z, i, j, k)`` with the tool axis fixed.

    Attributes:
        base: ``(w,)`` vector every grid point starts from (SI): the home position and the
            orientation held.
        names: ``(w,)`` names of its coordinates.
        lower, upper: ``(p,)`` default box of the position coordinates ``0 … p-1`` (m).
    """

    base: np.ndarray
    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray

    @property
    def positions(self) -> int:
        """Number of position coordinates (the ones a grid may vary)."""
        return len(self.lower)


def pose_frame(machine, orientation: Sequence[float] | None = None) -> PoseFrame:
    """The :class:`PoseFrame` of ``machine``.

    Args:
        machine: any machine with ``home_pose``, ``pose_names`` and ``default_box()``.
        orientation: the orientation held (SI: a rotation vector ``(3,)`` of a six-actuator
            full-pose machine, a tool axis ``(3,)`` of a joint-chain machine; default the home
            orientation).

    Raises:
        InputError: an orientation for a machine whose orientation is not free (a translational
            machine, a Verne-type module), a wrong length, a non-finite value or a zero tool
            axis.
    """
    home = np.asarray(machine.home_pose, dtype=float)
    lower, upper = (np.asarray(v, dtype=float) for v in machine.default_box())
    p = len(lower)
    if p == len(home) or machine.position_controlled:
        if orientation is not None:
            what = ("its rods impose its orientation" if p != len(home)
                    else "it only translates")
            raise InputError(f"machine {machine.id!r} takes no orientation: {what}")
        return PoseFrame(base=home[:p].copy(), names=tuple(machine.pose_names[:p]),
                         lower=lower, upper=upper)
    base = home.copy()
    if orientation is not None:
        values = np.asarray(orientation, dtype=float).reshape(-1)
        if values.shape != (len(home) - p,) or not np.isfinite(values).all():
            raise InputError(f"the orientation needs {len(home) - p} finite values, got "
                             f"{np.asarray(orientation).tolist()}")
        if machine.pose_names[p:] == ("i", "j", "k"):
            norm = float(np.linalg.norm(values))
            if not norm > 0:
                raise InputError("the tool axis must not be zero")
            values = values / norm
        base[p:] = values
    return PoseFrame(base=base, names=tuple(machine.pose_names), lower=lower, upper=upper)
