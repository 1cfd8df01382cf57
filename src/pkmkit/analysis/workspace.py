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
from scipy import ndimage

from pkmkit.analysis.grids import Grid, make_grid
from pkmkit.errors import InputError
from pkmkit.machines.machine import SINGULARITY_TOL, Machine
from pkmkit.status import Status

MASK_NAMES = ("reachable", "strokes", "bounds", "condition", "mode")


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
    """

    bounds: tuple[float, float] | None = None
    kappa_max: float | None = None
    strokes: bool = True
    q_limits: tuple[np.ndarray, np.ndarray] | None = None
    connected: bool = True
    tol: float = SINGULARITY_TOL

    def __post_init__(self) -> None:
        if self.bounds is not None:
            lo, hi = self.bounds
            if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
                raise InputError(
                    f"transmission-factor bounds must satisfy 0 < lo < hi, got {self.bounds}"
                )
        if self.kappa_max is not None and not self.kappa_max >= 1:
            raise InputError(f"kappa_max must be >= 1, got {self.kappa_max}")

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


def evaluate_poses(machine: Machine, points: np.ndarray, criteria: Criteria) -> PoseEvaluation:
    """Evaluate the criteria (without connectivity) at poses ``points (M, dims)``."""
    inv = machine.ik(points, full_output=True)
    q = inv.q
    reachable = inv.status == Status.OK
    jac = machine.jacobian(points, q=q, tol=criteria.tol)
    sv = jac.singular_values
    lo_q, hi_q = criteria.limits(machine)
    with np.errstate(invalid="ignore"):
        strokes = reachable & ((q >= lo_q) & (q <= hi_q)).all(axis=1)
        if criteria.bounds is None:
            bounds = reachable.copy()
        else:
            lo, hi = criteria.bounds
            bounds = reachable & (sv[:, -1] >= lo) & (sv[:, 0] <= hi)
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
        """Area (2 free axes) or volume (3) of the feasible set, grid-estimated."""
        return float(self.feasible.sum()) * self.grid.cell_measure

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


def compute_workspace(machine: Machine, grid: Grid, criteria: Criteria | None = None, *,
                      refine: bool = False) -> WorkspaceMap:
    """Masks, feasible set and largest inscribed square/cube of ``machine`` over ``grid``.

    With ``refine=True`` the inscribed box found on the grid is grown about its centre by
    bisection with dense checks (:func:`check_region`), which removes most of the grid's
    under-estimate (up to two steps)."""
    criteria = criteria or Criteria()
    evaluation = evaluate_poses(machine, grid.points, criteria)
    shape = grid.shape
    masks = {k: v.reshape(shape) for k, v in evaluation.masks.items()}
    feasible = evaluation.feasible.reshape(shape)
    reference = "all parts"
    if criteria.connected:
        feasible, reference = _connected_part(feasible, grid, machine.home_pose)
    box = largest_inscribed_box(feasible, grid)
    if refine and box is not None and box.side > 0:
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


def refine_box(machine: Machine, box: InscribedBox, criteria: Criteria, grid: Grid
               ) -> InscribedBox:
    """Grow a feasible square/cube about its centre, by bisection on the side between the grid
    result and two grid steps more, each candidate checked densely."""
    def ok(side: float) -> bool:
        return check_region(machine, box.center, side, criteria, free=grid.free).feasible

    good, bad = box.side, box.side + 2 * grid.step
    if not ok(good):
        return box
    if ok(bad):
        good = bad
    else:
        for _ in range(12):
            mid = 0.5 * (good + bad)
            good, bad = (mid, bad) if ok(mid) else (good, mid)
    lower = box.center.copy()
    for axis in grid.free:
        lower[axis] -= 0.5 * good
    return InscribedBox(side=float(good), center=box.center, lower=lower,
                        points_per_side=box.points_per_side)


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
    center = np.asarray(center, dtype=float).reshape(-1)
    if center.shape != (machine.dims,) or not np.isfinite(center).all():
        raise InputError(f"the centre must be {machine.dims} finite coordinates")
    if not side > 0:
        raise InputError(f"the side must be > 0, got {side}")
    free = tuple(range(machine.dims)) if free is None else free
    samples = samples or (41 if len(free) <= 2 else 25)
    lower = [center[k] - side / 2 for k in free]
    upper = [center[k] + side / 2 for k in free]
    return make_grid(lower, upper, free=free, base=center, names=machine.pose_names,
                     resolution=samples)


def check_region(machine: Machine, center: Any, side: float, criteria: Criteria | None = None,
                 *, free: tuple[int, ...] | None = None, samples: int | None = None
                 ) -> RegionCheck:
    """Is the axis-aligned square/cube of ``side`` centred at ``center`` usable, and where does
    it fail? Checks ``samples`` points per edge (faces included)."""
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


def _q_extremes(machine: Machine, grid: Grid, q: np.ndarray, reach: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest value of each actuator coordinate over the region: the sampled
    extremes, refined by bounded local optimisation (they may lie between samples, e.g. inside
    a face)."""
    from scipy.optimize import minimize

    points = grid.points
    bounds = [(axis[0], axis[-1]) for axis in grid.axes]

    def pose(y: np.ndarray) -> np.ndarray:
        full = grid.base.copy()
        full[list(grid.free)] = y
        return full

    lo = np.nanmin(np.where(reach[:, None], q, np.nan), axis=0)
    hi = np.nanmax(np.where(reach[:, None], q, np.nan), axis=0)
    for k in range(q.shape[1]):
        for sign, store in ((1.0, lo), (-1.0, hi)):
            start = int(np.nanargmin(sign * np.where(reach, q[:, k], np.nan)))

            def value(y: np.ndarray, k: int = k, sign: float = sign) -> float:
                qk = machine.ik(pose(y)[None])[0, k]
                return sign * qk if np.isfinite(qk) else np.inf

            res = minimize(value, points[start, list(grid.free)], method="L-BFGS-B",
                           bounds=bounds, options={"maxiter": 100, "ftol": 1e-15, "gtol": 1e-12})
            found = sign * res.fun  # the actuator coordinate reached
            if np.isfinite(found) and sign * found < sign * store[k]:
                store[k] = found
    return lo, hi


def _fmt(p: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


def _worst(name: str, bad: np.ndarray, points: np.ndarray, ev: PoseEvaluation,
           criteria: Criteria, machine: Machine, names) -> str:
    idx = np.flatnonzero(bad)
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
    reach = reach or 2.0 * float(machine.model.leg_length.max())
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max,
                     strokes=criteria.strokes, q_limits=criteria.q_limits, connected=False,
                     tol=criteria.tol)

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


def joint_space_map(machine: Machine, grid: Grid, criteria: Criteria | None = None
                    ) -> JointSpaceMap:
    """Evaluate the criteria over a grid of actuator vectors (direct model, working mode)."""
    criteria = criteria or Criteria()
    q = grid.points
    res = machine.fk(q, full_output=True)
    assembly = res.status == Status.OK
    jac = machine.jacobian(np.where(assembly[:, None], res.pose, machine.home_pose), q=q,
                           tol=criteria.tol)
    sv = np.where(assembly[:, None], jac.singular_values, np.nan)
    with np.errstate(invalid="ignore"):
        if criteria.bounds is None:
            bounds = assembly.copy()
        else:
            bounds = assembly & (sv[:, -1] >= criteria.bounds[0]) & (sv[:, 0] <= criteria.bounds[1])
        condition = assembly.copy() if criteria.kappa_max is None else (
            assembly & (jac.condition <= criteria.kappa_max))
    mode = assembly & (jac.parallel_measure >= criteria.tol)
    shape = grid.shape
    masks = {"assembly": assembly.reshape(shape), "bounds": bounds.reshape(shape),
             "condition": condition.reshape(shape), "mode": mode.reshape(shape)}
    feasible = np.logical_and.reduce(list(masks.values()))
    reference = "all parts"
    if criteria.connected:
        feasible, reference = _connected_part(feasible, grid, machine.home_q)
    return JointSpaceMap(grid=grid, masks=masks, feasible=feasible,
                         poses=res.pose.reshape((*shape, -1)), factors=sv.reshape((*shape, -1)),
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


def _joint_square_ok(machine: Machine, criteria: Criteria, center: np.ndarray, half: float,
                     samples: int = 61) -> bool:
    n = machine.n_actuators
    grid = make_grid(center - half, center + half, free=tuple(range(n)), base=center,
                     names=machine.actuator_names, resolution=samples)
    loose = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max, connected=False,
                     tol=criteria.tol)
    return bool(joint_space_map(machine, grid, loose).feasible.all())


def _refine_centred_square(machine: Machine, criteria: Criteria, square: InscribedBox,
                           step: float) -> InscribedBox:
    """Bisection on the half-side between the grid result (feasible) and one step more."""
    center = square.center
    good, bad = 0.5 * square.side, 0.5 * square.side + step
    if _joint_square_ok(machine, criteria, center, bad):
        return square  # the grid edge, not the criteria, limited the square
    for _ in range(30):
        mid = 0.5 * (good + bad)
        if _joint_square_ok(machine, criteria, center, mid):
            good = mid
        else:
            bad = mid
        if bad - good < 1e-6 * step:
            break
    return InscribedBox(side=2 * good, center=center, lower=center - good,
                        points_per_side=square.points_per_side)


@dataclass(frozen=True)
class UsefulWorkspace:
    """Seed 004's procedure: a square of actuator values where the criteria hold (the *useful
    zone*), its image in the workspace (the *useful workspace*), and the square inscribed in it.

    Attributes:
        joint: the joint-space map the square was taken from.
        joint_square: the useful zone (an :class:`InscribedBox` in actuator coordinates).
        workspace: workspace map of the image (actuator limits = the joint square).
        inscribed: largest square inscribed in the useful workspace.
        factor_range: (min, max) transmission factor over the useful workspace.
        inscribed_factor_range: (min, max) transmission factor over the inscribed square.
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

    Args:
        machine: any machine.
        criteria: criteria on the transmission factors / conditioning (strokes are replaced by
            the joint square).
        joint_lower, joint_upper: actuator box searched (default: home ± 2 × the longest leg).
        centred: the joint square is centred at the home configuration (seed 004: joint stops
            placed symmetrically about the isotropic configuration); otherwise the largest
            square anywhere.
        resolution: grid points along the longest side, in joint space and in the workspace.

    Raises:
        InputError: no feasible actuator vector around home.
    """
    reach = 2.0 * float(machine.model.leg_length.max())
    lo = machine.home_q - reach if joint_lower is None else np.asarray(joint_lower, float)
    hi = machine.home_q + reach if joint_upper is None else np.asarray(joint_upper, float)
    joint = joint_space_map(machine, joint_grid(machine, lo, hi, resolution), criteria)
    square = largest_inscribed_box(joint.feasible, joint.grid,
                                   center=machine.home_q if centred else None)
    if square is None or square.side == 0:
        raise InputError("no usable actuator square around the home configuration: the "
                         "criteria fail there")
    if centred:
        square = _refine_centred_square(machine, criteria, square, joint.grid.step)
    q_lo, q_hi = square.lower, square.lower + square.side
    samples = make_grid(q_lo, q_hi, free=tuple(range(machine.n_actuators)), base=q_lo,
                        names=machine.actuator_names, resolution=101)
    image = machine.fk(samples.points)
    p_lo, p_hi = np.nanmin(image, axis=0), np.nanmax(image, axis=0)
    margin = 0.02 * float((p_hi - p_lo).max())
    grid = make_grid(p_lo - margin, p_hi + margin, free=tuple(range(machine.dims)),
                     base=machine.home_pose, names=machine.pose_names, resolution=resolution)
    limited = Criteria(bounds=criteria.bounds, kappa_max=criteria.kappa_max,
                       q_limits=(q_lo, q_hi), connected=criteria.connected, tol=criteria.tol)
    ws = compute_workspace(machine, grid, limited)
    return UsefulWorkspace(joint=joint, joint_square=square, workspace=ws, inscribed=ws.inscribed,
                           factor_range=ws.factor_range(ws.feasible),
                           inscribed_factor_range=ws.factor_range())
