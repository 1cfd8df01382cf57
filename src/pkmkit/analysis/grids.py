"""Regular grids over boxes and plane slices of a pose space (or of the actuator space).

A :class:`Grid` varies some coordinates (``free``) on a regular lattice with **the same step on
every free axis** — so that k × k grid points span a true square — and keeps the others fixed
(a slice ``z = 0.2`` of a 3-D workspace, for instance). Points are listed in C order over
``axes`` (``indexing="ij"``), so a mask of shape ``grid.shape`` maps to ``grid.points`` by
``mask.ravel()``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pkmkit.errors import InputError


@dataclass(frozen=True)
class Grid:
    """Lattice of poses (or actuator vectors).

    Attributes:
        axes: coordinates along each free coordinate, one ``(n_k,)`` array per free axis.
        free: indices of the free coordinates in the full vector.
        base: ``(dims,)`` full vector holding the values of the fixed coordinates.
        step: common spacing of the free axes (units of the coordinates).
        names: names of all the coordinates (e.g. ``("x", "y", "z")``).
    """

    axes: tuple[np.ndarray, ...]
    free: tuple[int, ...]
    base: np.ndarray
    step: float
    names: tuple[str, ...]

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
        """Length, area or volume represented by one grid point (step ** number of free axes)."""
        return self.step ** len(self.free)

    @property
    def free_names(self) -> tuple[str, ...]:
        """Names of the free coordinates."""
        return tuple(self.names[k] for k in self.free)

    @property
    def points(self) -> np.ndarray:
        """All grid points ``(size, dims)``."""
        mesh = np.meshgrid(*self.axes, indexing="ij")
        out = np.tile(self.base, (self.size, 1))
        for k, m in zip(self.free, mesh, strict=True):
            out[:, k] = m.ravel()
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
        InputError: bounds with lower ≥ upper, non-finite bounds, resolution < 2, too many points.
    """
    lo = np.asarray(lower, dtype=float).reshape(-1)
    hi = np.asarray(upper, dtype=float).reshape(-1)
    if lo.shape != (len(free),) or hi.shape != (len(free),):
        raise InputError(f"the box needs {len(free)} lower and upper bounds")
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise InputError("the box bounds must be finite")
    for name, a, b in zip((names[k] for k in free), lo, hi, strict=True):
        if not a < b:
            raise InputError(f"box bounds for {name}: lower {a:g} must be below upper {b:g}")
    if resolution < 2:
        raise InputError(f"resolution must be at least 2, got {resolution}")
    step = float((hi - lo).max()) / (resolution - 1)
    axes = tuple(a + step * np.arange(int(np.floor((b - a) / step + 1e-9)) + 1)
                 for a, b in zip(lo, hi, strict=True))
    if int(np.prod([len(a) for a in axes])) > 20_000_000:
        raise InputError("the grid would exceed 2e7 points; lower the resolution")
    return Grid(axes=axes, free=tuple(int(k) for k in free),
                base=np.asarray(base, dtype=float).copy(), step=step, names=tuple(names))
