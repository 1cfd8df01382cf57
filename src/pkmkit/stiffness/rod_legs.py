"""Elastostatics of rod-leg machines (Orthoglide, linear Delta, five-bar, Delta robot, hexapods,
Verne-type module), batched.

Each rod j (unit direction u_j, from its base-side joint to the platform) has spherical (or
universal) joints at both ends and so carries only an axial force t_j. Its leg is a chain of two
springs in series along that force: the rod's axial compliance c_r,j = ℓ_j/(EA) (zero for rigid
rods) and the drive's compliance c_q,a = 1/k_a seen through the actuator. With the velocity model
in unit rows, ``A_u ẋ = B_u q̇`` (``A_u`` rows ``(u_j, (R b_j) × u_j)`` or ``u_j`` for a
translating platform, ``B_u = B / ℓ``):

- statics: a wrench w on the platform (at its reference point) is balanced by the rod forces,
  ``w = A_uᵀ t``; each actuator carries ``τ = B_uᵀ t`` (= Jᵀ w for square A_u);
- complementary energy ``½ τᵀ C_q τ + ½ tᵀ C_r t`` gives, for square ``A_u`` (as many rods as
  pose coordinates), ``C = J C_q Jᵀ + A_u⁻¹ C_r A_u⁻ᵀ`` (J = A_u⁻¹ B_u) and ``K = C⁻¹``; with
  rigid rods ``K = J⁻ᵀ K_q J⁻¹``;
- with more rods than pose coordinates (statically indeterminate) the displacement form
  ``K = A_uᵀ (C_r + B_u C_q B_uᵀ)⁻¹ A_u`` (it needs compliant rods).

A parallelogram is two rods in parallel: its equivalent leg has twice a rod's axial stiffness
(translating platforms: the parallelograms hold the platform's orientation rigidly, their
bending is not modelled). Units: SI; twists (δp, δθ) of the platform reference point.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, ParameterError
from pkmkit.machines.closed_form import RodClosedForm
from pkmkit.machines.full_pose_forms import FullPoseForms
from pkmkit.machines.machine import SINGULARITY_TOL
from pkmkit.numerics import small
from pkmkit.status import Status
from pkmkit.stiffness.compiled import rod_stiffness
from pkmkit.stiffness.data import StiffnessData


def rod_compliance(a_u: np.ndarray, b_u: np.ndarray, c_q: np.ndarray,
                   c_r: np.ndarray | None) -> np.ndarray:
    """Platform compliance ``(N, d, d)`` of rod legs (module docstring).

    Args:
        a_u: ``(N, m, d)`` unit-row parallel Jacobian. b_u: ``(N, m, n)`` serial Jacobian over
            the rod lengths. c_q: ``(n,)`` actuator compliances. c_r: ``(N, m)`` or ``(m,)`` rod
            axial compliances (None: rigid rods).

    Raises:
        InputError: more rods than pose coordinates with rigid rods.
    """
    n_rows, m, d = a_u.shape
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        if m == d:
            a_inv = _inverse(a_u)
            j = a_inv @ b_u
            c = np.einsum("nia,a,nja->nij", j, c_q, j)
            if c_r is not None:
                cr = np.broadcast_to(c_r, (n_rows, m))
                c = c + np.einsum("nij,nj,nkj->nik", a_inv, cr, a_inv)
        else:
            if c_r is None:
                raise InputError(f"{m} rods hold {d} pose coordinates: with rigid rods the "
                                 "stiffness is not determined; give the rods a section")
            cr = np.broadcast_to(c_r, (n_rows, m))
            leg = np.einsum("nia,a,nja->nij", b_u, c_q, b_u)
            leg[:, np.arange(m), np.arange(m)] += cr
            k = np.einsum("nji,njk,nkl->nil", a_u, _inverse(leg), a_u)
            c = _inverse(k)
    bad = ~np.isfinite(a_u).all(axis=(1, 2)) | ~np.isfinite(b_u).all(axis=(1, 2))
    c[bad] = np.nan
    return c


def _condition(mats: np.ndarray) -> np.ndarray:
    """Frobenius condition number ``(N,)`` of square or tall ``(N, m, d)`` matrices (inf where
    singular or not finite): ``‖M‖ ‖M⁺‖`` through the d×d normal matrix."""
    normal = np.einsum("nki,nkj->nij", mats, mats)
    inv = _inverse(normal)
    with np.errstate(invalid="ignore"):
        out = np.sqrt(np.einsum("nij,nij->n", mats, mats) * np.einsum("nii->n", inv))
    return np.where(np.isfinite(out), out, np.inf)


def _inverse(mats: np.ndarray) -> np.ndarray:
    """Batched inverse ``(N, d, d)``; NaN for rows that are not finite or are singular
    (2×2 and 3×3: the adjugate over the determinant, no LAPACK call per row)."""
    out = np.full(mats.shape, np.nan)
    ok = np.isfinite(mats).all(axis=(1, 2))
    if mats.shape[1] in (2, 3) and ok.any():
        m = np.ascontiguousarray(mats[ok].transpose(1, 2, 0))  # batch-last
        cof = small.cofactors(m)
        det = small.det(m, cof)
        good = np.abs(det) > 0
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = cof.transpose(2, 1, 0) / det[:, None, None]  # adj = cofactorsᵀ
        inv[~good] = np.nan
        out[ok] = inv
        return out
    ok[ok] = np.abs(np.linalg.det(mats[ok])) > 0
    if ok.any():
        out[ok] = np.linalg.inv(mats[ok])
    return out


def rod_leg_compliance(machine: Any, x: Any, data: StiffnessData
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Compliance of a rod-leg machine at poses ``x`` at its platform reference point.

    Args:
        machine: a :class:`~pkmkit.machines.machine.Machine` or
            :class:`~pkmkit.machines.full_pose.FullPoseMachine`.
        x: pose ``(dims,)`` / ``(N, dims)`` (m, rad); positions ``(3,)`` / ``(N, 3)`` for a
            machine with fewer than six actuators and a full pose.
        data: the elastic data.

    Returns:
        compliance ``(N, d, d)``, status ``(N,)``, the full poses ``(N, dims)``, single.

    Raises:
        InputError, UnreachablePoseError: as the machine's inverse model, for a single pose.
    """
    model = machine.model
    check_rod_data(machine, data)
    full = model.full_pose
    arr = np.asarray(x, dtype=float)
    single = arr.ndim == 1
    fast = None if single else rod_stiffness(machine, arr, data)
    if fast is not None:  # a large batch: the compiled kernels (same numbers and statuses)
        return fast.compliance, fast.status, arr, False
    # strokes are judged by the caller (the command line flags them, exit 3)
    inv = machine.ik(x, full_output=True, strokes="ignore")
    status = np.atleast_1d(np.asarray(inv.status, dtype=int)).copy()
    poses = getattr(inv, "pose", None)
    poses = np.atleast_2d(np.asarray(arr if poses is None else poses, dtype=float))
    q = np.atleast_2d(np.asarray(inv.q, dtype=float))
    ok = status == Status.OK
    rows, width = poses.shape[0], model.n_rods if full else model.n_legs
    a = np.full((rows, width, model.dims), np.nan)
    b = np.full((rows, width, machine.n_actuators), np.nan)
    if ok.any():  # the closed forms alone: no singular values, no Jacobian J
        forms = FullPoseForms(model) if full else RodClosedForm(model)
        a[ok], b[ok] = forms.jacobians(poses[ok], q[ok])
    with np.errstate(invalid="ignore", divide="ignore"):
        lengths = np.linalg.norm(a[:, :, :3] if full else a, axis=2)  # (N, m)
        a_u = a / lengths[:, :, None]
        b_u = b / lengths[:, :, None]
    c_q = 1.0 / data.actuator_stiffness
    c_r = None
    if data.rod_section is not None:
        c_r = _rod_compliances(machine, lengths, data)
    c = rod_compliance(a_u, b_u, c_q, c_r)
    # a parallel singularity: A_u (moments over the characteristic length) nearly singular
    scaled = a_u.copy()
    if full:
        scaled[:, :, 3:] /= machine.characteristic_length
    singular = _condition(scaled) > 1.0 / SINGULARITY_TOL
    status[(status == Status.OK) & (singular | ~np.isfinite(c).all(axis=(1, 2)))] = (
        Status.SINGULAR)
    c[status != Status.OK] = np.nan
    return c, status, poses, single


def _rod_compliances(machine: Any, lengths: np.ndarray, data: StiffnessData) -> np.ndarray:
    """``(N, m)`` axial compliance ℓ/(EA) of each row of A at its current length ``lengths``
    (m): a rod (full-pose machines) or an equivalent leg (translating platforms: its rods in
    parallel)."""
    model = machine.model
    ea = data.rod_material.E * data.rod_section.area
    if model.full_pose:
        return lengths / ea
    counts = np.bincount(model.rod_leg, minlength=model.n_legs)
    return lengths / (ea * counts[None, :])


def check_rod_data(machine: Any, data: StiffnessData) -> None:
    """Refuse elastic data that do not fit a rod-leg machine: an actuator stiffness per
    actuator, a rod section no larger than the shortest rod.

    Raises:
        InputError: a wrong count. ParameterError: a section larger than a rod.
    """
    model = machine.model
    n = machine.n_actuators
    if data.actuator_stiffness.shape != (n,):
        raise InputError(f"actuator_stiffness has {data.actuator_stiffness.size} values for "
                         f"{n} actuators")
    if data.rod_section is not None:
        shortest = float(model.rod_length[model.rod_kind != 1].min(initial=np.inf))
        if data.rod_section.size > shortest:
            raise ParameterError(f"rod section {data.rod_section.label} is larger than the "
                                 f"shortest rod ({shortest:g} m)", "rod_section")


def rod_leg_stiffness(machine: Any, x: Any, data: StiffnessData | None = None, *,
                      compliance: bool = True
                      ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """Stiffness and compliance ``(N, d, d)`` and status ``(N,)`` of a rod-leg machine at
    poses ``x (N, dims)``, without the eigen-analysis of :func:`pkmkit.stiffness.stiffness`:
    a large batch of a hexapod gets ``K = A_uᵀ D⁻¹ A_u`` from the compiled kernel
    (:mod:`pkmkit.stiffness.kernels`), other cases the inverse of the compliance. NaN rows
    where the pose is unreachable or singular. ``compliance=False`` may skip the compliance
    (returned as None where it was not computed: the memory of a large batch).

    Raises:
        InputError, ParameterError: elastic data that do not fit the machine.
    """
    from pkmkit.stiffness.data import default_data

    data = data or default_data(machine)
    check_rod_data(machine, data)
    arr = np.atleast_2d(np.asarray(x, dtype=float))
    fast = rod_stiffness(machine, arr, data, compliance=compliance)
    if fast is not None and fast.stiffness is not None:
        return fast.stiffness, fast.compliance, fast.status
    if fast is not None:
        c, status = fast.compliance, fast.status
    else:
        c, status, _, _ = rod_leg_compliance(machine, arr, data)
    return _inverse(c), c, status
