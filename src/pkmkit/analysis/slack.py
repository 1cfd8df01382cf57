"""Signed slack of the workspace criteria at poses, and its gradient along the free axes.

:func:`criteria_slack` is ≥ 0 where every criterion holds (connectivity aside) and < 0 elsewhere,
smooth between changes of the limiting criterion: the inscribed-box refinement
(:func:`pkmkit.analysis.workspace.refine_box`) maximises a box under "slack ≥ 0" at its lattice.
:func:`slack_and_gradient` gives the same values with their analytic gradient along the grid's
free axes, from the machine's :meth:`criteria_rates` (full-pose machines; None for the others,
whose gradients are then differenced): the slack of a point is the smallest of its parts, so
its gradient is that part's gradient.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from pkmkit.analysis.criteria import Criteria, solved_poses
from pkmkit.machines.machine import Machine
from pkmkit.status import Status
from pkmkit.stiffness.indices import stiffness_figures


def criteria_slack(machine: Machine, points: np.ndarray, criteria: Criteria,
                   length: float) -> np.ndarray:
    """``(M,)`` smallest signed slack of the criteria at poses ``points (M, dims)``: ≥ 0 where
    :func:`evaluate_poses` finds every criterion met (connectivity aside; the factor bounds
    without their rounding allowance ``criteria.rtol``), < 0 elsewhere,
    varying smoothly with the pose between changes of the limiting criterion. Lengths
    (reachability shortfall, strokes) are divided by ``length``; factor bounds and the
    condition number are relative; the assembly mode is the signed parallel measure minus its
    threshold."""
    return _slack(machine, points, criteria, length, None)[0]


def slack_and_gradient(machine: Machine, points: np.ndarray, criteria: Criteria,
                       length: float, free: tuple[int, ...]
                       ) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`criteria_slack` at ``points (M, dims)`` (the same values) and its gradient
    ``(M, len(free))`` along the pose coordinates ``free``; None when the machine has no
    analytic derivatives there (:meth:`criteria_rates` answers None) or a stiffness criterion
    is asked. Where the slack is not differentiable (a change of limiting criterion, a
    repeated singular value) the gradient is the limiting part's; where a part's derivative
    does not exist (unreachable pose, parallel singularity) it is 0."""
    if criteria.stiffness_bounded:
        return None
    out = _slack(machine, points, criteria, length, tuple(free))
    return None if out[1] is None else out


def _slack(machine: Machine, points: np.ndarray, criteria: Criteria, length: float,
           free: tuple[int, ...] | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The slack and, with ``free``, its gradient (None when the machine has no rates)."""
    inv = machine.ik(points, full_output=True)
    q = inv.q
    reach = -np.max(inv.shortfall, axis=1) / length
    # one velocity model (and its rates) per line along a common slide axis: the same along it
    lines = machine.translation_lines(points)
    rows = slice(None) if lines is None else lines.rows
    poses = solved_poses(points, inv)
    jac = machine.jacobian(poses[rows], q=q[rows], tol=criteria.tol)
    rates = None
    if free is not None:
        factors = criteria.bounds is not None or criteria.kappa_max is not None
        solved = inv if lines is None else SimpleNamespace(pose=poses[rows])
        rates = machine.criteria_rates(points[rows], solved, jac, free, factors=factors)
        if rates is None:
            return np.empty(0), None
    if lines is not None:
        jac = lines.spread(jac)
        rates = None if rates is None else lines.spread(rates)
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
        if criteria.stiffness_bounded:
            parts.extend(_stiffness_slack(machine, points, criteria))
        side = np.sign(jac.det_A) * machine.working_mode
        parts.append(np.where(side > 0, jac.parallel_measure, -jac.parallel_measure)
                     - criteria.tol)
    table = np.column_stack(parts)
    out = np.min(table, axis=1)
    # where the pose is unreachable the other criteria are NaN: the reach slack decides
    unreachable = inv.status != Status.OK
    out[unreachable] = np.minimum(reach[unreachable], -1e-12)
    grad = None
    if rates is not None:
        grads = _part_gradients(inv, jac, rates, criteria, length, (lo_q, hi_q), side)
        grad = _limiting_gradient(table, grads, reach, unreachable)
        grad[np.isnan(out)] = 0.0
    return np.where(np.isnan(out), -1.0, out), grad


def _part_gradients(inv, jac, rates, criteria: Criteria, length: float,
                    limits: tuple[np.ndarray, np.ndarray], side: np.ndarray
                    ) -> list[np.ndarray]:
    """``(M, d)`` gradients of the slack's parts, in :func:`_slack`'s order (the stiffness
    criterion has none: :func:`slack_and_gradient` refuses it)."""
    q, (lo_q, hi_q) = inv.q, limits
    with np.errstate(invalid="ignore", divide="ignore"):
        rod = np.argmax(np.nan_to_num(inv.shortfall, nan=-np.inf), axis=1)
        grads = [-np.take_along_axis(rates.shortfall, rod[:, None, None], 1)[:, 0] / length]
        ends = np.concatenate([q - lo_q[None], hi_q[None] - q], axis=1)
        end = np.argmin(np.nan_to_num(ends, nan=np.inf), axis=1)
        ends_rate = np.concatenate([rates.q, -rates.q], axis=1)
        g = np.take_along_axis(ends_rate, end[:, None, None], 1)[:, 0] / length
        stroke = np.take_along_axis(ends, end[:, None], 1)[:, 0]
        grads.append(np.where((stroke / length < 1e3)[:, None], g, 0.0))  # not capped
        if criteria.bounds is not None:
            lo, hi = criteria.bounds
            grads.append(rates.singular_values[:, -1] / lo)
            grads.append(-rates.singular_values[:, 0] / hi)
        if criteria.kappa_max is not None:
            sv, rate = jac.singular_values, rates.singular_values
            kappa_rate = (rate[:, 0] * sv[:, -1:] - sv[:, :1] * rate[:, -1]) / sv[:, -1:] ** 2
            grads.append(-kappa_rate / criteria.kappa_max)
        grads.append(np.where((side > 0)[:, None], rates.parallel_measure,
                              -rates.parallel_measure))
    return grads


def _limiting_gradient(table: np.ndarray, grads: list[np.ndarray], reach: np.ndarray,
                       unreachable: np.ndarray) -> np.ndarray:
    """The gradient of the smallest part of each row of ``table (M, parts)`` (the reach
    part's on unreachable rows below −1e-12, else 0), non-finite entries 0."""
    limiting = np.argmin(np.nan_to_num(table, nan=np.inf), axis=1)
    grad = np.take_along_axis(np.stack(grads, axis=1), limiting[:, None, None], 1)[:, 0]
    grad[unreachable] = np.where((reach[unreachable] < -1e-12)[:, None], grads[0][unreachable],
                                 0.0)
    return np.nan_to_num(grad, nan=0.0, posinf=0.0, neginf=0.0)


def _stiffness_slack(machine: Machine, points: np.ndarray, criteria: Criteria
                     ) -> list[np.ndarray]:
    """Relative slacks of the stiffness criterion (NaN where there is no stiffness)."""
    fig = stiffness_figures(machine, points, data=criteria.stiffness_data,
                            wrench=criteria.wrench)
    out = []
    if criteria.min_stiffness is not None:
        out.append(fig.smallest / criteria.min_stiffness - 1.0)
    if criteria.max_deflection is not None:
        out.append(1.0 - fig.deflection / criteria.max_deflection)
    return out
