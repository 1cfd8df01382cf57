"""The arms' axial stiffness a rod-leg machine needs for a stiffness bound over a region.

The machine's smallest translational stiffness at a pose, ``k_min(x; EA)``, is that of
:func:`pkmkit.stiffness.stiffness` with every rod given the axial rigidity EA (N) — each rod an
axial spring ``EA/ℓ_j`` in series with its drive (:mod:`pkmkit.stiffness.rod_legs`). It grows
with EA towards the rigid-rod value (the drives alone). The requirement is the least EA with

    min over the region's poses of k_min(x; EA) ≥ bound,

found by bisection on log EA (monotone); an arm of length ℓ then needs the axial stiffness
``EA/ℓ`` (:func:`pkmkit.dynamics.arms.size_arm`'s ``min_stiffness``). No EA meets a bound the
drives alone do not meet (rigid rods): that is reported, not hidden.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.stiffness.beam import Material as BeamMaterial
from pkmkit.stiffness.beam import Section
from pkmkit.stiffness.data import StiffnessData, default_data
from pkmkit.stiffness.indices import stiffness_figures

#: Relative bracket of the bisection on EA at which it stops.
EA_RTOL = 1e-9


@dataclass(frozen=True)
class RodRequirement:
    """Result of :func:`required_axial_rigidity` (SI).

    Attributes:
        axial_rigidity: the least EA (N) of every rod meeting the bound (inf when none does).
        bound: the required smallest translational stiffness, N/m.
        rigid_stiffness: the machine's smallest translational stiffness over the region with
            rigid rods (the drives alone), N/m.
        worst_pose: ``(dims,)`` m, the region's pose where the bound binds.
        feasible: whether some EA meets the bound.
    """

    axial_rigidity: float
    bound: float
    rigid_stiffness: float
    worst_pose: np.ndarray
    feasible: bool

    def arm_stiffness(self, length: float) -> float:
        """The axial stiffness ``EA/ℓ`` (N/m) an arm of ``length`` (m) needs."""
        return self.axial_rigidity / length


def _smallest(machine: Any, poses: np.ndarray, data: StiffnessData,
              ea: float | None) -> np.ndarray:
    if ea is None:
        trial = dataclasses.replace(data, rod_section=None)
    else:  # an axial rigidity alone: unit modulus, area EA (only E·A enters a rod's spring)
        section = Section(ea, 1.0, 1.0, 1.0, 1e-9, f"EA = {ea:.6g} N")
        trial = dataclasses.replace(data, rod_section=section,
                                    rod_material=BeamMaterial(1.0, 1.0))
    smallest = stiffness_figures(machine, poses, data=trial).smallest
    return np.where(np.isfinite(smallest), smallest, -np.inf)  # a failed pose meets no bound


def required_axial_rigidity(machine: Any, poses: Any, bound: float, *,
                            data: StiffnessData | None = None) -> RodRequirement:
    """The least axial rigidity EA (N) of a rod-leg machine's rods for which its smallest
    translational stiffness over ``poses`` is at least ``bound`` (module docstring).

    Args:
        machine: a rod-leg machine (translating or full-pose).
        poses: ``(M, dims)`` m, the region (e.g. :meth:`pkmkit.design.metrics.Region.points`).
        bound: N/m.
        data: the elastic data (its drives; its rod section is replaced), default the
            machine's.

    Raises:
        InputError: a joint-chain machine, a bound not > 0, a region with no reachable pose.
    """
    if machine.elastic_members != "rods":
        raise InputError(f"{machine.id!r} has links, not rods: arm sizing for a stiffness "
                         "bound needs a rod-leg machine")
    if not (math.isfinite(bound) and bound > 0):
        raise InputError(f"the stiffness bound must be a finite number > 0 N/m, got {bound}")
    data = data or default_data(machine)
    x = np.atleast_2d(np.asarray(poses, dtype=float))
    rigid = _smallest(machine, x, data, None)
    reachable = np.isfinite(rigid)
    if not reachable.any():
        raise InputError("no pose of the region is reachable (no stiffness to bound)")
    x = x[reachable]
    rigid_min = float(rigid[reachable].min())
    if rigid_min <= bound:
        return RodRequirement(math.inf, bound, rigid_min, x[np.argmin(rigid[reachable])], False)
    lo, hi = 1.0, 1e3
    while np.min(_smallest(machine, x, data, hi)) < bound:
        if hi > 1e30:  # cannot happen for a bound below the drives' (the limit of large EA)
            raise InputError(f"no axial rigidity up to {hi:g} N meets {bound:g} N/m")
        lo, hi = hi, hi * 1e3
    while hi - lo > EA_RTOL * hi:
        mid = math.sqrt(lo * hi)
        if np.min(_smallest(machine, x, data, mid)) >= bound:
            hi = mid
        else:
            lo = mid
    at = _smallest(machine, x, data, hi)
    return RodRequirement(hi, bound, rigid_min, x[int(np.argmin(at))], True)
