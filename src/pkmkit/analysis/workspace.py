"""Workspace of any machine on a grid: masks, measure, boundary, largest inscribed square/cube,
feasibility of a prescribed square/cube, and joint-space views.

A pose belongs to the workspace when every requested criterion holds:

- ``reachable`` — the inverse model exists (working branches);
- ``strokes`` — every actuator coordinate lies within its stroke (the machine's ``q_min``,
  ``q_max``, or limits given in :class:`Criteria`);
- ``bounds`` — every velocity transmission factor λ_i lies in ``[lo, hi]``;
- ``condition`` — κ ≤ ``kappa_max``;
- ``mode`` — the pose is in the working assembly mode (sign of det A) and not on a parallel
  singularity; with ``connected=True`` only the connected part containing the home pose is kept
  (the machine can reach it from home without crossing a parallel singularity).

The largest inscribed axis-aligned square (2-D) or cube (3-D) is exact on the grid (a binary
search over the side with separable minimum filters), so its side is known to within one grid
step; :func:`check_region` then verifies any square or cube densely and says where it fails.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.analysis.criteria import (  # noqa: F401  (re-exported: their old home)
    EVALUATION_CHUNK,
    FACTOR_RTOL,
    MASK_NAMES,
    Criteria,
    evaluate_grid,
    evaluate_poses,
    study_length,
)
from pkmkit.analysis.flood import flood_grid, floods
from pkmkit.analysis.grid_masks import erode_faces, label_faces, window_all
from pkmkit.analysis.grids import Grid
from pkmkit.analysis.inscribed import DEFAULT_RTOL as INSCRIBED_RTOL
from pkmkit.analysis.inscribed import largest_box, lattice_shell
from pkmkit.analysis.region_check import (  # noqa: F401  (re-exported: their old home)
    RegionCheck,
    _full,
    _surface_offsets,
    check_region,
    check_region_samples,
    criteria_slack,
    feasible_interval,
    region_grid,
)
from pkmkit.analysis.slack import slack_and_gradient
from pkmkit.machines.machine import Machine


@dataclass(frozen=True)
class InscribedBox:
    """Largest axis-aligned square (2 free axes) or cube (3) found in a mask.

    Attributes:
        side: side length (units of the grid), exact on the grid (within one step).
        center: ``(dims,)`` full coordinate vector of its centre.
        lower: ``(dims,)`` its lower corner.
        points_per_side: grid points along each side.
    """

    side: float
    center: np.ndarray
    lower: np.ndarray
    points_per_side: int


def largest_inscribed_box(mask: np.ndarray, grid: Grid, center: Any = None
                          ) -> InscribedBox | None:
    """Largest axis-aligned square/cube of grid points all true in ``mask`` (shape
    ``grid.shape``); None when the mask is empty (or false at ``center``).

    Args:
        mask: boolean array of shape ``grid.shape``.
        grid: the grid.
        center: if given (a full coordinate vector), the box must be centred at the grid point
            nearest to it; otherwise it may lie anywhere (ties go to the box nearest the grid
            centre).
    """
    mask = np.asarray(mask, bool)
    if not mask.any():
        return None
    if center is not None:
        return _centred_box(mask, grid, np.asarray(center, dtype=float))

    def centres(k: int) -> np.ndarray:
        # true where the k-point window [i - k//2, i - k//2 + k - 1] (each axis) is all true;
        # outside the grid counts as false
        return window_all(mask, k)

    lo, hi = 1, min(mask.shape)
    while lo < hi:  # largest k with a feasible k × k (× k) block
        mid = (lo + hi + 1) // 2
        if centres(mid).any():
            lo = mid
        else:
            hi = mid - 1
    k = lo
    candidates = np.argwhere(centres(k)) - k // 2  # lower corners
    middle = (np.array(mask.shape) - k) / 2.0
    best = candidates[np.argmin(((candidates - middle) ** 2).sum(axis=1))]
    lower = grid.point(best)
    side = (k - 1) * grid.step
    center = lower.copy()
    for axis in grid.free:
        center[axis] += 0.5 * side
    return InscribedBox(side=float(side), center=center, lower=lower, points_per_side=k)


def _centred_box(mask: np.ndarray, grid: Grid, center: np.ndarray) -> InscribedBox | None:
    index = grid.nearest_index(center)
    if index is None or not mask[index]:
        return None
    radius = 0
    while True:
        window = tuple(slice(i - radius - 1, i + radius + 2) for i in index)
        if any(w.start < 0 or w.stop > n for w, n in zip(window, mask.shape, strict=True)):
            break
        if not mask[window].all():
            break
        radius += 1
    lower = grid.point(tuple(i - radius for i in index))
    side = 2 * radius * grid.step
    middle = lower.copy()
    for axis in grid.free:
        middle[axis] += 0.5 * side
    return InscribedBox(side=float(side), center=middle, lower=lower,
                        points_per_side=2 * radius + 1)


def _part_next_to(labels: np.ndarray, grid: Grid, home: np.ndarray,
                  index: tuple[int, ...] | None) -> int:
    """The label of the feasible grid point nearest to ``home`` among the grid points of the
    cell around its nearest one (one step along each free axis), or 0: a home at the edge of
    the workspace (an actuator at its stroke end) rounds to a grid point just outside."""
    if index is None:
        return 0
    window = tuple(slice(max(i - 1, 0), i + 2) for i in index)
    offsets = np.argwhere(labels[window] > 0)
    if not offsets.size:
        return 0
    corners = offsets + np.array([w.start for w in window])
    coords = np.column_stack([np.asarray(axis)[corners[:, j]]
                              for j, axis in enumerate(grid.axes)])
    gap = np.linalg.norm(coords - np.asarray(home, dtype=float)[list(grid.free)], axis=1)
    return int(labels[tuple(corners[int(np.argmin(gap))])])


def _connected_part(feasible: np.ndarray, grid: Grid, home: np.ndarray) -> tuple[np.ndarray, str]:
    if not feasible.any():
        return feasible, "empty"
    labels, count = label_faces(feasible)
    index = grid.nearest_index(home)
    if index is not None and labels[index] > 0:
        return labels == labels[index], "home"
    near = _part_next_to(labels, grid, home, index)
    if near:  # home at the edge of a part (a stroke end): its nearest grid point just outside
        return labels == near, "home (within one grid step of it)"
    sizes = np.bincount(labels.ravel(), minlength=count + 1)[1:]
    return labels == (1 + int(np.argmax(sizes))), "largest connected part (home not in it)"


@dataclass(frozen=True)
class WorkspaceMap:
    """Workspace of a machine on a grid.

    Attributes:
        grid: the grid.
        masks: ``{name: mask of shape grid.shape}`` per criterion (before connectivity).
        feasible: points satisfying every criterion (and connected to home if requested).
        q: ``grid.shape + (n,)`` actuator coordinates.
        factors: ``grid.shape + (n,)`` velocity transmission factors.
        condition: ``grid.shape``.
        reference: which connected part was kept.
        criteria: the criteria used.
        inscribed: largest inscribed square/cube, or None.
        inscribed_check: dense verification of the inscribed box (its transmission-factor and
            actuator ranges), or None.
        stiffness: ``grid.shape`` smallest translational stiffness (N/m) when the criteria ask
            for stiffness (:attr:`Criteria.stiffness_bounded` or a wrench), else None.
        deflection: ``grid.shape`` deflection under the criteria's wrench (m), or None.
        evaluated: ``grid.shape`` the points whose criteria were evaluated, or None (every
            point). A flood fill from home (:mod:`pkmkit.analysis.flood`) evaluates the kept
            part and its rim only: elsewhere every mask is False and q, the factors and the
            condition NaN — not evaluated, not failing (:attr:`criteria_counts`).
    """

    grid: Grid
    masks: dict[str, np.ndarray]
    feasible: np.ndarray
    q: np.ndarray
    factors: np.ndarray
    condition: np.ndarray
    reference: str
    criteria: Criteria
    inscribed: InscribedBox | None = field(default=None)
    inscribed_check: RegionCheck | None = field(default=None)
    stiffness: np.ndarray | None = field(default=None)
    deflection: np.ndarray | None = field(default=None)
    evaluated: np.ndarray | None = field(default=None)

    @property
    def points_evaluated(self) -> int:
        """Number of grid points whose criteria were evaluated."""
        return self.grid.size if self.evaluated is None else int(self.evaluated.sum())

    @property
    def criteria_counts(self) -> dict[str, int]:
        """``{criterion: points passing it}`` among the points evaluated
        (:attr:`points_evaluated`; after a flood fill, not the whole grid)."""
        return {k: int(v.sum()) for k, v in self.masks.items()}

    @property
    def measure(self) -> float:
        """Area (2 free axes) or volume (3) of the feasible set: the sum of the cells of the
        feasible points (:meth:`Grid.measure`; cells clipped to the box, so a fully feasible
        box gives exactly its area/volume)."""
        return self.grid.measure(self.feasible)

    def global_conditioning_index(self, region: np.ndarray | None = None) -> float:
        """Mean of 1/κ over ``region`` (a mask of grid points; default the feasible set),
        each point weighted by its cell (:meth:`Grid.weights`): ∫ 1/κ dW / ∫ dW. Points on a
        parallel singularity count as 1/κ = 0 (the limit); NaN for an empty region."""
        region = self.feasible if region is None else np.asarray(region, bool)
        with np.errstate(divide="ignore"):
            inverse = 1.0 / self.condition  # 0 where κ = inf
        inverse[self.masks["reachable"] & np.isnan(self.condition)] = 0.0
        keep = region & ~np.isnan(inverse)
        if not keep.any():
            return float("nan")
        weights = self.grid.weights()[keep]
        return float(np.sum(inverse[keep] * weights) / np.sum(weights))

    @property
    def boundary(self) -> np.ndarray:
        """Feasible points with an infeasible (or off-grid) face neighbour."""
        inner = erode_faces(self.feasible)
        return self.feasible & ~inner

    def factor_range(self, region: np.ndarray | None = None) -> tuple[float, float]:
        """(smallest, largest) velocity transmission factor over ``region`` (a mask of grid
        points); by default over the inscribed box (densely checked), else the feasible set."""
        if region is None:
            if self.inscribed_check is not None:
                return self.inscribed_check.factor_range
            region = self.feasible
        values = self.factors[region]
        if values.size == 0:
            return (float("nan"), float("nan"))
        return float(np.nanmin(values)), float(np.nanmax(values))

    def box_mask(self) -> np.ndarray:
        """Grid points inside the inscribed box."""
        out = np.zeros(self.grid.shape, bool)
        if self.inscribed is None:
            return out
        start = self.grid.nearest_index(self.inscribed.lower)
        k = self.inscribed.points_per_side
        out[tuple(slice(s, s + k) for s in start)] = True
        return out

    def faces_reached(self, layers: int = 1) -> list[str]:
        """Faces of the grid's box the feasible set touches, e.g. ``["x-", "z+"]``: where the
        workspace may extend beyond the box studied (its measure is then a lower bound).
        ``layers``: how many grid layers next to a face count (2: the feasible set comes
        within one grid step of the face, and may cross it between samples)."""
        out = []
        for axis, k in enumerate(self.grid.free):
            name = self.grid.names[k]
            n = self.feasible.shape[axis]
            near = min(max(int(layers), 1), n)
            if self.feasible.take(range(near), axis=axis).any():
                out.append(f"{name}-")
            if self.feasible.take(range(n - near, n), axis=axis).any():
                out.append(f"{name}+")
        return out


def compute_workspace(machine: Machine, grid: Grid, criteria: Criteria | None = None, *,
                      refine: bool = False, scheduler: Any = None,
                      inscribed: bool = True, factors: bool = True) -> WorkspaceMap:
    """Masks, feasible set and largest inscribed square/cube of ``machine`` over ``grid``.

    ``inscribed=False`` stops at the feasible set (no inscribed box, no dense check of it: the
    map's ``inscribed`` and ``inscribed_check`` are None), e.g. to size the region studied
    from where the workspace reaches. With ``refine=True`` the inscribed box found on the grid
    is refined in its centre and side to 10⁻⁴ of the side (:func:`refine_box`), which removes
    the grid's under-estimate (up to two steps) and its centring on grid points.
    ``scheduler``: evaluate the grid on Dask (see :func:`evaluate_grid`); the rest runs
    here. Where only home's part is kept and the machine's inverse continues from neighbours
    (joint chains), the grid is evaluated by a flood fill from home instead
    (:mod:`pkmkit.analysis.flood`: the same kept part; ``criteria.whole_grid`` or a
    ``scheduler`` evaluates every point). ``factors=False``: the map's transmission factors
    and condition numbers are NaN unless a criterion reads them (:func:`evaluate_poses`),
    e.g. to size the region."""
    criteria = criteria or Criteria()
    flooded = (flood_grid(machine, grid, criteria, machine.home_pose, factors=factors)
               if floods(machine, criteria, scheduler) else None)
    if flooded is None:
        evaluation, evaluated = evaluate_grid(machine, grid, criteria, scheduler=scheduler,
                                              factors=factors), None
    else:
        evaluation, evaluated = flooded
    shape = grid.shape
    masks = {k: v.reshape(shape) for k, v in evaluation.masks.items()}
    feasible = evaluation.feasible.reshape(shape)
    reference = "all parts"
    if criteria.connected:
        feasible, reference = _connected_part(feasible, grid, machine.home_pose)
    box = largest_inscribed_box(feasible, grid) if inscribed else None
    # criteria through a numerical inverse (joint chains) have no smooth slack: grid box only
    if refine and box is not None and box.side > 0 and machine.closed_form_inverse:
        box = refine_box(machine, box, criteria, grid)
    box_check = None
    if box is not None and box.side > 0:
        box_check = check_region(machine, box.center, box.side, criteria, free=grid.free)
    return WorkspaceMap(
        grid=grid, masks=masks, feasible=feasible,
        q=evaluation.q.reshape((*shape, -1)), factors=evaluation.factors.reshape((*shape, -1)),
        condition=evaluation.condition.reshape(shape), reference=reference, criteria=criteria,
        inscribed=box, inscribed_check=box_check,
        stiffness=None if evaluation.stiffness is None else evaluation.stiffness.reshape(shape),
        deflection=(None if evaluation.deflection is None
                    else evaluation.deflection.reshape(shape)),
        evaluated=None if evaluated is None else evaluated.reshape(shape),
    )


def _inside(points: np.ndarray, center: np.ndarray, half: float) -> np.ndarray:
    """``(K,)`` bool: which lattice points ``(K, d)`` of the box ``center ± half`` are
    interior (off every face; an interior lattice point is at least a lattice step, 1/12 of
    the half-side for 25 per edge, inside each)."""
    return (np.abs(points - center) < (1.0 - 1e-6) * half).all(axis=1)


def refine_box(machine: Machine, box: InscribedBox, criteria: Criteria, grid: Grid, *,
               rtol: float = INSCRIBED_RTOL) -> InscribedBox:
    """Refine a feasible square/cube in all its unknowns — centre and side — beyond the grid.

    The box is a lattice of :func:`check_region` (41 points per edge for a square, 25 for a
    cube, edges and corners included) whose points move with the centre and the side; each
    criterion has a signed slack at each point (:func:`criteria_slack`), and the side is
    maximised under "every slack ≥ 0" and "inside the grid's box" by SLSQP
    (:func:`pkmkit.analysis.inscribed.largest_box`), with the slack's analytic gradient where
    the machine gives its rates (:func:`pkmkit.analysis.slack.slack_and_gradient`: full-pose
    machines along position axes), else finite differences — on the lattice's faces
    (:func:`~pkmkit.analysis.inscribed.lattice_shell`, 3,458 of a cube's 15,625 points; the
    optimum is the same unless an interior point holds the box, and if one fails at the
    optimum the box is optimised again on the whole lattice). The optimum is then checked with
    the boolean criteria and, if rounding left a point failing, shrunk about its centre by
    bisection — as it is if its faces fail on a lattice ten times denser (the region's boundary
    can bulge in between lattice points); the side is known to ``rtol`` (relative). The box
    never leaves the grid's box (``grid.lower_bounds`` … ``grid.upper_bounds``): the region
    studied bounds the answer."""
    free = list(grid.free)
    samples = check_region_samples(len(free))
    length = study_length(machine)

    def full_points(c: np.ndarray, half: float, offsets: np.ndarray) -> np.ndarray:
        points = np.tile(box.center, (len(offsets), 1))
        points[:, free] = c + half * offsets
        return points

    def slack(points: np.ndarray) -> np.ndarray:
        return criteria_slack(machine, points, criteria, length)

    def slack_gradient(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return slack_and_gradient(machine, points, criteria, length, grid.free)

    analytic = slack_and_gradient(machine, full_points(box.center[free], 0.5 * box.side,
                                                       np.zeros((1, len(free)))),
                                  criteria, length, grid.free) is not None

    def failing(c: np.ndarray, half: float, rows: Any = slice(None)) -> np.ndarray:
        """Indices into ``rows`` of the box's lattice of the points failing a criterion."""
        lattice = region_grid(machine, _full(box.center, free, c), 2.0 * half, grid.free,
                              samples)
        return np.flatnonzero(~evaluate_poses(machine, lattice.points[rows], criteria,
                                              factors=False).feasible)

    def feasible(c: np.ndarray, half: float) -> bool:
        return half <= 0 or failing(c, half).size == 0

    def optimum(offsets: np.ndarray | None) -> tuple[np.ndarray, float]:
        return largest_box(slack, full_points, box.center[free], 0.5 * box.side,
                           grid.lower_bounds, grid.upper_bounds, samples=samples, rtol=rtol,
                           slack_gradient=slack_gradient if analytic else None,
                           offsets=offsets)

    # the optimiser constrains the lattice's faces (a fifth of a cube's points); the whole
    # lattice is checked at its optimum, and optimised on if an interior point fails there
    center, half = optimum(lattice_shell(len(free), samples))
    start = (box.center[free], 0.5 * box.side)
    bad = failing(center, half) if half > 0 else np.empty(0, dtype=int)
    if bad.size and _inside(region_grid(machine, _full(box.center, free, center), 2.0 * half,
                                        grid.free, samples).points[bad][:, free],
                            center, half).any():
        center, half = optimum(None)
        bad = failing(center, half) if half > 0 else np.empty(0, dtype=int)
    if bad.size:  # rounding at the optimum: shrink about its centre
        for cut in (1e-10, 1e-8, 1e-6, 1e-5):
            # a cut box that still fails at one of the lattice points that failed fails: its
            # whole lattice is checked only once they pass
            if (failing(center, half * (1.0 - cut), bad).size == 0
                    and feasible(center, half * (1.0 - cut))):
                half *= 1.0 - cut
                break
        else:
            good, bad = 0.0, half
            while bad - good > 0.25 * rtol * bad:
                mid = 0.5 * (good + bad)
                good, bad = (mid, bad) if feasible(center, mid) else (good, mid)
            half = good
    # the region's boundary can bulge into the box between two lattice points (by ~κΔ²/8):
    # its faces are checked again on a lattice ten times denser, and the box shrunk until
    # they pass
    surface = _surface_offsets(len(free), 401 if len(free) <= 2 else 61)

    def faces_ok(c: np.ndarray, h: float) -> bool:
        points = np.tile(box.center, (len(surface), 1))
        points[:, free] = c + h * surface
        return bool(evaluate_poses(machine, points, criteria, factors=False).feasible.all())

    if not faces_ok(center, half):
        good, bad = 0.0, half
        while bad - good > 0.1 * rtol * bad:
            mid = 0.5 * (good + bad)
            good, bad = (mid, bad) if faces_ok(center, mid) and feasible(center, mid) \
                else (good, mid)
        half = good
    if half < start[1] and feasible(*start):  # never worse than the grid's box
        center, half = start
    middle = _full(box.center, free, center)
    lower = middle.copy()
    lower[free] -= half
    return InscribedBox(side=float(2.0 * half), center=middle, lower=lower,
                        points_per_side=box.points_per_side)
