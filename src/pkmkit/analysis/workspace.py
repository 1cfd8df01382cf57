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

import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from pkmkit.analysis.grids import Grid, make_grid, pose_frame
from pkmkit.analysis.inscribed import DEFAULT_RTOL as INSCRIBED_RTOL
from pkmkit.analysis.inscribed import largest_box
from pkmkit.errors import InputError
from pkmkit.machines.machine import SINGULARITY_TOL, Machine
from pkmkit.machines.strokes import signed_excess
from pkmkit.numerics.arrays import real, real_pair
from pkmkit.parallel import map_chunks
from pkmkit.status import Status

MASK_NAMES = ("reachable", "strokes", "bounds", "condition", "mode")


#: Relative tolerance of the transmission-factor bounds (rounding at a bound is not a failure).
FACTOR_RTOL = 1e-9


@dataclass(frozen=True)
class Criteria:
    """What makes a pose (or an actuator vector) usable.

    Attributes:
        bounds: ``(lo, hi)`` bounds on every velocity transmission factor, or None.
        kappa_max: largest admissible condition number, or None.
        strokes: enforce the actuator strokes.
        q_limits: ``(q_lo (n,), q_hi (n,))`` replacing the machine's strokes, or None.
        connected: keep only the part connected to the home pose (no parallel singularity
            crossed).
        tol: singularity threshold.
        rtol: relative tolerance of the bounds (rounding at a bound is not a failure).
    """

    bounds: tuple[float, float] | None = None
    kappa_max: float | None = None
    strokes: bool = True
    q_limits: tuple[np.ndarray, np.ndarray] | None = None
    connected: bool = True
    tol: float = SINGULARITY_TOL
    rtol: float = FACTOR_RTOL

    def __post_init__(self) -> None:
        if self.bounds is not None:
            lo, hi = real_pair(self.bounds, "the transmission-factor bounds")
            if not 0 < lo < hi:
                raise InputError(
                    f"transmission-factor bounds must satisfy 0 < lo < hi, got {self.bounds}"
                )
        if self.kappa_max is not None and not real(self.kappa_max, "kappa_max") >= 1:
            raise InputError(f"kappa_max must be >= 1, got {self.kappa_max}")

    def within_bounds(self, factors: np.ndarray) -> np.ndarray:
        """Rows of transmission factors ``(M, n)`` (largest first) within the bounds, up to a
        relative ``rtol`` (a design sized to touch a bound must pass): ``(M,)``."""
        lo, hi = self.bounds
        with np.errstate(invalid="ignore"):
            return ((factors[:, -1] >= lo * (1 - self.rtol))
                    & (factors[:, 0] <= hi * (1 + self.rtol)))

    def limits(self, machine: Machine) -> tuple[np.ndarray, np.ndarray]:
        """Actuator limits in force (±inf when strokes are not enforced)."""
        if self.q_limits is not None:
            return (np.asarray(self.q_limits[0], float), np.asarray(self.q_limits[1], float))
        if not self.strokes:
            n = machine.n_actuators
            return np.full(n, -np.inf), np.full(n, np.inf)
        return machine.model.q_min, machine.model.q_max


@dataclass(frozen=True)
class PoseEvaluation:
    """Criteria evaluated at M poses (flat arrays).

    Attributes:
        q: ``(M, n)`` actuator coordinates (NaN where unreachable), m.
        factors: ``(M, n)`` velocity transmission factors, decreasing.
        condition: ``(M,)``.
        masks: ``{name: (M,) bool}`` for every name of :data:`MASK_NAMES`.
    """

    q: np.ndarray
    factors: np.ndarray
    condition: np.ndarray
    masks: dict[str, np.ndarray]

    @property
    def feasible(self) -> np.ndarray:
        """``(M,)`` all masks true."""
        return np.logical_and.reduce(list(self.masks.values()))


#: Poses evaluated at once by :func:`evaluate_poses` / :func:`evaluate_grid` (bounds the
#: temporaries of the inverse and velocity models to a few tens of MB).
EVALUATION_CHUNK = 1 << 16


def evaluate_poses(machine: Machine, points: np.ndarray, criteria: Criteria) -> PoseEvaluation:
    """Evaluate the criteria (without connectivity) at poses ``points (M, dims)``, in chunks of
    :data:`EVALUATION_CHUNK` poses."""
    points = np.asarray(points, dtype=float)
    if len(points) <= EVALUATION_CHUNK:
        return _evaluate_chunk(machine, points, criteria)
    return _concatenate([_evaluate_chunk(machine, points[k:k + EVALUATION_CHUNK], criteria)
                         for k in range(0, len(points), EVALUATION_CHUNK)])


def evaluate_grid(machine: Machine, grid: Grid, criteria: Criteria, *,
                  scheduler: Any = None) -> PoseEvaluation:
    """:func:`evaluate_poses` over every point of ``grid`` (flat, C order), generating the
    points chunk by chunk — in this process, or with ``scheduler`` (a Dask address, ``"local:N"``
    or a client, see :mod:`pkmkit.parallel`) in tasks of :data:`TASK_CHUNKS` chunks, each
    generating and evaluating its own points; the results are identical."""
    if scheduler is None:
        return _evaluate_range(0, grid.size, machine, grid, criteria)
    parts = map_chunks(_evaluate_range, grid.size, chunk=TASK_CHUNKS * EVALUATION_CHUNK,
                       scheduler=scheduler, args=(machine, grid, criteria))
    return parts[0] if len(parts) == 1 else _concatenate(parts)


#: Evaluation chunks per Dask task of :func:`evaluate_grid` (a task then takes ~0.1 s).
TASK_CHUNKS = 4


def _evaluate_range(start: int, stop: int, machine: Machine, grid: Grid,
                    criteria: Criteria) -> PoseEvaluation:
    """Grid points ``start:stop`` evaluated in chunks of :data:`EVALUATION_CHUNK`."""
    parts = [_evaluate_chunk(machine, grid.points_between(k, min(k + EVALUATION_CHUNK, stop)),
                             criteria)
             for k in range(start, stop, EVALUATION_CHUNK)]
    return parts[0] if len(parts) == 1 else _concatenate(parts)


def _concatenate(parts: list[PoseEvaluation]) -> PoseEvaluation:
    return PoseEvaluation(
        q=np.concatenate([p.q for p in parts]),
        factors=np.concatenate([p.factors for p in parts]),
        condition=np.concatenate([p.condition for p in parts]),
        masks={k: np.concatenate([p.masks[k] for p in parts]) for k in parts[0].masks})


def is_joint_chain(machine: Any) -> bool:
    """A joint-chain machine (numerical inverse model, closure-based velocity model)."""
    from pkmkit.machines.joint_chain import JointChainMachine

    return isinstance(machine, JointChainMachine)


def _evaluate_chunk(machine: Machine, points: np.ndarray, criteria: Criteria) -> PoseEvaluation:
    if is_joint_chain(machine):
        from pkmkit.analysis.chain_workspace import evaluate_chain_poses

        return evaluate_chain_poses(machine, points, criteria)
    inv = machine.ik(points, full_output=True)
    q = inv.q
    reachable = inv.status == Status.OK
    jac = machine.jacobian(points, q=q, tol=criteria.tol)
    sv = jac.singular_values
    lo_q, hi_q = criteria.limits(machine)
    with np.errstate(invalid="ignore"):
        strokes = reachable & ~(signed_excess(q, lo_q, hi_q) != 0).any(axis=1)
        if criteria.bounds is None:
            bounds = reachable.copy()
        else:
            bounds = reachable & criteria.within_bounds(sv)
        condition = reachable.copy() if criteria.kappa_max is None else (
            reachable & (jac.condition <= criteria.kappa_max))
    mode = (reachable & (np.sign(jac.det_A) == machine.working_mode)
            & (jac.parallel_measure >= criteria.tol))
    masks = {"reachable": reachable, "strokes": strokes, "bounds": bounds,
             "condition": condition, "mode": mode}
    return PoseEvaluation(q=q, factors=sv, condition=jac.condition, masks=masks)


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
        return ndimage.minimum_filter(mask.view(np.uint8), size=k, mode="constant",
                                      cval=0).astype(bool)

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


def _connected_part(feasible: np.ndarray, grid: Grid, home: np.ndarray) -> tuple[np.ndarray, str]:
    if not feasible.any():
        return feasible, "empty"
    structure = ndimage.generate_binary_structure(feasible.ndim, 1)
    labels, count = ndimage.label(feasible, structure=structure)
    index = grid.nearest_index(home)
    if index is not None and labels[index] > 0:
        return labels == labels[index], "home"
    sizes = ndimage.sum_labels(feasible, labels, index=np.arange(1, count + 1))
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
        inner = ndimage.binary_erosion(self.feasible, border_value=0)
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
                      refine: bool = False, scheduler: Any = None) -> WorkspaceMap:
    """Masks, feasible set and largest inscribed square/cube of ``machine`` over ``grid``.

    With ``refine=True`` the inscribed box found on the grid is refined in its centre and side
    to 10⁻⁴ of the side (:func:`refine_box`), which removes the grid's under-estimate (up to two
    steps) and its centring on grid points. ``scheduler``: evaluate the grid on Dask (see
    :func:`evaluate_grid`); the rest runs here."""
    criteria = criteria or Criteria()
    evaluation = evaluate_grid(machine, grid, criteria, scheduler=scheduler)
    shape = grid.shape
    masks = {k: v.reshape(shape) for k, v in evaluation.masks.items()}
    feasible = evaluation.feasible.reshape(shape)
    reference = "all parts"
    if criteria.connected:
        feasible, reference = _connected_part(feasible, grid, machine.home_pose)
    box = largest_inscribed_box(feasible, grid)
    # a joint-chain machine's criteria have no smooth slack (numerical inverse): grid box only
    if refine and box is not None and box.side > 0 and not is_joint_chain(machine):
        box = refine_box(machine, box, criteria, grid)
    box_check = None
    if box is not None and box.side > 0:
        box_check = check_region(machine, box.center, box.side, criteria, free=grid.free)
    return WorkspaceMap(
        grid=grid, masks=masks, feasible=feasible,
        q=evaluation.q.reshape((*shape, -1)), factors=evaluation.factors.reshape((*shape, -1)),
        condition=evaluation.condition.reshape(shape), reference=reference, criteria=criteria,
        inscribed=box, inscribed_check=box_check,
    )


def refine_box(machine: Machine, box: InscribedBox, criteria: Criteria, grid: Grid, *,
               rtol: float = INSCRIBED_RTOL) -> InscribedBox:
    """Refine a feasible square/cube in all its unknowns — centre and side — beyond the grid.

    The box is a lattice of :func:`check_region` (41 points per edge for a square, 25 for a
    cube, edges and corners included) whose points move with the centre and the side; each
    criterion has a signed slack at each point (:func:`criteria_slack`), and the side is
    maximised under "every slack ≥ 0" and "inside the grid's box" by SLSQP
    (:func:`pkmkit.analysis.inscribed.largest_box`). The optimum is then checked with the
    boolean criteria and, if rounding left a point failing, shrunk about its centre by
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

    def feasible(c: np.ndarray, half: float) -> bool:
        if half <= 0:
            return True
        lattice = region_grid(machine, _full(box.center, free, c), 2.0 * half, grid.free,
                              samples)
        return bool(evaluate_poses(machine, lattice.points, criteria).feasible.all())

    center, half = largest_box(slack, full_points, box.center[free], 0.5 * box.side,
                               grid.lower_bounds, grid.upper_bounds, samples=samples,
                               rtol=rtol)
    start = (box.center[free], 0.5 * box.side)
    if not feasible(center, half):  # rounding at the optimum: shrink about its centre
        for cut in (1e-10, 1e-8, 1e-6, 1e-5):
            if feasible(center, half * (1.0 - cut)):
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
        return bool(evaluate_poses(machine, points, criteria).feasible.all())

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


def study_length(machine: Machine) -> float:
    """A length (m) that sizes the machine: its longest leg or rod, else (struts whose length
    is the actuator, a hexapod's) its longest finite stroke end, else 1 m. It scales the
    length slacks of :func:`criteria_slack` and the search of :func:`feasible_interval`."""
    leg = float(np.max(machine.model.leg_length, initial=0.0))
    if leg > 0:
        return leg
    q_max = np.asarray(machine.model.q_max, dtype=float)
    quantities = getattr(machine.model, "actuator_quantities", ("length",) * q_max.size)
    ends = [abs(v) for v, kind in zip(q_max, quantities, strict=False)
            if kind == "length" and np.isfinite(v)]
    return max(ends, default=0.0) or 1.0


def _surface_offsets(d: int, per_edge: int) -> np.ndarray:
    """Points of the faces of ``[-1, 1]^d``, ``per_edge`` per edge (duplicates removed)."""
    axis = np.linspace(-1.0, 1.0, per_edge)
    faces = []
    for k in range(d):
        grids = np.meshgrid(*([axis] * (d - 1)), indexing="ij")
        inner = np.stack([g.ravel() for g in grids], axis=-1) if d > 1 else np.zeros((1, 0))
        for side in (-1.0, 1.0):
            face = np.insert(inner, k, side, axis=1)
            faces.append(face)
    return np.unique(np.concatenate(faces), axis=0)


def _full(base: np.ndarray, free: list[int], values: np.ndarray) -> np.ndarray:
    out = np.array(base, dtype=float)
    out[free] = values
    return out


def criteria_slack(machine: Machine, points: np.ndarray, criteria: Criteria,
                   length: float) -> np.ndarray:
    """``(M,)`` smallest signed slack of the criteria at poses ``points (M, dims)``: ≥ 0 where
    :func:`evaluate_poses` finds every criterion met (connectivity aside; the factor bounds
    without their rounding allowance ``criteria.rtol``), < 0 elsewhere,
    varying smoothly with the pose between changes of the limiting criterion. Lengths
    (reachability shortfall, strokes) are divided by ``length``; factor bounds and the
    condition number are relative; the assembly mode is the signed parallel measure minus its
    threshold."""
    inv = machine.ik(points, full_output=True)
    q = inv.q
    reach = -np.max(inv.shortfall, axis=1) / length
    jac = machine.jacobian(points, q=q, tol=criteria.tol)
    parts = [reach]
    lo_q, hi_q = criteria.limits(machine)
    with np.errstate(invalid="ignore"):
        stroke = np.minimum((q - lo_q[None]).min(axis=1), (hi_q[None] - q).min(axis=1))
        parts.append(np.minimum(stroke / length, 1e3))
        if criteria.bounds is not None:
            lo, hi = criteria.bounds
            sv = jac.singular_values
            # the bounds themselves, not their rounding allowance: a refined box touching a
            # bound stays within it
            parts.append(sv[:, -1] / lo - 1.0)
            parts.append(1.0 - sv[:, 0] / hi)
        if criteria.kappa_max is not None:
            parts.append(1.0 - jac.condition / criteria.kappa_max)
        side = np.sign(jac.det_A) * machine.working_mode
        parts.append(np.where(side > 0, jac.parallel_measure, -jac.parallel_measure)
                     - criteria.tol)
    out = np.min(np.column_stack(parts), axis=1)
    # where the pose is unreachable the other criteria are NaN: the reach slack decides
    unreachable = inv.status != Status.OK
    out[unreachable] = np.minimum(reach[unreachable], -1e-12)
    return np.where(np.isnan(out), -1.0, out)


def check_region_samples(free_axes: int) -> int:
    """Lattice points per edge of :func:`check_region` for a square (2 free axes) or a cube."""
    return 41 if free_axes <= 2 else 25


@dataclass(frozen=True)
class RegionCheck:
    """Dense verification of a prescribed square/cube.

    Attributes:
        feasible: every sample satisfies every criterion, with no sign change of det A.
        samples: number of samples checked.
        failures: ``{criterion: number of failing samples}``.
        worst: ``{criterion: description of the worst violation with its pose}``.
        factor_range: (min, max) velocity transmission factor over the reachable samples.
        q_range: ``(q_lo (n,), q_hi (n,))`` actuator coordinates needed over the region.
    """

    feasible: bool
    samples: int
    failures: dict[str, int]
    worst: dict[str, str]
    factor_range: tuple[float, float]
    q_range: tuple[np.ndarray, np.ndarray]


def region_grid(machine: Machine, center: Any, side: float, free: tuple[int, ...] | None = None,
                samples: int | None = None) -> Grid:
    """Grid of ``samples`` points per edge over the square/cube of ``side`` centred at
    ``center``; ``free`` defaults to every pose coordinate."""
    # a machine that takes positions alone (a Verne-type module) may be given a position
    widths = {machine.dims} | ({3} if getattr(machine, "position_controlled", False) else set())
    expected = " or ".join(str(w) for w in sorted(widths))
    try:
        center = np.asarray(center, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(f"the centre must be {expected} finite coordinates, got "
                         f"{center!r}") from None
    if center.shape[0] not in widths or not np.isfinite(center).all():
        raise InputError(f"the centre must be {expected} finite coordinates")
    side = real(side, "the side", positive=True, limit=1e6)
    free = tuple(range(len(center))) if free is None else free
    samples = samples or check_region_samples(len(free))
    lower = [center[k] - side / 2 for k in free]
    upper = [center[k] + side / 2 for k in free]
    return make_grid(lower, upper, free=free, base=center,
                     names=machine.pose_names[:len(center)], resolution=samples)


def check_region(machine: Machine, center: Any, side: float, criteria: Criteria | None = None,
                 *, free: tuple[int, ...] | None = None, samples: int | None = None
                 ) -> RegionCheck:
    """Is the axis-aligned square/cube of ``side`` centred at ``center`` usable, and where does
    it fail? Checks ``samples`` points per edge (faces included).

    The Orthoglide prototype's 0.2 m cube under 1/2 ≤ λ ≤ 2 (seed 001), and a larger one:

    >>> import pkmkit
    >>> m = pkmkit.machine("orthoglide")
    >>> c = -0.0267446 * np.ones(3)
    >>> check_region(m, c, 0.199, Criteria(bounds=(0.5, 2.0))).feasible
    True
    >>> check = check_region(m, c, 0.21, Criteria(bounds=(0.5, 2.0)))
    >>> check.feasible, sorted(check.failures)
    (False, ['bounds', 'strokes'])
    """
    criteria = criteria or Criteria()
    grid = region_grid(machine, center, side, free, samples)
    points = grid.points
    ev = evaluate_poses(machine, points, criteria)
    failures: dict[str, int] = {}
    worst: dict[str, str] = {}
    names = machine.actuator_names
    for name in MASK_NAMES:
        bad = ~ev.masks[name]
        if name != "reachable":
            bad &= ev.masks["reachable"]
        if not bad.any():
            continue
        failures[name] = int(bad.sum())
        worst[name] = _worst(name, bad, points, ev, criteria, machine, names)
    reach = ev.masks["reachable"]
    if reach.any():
        lo_q, hi_q = _q_extremes(machine, grid, ev.q, reach)
    else:
        lo_q = hi_q = np.full(len(names), np.nan)
    factor_range = ((float(np.nanmin(ev.factors[reach])), float(np.nanmax(ev.factors[reach])))
                    if reach.any() else (float("nan"), float("nan")))
    return RegionCheck(feasible=not failures, samples=len(points), failures=failures,
                       worst=worst, factor_range=factor_range, q_range=(lo_q, hi_q))


def _bounded_minimum(fun: Callable[[np.ndarray], float], start: np.ndarray,
                     bounds: list[tuple[float, float]], fallback: float) -> float:
    """Local minimum of ``fun`` from ``start`` within ``bounds`` (L-BFGS-B).

    ``fun`` returns NaN where it is undefined (unreachable pose, no assembly): such points are
    given the finite value ``fallback + 1`` (worse than the start, whose value is ``fallback``)
    so that the finite-difference gradients stay finite. Numerical warnings of the optimiser are
    kept from the user. Returns the smallest *defined* value found (at least as good as
    ``fallback``)."""
    from scipy.optimize import minimize

    best = [fallback]

    def value(y: np.ndarray) -> float:
        v = float(fun(y))
        if not np.isfinite(v):
            return fallback + 1.0 + abs(fallback)
        best[0] = min(best[0], v)
        return v

    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)
        minimize(value, start, method="L-BFGS-B", bounds=bounds,
                 options={"maxiter": 100, "ftol": 1e-15, "gtol": 1e-12})
    return best[0]


def _grid_bounds(grid: Grid) -> list[tuple[float, float]]:
    return [(float(lo), float(max(hi, axis[-1]))) for lo, hi, axis in
            zip(grid.lower_bounds, grid.upper_bounds, grid.axes, strict=True)]


def _full_point(grid: Grid, y: np.ndarray) -> np.ndarray:
    full = grid.base.copy()
    full[list(grid.free)] = y
    return full


def _column_extremes(grid: Grid, values: np.ndarray, fun: Callable[[np.ndarray], np.ndarray],
                     columns: list[tuple[int, float]]) -> list[float]:
    """Refined extremes of columns of ``values (M, k)`` sampled at ``grid.points``:
    ``columns`` lists ``(column, sign)``, sign +1 for the minimum, −1 for the maximum; ``fun``
    maps a full point ``(dims,)`` to a row ``(k,)`` (NaN where undefined)."""
    points_free = list(grid.free)
    bounds = _grid_bounds(grid)
    out = []
    for column, sign in columns:
        signed = sign * values[:, column]
        if not np.isfinite(signed).any():
            out.append(float("nan"))
            continue
        start = int(np.nanargmin(signed))
        found = _bounded_minimum(
            lambda y, c=column, s=sign: s * fun(_full_point(grid, y))[c],
            grid.point(np.unravel_index(start, grid.shape))[points_free], bounds,
            float(signed[start]))
        out.append(sign * found)
    return out


def _q_extremes(machine: Machine, grid: Grid, q: np.ndarray, reach: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest value of each actuator coordinate over the region: the sampled
    extremes, refined by bounded local optimisation (they may lie between samples, e.g. inside
    a face)."""
    values = np.where(reach[:, None], q, np.nan)
    n = q.shape[1]
    found = _column_extremes(grid, values, lambda x: machine.ik(x[None])[0],
                             [(k, s) for k in range(n) for s in (1.0, -1.0)])
    return np.array(found[0::2]), np.array(found[1::2])


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def _worst(name: str, bad: np.ndarray, points: np.ndarray, ev: PoseEvaluation,
           criteria: Criteria, machine: Machine, names) -> str:
    idx = np.flatnonzero(bad)
    if is_joint_chain(machine) and name in ("reachable", "strokes"):
        what = ("the inverse model closes no loop there" if name == "reachable" else
                "a joint (actuator or passive) leaves its range")
        return f"at {_fmt(points[idx[0]])}: {what} ({len(idx)} samples)"
    if name == "reachable":
        short = machine._closed.shortfall(points[idx])
        k = int(np.nanargmax(short.max(axis=1)))
        leg = int(np.nanargmax(short[k]))
        return (f"at {_fmt(points[idx[k]])}: {machine.model.leg_names[leg]} too short by "
                f"{short[k, leg]:.6g} m")
    if name == "strokes":
        lo, hi = criteria.limits(machine)
        excess = np.maximum(lo - ev.q[idx], ev.q[idx] - hi)
        k, a = np.unravel_index(int(np.nanargmax(excess)), excess.shape)
        side = "below q_min" if ev.q[idx[k], a] < lo[a] else "above q_max"
        return (f"at {_fmt(points[idx[k]])}: {names[a]} = {ev.q[idx[k], a]:.6g} m is {side} "
                f"by {excess[k, a]:.6g} m")
    if name == "bounds":
        lo, hi = criteria.bounds
        ratio = np.maximum(lo / ev.factors[idx, -1], ev.factors[idx, 0] / hi)
        k = int(np.nanargmax(ratio))
        f = ev.factors[idx[k]]
        which = f"λ_min = {f[-1]:.6g} < {lo:g}" if f[-1] < lo else f"λ_max = {f[0]:.6g} > {hi:g}"
        return f"at {_fmt(points[idx[k]])}: {which}"
    if name == "condition":
        k = int(np.nanargmax(ev.condition[idx]))
        return (f"at {_fmt(points[idx[k]])}: condition {ev.condition[idx[k]]:.6g} > "
                f"{criteria.kappa_max:g}")
    k = 0
    return (f"at {_fmt(points[idx[k]])}: other assembly mode or parallel singularity "
            f"({len(idx)} samples)")


def feasible_interval(machine: Machine, point: Any, direction: Any, criteria: Criteria,
                      *, reach: float | None = None, samples: int = 2001) -> tuple[float, float]:
    """Interval ``(t_lo, t_hi)`` of the line ``point + t·direction`` around t = 0 where every
    criterion holds (``connected`` is implied: the interval contains 0), each end refined by
    bisection to machine precision.

    For the Orthoglide, the ends along the cube diagonal from the isotropic point are the
    reference points Q1 and Q2 of seed 001's sizing method.

    Raises:
        InputError: the criteria fail at ``point`` itself.
    """
    point = np.asarray(point, dtype=float)
    direction = np.asarray(direction, dtype=float)
    reach = reach or 2.0 * study_length(machine)
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max,
                     strokes=criteria.strokes, q_limits=criteria.q_limits, connected=False,
                     tol=criteria.tol, rtol=0.0)  # the ends are located exactly

    def ok(t: np.ndarray) -> np.ndarray:
        return evaluate_poses(machine, point + np.outer(t, direction), loose).feasible

    if not ok(np.zeros(1))[0]:
        raise InputError(f"the criteria fail at {point.tolist()} itself")
    ends = []
    for sign in (-1.0, 1.0):
        t = sign * np.linspace(0.0, reach, samples)
        good = ok(t)
        first_bad = int(np.argmin(good)) if not good.all() else None
        if first_bad is None:
            ends.append(t[-1])
            continue
        inside, outside = t[first_bad - 1], t[first_bad]
        for _ in range(60):
            mid = 0.5 * (inside + outside)
            inside, outside = (mid, outside) if ok(np.array([mid]))[0] else (inside, mid)
            if abs(outside - inside) <= 1e-15 * max(1.0, abs(inside)):
                break
        ends.append(inside)
    return float(ends[0]), float(ends[1])


@dataclass(frozen=True)
class JointSpaceMap:
    """Feasible set in actuator space and its image in the workspace.

    Attributes:
        grid: grid over the actuator coordinates.
        masks: ``{"assembly", "bounds", "condition", "mode"}`` masks of shape ``grid.shape``.
        feasible: all masks, connected to the home actuator vector if requested.
        poses: ``grid.shape + (dims,)`` direct model in the working mode (NaN if none).
        factors: ``grid.shape + (n,)`` velocity transmission factors.
        reference: which connected part was kept.
        inscribed: largest square/cube of actuator vectors in ``feasible``.
    """

    grid: Grid
    masks: dict[str, np.ndarray]
    feasible: np.ndarray
    poses: np.ndarray
    factors: np.ndarray
    reference: str
    inscribed: InscribedBox | None


def _evaluate_joint(machine: Machine, q: np.ndarray, criteria: Criteria
                    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Criteria at actuator vectors ``q (M, n)``: flat masks ``{"assembly", "bounds",
    "condition", "mode"}``, poses ``(M, dims)`` (direct model, working mode; NaN where there is
    no assembly) and transmission factors ``(M, n)`` (NaN there)."""
    res = machine.fk(q, full_output=True)
    assembly = res.status == Status.OK
    jac = machine.jacobian(np.where(assembly[:, None], res.pose, machine.home_pose), q=q,
                           tol=criteria.tol)
    sv = np.where(assembly[:, None], jac.singular_values, np.nan)
    with np.errstate(invalid="ignore"):
        if criteria.bounds is None:
            bounds = assembly.copy()
        else:
            bounds = assembly & criteria.within_bounds(sv)
        condition = assembly.copy() if criteria.kappa_max is None else (
            assembly & (jac.condition <= criteria.kappa_max))
    mode = assembly & (jac.parallel_measure >= criteria.tol)
    masks = {"assembly": assembly, "bounds": bounds, "condition": condition, "mode": mode}
    return masks, res.pose, sv


def joint_space_map(machine: Machine, grid: Grid, criteria: Criteria | None = None
                    ) -> JointSpaceMap:
    """Evaluate the criteria over a grid of actuator vectors (direct model, working mode)."""
    criteria = criteria or Criteria()
    flat, poses, sv = _evaluate_joint(machine, grid.points, criteria)
    shape = grid.shape
    masks = {k: v.reshape(shape) for k, v in flat.items()}
    feasible = np.logical_and.reduce(list(masks.values()))
    reference = "all parts"
    if criteria.connected:
        feasible, reference = _connected_part(feasible, grid, machine.home_q)
    return JointSpaceMap(grid=grid, masks=masks, feasible=feasible,
                         poses=poses.reshape((*shape, -1)), factors=sv.reshape((*shape, -1)),
                         reference=reference, inscribed=largest_inscribed_box(feasible, grid))


def joint_grid(machine: Machine, lower: Any = None, upper: Any = None,
               resolution: int = 201) -> Grid:
    """Grid over the actuator box (default: the strokes)."""
    lower = machine.model.q_min if lower is None else lower
    upper = machine.model.q_max if upper is None else upper
    if not (np.isfinite(lower).all() and np.isfinite(upper).all()):
        raise InputError("the actuator box needs finite limits (set the strokes or give them)")
    n = machine.n_actuators
    return make_grid(lower, upper, free=tuple(range(n)), base=np.zeros(n),
                     names=machine.actuator_names, resolution=resolution)


def _joint_samples(n: int) -> int:
    """Samples per edge of the dense checks of a joint square (2 actuators) or cube (3)."""
    return 61 if n <= 2 else 21


def _joint_square_ok(machine: Machine, criteria: Criteria, center: np.ndarray, half: float,
                     samples: int | None = None) -> bool:
    """Every criterion holds on a dense lattice (edges and corners included) of the joint box
    ``center ± half``; ``half = 0`` checks ``center`` alone."""
    n = machine.n_actuators
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max, connected=False,
                     tol=criteria.tol)
    if half <= 0:
        masks, _, _ = _evaluate_joint(machine, center[None], loose)
        return bool(np.logical_and.reduce(list(masks.values()))[0])
    grid = make_grid(center - half, center + half, free=tuple(range(n)), base=center,
                     names=machine.actuator_names, resolution=samples or _joint_samples(n))
    masks, _, _ = _evaluate_joint(machine, grid.points, loose)
    return bool(np.logical_and.reduce(list(masks.values())).all())


def _centred_joint_square(machine: Machine, criteria: Criteria, grid: Grid,
                          square: InscribedBox | None) -> InscribedBox:
    """Largest joint square/cube centred at home, to within 1e-6 of a grid step.

    The grid square (``square``, possibly of side 0 or None on a coarse grid) gives a bracket:
    its half-side is feasible on the grid and one more step is not (or leaves the grid). Both
    ends are checked densely (the upper one moved out step by step while it passes) and the
    half-side is bisected between a densely feasible value and an infeasible one, so a coarse
    grid does not decide the answer. The edge of the joint grid caps the square.

    Raises:
        InputError: the criteria fail at the home configuration itself.
    """
    center = machine.home_q
    if not _joint_square_ok(machine, criteria, center, 0.0):
        masks, _, sv = _evaluate_joint(machine, center[None], criteria)
        failing = ", ".join(k for k, v in masks.items() if not v[0])
        raise InputError(
            f"the criteria fail at the home configuration q = {_fmt(center)} ({failing}; "
            f"transmission factors {_fmt(sv[0])}): no useful zone can be centred there")
    radius = 0 if square is None else (square.points_per_side - 1) // 2
    room = float(np.min(np.minimum(center - grid.lower_bounds, grid.upper_bounds - center)))
    good, bad = 0.0, min((radius + 1) * grid.step, room)
    grid_half = radius * grid.step
    if grid_half > 0:
        if _joint_square_ok(machine, criteria, center, grid_half):
            good = grid_half
        else:
            bad = grid_half
    # grow by whole steps while the dense check passes (the grid may have missed room between
    # its points), up to the edge of the joint grid, which then limits the square
    while bad > good and _joint_square_ok(machine, criteria, center, bad):
        good, bad = bad, min(bad + grid.step, room)
    for _ in range(60):  # bisection between densely feasible and infeasible half-sides
        if not bad - good > 1e-6 * grid.step:
            break
        mid = 0.5 * (good + bad)
        if _joint_square_ok(machine, criteria, center, mid):
            good = mid
        else:
            bad = mid
    if good <= 0:
        raise InputError(f"no usable actuator square around the home configuration "
                         f"q = {_fmt(center)}: the criteria fail arbitrarily close to it")
    n = machine.n_actuators
    return InscribedBox(side=2 * good, center=center.copy(), lower=center - good,
                        points_per_side=max(2 * radius + 1, _joint_samples(n)))


def joint_box_factor_range(machine: Machine, lower: Any, upper: Any, *,
                           samples: int | None = None) -> tuple[float, float]:
    """(smallest λ_min, largest λ_max) over the image of the actuator box ``[lower, upper]``
    (direct model, working mode), m/m.

    The factors are sampled on a lattice of the box that contains its edges and corners
    (``samples`` per edge; default 201 for 2 actuators, 41 for 3), and the best sample of each
    extreme is refined by bounded optimisation (L-BFGS-B) over the box, so an extreme between
    samples or on an edge is found to optimiser precision. This is the exact range over a useful
    workspace, the image of its joint square — a grid in the *workspace* only approaches it
    from inside, one step short of the boundary.
    """
    lower = np.asarray(lower, dtype=float)
    upper = np.asarray(upper, dtype=float)
    n = machine.n_actuators
    grid = make_grid(lower, upper, free=tuple(range(n)), base=lower,
                     names=machine.actuator_names,
                     resolution=samples or (201 if n <= 2 else 41))
    loose = Criteria(connected=False)

    def factors(q: np.ndarray) -> np.ndarray:
        return _evaluate_joint(machine, np.atleast_2d(q), loose)[2]

    values = factors(grid.points)
    lo, hi = _column_extremes(grid, values, lambda q: factors(q)[0],
                              [(n - 1, 1.0), (0, -1.0)])
    return float(lo), float(hi)


def region_factor_range(machine: Machine, center: Any, side: float, *,
                        free: tuple[int, ...] | None = None, samples: int | None = None
                        ) -> tuple[float, float]:
    """(smallest λ_min, largest λ_max) over the reachable poses of the square/cube of ``side``
    centred at ``center``: sampled (faces included) then refined by bounded optimisation."""
    grid = region_grid(machine, center, side, free, samples)
    values = machine.jacobian(grid.points).singular_values
    lo, hi = _column_extremes(grid, values,
                              lambda x: machine.jacobian(x[None]).singular_values[0],
                              [(machine.n_actuators - 1, 1.0), (0, -1.0)])
    return float(lo), float(hi)


@dataclass(frozen=True)
class UsefulWorkspace:
    """Seed 004's procedure: a square of actuator values where the criteria hold (the *useful
    zone*), its image in the workspace (the *useful workspace*), and the square inscribed in it.
    With 3 actuators the same with cubes.

    Attributes:
        joint: the joint-space map the square was taken from.
        joint_square: the useful zone (an :class:`InscribedBox` in actuator coordinates).
        workspace: workspace map of the image (actuator limits = the joint square).
        inscribed: largest square inscribed in the useful workspace.
        factor_range: (min λ_min, max λ_max) over the useful workspace, exact
            (:func:`joint_box_factor_range`).
        inscribed_factor_range: the same over the inscribed square (sampled and refined,
            :func:`region_factor_range`), or the grid range when there is no inscribed square.
    """

    joint: JointSpaceMap
    joint_square: InscribedBox
    workspace: WorkspaceMap
    inscribed: InscribedBox | None
    factor_range: tuple[float, float]
    inscribed_factor_range: tuple[float, float]


def useful_workspace(machine: Machine, criteria: Criteria, *, joint_lower: Any = None,
                     joint_upper: Any = None, centred: bool = True, resolution: int = 301
                     ) -> UsefulWorkspace:
    """Useful zone in joint space, its image and the square/cube inscribed in the image.

    Works for 2 actuators (squares, seed 004) and 3 (cubes; keep ``resolution`` near 41–61:
    both grids have ``resolution`` points per side).

    Args:
        machine: any machine.
        criteria: criteria on the transmission factors / conditioning (strokes are replaced by
            the joint square).
        joint_lower, joint_upper: actuator box searched (default: home ± 2 × the longest leg).
        centred: the joint square is centred at the home configuration (seed 004: joint stops
            placed symmetrically about the isotropic configuration) and sized by bisection with
            dense checks, whatever the grid (a coarse grid only slows the bisection); otherwise
            the largest square of grid points anywhere.
        resolution: grid points along the longest side, in joint space and in the workspace.

    Raises:
        InputError: the criteria fail at home (centred), or no joint square of at least two grid
            points per side is feasible (not centred).
    """
    reach = 2.0 * float(machine.model.leg_length.max())
    lo = machine.home_q - reach if joint_lower is None else np.asarray(joint_lower, float)
    hi = machine.home_q + reach if joint_upper is None else np.asarray(joint_upper, float)
    joint = joint_space_map(machine, joint_grid(machine, lo, hi, resolution), criteria)
    if centred:
        square = largest_inscribed_box(joint.feasible, joint.grid, center=machine.home_q)
        square = _centred_joint_square(machine, criteria, joint.grid, square)
    else:
        square = largest_inscribed_box(joint.feasible, joint.grid)
        if square is None or square.side == 0:
            raise InputError("no square of actuator values with two grid points per side "
                             "satisfies the criteria; raise the resolution or relax them")
    q_lo, q_hi = square.lower, square.lower + square.side
    samples = make_grid(q_lo, q_hi, free=tuple(range(machine.n_actuators)), base=q_lo,
                        names=machine.actuator_names,
                        resolution=101 if machine.n_actuators <= 2 else 31)
    frame = pose_frame(machine)  # positions (a Verne-type module's orientation follows)
    image = machine.fk(samples.points)[:, :frame.positions]
    p_lo, p_hi = np.nanmin(image, axis=0), np.nanmax(image, axis=0)
    margin = 0.02 * float((p_hi - p_lo).max())
    grid = make_grid(p_lo - margin, p_hi + margin, free=tuple(range(frame.positions)),
                     base=frame.base, names=frame.names, resolution=resolution)
    limited = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max,
                       q_limits=(q_lo, q_hi), connected=criteria.connected, tol=criteria.tol)
    ws = compute_workspace(machine, grid, limited, refine=True)
    box = ws.inscribed
    inscribed_range = (region_factor_range(machine, box.center, box.side, free=grid.free)
                       if box is not None and box.side > 0 else ws.factor_range())
    return UsefulWorkspace(joint=joint, joint_square=square, workspace=ws, inscribed=box,
                           factor_range=joint_box_factor_range(machine, q_lo, q_hi),
                           inscribed_factor_range=inscribed_range)
