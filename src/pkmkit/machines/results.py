"""Result records returned by the machines' protocol methods (every family).

Shapes: N poses, n actuators, ``dims`` pose coordinates. A single-pose call returns the same
records with the leading N axis removed.

One record type per question, whatever the family: ``ik(..., full_output=True)`` gives an
:class:`InverseResult` (a joint-chain machine's adds its direct model), ``fk(...,
full_output=True)`` a :class:`DirectResult`, ``jacobian`` a :class:`VelocityModel`
(:class:`Jacobians` for rod legs, a joint-chain machine's ``ChainJacobians``), ``jacobian_dot``
a :class:`JacobianRates`.

Every array a record hands out is read-only (:class:`~pkmkit.machines.lazy_records.
ReadOnlyFields`, a view: no copy): writing into a field raises ``ValueError`` instead of
changing what later reads, and fields derived afterwards, see (docs/kinematics.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntFlag

import numpy as np

from pkmkit.machines.lazy_records import ReadOnlyFields


class Singularity(IntFlag):
    """Singularity class of a configuration (flags combine)."""

    REGULAR = 0
    #: det B = 0: a leg is perpendicular to its slide (workspace boundary, loss of a velocity).
    SERIAL = 1
    #: det A = 0: the legs are linearly dependent (assembly modes merge, loss of stiffness).
    PARALLEL = 2

    @property
    def label(self) -> str:
        """``"regular"``, ``"serial"``, ``"parallel"`` or ``"serial+parallel"``."""
        if self == Singularity.REGULAR:
            return "regular"
        parts = [f.name.lower() for f in (Singularity.SERIAL, Singularity.PARALLEL) if f & self]
        return "+".join(parts)


@dataclass(frozen=True)
class InverseResult(ReadOnlyFields):
    """Inverse kinematics of N poses.

    Attributes:
        q: ``(N, n)`` actuator coordinates, m (NaN for failed rows).
        status: ``(N,)`` :class:`~pkmkit.status.Status` codes.
        branches: ``(n,)`` inverse-model branch of each leg used (±1).
        shortfall: ``(N, n)`` how much each leg is too short to reach the pose (m, > 0 means
            out of reach, ≤ 0 reachable).
        method: ``"closed"`` or ``"numeric"``.
        mode: ``(N,)`` assembly mode of each configuration (sign of det A; 0 where there is
            none). A reachable pose may lie in the *other* assembly mode than the working one
            (beyond a parallel singularity): ``fk(q)`` then returns another pose unless asked
            for that mode.
        iterations: ``(N,)`` engine iterations (numeric method), else None.
        residual: ``(N,)`` largest rod closure residual (numeric method), m, else None.
        pose: ``(N, 6)`` full poses found with q when the input gave positions only (a
            full-pose machine with fewer than six actuators), else None.
        out_of_stroke: ``(N,)`` bool, an actuator of the row lies outside its stroke
            (:mod:`pkmkit.machines.strokes`; the status stays OK unless ``strokes="refuse"``);
            None when the strokes were ignored or are unlimited.
        stroke_excess: ``(N, n)`` signed excess of each actuator over its stroke (m, rad; > 0
            beyond the upper end, < 0 below the lower end, 0 within), or None.
    """

    q: np.ndarray
    status: np.ndarray
    branches: np.ndarray
    shortfall: np.ndarray
    method: str
    mode: np.ndarray
    iterations: np.ndarray | None = None
    residual: np.ndarray | None = None
    pose: np.ndarray | None = None
    out_of_stroke: np.ndarray | None = None
    stroke_excess: np.ndarray | None = None


@dataclass(frozen=True)
class DirectResult(ReadOnlyFields):
    """Direct kinematics of N actuator vectors in one requested assembly mode.

    Attributes:
        pose: ``(N, dims)`` platform position, m (NaN for failed rows).
        status: ``(N,)`` status codes.
        mode: ``(N,)`` assembly-mode sign of the solution (sign of det A; 0 if none).
        mode_label: name of the requested mode.
        branches: ``(N, n)`` inverse-model branch (±1) of each leg at the solution.
        method: ``"closed"`` or ``"numeric"``.
        rotation: ``(N, 3)`` rotation vector of the platform (numeric method with
            ``dof="full"``), rad, else None.
        iterations, residual: engine diagnostics (numeric method), else None.
        out_of_stroke, stroke_excess: the given actuator values against their strokes, as for
            :class:`InverseResult`.
    """

    pose: np.ndarray
    status: np.ndarray
    mode: np.ndarray
    mode_label: str
    branches: np.ndarray
    method: str
    rotation: np.ndarray | None = None
    iterations: np.ndarray | None = None
    residual: np.ndarray | None = None
    out_of_stroke: np.ndarray | None = None
    stroke_excess: np.ndarray | None = None


@dataclass(frozen=True)
class AssemblyModes(ReadOnlyFields):
    """Every real assembly mode of N actuator vectors.

    Attributes:
        poses: ``(N, 2, dims)`` — index 0 is the working mode, index 1 the other mode; NaN where
            that mode has no real solution.
        valid: ``(N, 2)`` bool, a real solution exists in that mode.
        mode_signs: ``(2,)`` sign of det A of each column (working mode first).
        labels: ``(2,)`` mode names, working mode first.
        branches: ``(N, 2, n)`` inverse-model branches at each solution (0 where invalid).
        status: ``(N,)`` OK if at least one mode exists, else NO_ASSEMBLY / INVALID_INPUT /
            SINGULAR.
    """

    poses: np.ndarray
    valid: np.ndarray
    mode_signs: np.ndarray
    labels: tuple[str, str]
    branches: np.ndarray
    status: np.ndarray

    @property
    def count(self) -> np.ndarray:
        """Number of real assembly modes per row ``(N,)``."""
        return self.valid.sum(axis=-1)


class VelocityModel(ReadOnlyFields):
    """What every velocity-model record shares (``machine.jacobian(...)`` of any family).

    Attributes (fields of the concrete records):
        J: ``(N, t, n)`` tool (platform) velocity per unit actuator rate: t = dims for a
            translating platform, 6 (linear rows first, then angular) otherwise; NaN rows where
            the velocity model does not exist (out of reach, no assembly, parallel singularity).
        singular_values: ``(N, k)`` singular values of J (of the homogenised J where it mixes
            translation and rotation), decreasing.
        condition: ``(N,)`` σ_max/σ_min of the same matrix.
        q: ``(N, n)`` actuator coordinates the model was taken at.
    """

    @property
    def exists(self) -> np.ndarray | bool:
        """``(N,)`` bool (one bool for a single pose): the velocity model exists (J is finite)."""
        return np.isfinite(np.asarray(self.J)).all(axis=(-2, -1))


@dataclass(frozen=True)
class Jacobians(VelocityModel):
    """Velocity model ``A ẋ = B q̇``, ``ẋ = J q̇`` at N poses.

    Attributes:
        A: ``(N, n, dims)`` parallel Jacobian, rows ``(p − c_i)ᵀ`` (m).
        B: ``(N, n, n)`` serial Jacobian (diagonal, m).
        J: ``(N, dims, n)`` ``A⁻¹B`` (dimensionless for translational machines); NaN where the
            pose is classified as a parallel singularity (J does not exist there).
        J_inv: ``(N, n, dims)`` ``B⁻¹A``; NaN at a serial singularity.
        singular_values: ``(N, n)`` singular values of J, decreasing — the velocity
            transmission factors (NaN at a parallel singularity).
        condition: ``(N,)`` σ_max/σ_min of J: very large near a serial singularity (inf when a
            singular value is exactly 0), NaN at a parallel one.
        det_A, det_B: ``(N,)`` determinants (m^n).
        parallel_measure: ``(N,)`` σ_min/σ_max of A with unit rows (0 at a parallel
            singularity, 1 when the legs are orthogonal).
        serial_measure: ``(N,)`` smallest |cos| of the angle between a leg and its slide
            (0 at a serial singularity).
        singularity: ``(N,)`` :class:`Singularity` flags.
        tolerance: threshold applied to both measures to classify a singularity.
        q: ``(N, n)`` actuator coordinates used.
        mode: ``(N,)`` assembly mode (sign of det A) of each configuration.
    """

    A: np.ndarray
    B: np.ndarray
    J: np.ndarray
    J_inv: np.ndarray
    singular_values: np.ndarray
    condition: np.ndarray
    det_A: np.ndarray
    det_B: np.ndarray
    parallel_measure: np.ndarray
    serial_measure: np.ndarray
    singularity: np.ndarray
    tolerance: float
    q: np.ndarray
    mode: np.ndarray

    @property
    def reachable(self) -> np.ndarray | bool:
        """Poses whose actuator coordinates are finite (the others have NaN Jacobians)."""
        return np.isfinite(self.q).all(axis=-1)

    @property
    def status(self) -> list[str] | str:
        """``"regular"``, ``"serial"``, ``"parallel"``, ``"serial+parallel"`` or
        ``"unreachable"``: one string for a single pose, else a list of N strings."""
        flags = np.asarray(self.singularity)
        reach = np.asarray(self.reachable).ravel()
        labels = [Singularity(int(f)).label if ok else "unreachable"
                  for f, ok in zip(flags.ravel(), reach, strict=True)]
        return labels[0] if flags.ndim == 0 else labels


@dataclass(frozen=True)
class JacobianRates(ReadOnlyFields):
    """Time derivatives of the velocity model along a motion (N samples).

    Attributes:
        qd: ``(N, n)`` actuator rates q̇ = J⁻¹ ẋ, m/s.
        A_dot: ``(N, n, dims)`` Ȧ, m/s.
        B_dot: ``(N, n, n)`` Ḃ, m/s.
        J_dot: ``(N, dims, n)`` J̇ = A⁻¹(Ḃ − ȦJ), 1/s.
    """

    qd: np.ndarray
    A_dot: np.ndarray
    B_dot: np.ndarray
    J_dot: np.ndarray


@dataclass(frozen=True)
class PoseSolutions(ReadOnlyFields):
    """Every real assembly mode of N actuator vectors of a full-pose machine (up to K).

    Attributes:
        poses: ``(N, K, 6)`` position (m) and rotation vector (rad) of each real solution, NaN
            past ``count``; ``working`` says which one the working mode is.
        count: ``(N,)`` number of real assembly modes.
        working: ``(N,)`` index of the working-mode solution (the one reached continuously from
            the home configuration by the engine), −1 if none of them.
        mode_sign: ``(N, K)`` sign of det A of each solution (0 where unused).
        residual: ``(N, K)`` largest rod-length error of each solution, m.
        condition: ``(N, K)`` condition number of the rod Jacobian at each solution.
        multiplicity: ``(N, K)`` paths meeting at each solution (≥ 2: a singular one).
        n_finite: ``(N,)`` finite complex solutions (40 for a general 6-6 geometry).
        status: ``(N,)`` OK (the list is certified complete), NO_ASSEMBLY (complete, none
            real), SINGULAR, NOT_CONVERGED (completeness not certified), INVALID_INPUT.
    """

    poses: np.ndarray
    count: np.ndarray
    working: np.ndarray
    mode_sign: np.ndarray
    residual: np.ndarray
    condition: np.ndarray
    multiplicity: np.ndarray
    n_finite: np.ndarray
    status: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        """``(N, K)`` bool, the slots holding a solution."""
        return ~np.isnan(self.poses[..., 0])

    @property
    def labels(self) -> list:
        """Per row, one label per solution: ``"working"`` for the working mode, ``"mode k"``
        (k from 2, in the order of the list) for the others."""
        count = np.atleast_1d(self.count)
        working = np.atleast_1d(self.working)
        out = []
        for n, w in zip(count, working, strict=True):
            row, k = [], 2
            for i in range(int(n)):
                if i == w:
                    row.append("working")
                else:
                    row.append(f"mode {k}")
                    k += 1
            out.append(row)
        return out[0] if np.ndim(self.count) == 0 else out
