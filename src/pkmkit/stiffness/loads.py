"""Deflection of a translating rod-leg machine under the weight of its moving parts and a tool
force, batched over poses.

Loads (the masses of :class:`~pkmkit.dynamics.masses.MassProperties`, the same as the inverse
dynamics uses; gravity ``g``):

- the **platform** (with spindle and tool) and the platform half of every rod: the force
  ``W_g = (M_p + Σ_rods m_r/2) g`` on the platform (a rod with a ball joint at each end puts
  half its weight on each: moments about either end);
- each **carriage** and the carriage half of its rods: ``f_k = (m_c,k + Σ_{rods of k} m_r/2)
  (g · u_k)`` along its slide ``u_k`` (the guide carries the rest, rigidly);
- the **tool force** ``F`` on the platform.

With the platform compliance ``C`` (:func:`~pkmkit.stiffness.api.stiffness`) and ``ẋ = J q̇``,
the deflection is the superposition

    δx = C (W_g + F) + J C_q f

(a carriage load stretches its drive by ``f_k/k_a`` and the platform follows with unloaded rods).
With rigid rods this is ``−J C_q f_s``, ``f_s`` the static actuator forces of the inverse
dynamics (``tests/stiffness/test_loads.py`` checks it, and the compliant-rod case against the
Hessian of the elastic energy by finite differences of the rod geometry).

Inertia forces are not included (quasi-static: the loads of a slow feed).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.masses import MassProperties
from pkmkit.exceptions import InputError
from pkmkit.model.rods import SLIDE
from pkmkit.stiffness.api import stiffness
from pkmkit.stiffness.data import StiffnessData, default_data


@dataclass(frozen=True)
class LoadDeflection:
    """Deflection of the platform at N poses (d = 2 or 3 translations), m.

    Attributes:
        gravity: ``(N, d)`` under the weight of the moving parts.
        force: ``(N, d)`` under the tool force (zeros without one).
        total: ``(N, d)`` their sum.
        status: ``(N,)`` :class:`~pkmkit.status.Status` of the stiffness (NaN rows where not OK).
    """

    gravity: np.ndarray
    force: np.ndarray
    total: np.ndarray
    status: np.ndarray


def gravity_loads(machine: Any, masses: MassProperties) -> tuple[np.ndarray, np.ndarray]:
    """The weight of the moving parts as a platform force ``(dims,)`` N and carriage forces
    along the slides ``(n,)`` N (module docstring).

    Raises:
        InputError: a machine that is not a translating platform on slides (cranks and struts
            with mass: their arms' weight is not modelled), masses that do not fit it.
    """
    model = machine.model
    if not machine.orientation_fixed:
        raise InputError(f"gravity deflection needs a translating platform; the platform of "
                         f"{machine.id!r} also turns")
    masses.check(machine)
    if (model.leg_kind != SLIDE).any():
        raise InputError(f"gravity deflection of {machine.id!r}: its actuators are not all "
                         "slides (the weight of cranks and struts is not modelled)")
    g = np.asarray(masses.gravity, dtype=float)
    half = 0.5 * np.asarray(masses.rod_mass, dtype=float)
    platform = (masses.platform_mass + half.sum()) * g
    carriage = np.asarray(masses.carriage_mass, dtype=float).copy()
    np.add.at(carriage, model.rod_actuator, half)
    along = carriage * (model.leg_axis @ g)
    return platform[: machine.dims], along


def load_deflection(machine: Any, poses: Any, masses: MassProperties | None = None, *,
                    force: Any = None, data: StiffnessData | None = None) -> LoadDeflection:
    """Platform deflection under gravity (``masses``) and a tool force at poses.

    Args:
        machine: a translating rod-leg machine on slides.
        poses: ``(N, dims)`` m.
        masses: the moving masses (None: no gravity load).
        force: ``(3,)`` or ``(N, 3)`` tool force, N (components beyond ``dims`` of a planar
            machine are ignored), or None.
        data: the elastic data (default: the machine's).

    Returns:
        :class:`LoadDeflection`; rows where the pose is unreachable or singular are NaN.

    Raises:
        InputError: see :func:`gravity_loads`; a force of the wrong shape or not finite.
    """
    data = data or default_data(machine)
    x = np.atleast_2d(np.asarray(poses, dtype=float))
    n_rows, d = x.shape
    result = stiffness(machine, x, data=data)
    c = np.asarray(result.compliance)
    gravity = np.zeros((n_rows, d))
    if masses is not None:
        w_g, f_c = gravity_loads(machine, masses)
        jac = np.asarray(machine.jacobian(x).J)
        gravity = (np.einsum("nij,j->ni", c, w_g)
                   + np.einsum("nia,a->ni", jac, f_c / data.actuator_stiffness))
    loaded = np.zeros((n_rows, d))
    if force is not None:
        f = np.asarray(force, dtype=float)
        if f.shape not in ((3,), (n_rows, 3)) or not np.isfinite(f).all():
            raise InputError(f"the tool force must be (3,) or ({n_rows}, 3) finite numbers (N), "
                             f"got shape {f.shape}")
        f = np.broadcast_to(f, (n_rows, 3))[:, :d]
        loaded = np.einsum("nij,nj->ni", c, f)
    bad = ~np.isfinite(c).all(axis=(1, 2))
    gravity[bad] = np.nan
    loaded[bad] = np.nan
    return LoadDeflection(gravity=gravity, force=loaded, total=gravity + loaded,
                          status=np.asarray(result.status))
