"""Deflection of a full-pose rod machine (hexapods, Verne-type module, machine files) under the
weight of its moving parts, batched over poses.

Loads (the masses of :class:`~pkmkit.dynamics.masses.MassProperties`, as the inverse dynamics
uses them; gravity ``g``), as a wrench ``W = (F, M)`` at the platform frame's origin ``p`` (its
reference point) and forces ``f`` along the slides:

- the **platform** (with spindle and tool) ``M_p`` at its centre of mass ``p + R c``:
  ``F += M_p g``, ``M += (R c) × M_p g``;
- a **slide rod** (uniform, a ball joint at each end: half its weight on each end): ``m_r g / 2``
  at its platform joint ``p + R b_j`` and ``(m_r / 2)(g · u_k)`` along its slide ``u_k``; each
  **carriage** ``m_c (g · u_k)`` (the guide carries the rest);
- a **strut** (cylinder ``m₁`` of length ``ℓ₁`` hinged at its base joint A, piston ``m₂`` of
  length ``ℓ₂`` hinged at its platform joint P, ``L = |P − A|``, ``ê = (P − A)/L``): by virtual
  work (``δê = (I − êêᵀ) δP / L``, A fixed) the force ``w_j = m₂ g + (I − êêᵀ)(ℓ₁ m₁ − ℓ₂ m₂)
  g / (2L)`` at P — the strut's weight the platform feels, the rest goes to the base.
  A strut's "carriage" (the motor's equivalent translating inertia) has no weight along it.

With the platform compliance ``C`` (:func:`~pkmkit.stiffness.api.stiffness`) and ``ẋ = J q̇``
the twist of the platform reference point is ``δx = C W + J C_q f`` (as
:mod:`pkmkit.stiffness.loads`: a carriage load stretches its drive, the platform follows), and a
point ``r`` of the platform frame (the tool tip) moves by ``δp + δθ × R r``.
``tests/stiffness/test_platform_gravity.py`` checks it against the minimum of the elastic plus
potential energy of the exact rod geometry (its Hessian and gradient by central differences).
Linear, quasi-static.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.dynamics.masses import MassProperties
from pkmkit.exceptions import InputError
from pkmkit.model.rods import CRANK, SLIDE, STRUT
from pkmkit.spatial.rotation import rotvec_to_matrix
from pkmkit.stiffness.data import StiffnessData, default_data


def platform_masses(machine: Any) -> MassProperties:
    """The illustrative masses of :func:`pkmkit.dynamics.defaults.default_masses` (strut tubes
    sized on the home strut lengths)."""
    from pkmkit.dynamics.defaults import default_masses

    return default_masses(machine, tubes_at_home=bool((machine.model.rod_kind == STRUT).any()))


def platform_gravity_loads(machine: Any, masses: MassProperties, poses: np.ndarray
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The weight of the moving parts of a full-pose rod machine at full poses ``(N, 6)``
    (m, rotation vector): the wrench ``(N, 6)`` (N, N·m) at the platform frame's origin and the
    forces ``(n,)`` (N) along the slides (module docstring).

    Raises:
        InputError: a machine with cranks (their arms' weight is not modelled), masses that do
            not fit the machine.
    """
    model = machine.model
    masses.check(machine)
    if (model.rod_kind == CRANK).any():
        raise InputError(f"gravity deflection of {machine.id!r}: its cranks' weight is not "
                         "modelled (slides and struts only)")
    g = np.asarray(masses.gravity, dtype=float)
    x = np.atleast_2d(np.asarray(poses, dtype=float))
    rot = rotvec_to_matrix(np.nan_to_num(x[:, 3:6]))
    p = x[:, :3]
    b = np.einsum("nij,mj->nmi", rot, model.rod_platform)           # (N, m, 3) R b_j
    slide = model.rod_kind == SLIDE
    strut = model.rod_kind == STRUT
    force = np.zeros(b.shape)                                        # (N, m, 3) at P_j
    force[:, slide] = 0.5 * masses.rod_mass[slide, None] * g
    if strut.any():
        piston, l1, l2 = masses.strut_parts(model.n_rods)
        d = p[:, None, :] + b[:, strut] - model.rod_base[strut]
        length = np.linalg.norm(d, axis=2, keepdims=True)
        e = d / length
        lever = (l1[strut] * masses.rod_mass[strut] - l2[strut] * piston[strut])[None, :, None]
        side = lever * g / (2.0 * length)
        side = side - np.einsum("nmi,nmi->nm", side, e)[:, :, None] * e
        force[:, strut] = piston[strut, None] * g + side
    com = np.einsum("nij,j->ni", rot, np.asarray(masses.platform_com, dtype=float))
    f_p = masses.platform_mass * g
    wrench = np.zeros((len(x), 6))
    wrench[:, :3] = f_p + force.sum(axis=1)
    wrench[:, 3:] = np.cross(com, f_p) + np.cross(b, force).sum(axis=1)
    along = np.zeros(machine.n_actuators)
    carriage = np.asarray(masses.carriage_mass, dtype=float).copy()
    slides = np.zeros(machine.n_actuators, dtype=bool)
    slides[model.rod_actuator[slide]] = True
    np.add.at(carriage, model.rod_actuator[slide], 0.5 * masses.rod_mass[slide])
    axis = np.zeros((machine.n_actuators, 3))
    axis[model.rod_actuator[slide]] = model.rod_axis[slide]
    along[slides] = carriage[slides] * (axis[slides] @ g)
    return wrench, along


def platform_gravity_deflection(machine: Any, poses: Any, masses: MassProperties | None = None,
                                *, data: StiffnessData | None = None, point: Any = None
                                ) -> tuple[np.ndarray, np.ndarray]:
    """Small displacement of a full-pose rod machine's platform under its own weight.

    Args:
        machine: a full-pose rod machine (slides or struts).
        poses: as :func:`~pkmkit.stiffness.api.stiffness` takes them: ``(N, 6)`` full poses
            (``(N, 3)`` positions for a machine with fewer than six actuators).
        masses: the moving masses (default :func:`platform_masses`).
        data: the elastic data (default the machine's).
        point: ``(3,)`` or ``(N, 3)`` point of the platform frame whose displacement is wanted
            (m; default the frame's origin; a tool tip ``tool_length`` below: ``(0, 0, −tl)``).

    Returns:
        ``(deflection (N, 6), status (N,))``: the point's displacement (m) then the platform's
        rotation (rad), base axes; NaN rows where the pose is unreachable or singular.

    Raises:
        InputError: see :func:`platform_gravity_loads`.
    """
    from pkmkit.stiffness.api import stiffness

    data = data or default_data(machine)
    masses = masses or platform_masses(machine)
    arr = np.atleast_2d(np.asarray(poses, dtype=float))
    result = stiffness(machine, arr, data=data)
    c = np.asarray(result.compliance)
    inv = machine.ik(arr, full_output=True, strokes="ignore")
    full = np.atleast_2d(np.asarray(getattr(inv, "pose", None) if arr.shape[1] != 6 else arr,
                                    dtype=float))
    out = np.full((len(arr), 6), np.nan)
    ok = np.isfinite(c).all(axis=(1, 2)) & np.isfinite(full).all(axis=1)
    if ok.any():
        w, f = platform_gravity_loads(machine, masses, full[ok])
        defl = np.einsum("nij,nj->ni", c[ok], w)
        if np.any(f):
            jac = np.asarray(machine.jacobian(full[ok]).J).reshape(-1, 6, machine.n_actuators)
            defl = defl + np.einsum("nia,a->ni", jac, f / data.actuator_stiffness)
        if point is not None:
            r = np.broadcast_to(np.asarray(point, dtype=float), (len(arr), 3))[ok]
            rot = rotvec_to_matrix(full[ok, 3:6])
            defl[:, :3] += np.cross(defl[:, 3:], np.einsum("nij,nj->ni", rot, r))
        out[ok] = defl
    return out, np.asarray(result.status)
