"""The loaded equilibrium of a rod-leg machine under a wrench: the exact rod geometry solved by
Newton from the linear deflection, beside the linear deflection and their difference (the
geometric-stiffness term), batched.

Unknowns per pose (rod and actuator data of :mod:`pkmkit.stiffness.rod_legs`): the platform's
displacement ``u`` (``δp``, then the rotation vector ``θ`` of ``R R₀ᵀ`` for a turning platform),
the drives' deflections ``δq`` and the rods' tensions ``t``. Rod j joins ``a_j(q)`` (its base
joint, moved along its slide ``a_j = b⁰_j + q u_j``, fixed for a strut) to ``P_j = p + R b_j``,
``L_j = |P_j − a_j|``, ``e_j = (P_j − a_j)/L_j``; its rest length ``λ_j`` is its unloaded length
(a strut's plus its drive's deflection), its elongation ``ε_j = L_j − λ_j``. Equations:

- platform: ``F − Σ t_j e_j = 0`` and ``M + (R r) × F − Σ t_j (R b_j) × e_j = 0`` (moments
  about the platform origin; the wrench ``(F, M)`` fixed in the base frame, ``F`` applied at the
  reference point ``p + R r`` that moves with the platform);
- drives: ``k_a δq_a + Σ_j t_j ∂ε_j/∂q_a = 0``;
- rods: ``ε_j = c_j t_j`` (``c_j = ℓ_j/(EA)``, zero for rigid rods: the mixed form keeps rigid
  rods as constraints).

At ``u = 0`` the linearisation of these equations is the linear model (``δ = C w``); the
difference ``loaded − linear`` is of second order in the load (the change of the rod directions
and lever arms under load): the **geometric-stiffness** term. Its share
``‖loaded − linear‖ / ‖loaded‖`` (rotations times the machine's characteristic length) is
reported. Newton's Jacobian is by central differences of these residuals (a few dozen unknowns
at most). A pose whose equilibrium is not found in :data:`MAX_ITERATIONS` steps is flagged
``NOT_CONVERGED``: a load beyond the small-displacement range, or a configuration near a
singularity.

Checked (``tests/stiffness/test_equilibrium.py``) against the independent equilibrium of a cubic
hexapod with compliant drives and rods, against the minimum of the drives' energy minus the
work of a force through the machine's direct model (rigid rods), and by the difference growing
as the square of the load.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pkmkit.exceptions import ConvergenceError, InputError
from pkmkit.model.rods import CRANK, SLIDE, STRUT
from pkmkit.spatial.rotation import rotvec_to_matrix
from pkmkit.status import Status
from pkmkit.stiffness.data import StiffnessData, default_data

#: Most Newton steps.
MAX_ITERATIONS = 30
#: Poses solved together (the finite-difference Jacobians take (d + n + m)² numbers each).
BLOCK = 4096
#: Newton stops when its step (scaled unknowns, m) is below this fraction of the unknowns plus
#: :data:`FLOOR` times the machine's size (the rounding of its rod lengths).
STEP_TOL = 1e-9
FLOOR = 1e-15
#: Components of the loaded deflection and of the difference below this many machine sizes (m)
#: or radians are zero: under the rounding of the rod lengths the residuals are computed with.
RESOLUTION = 1e-13


@dataclass(frozen=True)
class LoadedDeflection:
    """The linear and the loaded-equilibrium deflection at N poses (d twist coordinates).

    Attributes:
        linear: ``(N, d)`` C w (m, rad).
        loaded: ``(N, d)`` the equilibrium of the exact geometry (m, rad).
        difference: ``(N, d)`` loaded − linear (components below :data:`RESOLUTION` times
            the machine's size, or radians, are zero in both).
        share: ``(N,)`` ‖difference‖ / ‖loaded‖ (rotations times ``length``).
        iterations: ``(N,)`` Newton steps taken.
        status: ``(N,)`` :class:`~pkmkit.status.Status` (``NOT_CONVERGED``: no equilibrium
            found; NaN rows).
        length: m, the length that weighs rotations in ``share``.
    """

    linear: np.ndarray
    loaded: np.ndarray
    difference: np.ndarray
    share: np.ndarray
    iterations: np.ndarray
    status: np.ndarray
    length: float

    def single(self) -> LoadedDeflection:
        """The first row without its batch axis."""
        return LoadedDeflection(self.linear[0], self.loaded[0], self.difference[0],
                                self.share[0], self.iterations[0], self.status[0], self.length)


class _Rods:
    """The rows of a rod machine's equilibrium (rods of a full-pose machine, equivalent legs of
    a translating one)."""

    def __init__(self, machine: Any, data: StiffnessData):
        model = machine.model
        self.full = bool(model.full_pose)
        pre = "rod_" if self.full else "leg_"
        self.base = getattr(model, pre + "base")
        self.axis = getattr(model, pre + "axis")
        self.platform = getattr(model, pre + "platform")
        self.actuator = getattr(model, pre + "actuator")
        self.kind = getattr(model, pre + "kind")
        if (self.kind == CRANK).any():
            raise InputError(f"loaded equilibrium of {machine.id!r}: its cranks are not "
                             "modelled (slides and struts only)")
        self.count = (np.ones(len(self.base)) if self.full
                      else np.bincount(model.rod_leg, minlength=model.n_legs).astype(float))
        self.ea = (None if data.rod_section is None
                   else data.rod_material.E * data.rod_section.area)
        self.k_a = np.asarray(data.actuator_stiffness, dtype=float)
        self.n = machine.n_actuators
        self.m = len(self.base)
        self.d = machine.dims if self.full else min(machine.dims, 3)
        self.dims = machine.dims

    def ends(self, p: np.ndarray, rot: np.ndarray, q: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lever arms ``R b_j (N, m, 3)``, rod vectors ``P_j − a_j (N, m, 3)`` at platform
        positions ``p (N, 3)``, rotations ``(N, 3, 3)`` and actuator values ``q (N, n)``."""
        arm = np.einsum("nij,mj->nmi", rot, self.platform)
        qa = q[:, self.actuator]
        a = self.base + np.where((self.kind == SLIDE)[None, :, None],
                                 qa[:, :, None] * self.axis, 0.0)
        return arm, p[:, None, :] + arm - a, qa


def loaded_equilibrium(machine: Any, pose: Any, wrench: Any, *, data: StiffnessData | None = None,
                       reference: Any = None) -> LoadedDeflection:
    """The loaded equilibrium of a rod-leg machine under ``wrench`` beside the linear deflection
    (module docstring).

    Args:
        machine: a rod-leg machine with slides or struts (translating or full-pose).
        pose: as :func:`~pkmkit.stiffness.api.stiffness`: ``(dims,)`` / ``(N, dims)`` (positions
            for a machine with fewer than six actuators and a full pose).
        wrench: ``(d,)`` or ``(N, d)`` force (N) then moment (N·m) at the reference point.
        data: the elastic data (default the machine's).
        reference: ``(3,)`` offset (m) of the reference point in the platform frame (full-pose
            machines).

    Returns:
        :class:`LoadedDeflection` (batch axis dropped for a single pose).

    Raises:
        InputError: a machine with cranks or joint chains, a wrench of the wrong width, data
            that do not fit; for a single pose the typed errors of :func:`stiffness`.
        ConvergenceError: a single pose whose equilibrium is not found (a batch flags the row
            ``NOT_CONVERGED``).
    """
    from pkmkit.stiffness.api import stiffness

    if machine.stiffness_from_actuators:
        raise InputError(f"loaded equilibrium of {machine.id!r}: joint-chain machines have the "
                         "linear deflection only")
    data = data or default_data(machine)
    rods = _Rods(machine, data)
    arr = np.asarray(pose, dtype=float)
    single = arr.ndim == 1
    arr = np.atleast_2d(arr)
    result = stiffness(machine, arr, wrench=wrench, data=data, reference=reference)
    linear = np.atleast_2d(result.deflection)
    w = np.broadcast_to(np.asarray(wrench, dtype=float), linear.shape)
    inv = machine.ik(arr, full_output=True, strokes="ignore")
    q0 = np.atleast_2d(np.asarray(inv.q, dtype=float))
    full = getattr(inv, "pose", None)
    full = np.atleast_2d(np.asarray(arr if full is None else full, dtype=float))
    r = np.zeros(3) if reference is None else np.asarray(reference, dtype=float).reshape(3)
    length = float(machine.length_scale)
    status = np.asarray(result.status, dtype=int).copy()
    ok = (status == Status.OK) & np.isfinite(linear).all(axis=1)
    loaded = np.full(linear.shape, np.nan)
    steps = np.zeros(len(linear), dtype=int)
    good = np.flatnonzero(ok)
    for start in range(0, good.size, BLOCK):  # blocks: the Jacobians' memory
        rows = good[start:start + BLOCK]
        got, conv, its = _solve(rods, full[rows], q0[rows], w[rows], linear[rows], data, r,
                                length)
        loaded[rows[conv]] = got[conv]
        steps[rows] = its
        status[rows[~conv]] = Status.NOT_CONVERGED
    # below the solver's resolution (the rounding of the rod lengths): zero
    loaded[np.abs(loaded) < RESOLUTION * np.where(np.arange(loaded.shape[1]) < 3, length,
                                                  1.0)] = 0.0
    diff = loaded - linear
    diff[np.abs(diff) < RESOLUTION * np.where(np.arange(diff.shape[1]) < 3, length, 1.0)] = 0.0
    scale = np.ones(linear.shape[1])
    scale[3:] = length
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.linalg.norm(diff * scale, axis=1) / np.linalg.norm(loaded * scale, axis=1)
    share = np.where(np.linalg.norm(loaded, axis=1) > 0, share, 0.0)
    share[~np.isfinite(loaded).all(axis=1)] = np.nan
    out = LoadedDeflection(linear, loaded, diff, share, steps, status, length)
    if not single:
        return out
    if status[0] == Status.NOT_CONVERGED:
        raise ConvergenceError(
            f"no loaded equilibrium of {machine.id!r} found from the linear deflection in "
            f"{MAX_ITERATIONS} Newton steps: the load is beyond the small-displacement range or "
            "the pose is near a singularity")
    return out.single()


def _solve(rods: _Rods, x0: np.ndarray, q0: np.ndarray, w: np.ndarray, linear: np.ndarray,
           data: StiffnessData, r: np.ndarray, length: float
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Newton on the scaled residuals from the linear deflection: loaded deflections
    ``(N, d)``, converged ``(N,)`` and steps ``(N,)``."""
    n_rows, d = linear.shape
    full = rods.full
    k_ref = float(np.mean(rods.k_a))
    p0 = np.zeros((n_rows, 3))
    p0[:, :min(rods.dims, 3)] = x0[:, :min(rods.dims, 3)]
    r0 = rotvec_to_matrix(x0[:, 3:6]) if full else np.tile(np.eye(3), (n_rows, 1, 1))
    _, vec0, _ = rods.ends(p0, r0, q0)
    rest0 = np.linalg.norm(vec0, axis=2)                         # unloaded lengths (N, m)
    if rods.ea is None:
        comp = np.zeros_like(rest0)
    else:
        comp = rest0 / (rods.ea * rods.count)
    strut = rods.kind == STRUT
    force = np.zeros((n_rows, 3))
    force[:, :min(d, 3)] = w[:, :min(d, 3)]
    moment = w[:, 3:6] if full else np.zeros((n_rows, 3))
    lever = np.einsum("nij,j->ni", r0, r)
    nu = d + rods.n + rods.m

    def unpack(z):
        u = z[:, :d].copy()
        if full:
            u[:, 3:] /= length
        return u, z[:, d:d + rods.n], z[:, d + rods.n:] * k_ref

    def geometry(u, idx):
        p = p0[idx].copy()
        p[:, :min(d, 3)] += u[:, :min(d, 3)]
        rot = rotvec_to_matrix(u[:, 3:6]) @ r0[idx] if full else r0[idx]
        return p, rot

    def residual(z, idx):
        """Scaled residuals ``(k, nu)`` at unknowns ``z (k, nu)`` of the rows ``idx (k,)``."""
        u, dq, t = unpack(z)
        p, rot = geometry(u, idx)
        arm, vec, _ = rods.ends(p, rot, q0[idx] + dq)
        lengths = np.linalg.norm(vec, axis=2)
        e = vec / lengths[:, :, None]
        rest = rest0[idx] + np.where(strut, dq[:, rods.actuator], 0.0)
        pull = t[:, :, None] * e
        out = np.empty((len(z), nu))
        out[:, :min(d, 3)] = (force[idx] - pull.sum(axis=1))[:, :min(d, 3)] / k_ref
        if full:
            tip = np.einsum("nij,j->ni", rot, r)
            out[:, 3:6] = (moment[idx] + np.cross(tip, force[idx])
                           - np.cross(arm, pull).sum(axis=1)) / (k_ref * length)
        # ∂ε/∂q_a: −e·u_j for a slide, −1 for a strut
        de = np.where(strut, -1.0, -np.einsum("nmi,mi->nm", e, rods.axis))
        drive = rods.k_a * dq
        np.add.at(drive.T, rods.actuator, (t * de).T)
        out[:, d:d + rods.n] = drive / k_ref
        out[:, d + rods.n:] = (lengths - rest) - comp[idx] * t
        return out

    z = np.zeros((n_rows, nu))
    z[:, :d] = linear
    if full:
        z[:, 3:d] *= length
        # the reference point's deflection back to the platform origin's
        z[:, :3] -= np.cross(linear[:, 3:6], lever)
    h = 1e-6 * length
    done = np.zeros(n_rows, dtype=bool)
    steps = np.zeros(n_rows, dtype=int)
    for _ in range(MAX_ITERATIONS):
        act = np.flatnonzero(~done)
        if not act.size:
            break
        za = z[act]
        f0 = residual(za, act)
        jac = np.empty((len(act), nu, nu))
        for k in range(nu):
            dz = np.zeros(nu)
            dz[k] = h
            jac[:, :, k] = (residual(za + dz, act) - residual(za - dz, act)) / (2 * h)
        with np.errstate(invalid="ignore"):
            good = np.isfinite(jac).all(axis=(1, 2)) & (np.abs(np.linalg.det(
                jac / np.abs(jac).max(axis=(1, 2), keepdims=True))) > 1e-14)
        step = np.full((len(act), nu), np.nan)
        if good.any():
            step[good] = _steps(jac[good], f0[good])
        z[act] = za + step
        steps[act] += 1
        small = (np.abs(step).max(axis=1)
                 <= STEP_TOL * np.abs(za).max(axis=1) + FLOOR * length) & (steps[act] > 1)
        bad = ~np.isfinite(step).all(axis=1)
        done[act[small | bad]] = True
        z[act[bad]] = np.nan
    converged = done & np.isfinite(z).all(axis=1)
    u, _, _ = unpack(z)
    if full:
        _, rot = geometry(u, np.arange(n_rows))
        u[:, :3] += np.einsum("nij,j->ni", rot, r) - lever  # the reference point's move
    u[~converged] = np.nan
    return u, converged, steps


def _steps(jac: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Newton steps ``−J⁻¹ f`` ``(k, nu)`` of ``jac (k, nu, nu)``; NaN rows where a Jacobian
    is singular to working precision."""
    with np.errstate(all="ignore"):
        try:
            return -np.linalg.solve(jac, f[:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            out = np.full(f.shape, np.nan)
            for k in range(len(jac)):  # the rare batch holding a singular row: row by row
                try:
                    out[k] = -np.linalg.solve(jac[k], f[k])
                except np.linalg.LinAlgError:
                    pass
            return out
