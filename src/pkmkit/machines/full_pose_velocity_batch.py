"""The batched velocity model of a full-pose rod machine, its costly fields computed when read
(issue 22 §3).

:meth:`FullPoseMachine.jacobian` of a batch returns a
:class:`~pkmkit.machines.full_pose.FullPoseJacobians` whose cheap fields — ``A``, ``B``, the
serial measure and the flags, ``det_A``, ``mode`` — are computed at once, and whose costly
ones — ``J`` (a 6×6 solve per row), ``J_homogeneous``, ``singular_values`` and ``condition``
(an SVD per row), ``translation_singular_values`` and ``rotation_singular_values`` (two more),
``J_inv``, ``det_B`` and ``parallel_measure`` (an SVD of A with unit rows) — when first read,
with the same formulas on the same arrays, hence the same bits. The parallel-singularity flag
takes the parallel measure only on the rows where its lower bound |det U| / (‖U‖²_F / 3)³ does
not clear the tolerance (as the compiled single-pose model does). A workspace's criteria read
the assembly mode (``det_A`` and that flag: :meth:`FullPoseMachine.in_working_mode`) and,
with factor bounds or a condition bound, the singular values of J: the two SVDs of J's linear
and angular rows and J⁻¹ are never computed for them.

A record built with every field (``dataclasses.replace``, pickling, a single pose's
``_restore``) is a plain record.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.machines.full_pose_rates import base_joint_speeds, rod_b_pinv, solve_j
from pkmkit.machines.lazy_records import lazy_record_class
from pkmkit.machines.results import Singularity
from pkmkit.model.rods import STRUT
from pkmkit.numerics.linalg import small_singular_values

#: The fields computed when first read.
LAZY_FIELDS = ("J", "J_homogeneous", "singular_values", "condition", "J_inv", "det_B",
               "translation_singular_values", "rotation_singular_values", "parallel_measure")


class BatchFullVelocity:
    """The costly fields of a batched full-pose velocity model, computed when read.

    Args:
        a: ``(N, m, 6)`` A. b: ``(N, m, n)`` B. ok: ``(N,)`` rows with finite x and q.
        at_parallel: ``(N,)`` rows classified as a parallel singularity (no J there).
        length: the characteristic length L (m).
        unit: ``(N, m, 6)`` A with unit rows, moments over L (its singular values give the
            parallel measure).
    """

    __slots__ = ("_values", "a", "at_parallel", "b", "length", "ok", "unit")

    def __init__(self, a: np.ndarray, b: np.ndarray, ok: np.ndarray, at_parallel: np.ndarray,
                 length: float, unit: np.ndarray):
        self.a, self.b, self.ok = a, b, ok
        self.at_parallel, self.length, self.unit = at_parallel, length, unit
        self._values: dict[str, Any] = {}

    def field(self, name: str) -> Any:
        """The value of field ``name`` (one of :data:`LAZY_FIELDS`)."""
        values = self._values
        if name in values:
            return values[name]
        a, b, ok = self.a, self.b, self.ok
        size, n = b.shape[0], b.shape[2]
        if name == "J":
            j = np.full((size, 6, n), np.nan)  # no J at a parallel singularity (where an
            good = ok & ~self.at_parallel  # exactly singular A made np.linalg.solve raise)
            if good.any():
                j[good] = solve_j(a[good], b[good])
            values[name] = j
        elif name == "J_homogeneous":
            scale = np.array([1.0, 1.0, 1.0, self.length, self.length, self.length])
            values[name] = self.field("J") * scale[None, :, None]
        elif name == "singular_values":
            values[name] = small_singular_values(self.field("J_homogeneous"))
        elif name == "condition":
            sv = self.field("singular_values")
            with np.errstate(invalid="ignore", divide="ignore"):
                values[name] = sv[:, 0] / sv[:, -1]
        elif name == "translation_singular_values":
            values[name] = small_singular_values(self.field("J")[:, :3])
        elif name == "rotation_singular_values":
            values[name] = small_singular_values(self.field("J")[:, 3:])
        elif name == "J_inv":
            j_inv = np.full((size, n, 6), np.nan)
            good = ok & ~self.at_parallel
            if good.any():
                j_inv[good] = rod_b_pinv(b[good]) @ a[good]
            values[name] = j_inv
        elif name == "parallel_measure":
            values[name] = _parallel_measure(self.unit, ok)
        elif name == "det_B":
            det_b = np.full(size, np.nan)
            if b.shape[1] == n and ok.any():
                det_b[ok] = np.linalg.det(b[ok])
            values[name] = det_b
        else:
            raise AttributeError(name)
        return values[name]


def velocity_model(machine: Any, record: type, xb: np.ndarray, qb: np.ndarray,
                   tol: float) -> Any:
    """The velocity model of pose rows ``xb (N, 6)`` with actuator coordinates ``qb (N, n)``
    as a lazy ``record`` (:func:`lazy_class` of
    :class:`~pkmkit.machines.full_pose.FullPoseJacobians`): the cheap fields now, the costly
    ones (:data:`LAZY_FIELDS`) when read."""
    n, size = machine.n_actuators, xb.shape[0]
    length = float(machine.characteristic_length)
    ok = np.isfinite(qb).all(axis=1) & np.isfinite(xb).all(axis=1)
    m = machine.model.n_rods
    a = np.full((size, m, 6), np.nan)
    b = np.full((size, m, n), np.nan)
    if ok.any():
        a[ok], b[ok] = machine.rod_jacobians(xb[ok], qb[ok])
    # singularity measures: unit rows, moments over L; base-joint motion vs rod direction
    with np.errstate(invalid="ignore", divide="ignore"):
        dist = np.linalg.norm(a[:, :, :3], axis=2)
        unit = a / dist[:, :, None]
        unit[:, :, 3:] /= length
        speed = base_joint_speeds(machine.model, qb)
        strut = machine.model.rod_kind == STRUT
        cos = np.abs(np.take_along_axis(b, machine.model.rod_actuator[None, :, None], 2)[:, :, 0]
                     ) / (dist * speed)
        cos[:, strut] = 1.0
        serial = cos.min(axis=1)
    det_a = np.full(size, np.nan)
    if m == 6 and ok.any():
        det_a[ok] = np.linalg.det(a[ok])
    # the parallel measure (an SVD per row) only where its lower bound cannot settle the flag
    if m == 6:  # det U from det A: rows over |d_j|, moment columns over L
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            det_u = det_a / np.prod(dist, axis=1) / length**3
        near = ok & ~_surely_above(unit, det_u, tol)
    else:
        near = ok
    parallel = np.full(size, np.nan)
    parallel[near] = _parallel_measure(unit[near], ok[near])
    flags = np.where(serial < tol, int(Singularity.SERIAL), 0)
    flags |= np.where(parallel < tol, int(Singularity.PARALLEL), 0)
    at_parallel = (flags & Singularity.PARALLEL).astype(bool)
    evaluation = BatchFullVelocity(a, b, ok, at_parallel, length, unit)
    return record(evaluation, A=a, B=b, det_A=det_a, serial_measure=serial,
                  singularity=flags, tolerance=tol, q=qb.copy(),  # not the caller's q array
                  mode=np.sign(np.nan_to_num(det_a)).astype(int), characteristic_length=length)


def _parallel_measure(unit: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """``(N,)`` σ_min/σ_max of each ``unit (N, m, 6)`` row where ``ok``, NaN elsewhere."""
    sv_a = np.full((unit.shape[0], 6), np.nan)
    if ok.any():
        sv_a[ok] = small_singular_values(unit[ok])[:, :6]
    with np.errstate(invalid="ignore", divide="ignore"):
        return sv_a[:, -1] / sv_a[:, 0]


def _surely_above(unit: np.ndarray, det_u: np.ndarray, tol: float) -> np.ndarray:
    """``(N,)`` rows of square ``unit (N, 6, 6)`` (determinants ``det_u (N,)``) whose
    σ_min/σ_max is surely ≥ ``tol``: the lower bound |det U| / (‖U‖²_F / 3)³ of the compiled
    single-pose model (:func:`pkmkit.machines.full_pose_velocity_kernel._surely_above`, its
    margins for the rounding of the determinant and of the singular values); False on rows
    not finite."""
    with np.errstate(invalid="ignore", over="ignore"):
        frobenius = np.einsum("nij,nij->n", unit, unit)
        return np.abs(det_u) > (4.0 * tol + 2e-12) * (frobenius / 3.0) ** 3


def lazy_class(base: type) -> type:
    """The subclass of the record class ``base`` (a ``FullPoseJacobians``) whose fields are
    read from a :class:`BatchFullVelocity` when not given
    (:func:`~pkmkit.machines.lazy_records.lazy_record_class`)."""
    return lazy_record_class(
        base, "Lazy",
        lambda r: (f"{len(r.q)} poses, {r.q.shape[1]} actuators, tolerance {r.tolerance:g}; "
                   "J and its singular values computed when read"),
        "A batched velocity model, its costly fields computed when read (module doc).")
