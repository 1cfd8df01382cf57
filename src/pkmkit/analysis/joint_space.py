"""Joint-space views of a workspace: maps over actuator coordinates, the largest centred joint
square, transmission-factor ranges, and seed 004's useful workspace."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.analysis.criteria import Criteria
from pkmkit.analysis.grids import Grid, make_grid, pose_frame
from pkmkit.analysis.region_check import _column_extremes, _fmt, region_grid
from pkmkit.analysis.workspace import (
    InscribedBox,
    WorkspaceMap,
    _connected_part,
    compute_workspace,
    largest_inscribed_box,
)
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.status import Status


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
