"""The :class:`FullPoseMachine`: rod-leg machines whose platform moves in SE(3).

The Gough–Stewart hexapod (six struts), the Verne-type module (three slides carrying six rods,
whose platform tilts with its position) and any six-DOF rod machine from a file. Poses are
rows ``(x, y, z, rx, ry, rz)``: position (m) and rotation vector (rad) of the platform frame
(:mod:`pkmkit.spatial.poses`); angles in a named convention only at the command line.

- :meth:`~FullPoseMachine.ik` — closed form rod by rod (:mod:`pkmkit.machines.full_pose_forms`);
  a machine with fewer than six actuators (the Verne-type module) also takes platform
  *positions* ``(N, 3)``, its orientation being then found with the actuators by the engine;
- :meth:`~FullPoseMachine.fk` — the least-squares engine from a guess (warm starts), in the
  working assembly mode;
- :meth:`~FullPoseMachine.jacobian` — ``A t = B q̇`` for the platform twist t = (v, ω), J, the
  homogenised J (characteristic length, documented per machine), transmission factors and
  conditioning, separately for translation and rotation, and singularity measures.

Conventions as for :class:`~pkmkit.machines.machine.Machine`: SI units, single rows raise typed
errors, batches flag rows with a status and NaN.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from pkmkit.exceptions import (
    ConvergenceError,
    InputError,
    NoAssemblyError,
    ParameterError,
    UnreachablePoseError,
)
from pkmkit.machines import full_pose_direct as direct
from pkmkit.machines import full_pose_velocity_batch as velocity_batch
from pkmkit.machines import full_pose_velocity_one as velocity_one
from pkmkit.machines.chunks import chunked
from pkmkit.machines.common import (
    HOME_TOL,
    MAX_COORDINATE,
    SINGULARITY_TOL,
    MachineKind,
    _checked_batch,
    _restore,
    _rows_like,
    _valid_rows,
)
from pkmkit.machines.error_faces import FullPoseErrors
from pkmkit.machines.export_layouts import FullPoseLayout
from pkmkit.machines.full_pose_criteria_rates import FullPoseCriteriaRates
from pkmkit.machines.full_pose_forms import FullPoseForms, default_characteristic_length
from pkmkit.machines.full_pose_inverse_record import assembly_modes, lazy_inverse_record
from pkmkit.machines.full_pose_modes import FullPoseModes
from pkmkit.machines.full_pose_one import OnePoseInverse, native_one
from pkmkit.machines.full_pose_position import PositionInverse, _stroke_fields
from pkmkit.machines.full_pose_rates import FullPoseRates
from pkmkit.machines.inverse_rows import RodInverseRows
from pkmkit.machines.joint_motion import JointMotion, full_pose_joint_motion
from pkmkit.machines.machine import Machine
from pkmkit.machines.measurement_models import FullPoseMeasurement
from pkmkit.machines.modes import ModeNaming
from pkmkit.machines.out_arrays import checked_out, filled, into
from pkmkit.machines.protocol import MachineFace
from pkmkit.machines.results import (
    DirectResult,
    InverseResult,
    Jacobians,
)
from pkmkit.machines.strokes import STROKE_MODES, check_mode, judge_rows, refuse_absurd_home
from pkmkit.machines.workspace_reports import RodReports
from pkmkit.model.mobility import grubler_count
from pkmkit.model.parameters import is_plain_number, resolve_parameters
from pkmkit.model.rods import RodModel
from pkmkit.numerics import jit
from pkmkit.numerics.arrays import as_batch, restore_shape
from pkmkit.solve.rod_closure import (
    instantaneous_mobility,
    solve_direct,
    solve_position_inverse,
)
from pkmkit.spatial.rotation import compose_rotvec
from pkmkit.status import Status

#: Rods of one actuator must agree on its coordinate within this (m or rad, relative to
#: 1 + the longest rod for lengths) for a full pose to be reachable by a machine with fewer
#: than six actuators.
CONSISTENCY_TOL = 1e-9


#: ``strokes`` of an ``ik`` that may run unchunked (:meth:`FullPoseMachine.unchunked_call`).
_UNCHUNKED = ("flag", "ignore")


@dataclass(frozen=True)
class FullPoseJacobians(Jacobians):
    """Velocity model of a full-pose machine at N poses (single pose: leading axis dropped).

    Inherited fields, with these shapes and meanings (m rods, n actuators):
    ``A (N, m, 6)`` rows ``(d_jᵀ, (R b_j × d_j)ᵀ)``; ``B (N, m, n)``; ``J (N, 6, n)`` twist per
    unit actuator rate (linear rows m/m or m/rad, angular rows 1/m or rad/rad); ``J_inv (N, n, 6)``
    = B⁺A; ``singular_values`` and ``condition`` of the **homogenised** J; ``det_A`` (six rods;
    NaN otherwise); ``parallel_measure`` σ_min/σ_max of A with unit rows, moments divided by
    the characteristic length; ``serial_measure`` the smallest |cos| between a rod and the
    motion of its base joint (1 for struts).

    Attributes:
        J_homogeneous: ``(N, 6, n)`` ``diag(1, 1, 1, L, L, L) J``.
        characteristic_length: L (m).
        translation_singular_values: ``(N, min(3, n))`` singular values of J's linear rows.
        rotation_singular_values: ``(N, min(3, n))`` of J's angular rows (rad per m or rad).
    """

    J_homogeneous: np.ndarray = None
    characteristic_length: float = 1.0
    translation_singular_values: np.ndarray = None
    rotation_singular_values: np.ndarray = None


#: The fields of a velocity model with a batch axis.
_JACOBIAN_FIELDS = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
                    "parallel_measure", "serial_measure", "singularity", "q", "mode",
                    "J_homogeneous", "translation_singular_values", "rotation_singular_values")
_ONE_POSE_JACOBIANS = velocity_one.one_pose_class(FullPoseJacobians)
_LAZY_JACOBIANS = velocity_batch.lazy_class(FullPoseJacobians)


def _pose_distance(a: np.ndarray, b: np.ndarray, length: float) -> np.ndarray:
    """Distance between pose rows: position difference plus L × rotation angle (m)."""
    from scipy.spatial.transform import Rotation

    # copies: scipy takes writeable buffers only, and records hand out read-only arrays
    angle = (Rotation.from_rotvec(np.array(a[..., 3:].reshape(-1, 3)))
             * Rotation.from_rotvec(np.array(b[..., 3:].reshape(-1, 3))).inv()).magnitude()
    return np.linalg.norm(a[..., :3] - b[..., :3], axis=-1) + length * angle.reshape(
        a.shape[:-1])


@dataclass(frozen=True, eq=False)
class FullPoseMachine(PositionInverse, FullPoseCriteriaRates, FullPoseModes, FullPoseRates,
                      ModeNaming, FullPoseErrors, FullPoseMeasurement, FullPoseLayout, RodReports,
                      RodInverseRows, MachineFace):
    """A rod-leg machine whose platform has a full SE(3) pose (``dims = 6``).

    Attributes:
        id, name, kind, params, model, description, source, extra_poses: as for
            :class:`~pkmkit.machines.machine.Machine`.
        characteristic_length: L (m) that homogenises the angular rows of J (default: the
            radius of the platform joints around the platform origin, or 1 m if they coincide);
            set it with :meth:`with_characteristic_length` or ``[machine]
            characteristic_length`` in a machine file.
        length_given: True when L was given rather than defaulted (it then survives
            :meth:`with_params`).
    """

    family: ClassVar[str] = "full-pose"

    id: str
    name: str
    kind: MachineKind | None
    params: Mapping[str, Any]
    model: RodModel
    description: str = ""
    source: str = ""
    extra_poses: Mapping[str, np.ndarray] = field(default_factory=dict)
    characteristic_length: float | None = None
    length_given: bool = field(init=False, default=False, repr=False)

    def __post_init__(self) -> None:
        if not self.model.full_pose:
            raise ParameterError(f"machine {self.id!r}: a full-pose machine needs dims = 6")
        if self.characteristic_length is not None:
            length = self.characteristic_length
            if not (is_plain_number(length) and np.isfinite(length) and length > 0):
                raise ParameterError(f"machine {self.id!r}: the characteristic length must be a "
                                     f"finite length > 0, got {length!r}",
                                     "characteristic_length")
            object.__setattr__(self, "characteristic_length", float(length))
            object.__setattr__(self, "length_given", True)
        if self.model.n_rods < 6:
            raise ParameterError(
                f"machine {self.id!r} has {self.model.n_rods} rods: a six-DOF platform needs at "
                "least six to be held")
        if self.characteristic_length is None:
            length = default_characteristic_length(self.model)
            object.__setattr__(self, "characteristic_length", length)
        forms = FullPoseForms(self.model)
        object.__setattr__(self, "_forms", forms)
        home = self.model.home_pose[None]
        q_rod = forms.rod_coordinates(home)
        q_home, spread = forms.combine(q_rod)
        if not np.isfinite(q_home).all():
            short = forms.shortfall(home)[0]
            rod = int(np.argmax(short))
            raise ParameterError(
                f"machine {self.id!r}: the home pose {self.model.home_pose.tolist()} does not "
                f"assemble ({self._rod_name(rod)} out of reach by {short[rod]:.6g} m); choose "
                "other dimensions or another home pose")
        if spread[0] > self._consistency_tol() and self.model.n_actuators < 6:
            # fewer than six actuators: the home *position* fixes the orientation, which a
            # changed geometry (defects) may have moved a little: solve it from the rods
            u0 = np.concatenate([q_home[0], self.model.home_pose[3:]])[None]
            res = solve_position_inverse(self.model, self.model.home_pose[None, :3], u0,
                                         compute_rank=False)
            if res.status[0] == Status.OK:
                home = np.concatenate([self.model.home_pose[:3], res.u[0, q_home.shape[1]:]])[
                    None]
                q_home, spread = forms.combine(forms.rod_coordinates(home))
        if spread[0] > self._consistency_tol():
            raise ParameterError(
                f"machine {self.id!r}: the home pose {self.model.home_pose.tolist()} does not "
                f"assemble: rods on one actuator disagree by {spread[0]:.6g}; give a home pose "
                "that the rods reach (a machine with fewer than six actuators reaches only some "
                "orientations)")
        refuse_absurd_home(self, q_home[0])
        object.__setattr__(self, "_home_q", q_home[0])
        object.__setattr__(self, "_home_pose", home[0].copy())
        jac = self._jacobians(home, q_home, SINGULARITY_TOL)
        if not (jac.parallel_measure[0] >= HOME_TOL and jac.serial_measure[0] >= HOME_TOL):
            which = "a parallel" if not jac.parallel_measure[0] >= HOME_TOL else "a serial"
            raise ParameterError(
                f"machine {self.id!r}: the home pose {self.model.home_pose.tolist()} is (nearly) "
                f"{which} singularity; choose other dimensions")
        object.__setattr__(self, "_home_jacobian", jac.J[0])
        sign = int(np.sign(jac.det_A[0])) if np.isfinite(jac.det_A[0]) else 1
        object.__setattr__(self, "_working_mode", sign or 1)

    # ---------------------------------------------------------------- properties
    @property
    def dims(self) -> int:
        """Pose width: 6 (position + rotation vector)."""
        return 6

    @property
    def n_actuators(self) -> int:
        """Number of actuators."""
        return self.model.n_actuators

    @property
    def pose_names(self) -> tuple[str, ...]:
        """``("x", "y", "z", "rx", "ry", "rz")``."""
        return self.model.pose_names

    @property
    def actuator_quantities(self) -> tuple[str, ...]:
        """``"length"`` (m) or ``"angle"`` (rad) per actuator."""
        return self.model.actuator_quantities

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """Names of the actuator coordinates."""
        return self.model.actuator_names

    @property
    def home_pose(self) -> np.ndarray:
        """Reference pose ``(6,)`` (for a machine with fewer than six actuators, the model's
        home position with the orientation its rods impose there)."""
        return self._home_pose.copy()

    @property
    def home_q(self) -> np.ndarray:
        """Actuator coordinates at the home pose ``(n,)``."""
        return self._home_q.copy()

    @property
    def position_controlled(self) -> bool:
        """True when the machine has fewer than six actuators: its orientation follows its
        position (a Verne-type module), and :meth:`ik` also accepts positions ``(N, 3)``."""
        return self.n_actuators < 6

    @property
    def length_scale(self) -> float:
        """L (m): the characteristic length (see the protocol's ``length_scale``)."""
        return float(self.characteristic_length)

    @property
    def six_dof(self) -> bool:
        """True with six actuators or more (the whole pose is commanded); see
        :attr:`~pkmkit.machines.protocol.MachineFace.six_dof`."""
        return not self.position_controlled

    def default_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Position region ``(lower (3,), upper (3,))`` (m) for workspace studies: the kind's
        choice, else home ± 0.4 × the shortest rod."""
        if self.kind is not None and self.kind.default_box is not None:
            lo, hi = self.kind.default_box(self.params, self.model)
            return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        half = 0.4 * float(self.model.rod_length.min())
        return self.home_pose[:3] - half, self.home_pose[:3] + half

    def with_params(self, **overrides: Any) -> FullPoseMachine:
        """A new machine of the same kind with some parameters changed (SI units)."""
        if self.kind is None:
            raise ParameterError(
                f"machine {self.id!r} is described leg by leg and has no named parameters; "
                "edit its machine file instead")
        params = resolve_parameters(self.kind.parameters, {**self.params, **overrides}, self.id)
        model = self.kind.build(params)
        poses = dict(self.kind.reference_poses(params, model))  # then the others kept
        poses.update((k, v) for k, v in self.extra_poses.items() if k not in poses)
        # one build; L this machine's when given, else the new geometry's default (not given)
        length = self.characteristic_length if self.length_given else None
        return type(self)(id=self.id, name=self.name, kind=self.kind, params=dict(params),
                          model=model, description=self.description, source=self.source,
                          extra_poses=poses, characteristic_length=length)

    def with_characteristic_length(self, length: float) -> FullPoseMachine:
        """The same machine with the characteristic length L (m) of its homogenised Jacobian
        set (conditioning and transmission indices mix translation and rotation through it).

        Raises:
            ParameterError: L not a finite length > 0.
        """
        return replace(self, characteristic_length=length)

    # ---------------------------------------------------------------- helpers
    def _rod_name(self, rod: int) -> str:
        leg = int(self.model.rod_leg[rod])
        name = self.model.leg_names[leg]
        rods = np.flatnonzero(self.model.rod_leg == leg)
        return name if len(rods) == 1 else f"{name} rod {int(np.flatnonzero(rods == rod)[0]) + 1}"

    def _consistency_tol(self) -> float:
        return CONSISTENCY_TOL * (1.0 + float(self.model.rod_length.max()))

    def _branches(self, branches: Any) -> np.ndarray:
        """Per-rod branches from per-leg values (default: the working ones)."""
        legs = self.model.leg_branch
        if branches is not None:
            arr = np.asarray(branches, dtype=float).reshape(-1)
            if arr.shape != (self.model.n_legs,) or not np.isin(arr, (-1.0, 1.0)).all():
                raise InputError(f"branches must be {self.model.n_legs} values of +1 or -1, "
                                 f"got {branches!r}")
            legs = arr.astype(int)
        return legs[self.model.rod_leg]

    def first_order_pose(self, q: np.ndarray) -> np.ndarray:
        """First-order guess ``(N, 6)`` of the pose of actuator coordinates ``q (N, n)``: the
        twist J(home)(q − q_home) applied to the home pose (the engine's default start)."""
        bad = ~_valid_rows(q)  # non-finite or beyond MAX_COORDINATE: no guess, the row alone
        twist = (np.where(bad[:, None], self._home_q, q) - self._home_q) @ self._home_jacobian.T
        guess = np.empty((q.shape[0], 6))
        guess[:, :3] = self._home_pose[:3] + twist[:, :3]
        guess[:, 3:] = compose_rotvec(twist[:, 3:], np.broadcast_to(self._home_pose[3:],
                                                                    (q.shape[0], 3)))
        guess[bad] = np.nan
        return guess

    # ---------------------------------------------------------------- inverse
    def unchunked_call(self, name: str, x: np.ndarray, kwargs: Mapping[str, Any]) -> bool:
        """Whether the batch call ``name(x (N, w), **kwargs)`` runs whole instead of in memory
        chunks (:mod:`pkmkit.machines.chunks`): a plain ``ik`` of full poses on the fused
        compiled kernel (no record, no warm start, strokes flagged or ignored) holds nothing
        but its input and its output ``q (N, n)``, ``status (N,)``, and run whole its pieces
        go to both cores in one :func:`pkmkit.numerics.jit.run_chunks` with no serial joining
        copy per chunk (issue 22 §2)."""
        return (name == "ik" and x.shape[1] == 6 and not kwargs.get("full_output")
                and kwargs.get("q0") is None and kwargs.get("strokes", "flag") in _UNCHUNKED
                and kwargs.keys() <= {"branches", "full_output", "q0", "strokes", "out"}
                and jit.use_compiled(x.shape[0], native=True))

    @chunked
    def ik(
        self,
        x: Any,
        *,
        branches: Any = None,
        q0: Any = None,
        full_output: bool = False,
        strokes: str = "flag",
        out: np.ndarray | None = None,
        **engine_options: Any,
    ) -> np.ndarray | InverseResult:
        """Inverse kinematics.

        Args:
            x: full poses ``(6,)`` / ``(N, 6)`` (closed form, rod by rod); for a machine with
                fewer than six actuators also platform positions ``(3,)`` / ``(N, 3)`` (the
                orientation is solved with the actuators by the engine from ``q0`` or from
                home, and returned in ``InverseResult.pose``).
            branches: per-leg inverse-model branches (±1); default: the working ones.
            q0: warm start for positions (``(n,)`` or ``(N, n)``).
            full_output: return an :class:`InverseResult`.
            strokes: actuator values outside their strokes: ``"flag"`` (default),
                ``"refuse"`` or ``"ignore"``, as for
                :meth:`pkmkit.machines.machine.Machine.ik`.
            out: ``(N, n)`` float64 C-contiguous array the batch's q is written into (the
                compiled kernel's own output) and returned (:mod:`pkmkit.machines.out_arrays`).
            **engine_options: forwarded to the engine (positions only).

        Returns:
            q ``(n,)`` / ``(N, n)`` (NaN rows where unreachable), or an :class:`InverseResult`
            (``shortfall`` is per rod for this family).

        Raises:
            InputError: mis-shaped input, non-finite single pose.
            UnreachablePoseError: a single pose out of reach (names the rod and by how much),
                or a full pose that a machine with fewer than six actuators cannot take.
            ConvergenceError: a single position whose orientation the engine did not find.
            OutOfStrokeError: a single pose beyond a stroke with ``strokes="refuse"``.
        """
        if (branches is None and q0 is None and not full_output and not engine_options
                and strokes in STROKE_MODES and out is None):  # one plain pose: µs
            one = native_one(self)
            q1 = NotImplemented if one is None else one.ik(x, strokes != "ignore")
            if q1 is NotImplemented:  # no C extension, or a pose of another type
                q1 = self.one_pose_inverse()(x)
                if q1 is not None and (strokes == "ignore" or self.within_strokes(q1)):
                    return np.array(q1)
            elif q1 is not None:
                return q1
        check_mode(strokes)
        try:  # an int beyond a double, a string: the typed error as_batch gives
            arr = np.asarray(x, dtype=float) if not isinstance(x, np.ndarray) else x
        except (TypeError, ValueError, OverflowError) as exc:
            raise InputError(f"pose must be an array of real numbers: {exc}") from None
        width = arr.shape[-1] if arr.ndim in (1, 2) else 6
        if width == 3 and self.position_controlled:
            return into(out, x, self._ik_position(arr, q0, branches, full_output,
                                                  engine_options, strokes), self.n_actuators)
        xb, single = _checked_batch(x, 6, "pose")
        if out is not None:
            checked_out(out, x, xb, single, self.n_actuators, "ik")
        sigma = self._branches(branches)
        fused = not single and jit.use_compiled(xb.shape[0], native=True)
        if fused:  # one pass, q NaN on every row whose status is not OK
            # a plain batch (no record, strokes flagged or ignored) never reads the statuses
            q, status = self._forms.inverse_compiled(
                xb, sigma, self._consistency_tol(), full_output or strokes == "refuse", out)
        else:
            q, status, spread = self._inverse_numpy(xb, sigma)
            q = filled(out, q)
        if single and status[0] != Status.OK:
            self._raise_inverse(xb, status[0], spread[0])
        check = judge_rows(self, q, status, strokes, single, f"pose {xb[0].tolist()}",
                           full_output)
        if not fused or strokes == "refuse":  # only "refuse" turns OK rows into others
            q[status != Status.OK] = np.nan
        if not full_output:
            return restore_shape(q, single)
        fields = dict(q=q, status=status, branches=sigma.copy(), method="closed",
                      **_stroke_fields(check))
        if not single:  # the mode (det A per row) and the shortfalls computed when read
            return lazy_inverse_record(self._forms, self.model.n_rods, xb, **fields)
        return _restore(InverseResult(mode=self._mode_of(xb, q),
                                      shortfall=self._forms.shortfall(xb), **fields), single,
                        ("q", "status", "shortfall", "mode", "out_of_stroke", "stroke_excess"))

    def _inverse_numpy(self, xb: np.ndarray, sigma: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The NumPy inverse of pose rows ``xb (N, 6)`` (small batches, no compiled kernel):
        ``(q (N, n), status (N,), spread (N,))``, q NaN where the status is not OK."""
        with np.errstate(invalid="ignore", over="ignore"):
            q_rod = self._forms.rod_coordinates(xb, sigma)
            q, spread = self._forms.combine(q_rod)
        status = np.full(xb.shape[0], int(Status.OK))
        unreachable = ~np.isfinite(q_rod).all(axis=1)
        inconsistent = ~unreachable & ~(spread <= self._consistency_tol())
        status[unreachable | inconsistent] = Status.UNREACHABLE
        status[~_valid_rows(xb)] = Status.INVALID_INPUT
        q[status != Status.OK] = np.nan
        return q, status, spread

    def _raise_inverse(self, xb: np.ndarray, status: int, spread: float) -> None:
        if status == Status.INVALID_INPUT:
            raise InputError(f"pose {xb[0].tolist()} has a coordinate beyond "
                             f"{MAX_COORDINATE:g} m")
        short = self._forms.shortfall(xb)[0]
        rod = int(np.argmax(short))
        if short[rod] > 0 or not np.isfinite(spread):
            leg = int(self.model.rod_leg[rod])
            raise UnreachablePoseError(leg, self._rod_name(rod), short[rod])
        raise UnreachablePoseError(
            -1, "the rods", spread, detail=(
                f"the pose needs the rods of one actuator at coordinates {spread:.6g} apart: "
                f"{self.id!r} has {self.n_actuators} actuators and reaches only the orientations "
                "its rods impose; give a position (3 values) instead"))

    def _mode_of(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        return assembly_modes(self._forms, self.model.n_rods, x, q)

    # ---------------------------------------------------------------- direct
    @chunked
    def fk(
        self,
        q: Any,
        *,
        x0: Any = None,
        full_output: bool = False,
        strokes: str = "flag",
        out: np.ndarray | None = None,
        **engine_options: Any,
    ) -> np.ndarray | DirectResult:
        """Direct kinematics by the least-squares engine over every rod, from ``x0`` (a warm
        start, one pose or one per row) or from the first-order guess J(home)(q − q_home).

        Returns:
            poses ``(6,)`` / ``(N, 6)`` (NaN rows where the engine found no assembly), or a
            :class:`DirectResult`.

        ``strokes`` (``"flag"``, ``"refuse"``, ``"ignore"``) treats given actuator values
        outside their strokes as :meth:`ik` does; ``out`` receives a batch's poses as
        :meth:`ik`'s ``out`` its q.

        Raises:
            InputError: mis-shaped input or non-finite single q.
            NoAssemblyError: a single q with no assembly reached from the guess.
            OutOfStrokeError: a single q beyond a stroke with ``strokes="refuse"``.
        """
        if (x0 is None and not full_output and not engine_options and strokes in STROKE_MODES
                and out is None):
            one = native_one(self)  # one plain configuration: µs
            fast = (one.fk(q, strokes != "ignore") if one is not None
                    else direct.direct_one(self, q, strokes))
            if fast is not None:
                return fast
        check_mode(strokes)
        qb, single = _checked_batch(q, self.n_actuators, "q")
        if direct.usable(engine_options, qb.shape[0], native=True):  # compiled per-pose solve
            pose, status, iterations, residual = self.direct_kernel().solve(
                qb, None if x0 is None else _rows_like(x0, 6, "x0", qb.shape[0]),
                engine_options)
        else:
            guess = (self.first_order_pose(qb) if x0 is None
                     else _rows_like(x0, 6, "x0", qb.shape[0]))
            guess[~_valid_rows(qb)] = np.nan
            engine_options.setdefault("compute_rank", False)
            with np.errstate(invalid="ignore", over="ignore"):
                result = solve_direct(self.model, qb, guess, dof="full", **engine_options)
            pose, status = result.u.copy(), result.status.copy()
            iterations, residual = result.iterations, result.residual
        status[status == Status.INCONSISTENT] = Status.NO_ASSEMBLY
        status[~_valid_rows(qb)] = Status.INVALID_INPUT
        if out is not None:
            pose = filled(checked_out(out, q, qb, single, 6, "fk"), pose)
        check = None
        if not single or status[0] == Status.OK:
            check = judge_rows(self, qb, status, strokes, single, f"q = {qb[0].tolist()}",
                               full_output)
        ok = status == Status.OK
        pose[~ok] = np.nan
        if single and not ok[0]:
            self._raise_direct(qb[0], int(status[0]), float(residual[0]))
        if not full_output:
            return restore_shape(pose, single)
        mode = self._mode_of(pose, qb)
        record = DirectResult(pose=pose, status=status, mode=mode,
                              mode_label=self.mode_labels[0], branches=np.zeros(
                                  (qb.shape[0], self.model.n_legs), dtype=int),
                              method="numeric", iterations=iterations,
                              residual=residual, **_stroke_fields(check))
        return _restore(record, single, ("pose", "status", "mode", "branches", "iterations",
                                         "residual", "out_of_stroke", "stroke_excess"))

    @staticmethod
    def _raise_direct(q: np.ndarray, status: int, residual: float) -> None:
        """The typed error of one configuration ``q`` whose direct model has ``status``."""
        if status == Status.INVALID_INPUT:
            raise InputError(f"q = {q.tolist()} has a coordinate beyond {MAX_COORDINATE:g}")
        if status == Status.NO_ASSEMBLY:
            raise NoAssemblyError(
                f"q = {q.tolist()}: no assembly found from the guess (closure residual "
                f"{residual:.3g} m); the rods may not meet, or pass x0")
        raise ConvergenceError(f"the direct model did not converge ({Status(status).label})")

    # ------------------------------------------------ the kernels of its helper modules
    # (full_pose_one, full_pose_direct, full_pose_velocity_one and _batch): built once per
    # machine, asked for by name rather than read from its fields
    within_strokes = Machine.within_strokes

    def one_pose_inverse(self) -> OnePoseInverse:
        """The closed-form inverse of one plain pose (built once, kept on the machine)."""
        inverse = self.__dict__.get("_one_inverse")
        if inverse is None:
            inverse = OnePoseInverse(self._forms, self._consistency_tol())
            object.__setattr__(self, "_one_inverse", inverse)
        return inverse

    def direct_kernel(self) -> direct.DirectKernel:
        """The compiled direct model's constants (``geom``, ``home``; built once, kept)."""
        kernel = self.__dict__.get("_direct")
        if kernel is None:
            kernel = direct.DirectKernel.of(self.model, self._home_pose, self._home_q,
                                            self._home_jacobian)
            object.__setattr__(self, "_direct", kernel)
        return kernel

    def rod_jacobians(self, x: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A ``(N, m, 6)`` and B ``(N, m, n)`` of finite pose rows ``x (N, 6)`` at actuator
        rows ``q (N, n)`` (the closed forms rod by rod: A ṗ = B q̇)."""
        return self._forms.jacobians(x, q)

    # ---------------------------------------------------------------- velocity
    def jacobian(self, x: Any = None, *, q: Any = None, branches: Any = None,
                 tol: float = SINGULARITY_TOL) -> FullPoseJacobians:
        """Velocity model at full poses (see :class:`FullPoseJacobians`).

        Args:
            x: ``(6,)`` or ``(N, 6)`` poses (or positions ``(3,)``/``(N, 3)`` for a machine
                with fewer than six actuators); default: the direct model of ``q``.
            q: actuator coordinates at those poses (default: the inverse model).
            branches: inverse-model branches when q is not given.
            tol: threshold of the singularity measures.
        """
        if q is None and branches is None and type(tol) is float and 0.0 < tol < np.inf:
            fast = self._jacobian_one(x, tol)  # one plain pose: µs, same numbers
            if fast is not None:
                return fast
        if not (isinstance(tol, int | float | np.floating) and np.isfinite(tol) and tol > 0):
            raise InputError(f"tol must be a positive number, got {tol!r}")
        if x is None:
            if q is None:
                raise InputError("jacobian needs the poses x or the actuator coordinates q")
            x = self.fk(q, strokes="ignore")
        arr = np.asarray(x, dtype=float)
        if self.position_controlled and arr.ndim in (1, 2) and arr.shape[-1] == 3:
            inv = self.ik(arr, branches=branches, full_output=True)
            xb, single = as_batch(np.asarray(inv.pose), 6, "pose")
            qb = np.atleast_2d(inv.q)
        else:
            xb, single = _checked_batch(x, 6, "pose")
            if q is None:
                qb = np.atleast_2d(self.ik(xb[0] if single else xb, branches=branches))
            else:
                qb, _ = as_batch(q, self.n_actuators, "q")
                if qb.shape[0] != xb.shape[0]:
                    raise InputError(f"x has {xb.shape[0]} rows but q has {qb.shape[0]}")
                qb = self._fitting_q(xb, qb, single)
        jac = self._jacobians(xb, qb, float(tol))
        return _restore(jac, True, _JACOBIAN_FIELDS) if single else jac

    def _jacobian_one(self, x: Any, tol: float) -> FullPoseJacobians | None:
        """The compiled velocity model of one plain full pose within the strokes, computed
        when read (:mod:`pkmkit.machines.full_pose_velocity_one`), or None."""
        if x is None:
            return None
        one = native_one(self)
        if one is not None:  # one C call now, one when a field is first read
            evaluation = one.jacobian(x, tol, True, self._jacobian_row)
            if evaluation is not NotImplemented:
                return None if evaluation is None else _ONE_POSE_JACOBIANS(evaluation)
        q1 = self.one_pose_inverse()(x)
        if q1 is None or not self.within_strokes(q1) or not velocity_one.usable(self):
            return None
        x1 = [float(v) for v in (x.tolist() if isinstance(x, np.ndarray) else x)]

        def batch() -> FullPoseJacobians:
            return self._jacobian_row(x1, q1, tol)

        constants = self.__dict__.get("_velocity_one_constants")
        if constants is None:  # once per machine
            constants = (self.direct_kernel().geom, self.n_actuators,
                         float(self.characteristic_length))
            object.__setattr__(self, "_velocity_one_constants", constants)
        return _ONE_POSE_JACOBIANS(velocity_one.OnePoseFullVelocity(*constants, x1, q1, tol,
                                                                    batch))

    def _jacobian_row(self, x: list[float], q: list[float], tol: float) -> FullPoseJacobians:
        """The batch path's velocity model of one pose ``x`` at ``q`` (a row the one-pose
        kernel refused), its leading axis dropped."""
        xb, qb = np.array([x], dtype=float), np.array([q], dtype=float)
        return _restore(self._jacobians(xb, qb, tol), True, _JACOBIAN_FIELDS)

    def _jacobians(self, xb: np.ndarray, qb: np.ndarray, tol: float) -> FullPoseJacobians:
        """The velocity model of pose rows ``xb`` at ``qb``, its costly fields (J, its singular
        values, J⁻¹) computed when read (:mod:`pkmkit.machines.full_pose_velocity_batch`)."""
        return velocity_batch.velocity_model(self, _LAZY_JACOBIANS, xb, qb, tol)

    def joint_motion(self, x: Any, xd: Any, xdd: Any, *, tol: float = SINGULARITY_TOL,
                     orientation: Any = None) -> JointMotion:
        """Actuator motion of the platform point along positions, velocities, accelerations
        ``(N, 3)`` at a held orientation (rotation vector ``(3,)``, default the home one; a
        position-controlled machine takes the one its rods impose:
        :func:`~pkmkit.machines.joint_motion.full_pose_joint_motion`).

        Raises:
            InputError: an orientation given to a position-controlled machine, or not 3
                finite values.
        """
        if orientation is not None:
            if self.position_controlled:
                raise InputError(f"{self.id!r} has {self.n_actuators} actuators: its rods set "
                                 "its orientation, which cannot be held; give no orientation")
            orientation, _ = _checked_batch(orientation, 3, "orientation")
            orientation = orientation[0]
        return full_pose_joint_motion(self, x, xd, xdd, tol, orientation)

    # ---------------------------------------------------------------- structure
    def mobility(self) -> dict[str, Any]:
        """Grübler–Kutzbach count and rank-based mobility at the home configuration."""
        return {
            "grubler": grubler_count(self.model),
            "instantaneous": instantaneous_mobility(self.model, self._home_pose,
                                                    self._home_q),
        }

