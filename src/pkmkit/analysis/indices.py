"""Kinetostatic indices of any machine, batched over poses.

Conventions (DESIGN.md): ẋ = J q̇; the **velocity transmission factors** λ_i are the singular values
of J (a unit vector of actuator speeds, ‖q̇‖ = 1 m/s, gives a tool speed between λ_min and λ_max
m/s). By virtual work the actuator forces balancing a tool force F are f = Jᵀ F, and the tool force
produced by actuator forces f is F = J⁻ᵀ f. The **force transmission factors** are the singular
values of J⁻ᵀ, 1/λ_i in reverse order (1/λ_min … 1/λ_max): a unit vector of actuator forces
(‖f‖ = 1 N) produces a tool force between 1/λ_max and 1/λ_min N — equivalently, holding a unit
tool force takes actuator forces of norm between λ_min and λ_max N. Conditioning
κ = λ_max/λ_min ≥ 1 (its inverse 1/κ ∈ [0, 1] is the "conditioning" of seed 001). The velocity
manipulability ellipsoid {J q̇ : ‖q̇‖ ≤ 1} has semi-axes λ_i along the left singular vectors of J.

Jacobians that mix translations and rotations are made homogeneous with a characteristic length
(:func:`homogenize`, or ``indices(..., rotational_rows=..., characteristic_length=...)``) before
any of these indices are taken. The built-in machines are translational (no rotational rows).

Accuracy: the factors are computed from J = adj(A)B/det A; near a parallel singularity the
rounding of J's entries limits them, not the singular-value step, which keeps λ_min to about
eps·κ (7.7e-5 relative error measured at κ = 5e6; docs/analysis.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.machines.machine import SINGULARITY_TOL, Machine
from pkmkit.machines.results import Jacobians
from pkmkit.numerics.linalg import condition_number, singular_values
from pkmkit.parallel import DEFAULT_CHUNK, map_rows


@dataclass(frozen=True)
class Indices:
    """Kinetostatic indices at N poses (single pose: leading axis dropped).

    Attributes:
        velocity_factors: ``(N, n)`` singular values of J, decreasing (λ_max … λ_min), m/m.
        force_factors: ``(N, n)`` singular values of J⁻ᵀ, decreasing (1/λ_min … 1/λ_max): the
            tool force (N) produced by a unit vector of actuator forces lies between the last
            and the first; a unit tool force needs actuator forces between λ_min and λ_max.
        condition: ``(N,)`` κ = λ_max/λ_min (inf at a serial singularity, NaN at a parallel one
            and at unreachable poses).
        inverse_condition: ``(N,)`` 1/κ ∈ [0, 1] (0 where κ = inf, NaN where κ is NaN).
        isotropic: ``(N,)`` κ ≤ 1 + ``isotropy_tol``.
        parallel_distance: ``(N,)`` σ_min/σ_max of A with unit rows (the legs' unit vectors): 0
            on a parallel singularity, 1 for mutually orthogonal legs. Not σ_min of A.
        serial_distance: ``(N,)`` smallest singular value of B scaled by the rod lengths, i.e.
            the smallest |cos| between a leg and its slide (0 on a serial singularity).
        ellipsoid_axes: ``(N, n)`` semi-axes of the velocity ellipsoid (= velocity_factors).
        ellipsoid_directions: ``(N, dims, n)`` unit principal directions (columns), or None.
        singularity: ``(N,)`` :class:`~pkmkit.machines.results.Singularity` flags.
        reachable: ``(N,)`` the inverse model exists (other rows are NaN).
    """

    velocity_factors: np.ndarray
    force_factors: np.ndarray
    condition: np.ndarray
    inverse_condition: np.ndarray
    isotropic: np.ndarray
    parallel_distance: np.ndarray
    serial_distance: np.ndarray
    ellipsoid_axes: np.ndarray
    ellipsoid_directions: np.ndarray | None
    singularity: np.ndarray
    reachable: np.ndarray


#: Scalar index names accepted by :func:`scalar_index` (maps, workspace criteria, CLI).
SCALAR_INDICES = {
    "lambda_min": "smallest velocity transmission factor λ_min",
    "lambda_max": "largest velocity transmission factor λ_max",
    "condition": "condition number κ = λ_max/λ_min",
    "inverse_condition": "inverse condition number 1/κ",
    "force_min": "smallest force transmission factor 1/λ_max",
    "force_max": "largest force transmission factor 1/λ_min",
    "parallel_distance": "distance to parallel singularity (σ_min/σ_max of A with unit rows)",
    "serial_distance": "distance to serial singularity (smallest |cos| leg/slide)",
    "manipulability": "product of the velocity transmission factors (|det J|)",
}


def indices_from_jacobians(jac: Jacobians, *, ellipsoids: bool = False,
                           isotropy_tol: float = 1e-9) -> Indices:
    """Indices from an already computed :class:`Jacobians` (batched or single)."""
    sv = np.asarray(jac.singular_values)
    with np.errstate(divide="ignore", invalid="ignore"):
        force = 1.0 / sv[..., ::-1]
        inverse = np.where(np.isinf(jac.condition), 0.0, 1.0 / jac.condition)
    directions = None
    if ellipsoids:
        j = np.asarray(jac.J)
        directions = np.full((*j.shape[:-1], j.shape[-1]), np.nan)
        ok = np.isfinite(j).all(axis=(-2, -1))
        if ok.any():
            u, _, _ = np.linalg.svd(j[ok])
            directions[ok] = u[..., : j.shape[-1]]
    return Indices(
        velocity_factors=sv,
        force_factors=force,
        condition=np.asarray(jac.condition),
        inverse_condition=inverse,
        isotropic=np.asarray(jac.condition) <= 1.0 + isotropy_tol,
        parallel_distance=np.asarray(jac.parallel_measure),
        serial_distance=np.asarray(jac.serial_measure),
        ellipsoid_axes=sv,
        ellipsoid_directions=directions,
        singularity=np.asarray(jac.singularity),
        reachable=np.asarray(jac.reachable),
    )


def indices(machine: Machine, x: Any, *, q: Any = None, ellipsoids: bool = False,
            tol: float = SINGULARITY_TOL, isotropy_tol: float = 1e-9,
            rotational_rows: Sequence[int] = (), characteristic_length: float | None = None
            ) -> Indices:
    """Kinetostatic indices of ``machine`` at poses ``x`` (``(dims,)`` or ``(N, dims)``, m).

    Args:
        machine: any machine.
        x: poses.
        q: actuator coordinates (default: inverse model, working branches).
        ellipsoids: also compute the principal directions of the velocity ellipsoid.
        tol: singularity threshold (see :meth:`Machine.jacobian`).
        isotropy_tol: κ ≤ 1 + isotropy_tol counts as isotropic.
        rotational_rows, characteristic_length: for a Jacobian whose ``rotational_rows`` are
            angular velocities (rad/s), every index is taken on J homogenised with the
            characteristic length L_c (m) (:func:`homogenize`); report L_c with the results.
            Both or neither.
    """
    jac = machine.jacobian(x, q=q, tol=tol)
    if characteristic_length is not None or len(rotational_rows):
        if characteristic_length is None or not len(rotational_rows):
            raise InputError("homogenisation needs both rotational_rows and "
                             "characteristic_length")
        j = homogenize(jac.J, rotational_rows, characteristic_length)
        sv = singular_values(j)
        condition = np.where(np.isnan(jac.condition), np.nan, condition_number(sv))
        jac = replace(jac, J=j, singular_values=sv, condition=condition)
    return indices_from_jacobians(jac, ellipsoids=ellipsoids, isotropy_tol=isotropy_tol)


def scalar_index(ind: Indices, name: str) -> np.ndarray:
    """One scalar index per pose (see :data:`SCALAR_INDICES`) from :class:`Indices`."""
    sv = ind.velocity_factors
    values = {
        "lambda_min": lambda: sv[..., -1],
        "lambda_max": lambda: sv[..., 0],
        "condition": lambda: ind.condition,
        "inverse_condition": lambda: ind.inverse_condition,
        "force_min": lambda: ind.force_factors[..., -1],
        "force_max": lambda: ind.force_factors[..., 0],
        "parallel_distance": lambda: ind.parallel_distance,
        "serial_distance": lambda: ind.serial_distance,
        "manipulability": lambda: np.prod(sv, axis=-1),
    }
    if name not in values:
        raise InputError(f"unknown index {name!r}; valid indices: {', '.join(SCALAR_INDICES)}")
    return values[name]()


def index_values(machine: Machine, points: Any, name: str, *, scheduler: Any = None,
                 chunk: int = DEFAULT_CHUNK) -> np.ndarray:
    """One scalar index (:data:`SCALAR_INDICES`) at every pose ``points (M, dims)`` — the
    values of an index map — computed in blocks of ``chunk`` poses, in this process or with
    ``scheduler`` on Dask (see :mod:`pkmkit.parallel`; identical results). NaN where a pose is
    out of reach."""
    if name not in SCALAR_INDICES:
        raise InputError(f"unknown index {name!r}; valid indices: {', '.join(SCALAR_INDICES)}")
    points = np.atleast_2d(np.asarray(points, dtype=float))
    return map_rows(_index_block, points, chunk=chunk, scheduler=scheduler,
                    args=(machine, name))


def _index_block(points: np.ndarray, machine: Machine, name: str) -> np.ndarray:
    if not machine.velocity_split:  # J from a closure: the indices of J alone
        from pkmkit.analysis.chain_workspace import chain_index_values

        return chain_index_values(machine, points, name)
    return np.asarray(scalar_index(indices(machine, points), name), dtype=float)


def global_conditioning_index(machine: Machine, points: np.ndarray,
                              mask: np.ndarray | None = None,
                              weights: np.ndarray | None = None) -> float:
    """Global conditioning index (Gosselin & Angeles): the mean of 1/κ over a region.

    Args:
        machine: any machine.
        points: ``(M, dims)`` poses sampling the region uniformly (a grid or random samples), m.
        mask: ``(M,)`` points that belong to the region (default: every point). Unreachable
            points never count: the region is always restricted to the reachable poses.
        weights: ``(M,)`` measure of each sample (e.g. :meth:`Grid.weights` raveled); default
            equal weights.

    Returns:
        ∫ (1/κ) dW / ∫ dW estimated on the samples, in [0, 1]; NaN for an empty region.
        Reachable points on a parallel singularity (κ undefined, J infinite) count with the
        limit value 1/κ = 0.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    jac = machine.jacobian(points)
    with np.errstate(divide="ignore"):
        inv = 1.0 / np.asarray(jac.condition, dtype=float)  # 0 where κ = inf
    reach = np.asarray(jac.reachable, bool)
    inv[reach & np.isnan(inv)] = 0.0
    keep = reach & ~np.isnan(inv)
    if mask is not None:
        keep &= np.asarray(mask, bool)
    if not keep.any():
        return float("nan")
    w = np.ones(len(points)) if weights is None else np.asarray(weights, dtype=float)
    return float(np.sum(inv[keep] * w[keep]) / np.sum(w[keep]))


def homogenize(jacobian: np.ndarray, rotational_rows: np.ndarray | list[int],
               length: float) -> np.ndarray:
    """Make a twist Jacobian dimensionally homogeneous with a characteristic length.

    A Jacobian mapping actuator rates to a twist (v, ω) mixes m/s and rad/s rows; multiplying the
    angular rows by a characteristic length L_c (m) turns them into the linear velocity of a point
    at distance L_c, so that singular values and conditioning become meaningful (Angeles). The
    result depends on L_c: report it with every index computed from the homogenised matrix.

    Args:
        jacobian: ``(..., r, n)`` twist Jacobian(s).
        rotational_rows: indices of the angular-velocity rows.
        length: characteristic length L_c > 0, m.

    Returns:
        A scaled copy ``(..., r, n)``.
    """
    if not length > 0:
        raise InputError(f"the characteristic length must be > 0, got {length}")
    out = np.array(jacobian, dtype=float, copy=True)
    out[..., list(rotational_rows), :] *= length
    return out
