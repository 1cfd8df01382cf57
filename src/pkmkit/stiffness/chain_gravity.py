"""Deflection of a joint-chain machine (Tripteor X7, TriMule 600, …) under the weight of its
moving parts, by the virtual-joint model of :mod:`pkmkit.stiffness.joint_chains`.

Masses (:class:`ChainMasses`; pkmkit's inverse dynamics has none for joint chains, so
:func:`illustrative_masses` gives *illustrative* values derived from the machine's geometry,
say so beside every figure):

- the **platform** ``m_p`` at its frame origin, with half of every leg's moving tube ``m_l/2``
  (a leg between a base joint and the platform puts half its weight on each end, as the rods of
  :mod:`pkmkit.stiffness.loads`; the base half goes to the rigid base);
- the **head** (spindle and its wrist) ``m_h`` lumped at the spindle nose (the tool frame's
  origin, on the last body of the head).

With the assembled problem z = (u, s, p) (platform twist, springs, passive joints), closure
constraints ``G z = 0`` and spring energy ``½ zᵀ H z``, the weights do the work ``Qᵀ z`` with

    Q = Pᵀ (F_p, 0) + Tᵀ (F_h, (nose − tool point) × F_h),
    F_p = (m_p + Σ m_l/2) g,   F_h = m_h g

(``P``: the platform origin's twist, ``T``: the tool point's), and the equilibrium on the null
space N of G gives the tool point's small displacement

    δt = T N (Nᵀ H N)⁺ Nᵀ Q.

``tests/stiffness/test_chain_gravity.py`` checks it against the machine's kinematics alone
(rigid links: the drives' springs loaded by the weights' generalized forces, the Jacobians by
central differences of ``fk``) and against a Lagrange-multiplier solution with compliant links.
Linear, quasi-static: no inertia forces, no geometric stiffness.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.dynamics.masses import refuse_beyond
from pkmkit.exceptions import InputError
from pkmkit.numerics.magnitudes import MAX_GRAVITY, MAX_MASS
from pkmkit.status import Status
from pkmkit.stiffness.data import StiffnessData, default_data
from pkmkit.stiffness.joint_chains import assemble, null_space_compliance

#: Illustrative leg tube: Ø 120/100 mm steel (7850 kg/m³), kg per metre of leg.
LEG_TUBE_KG_PER_M = 7850.0 * np.pi / 4 * (0.120 ** 2 - 0.100 ** 2)
#: Illustrative platform (with its joints) and head (spindle, motors, wrist), kg.
PLATFORM_KG = 50.0
HEAD_KG = 80.0


@dataclass(frozen=True)
class ChainMasses:
    """Moving masses of a joint-chain machine (SI).

    Attributes:
        platform: kg, at the platform frame origin.
        head: kg, at the spindle nose (tool frame origin).
        legs: ``(L,)`` kg, each leg's moving tube (half on the platform).
        gravity: ``(3,)`` m/s².
        note: where the values come from (printed beside every figure).
    """

    platform: float
    head: float
    legs: np.ndarray
    gravity: np.ndarray
    note: str = ""

    def check(self, machine: Any) -> None:
        """Raise :class:`InputError` for negative or non-finite masses, a leg count that is
        not the machine's, or a non-finite gravity."""
        legs = np.asarray(self.legs, dtype=float)
        n_legs = len(machine.model.legs)
        if legs.shape != (n_legs,):
            raise InputError(f"{legs.size} leg masses for {n_legs} legs of {machine.id!r}")
        for name, value in (("platform", self.platform), ("head", self.head)):
            if not (np.isfinite(value) and value >= 0):
                raise InputError(f"{name} mass must be a finite number >= 0 kg, got {value}")
        bad = np.flatnonzero(~(np.isfinite(legs) & (legs >= 0)))
        if bad.size:
            raise InputError(f"leg {bad[0]} mass must be a finite number >= 0 kg, "
                             f"got {legs[bad[0]]}")
        g = np.asarray(self.gravity, dtype=float)
        if g.shape != (3,) or not np.isfinite(g).all():
            raise InputError(f"gravity must be 3 finite numbers (m/s²), got {self.gravity!r}")
        for what, values, limit, unit in (
                ("platform mass", [self.platform], MAX_MASS, "kg"),
                ("head mass", [self.head], MAX_MASS, "kg"), ("leg mass", legs, MAX_MASS, "kg"),
                ("gravity component", g, MAX_GRAVITY, "m/s²")):
            refuse_beyond(what, np.asarray(values, dtype=float), limit, unit)


def illustrative_masses(machine: Any, gravity: Any = (0.0, 0.0, -9.81)) -> ChainMasses:
    """Illustrative masses of a joint-chain machine from its geometry: each leg a Ø 120/100 mm
    steel tube as long as its links at home (27.1 kg/m), a 50 kg platform and an 80 kg head
    (spindle and wrist). No source gives these masses."""
    from pkmkit.stiffness.joint_chains import _links

    lengths = np.zeros(len(machine.model.legs))
    for link in _links(machine):
        if link.chain == "leg":
            lengths[link.index] += link.home_length
    legs = LEG_TUBE_KG_PER_M * lengths
    listed = ", ".join(f"{v:.1f}" for v in legs)
    note = (f"illustrative masses (no source gives them): legs {listed}"
            f" kg (Ø 120/100 mm steel tubes, 27.1 kg/m, half on the platform), platform "
            f"{PLATFORM_KG:g} kg, head {HEAD_KG:g} kg at the spindle nose")
    return ChainMasses(PLATFORM_KG, HEAD_KG, legs, np.asarray(gravity, dtype=float), note)


def generalized_gravity(system: Any, masses: ChainMasses, tool_length: float) -> np.ndarray:
    """The weights' generalized force ``Q (k, nz)`` on the unknowns z of ``system``
    (:class:`~pkmkit.stiffness.joint_chains.ChainSystem`; module docstring), N / N·m."""
    g = np.asarray(masses.gravity, dtype=float)
    f_p = (masses.platform + 0.5 * float(np.sum(masses.legs))) * g
    f_h = masses.head * g
    nose = system.tool_point - tool_length * system.tool_axes[:, :, 2]
    w_p = np.concatenate([f_p, np.zeros(3)])
    w_t = np.concatenate([np.broadcast_to(f_h, nose.shape),
                          np.cross(nose - system.tool_point, f_h)], axis=1)
    return (np.einsum("kaz,a->kz", system.P, w_p)
            + np.einsum("kaz,ka->kz", system.T, w_t))


def chain_gravity_deflection(machine: Any, q: Any, masses: ChainMasses | None = None, *,
                             data: StiffnessData | None = None,
                             tool_length: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Tool-point deflection of a joint-chain machine under its own weight.

    Args:
        machine: a joint-chain machine.
        q: actuator coordinates ``(n,)`` or ``(N, n)`` (m, rad).
        masses: the moving masses (default :func:`illustrative_masses`).
        data: the elastic data (default the machine's).
        tool_length: m (default the machine's).

    Returns:
        ``(deflection (N, 6), status (N,))``: the tool point's small displacement (m) then
        rotation (rad) in base axes; NaN rows where the configuration does not assemble or is
        singular (their status says which).

    Raises:
        InputError: masses that do not fit the machine, a q of the wrong width.
    """
    data = data or default_data(machine)
    masses = masses or illustrative_masses(machine)
    masses.check(machine)
    qb = np.atleast_2d(np.asarray(q, dtype=float))
    if qb.ndim != 2 or qb.shape[1] != machine.n_actuators:
        raise InputError(f"q must have {machine.n_actuators} columns, got shape {qb.shape}")
    tl = machine.tool_length if tool_length is None else float(tool_length)
    system = assemble(machine, qb, data, tool_length=tool_length)
    load = generalized_gravity(system, masses, tl)
    # Q as a seventh "output" row: the compliance's (tool, Q) block is T N R⁺ Nᵀ Q; Q is
    # scaled to the size of T so that the mechanism test compares like with like
    scale = np.abs(load).max(axis=1, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    t_ext = np.concatenate([system.T, (load / scale)[:, None, :]], axis=1)
    c, status = null_space_compliance(system.G, system.H, t_ext, system.status)
    deflection = c[:, :6, 6] * scale
    deflection[status != Status.OK] = np.nan
    return deflection, status
