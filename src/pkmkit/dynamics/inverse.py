"""Inverse dynamics of translational rod-leg machines by the principle of virtual work.

Bodies (all moving masses, none neglected):

- the **carriage** (moving part of the motor) of each slide: mass m_c, moving along u_k (for a
  strut leg: the motor's equivalent translating inertia, u = 0);
- every **rod** as a uniform cylinder of mass m, length ℓ and radius ρ, with a spherical joint at
  each end: its centre of mass is the mid-point of its ends A (carriage) and P (platform), and its
  inertia about any transverse axis through the centre is m(ℓ²/12 + ρ²/4). Such a rod never spins
  about its own axis, so its angular velocity and acceleration are
  ω = d̂ × (v_P − v_A)/ℓ and α = d̂ × (a_P − a_A)/ℓ (d̂ the unit rod vector);
- the **platform** with spindle and tool: mass M_p (it only translates, so its centre of mass and
  inertia tensor do not enter the actuator forces — they only load the rods' constraint forces);
- **gravity** g along any direction and an **external wrench** (F, M) at the tool point, constant or
  one per sample (M does no virtual work on a platform that does not rotate).

With δq the actuator displacements, δx = J δq, δA = u_k δq_k, δP = δx, the virtual work of the
inertia and external forces equals f·δq, which gives, per sample::

    f = m_c (q̈ − g·u) + Jᵀ [M_p (ẍ − g) − F]
        + Σ_rods { Jᵀ G_P + e_k (u·G_A) },
    G_P = F_m / 2 + (M_r × d̂)/ℓ,  G_A = F_m / 2 − (M_r × d̂)/ℓ,
    F_m = m (a_com − g),  M_r = I_t α.

**Strut legs** (actuated rods, base joint A fixed): a cylinder (mass m₁, tube length ℓ₁) hinged
at A and a piston (m₂, ℓ₂) hinged at P, uniform tubes with their centres of mass at mid-length,
turning with the strut and not spinning about its axis. With L = |P − A|, ê = (P − A)/L and its
derivatives ê̇ = (v_P − L̇ ê)/L, ê̈ = (a_P − L̈ ê − 2 L̇ ê̇)/L, the angular acceleration is α = ê × ê̈,
the centres of mass accelerate at (ℓ₁/2) ê̈ and a_P − (ℓ₂/2) ê̈, and since δA = 0 and
δê = (I − êêᵀ) δP / L, the strut adds Jᵀ G_P with::

    G_P = F₂ + (I − êêᵀ) [ (ℓ₁/2) F₁ − (ℓ₂/2) F₂ + (I₁ + I₂) α × ê ] / L,
    F₁ = m₁ ((ℓ₁/2) ê̈ − g),  F₂ = m₂ (a_P − (ℓ₂/2) ê̈ − g).

Everything is batched over samples (no per-sample Python loop), in blocks that fit in cache.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.masses import MassProperties, refuse_beyond
from pkmkit.exceptions import InputError
from pkmkit.machines.machine import Machine
from pkmkit.machines.protocol import require_translational
from pkmkit.model.rods import CRANK, SLIDE
from pkmkit.numerics import small
from pkmkit.numerics.magnitudes import MAX_FORCE


@dataclass(frozen=True)
class ForceResult:
    """Actuator forces along a motion (N samples, n actuators).

    Attributes:
        force: ``(N, n)`` actuator forces along the slides, N (positive along u_k).
        power: ``(N, n)`` mechanical power f_k q̇_k, W.
        parts: ``{name: (N, n)}`` contributions: ``carriages``, ``rods``, ``platform``,
            ``external`` (they sum to ``force``).
        leg_axial: ``(N, n)`` axial force of each leg (sum over its rods, tension > 0) at the
            rod end where it is largest — the design load of the rods: from the carriage's
            equilibrium along its slide (which gives the mid-span value) and the rods' own axial
            inertia and weight, N; NaN where the leg is perpendicular to the slide. For a strut
            leg, minus its actuator force.
    """

    force: np.ndarray
    power: np.ndarray
    parts: dict[str, np.ndarray]
    leg_axial: np.ndarray


#: Samples per block: the rod temporaries, (3, rods, block) doubles, stay in cache.
CHUNK = 8192
#: Names of the force contributions in :attr:`ForceResult.parts`.
PARTS = ("carriages", "rods", "platform", "external")


def require_linear_actuators(machine: Machine, what: str) -> None:
    """Refuse machines with crank (rotary) actuators, whose arm inertia is not modelled."""
    if (machine.model.leg_kind == CRANK).any():
        raise InputError(
            f"{what} is not available for {machine.id!r}: it has rotary (crank) actuators, and "
            "pkmkit's dynamics model only slides and struts so far (the arms' inertia and the "
            "motor torques are not modelled); joint trajectories (q, q̇, q̈) are available")


def _pad(a: np.ndarray) -> np.ndarray:
    if a.shape[-1] == 3:
        return a
    out = np.zeros((*a.shape[:-1], 3))
    out[..., : a.shape[-1]] = a
    return out


def inverse_dynamics(machine: Machine, masses: MassProperties, x: np.ndarray, xd: np.ndarray,
                     xdd: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
                     *, wrench: Any = None) -> ForceResult:
    """Actuator forces and powers for a motion (see the module docstring).

    Raises:
        InputError: a machine with crank (rotary) actuators — the inertia of its arms and the
            motor torques are not modelled yet —, or mis-shaped arrays.

    Args:
        machine: a translational rod-leg machine with slide legs.
        masses: its mass properties.
        x, xd, xdd: ``(N, dims)`` tool position (m), velocity (m/s), acceleration (m/s²).
        q, qd, qdd: ``(N, n)`` actuator positions, speeds, accelerations.
        wrench: external force on the tool, ``(3,)`` or ``(N, 3)`` N (a moment may follow as
            components 3–5: it does no work on a translating platform and is ignored).

    Raises:
        InputError: mismatched shapes, non-finite wrench, masses that do not fit the machine.
    """
    require_translational(machine, "inverse dynamics along a path",
                          "motion.joint_trajectory gives its actuator motion (q, q̇, q̈)")
    require_linear_actuators(machine, "inverse dynamics")
    masses.check(machine)
    n_samples = x.shape[0]
    for name, arr, width in (("xd", xd, machine.dims), ("xdd", xdd, machine.dims),
                             ("q", q, machine.n_actuators), ("qd", qd, machine.n_actuators),
                             ("qdd", qdd, machine.n_actuators)):
        if arr.shape != (n_samples, width):
            raise InputError(f"{name} must have shape ({n_samples}, {width}), got {arr.shape}")
    force_ext = np.zeros((n_samples, 3))
    if wrench is not None:
        try:
            w = np.asarray(wrench, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"the wrench must be numbers, got {wrench!r}") from None
        if w.ndim == 1:
            w = np.broadcast_to(w, (n_samples, w.shape[0]))
        if w.ndim != 2 or w.shape[0] != n_samples or w.shape[1] not in (2, 3, 6):
            raise InputError(f"the wrench must be (3,), (6,), (N, 3) or (N, 6); got {w.shape}")
        if not np.isfinite(w).all():
            raise InputError("the wrench must be finite")
        refuse_beyond("a wrench component", w, MAX_FORCE, "N (or N·m)")
        force_ext[:, : min(3, w.shape[1])] = w[:, :3] if w.shape[1] >= 3 else w
    force = np.empty((machine.n_actuators, n_samples))
    parts = {name: np.empty_like(force) for name in PARTS}
    axial = np.empty_like(force)
    # blocks of samples small enough for the temporaries to stay in cache
    for first in range(0, n_samples, CHUNK):
        block = slice(first, first + CHUNK)
        _forces_block(machine, masses, x[block], xd[block], xdd[block], q[block], qdd[block],
                      force_ext[block], force[:, block], axial[:, block],
                      {name: part[:, block] for name, part in parts.items()})
    return ForceResult(force=force.T, power=force.T * qd,
                       parts={name: part.T for name, part in parts.items()},
                       leg_axial=axial.T)


def _forces_block(machine: Machine, masses: MassProperties, x: np.ndarray, xd: np.ndarray,
                  xdd: np.ndarray, q: np.ndarray, qdd: np.ndarray, force_ext: np.ndarray,
                  force: np.ndarray, axial: np.ndarray, parts: dict[str, np.ndarray]) -> None:
    """Forces of one block of samples, written into ``force``, ``axial`` and ``parts``
    (``(n, N)`` views, batch-last)."""
    model = machine.model
    g = masses.gravity
    # batch-last layout: vectors are (3, ..., N) with contiguous components
    a_leg, b_leg = machine.closed_form.jacobians_t(x, q)  # A (n, dims, N), diag B (n, N)
    cof = small.cofactors(a_leg)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_det = 1.0 / small.det(a_leg, cof)

    def apply_jt(v: np.ndarray) -> np.ndarray:
        """Jᵀ v for platform-space vectors v (3, N): J = A⁻¹B, so Jᵀv = B (A⁻ᵀ v) and
        A⁻ᵀ = cofactors / det A. Returns (n, N)."""
        v = v[: machine.dims]
        with np.errstate(invalid="ignore"):
            return b_leg * np.einsum("ijn,jn->in", cof, v) * inv_det

    p = _pad(x).T
    pdd = _pad(xdd).T
    q_t, qdd_t = q.T, qdd.T
    # carriages
    u_leg = model.leg_axis
    carriages = masses.carriage_mass[:, None] * (qdd_t - (u_leg @ g)[:, None])
    # platform and external force
    platform = apply_jt(masses.platform_mass * (pdd - g[:, None]))
    external = -apply_jt(force_ext.T)
    rods = np.zeros_like(force)
    slide = model.rod_kind == SLIDE
    # slide rods, as (3, m, N)
    k_of = model.rod_actuator[slide]
    u_rod = model.rod_axis[slide]
    u = u_rod.T[:, :, None]
    qr, qddr = q_t[k_of], qdd_t[k_of]
    a_pt = model.rod_base[slide].T[:, :, None] + u * qr
    d = p[:, None, :] + model.rod_platform[slide].T[:, :, None] - a_pt
    length = np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
    inv_len = 1.0 / length
    unit = d * inv_len
    acc_a = u * qddr
    acc_p = pdd[:, None, :]
    rod_mass = masses.rod_mass[slide][:, None]
    f_m = rod_mass * (0.5 * (acc_a + acc_p) - g[:, None, None])
    inertia = rod_mass * (length**2 / 12 + masses.rod_radius[slide][:, None] ** 2 / 4)
    alpha = _cross(unit, acc_p - acc_a) * inv_len
    torque_term = _cross(inertia * alpha, unit) * inv_len
    g_p = 0.5 * f_m + torque_term
    g_a = 0.5 * f_m - torque_term
    rods += apply_jt(g_p.sum(axis=1))
    along = np.einsum("imn,im->mn", g_a, u_rod.T)  # (m, N)
    np.add.at(rods, k_of, along)
    if not slide.all():
        rods += apply_jt(_strut_forces(model, masses, p, _pad(xd).T, pdd, ~slide))
    np.add(carriages + platform, external + rods, out=force)
    # leg axial force from the carriage's equilibrium along its slide:
    # f = m_c (q̈ − g·u) + Σ u·G_A − Σ T (d̂·u), equal split within a parallelogram
    cos = np.zeros_like(force)
    np.add.at(cos, k_of, np.einsum("imn,im->mn", unit, u_rod.T))
    with np.errstate(divide="ignore", invalid="ignore"):
        cos /= np.bincount(k_of, minlength=machine.n_actuators)[:, None]
    carriage_side = np.zeros_like(force)
    np.add.at(carriage_side, k_of, along)
    with np.errstate(divide="ignore", invalid="ignore"):
        mid = (carriages + carriage_side - force) / cos
    # along each rod the tension changes by its own axial load F_m·d̂ (inertia and weight):
    # N_P − N_A = F_m·d̂, the mid-span value is their mean, the larger end |N_mid| + |F_m·d̂|/2
    half = np.zeros_like(force)
    np.add.at(half, k_of, 0.5 * np.einsum("imn,imn->mn", f_m, unit))
    np.copyto(axial, mid + np.sign(mid) * np.abs(half))
    axial[np.abs(cos) < 1e-9] = np.nan
    # a strut carries its actuator's force: a pushing actuator (f > 0) compresses it
    strut_legs = model.leg_kind != SLIDE
    axial[model.leg_actuator[strut_legs]] = -force[model.leg_actuator[strut_legs]]
    for name, value in zip(PARTS, (carriages, rods, platform, external), strict=True):
        parts[name][...] = value


def _strut_forces(model, masses: MassProperties, p: np.ndarray, pd: np.ndarray,
                  pdd: np.ndarray, strut: np.ndarray) -> np.ndarray:
    """Σ over strut rods of the platform-side generalised force G_P ``(3, N)`` (see the module
    docstring): cylinder hinged at the fixed base joint A, piston at the platform joint P."""
    g = masses.gravity[:, None, None]
    piston_mass, cylinder_length, piston_length = masses.strut_parts(model.n_rods)
    d = p[:, None, :] + (model.rod_platform[strut] - model.rod_base[strut]).T[:, :, None]
    length = np.sqrt(np.einsum("imn,imn->mn", d, d))
    unit = d / length
    v, a = pd[:, None, :], pdd[:, None, :]
    rate = np.einsum("imn,imn->mn", unit, np.broadcast_to(v, d.shape))  # L̇
    unit_d = (v - rate * unit) / length  # dê/dt
    accel = (np.einsum("imn,imn->mn", unit_d, np.broadcast_to(v, d.shape))
             + np.einsum("imn,imn->mn", unit, np.broadcast_to(a, d.shape)))  # L̈
    unit_dd = (a - accel * unit - 2 * rate * unit_d) / length  # d²ê/dt²
    alpha = _cross(unit, unit_dd)
    m1, m2 = masses.rod_mass[strut][:, None], piston_mass[strut][:, None]
    l1, l2 = cylinder_length[strut][:, None], piston_length[strut][:, None]
    r2 = masses.rod_radius[strut][:, None] ** 2 / 4
    inertia = m1 * (l1**2 / 12 + r2) + m2 * (l2**2 / 12 + r2)
    f_cylinder = m1 * (0.5 * l1 * unit_dd - g)
    f_piston = m2 * (a - 0.5 * l2 * unit_dd - g)
    moment = 0.5 * l1 * f_cylinder - 0.5 * l2 * f_piston + _cross(inertia * alpha, unit)
    normal = (moment - np.einsum("imn,imn->mn", moment, unit) * unit) / length
    return (f_piston + normal).sum(axis=1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of component-first arrays (3, ...)."""
    return np.stack([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def mechanical_energy(machine: Machine, masses: MassProperties, x: np.ndarray, xd: np.ndarray,
                      q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Kinetic plus potential energy ``(N,)`` of every moving body (J), for power-balance
    checks: d/dt of it equals Σ f_k q̇_k + F·ẋ."""
    model = machine.model
    g = masses.gravity
    p, pd = _pad(x), _pad(xd)
    u = model.leg_axis
    carriage_pos = model.leg_base[None] + q[:, :, None] * u[None]
    energy = 0.5 * (masses.carriage_mass * qd**2).sum(axis=1)
    energy -= (masses.carriage_mass[None, :, None] * carriage_pos * g).sum(axis=(1, 2))
    energy += 0.5 * masses.platform_mass * (pd**2).sum(axis=1) - masses.platform_mass * (p @ g)
    slide = model.rod_kind == SLIDE
    k_of = model.rod_actuator[slide]
    ur = model.rod_axis[slide]
    a_pt = model.rod_base[slide][None] + q[:, k_of][:, :, None] * ur[None]
    d = p[:, None, :] + model.rod_platform[slide][None] - a_pt
    length = np.linalg.norm(d, axis=2)
    unit = d / length[:, :, None]
    v_a = qd[:, k_of][:, :, None] * ur[None]
    v_p = np.broadcast_to(pd[:, None, :], v_a.shape)
    com = 0.5 * (a_pt + p[:, None, :] + model.rod_platform[slide][None])
    v_com = 0.5 * (v_a + v_p)
    omega = np.cross(unit, v_p - v_a) / length[:, :, None]
    rod_mass = masses.rod_mass[slide]
    inertia = rod_mass[None] * (length**2 / 12 + masses.rod_radius[slide][None] ** 2 / 4)
    energy += (0.5 * rod_mass[None] * (v_com**2).sum(axis=2)
               + 0.5 * inertia * (omega**2).sum(axis=2)).sum(axis=1)
    energy -= (rod_mass[None, :, None] * com * g).sum(axis=(1, 2))
    if slide.all():
        return energy
    # struts: cylinder hinged at the fixed base joint, piston at the platform joint
    strut = ~slide
    piston_mass, cylinder_length, piston_length = masses.strut_parts(model.n_rods)
    base = model.rod_base[strut][None]
    joint = p[:, None, :] + model.rod_platform[strut][None]
    d = joint - base
    length = np.linalg.norm(d, axis=2)[:, :, None]
    unit = d / length
    v_p = np.broadcast_to(pd[:, None, :], d.shape)
    omega = np.cross(unit, v_p) / length
    unit_rate = np.cross(omega, unit)
    r2 = masses.rod_radius[strut] ** 2 / 4
    for mass, tube, com, v_com in (
            (masses.rod_mass[strut], cylinder_length[strut],
             base + 0.5 * cylinder_length[strut][None, :, None] * unit,
             0.5 * cylinder_length[strut][None, :, None] * unit_rate),
            (piston_mass[strut], piston_length[strut],
             joint - 0.5 * piston_length[strut][None, :, None] * unit,
             v_p - 0.5 * piston_length[strut][None, :, None] * unit_rate)):
        inertia = mass * (tube**2 / 12 + r2)
        energy += (0.5 * mass[None] * (v_com**2).sum(axis=2)
                   + 0.5 * inertia[None] * (omega**2).sum(axis=2)).sum(axis=1)
        energy -= (mass[None, :, None] * com * g).sum(axis=(1, 2))
    return energy
