"""The :class:`Machine`: a rod-leg model with named parameters and its kinematic models.

One class serves every translational rod-leg machine (built-in kinds and machines from files):
the machine modules only declare parameters and build the geometry. Closed-form models come from
:mod:`pkmkit.machines.closed_form`; ``method="numeric"`` solves the same problems with the
generic least-squares engine over every rod (:mod:`pkmkit.solve.rod_closure`).

Conventions: SI units (m, rad); poses ``(dims,)`` or ``(N, dims)``; actuator coordinates ``(n,)``
or ``(N, n)``. Single-row calls raise a typed error on failure; batched calls return NaN rows
and a per-row status (``full_output=True``). One plain pose or configuration (no options) of
``ik``, ``fk``, ``jacobian`` is one C call (:mod:`pkmkit.machines.closed_form_one`,
:mod:`pkmkit.machines.velocity_one`), asked before the chunked batch paths; whatever it does
not answer takes them (the same numbers, the typed errors).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from pkmkit.exceptions import (
    InputError,
    ParameterError,
)
from pkmkit.machines.chunks import chunked
from pkmkit.machines.closed_form import RodClosedForm
from pkmkit.machines.closed_form_one import direct_one, one_pose_pack
from pkmkit.machines.common import (
    HOME_TOL,
    MAX_COORDINATE,  # noqa: F401  (re-exported: pkmkit.machines.machine.MAX_COORDINATE)
    SINGULARITY_TOL,
    MachineKind,
    _checked_batch,
    _restore,
    _valid_rows,
)
from pkmkit.machines.error_faces import TranslationalErrors
from pkmkit.machines.export_layouts import TranslationalLayout
from pkmkit.machines.inverse_rows import RodInverseRows
from pkmkit.machines.joint_motion import JointMotion, rod_joint_motion
from pkmkit.machines.measurement_models import TranslationalMeasurement
from pkmkit.machines.modes import ModeNaming
from pkmkit.machines.out_arrays import checked_out, filled
from pkmkit.machines.protocol import MachineFace
from pkmkit.machines.results import (
    AssemblyModes,
    DirectResult,
    InverseResult,
    JacobianRates,
    Jacobians,
)
from pkmkit.machines.rod_refusals import RodRefusals
from pkmkit.machines.rod_solves import RodSolveRows
from pkmkit.machines.strokes import (
    STROKE_MODES,
    check_mode,
    judge_rows,
    refuse_absurd_home,
    stroke_limits,
)
from pkmkit.machines.velocity import LazyJacobians, VelocityEvaluation
from pkmkit.machines.velocity_one import jacobian_one, native_record
from pkmkit.machines.workspace_reports import RodReports
from pkmkit.model.mobility import grubler_count
from pkmkit.model.parameters import is_plain_number, resolve_parameters
from pkmkit.model.rods import SLIDE, RodModel
from pkmkit.numerics.arrays import as_batch, restore_shape
from pkmkit.numerics.jit import native_kernels_now
from pkmkit.numerics.linalg import batched_det
from pkmkit.solve.rod_closure import instantaneous_mobility
from pkmkit.status import Status

_LE = operator.le
_WORKING = "working"  # interned: `mode is _WORKING` for the default (else _mode_sign decides)


@dataclass(frozen=True, eq=False)
class Machine(RodSolveRows, RodRefusals, ModeNaming, TranslationalErrors,
              TranslationalMeasurement, TranslationalLayout, RodReports, RodInverseRows,
              MachineFace):
    """A parallel kinematic machine (translational rod-leg family).

    Attributes:
        id: identifier (preset id or file path).
        name: human-readable name.
        kind: the :class:`MachineKind` it was built from (None for a ``rod-legs`` file machine).
        params: parameter values in SI units (empty for ``rod-legs`` machines).
        model: the immutable :class:`~pkmkit.model.rods.RodModel`.
        description, source: documentation strings.
        extra_poses: named sample poses in addition to ``home``.
    """

    family: ClassVar[str] = "translational"

    id: str
    name: str
    kind: MachineKind | None
    params: Mapping[str, Any]
    model: RodModel
    description: str = ""
    source: str = ""
    extra_poses: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        closed = RodClosedForm(self.model)
        home = self.model.home_pose[None]
        q_home = closed.inverse(home, self.model.leg_branch)
        if not np.isfinite(q_home).all():
            short = closed.shortfall(home)[0]
            leg = int(np.argmax(short))
            raise ParameterError(
                f"machine {self.id!r}: the home pose {self.model.home_pose.tolist()} is out of "
                f"reach ({self.model.leg_names[leg]} too short by {short[leg]:.6g} m); "
                "choose other dimensions"
            )
        refuse_absurd_home(self, q_home[0])
        a, b = closed.jacobians(home, q_home)
        det_a = float(batched_det(a)[0])
        lengths = np.linalg.norm(a[0], axis=1)
        sv_unit = np.linalg.svd(a[0] / lengths[:, None], compute_uv=False)
        serial = float(np.min(np.abs(np.diag(b[0])) / lengths))
        if not (sv_unit[-1] / sv_unit[0] >= HOME_TOL and serial >= HOME_TOL):
            kind = "a parallel" if sv_unit[-1] / sv_unit[0] < HOME_TOL else "a serial"
            raise ParameterError(
                f"machine {self.id!r}: the home pose {self.model.home_pose.tolist()} is (nearly) "
                f"{kind} singularity; choose other dimensions"
            )
        object.__setattr__(self, "_closed", closed)
        object.__setattr__(self, "_home_q", q_home[0])
        object.__setattr__(self, "_working_mode", 1 if det_a > 0 else -1)
        object.__setattr__(self, "_home_jacobian", np.linalg.solve(a[0], b[0]))
        lo, hi = stroke_limits(self)  # the one-pose C entries' constants, packed once
        # the strokes without STROKE_TOL: as within_strokes
        object.__setattr__(self, "_one_pack", one_pose_pack(closed, self._default_branches, lo, hi))

    # ---------------------------------------------------------------- properties
    @property
    def dims(self) -> int:
        """Number of pose coordinates (2 planar, 3 spatial)."""
        return self.model.dims

    @property
    def n_actuators(self) -> int:
        """Number of actuators."""
        return self.model.n_actuators

    @property
    def pose_names(self) -> tuple[str, ...]:
        """Names of the pose coordinates."""
        return self.model.pose_names

    @property
    def closed_form(self) -> RodClosedForm:
        """The machine's closed-form kernels (:class:`~pkmkit.machines.closed_form.
        RodClosedForm`: inverse, shortfall, batch-last Jacobians), built once."""
        return self._closed

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
        """Reference pose ``(dims,)``, m."""
        return self.model.home_pose.copy()

    @property
    def home_q(self) -> np.ndarray:
        """Actuator coordinates at the home pose ``(n,)``, m."""
        return self._home_q.copy()

    def default_box(self) -> tuple[np.ndarray, np.ndarray]:
        """Region ``(lower (dims,), upper (dims,))`` (m) for workspace studies: the kind's
        choice, else the home pose ± 0.6 × the longest leg."""
        if self.kind is not None and self.kind.default_box is not None:
            lo, hi = self.kind.default_box(self.params, self.model)
            return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        half = 0.6 * float(self.model.leg_length.max())
        return self.home_pose - half, self.home_pose + half

    def with_params(self, **overrides: Any) -> Machine:
        """A new machine of the same kind with some parameters changed (SI units)."""
        if self.kind is None:
            raise ParameterError(
                f"machine {self.id!r} is described leg by leg and has no named parameters; "
                "edit its machine file instead"
            )
        params = resolve_parameters(self.kind.parameters, {**self.params, **overrides}, self.id)
        model = self.kind.build(params)
        poses = dict(self.kind.reference_poses(params, model))  # then the others kept: one build
        poses.update((k, v) for k, v in self.extra_poses.items() if k not in poses)
        return type(self)(id=self.id, name=self.name, kind=self.kind, params=dict(params),
                          model=model, description=self.description, source=self.source,
                          extra_poses=poses)

    # ---------------------------------------------------------------- helpers
    @property
    def _default_branches(self) -> tuple[float, ...]:
        cached = self.__dict__.get("_branch_tuple")
        if cached is None:
            cached = tuple(float(b) for b in self.model.leg_branch)
            object.__setattr__(self, "_branch_tuple", cached)
        return cached

    def within_strokes(self, q: list[float]) -> bool:
        """Every value of one configuration within its stroke, the one-pose paths' test: the
        limits themselves, not widened by ``STROKE_TOL`` as :func:`signed_excess` does — a value
        in that band goes to the batch path, whose q may round otherwise by an ulp (at the
        band's edge the two answered differently)."""
        limits = self.__dict__.get("_stroke_tuples")
        if limits is None:
            lo, hi = stroke_limits(self)
            limits = (lo.tolist(), hi.tolist())
            object.__setattr__(self, "_stroke_tuples", limits)
        if len(q) != len(limits[0]):
            raise ValueError(f"{len(q)} actuator values for {len(limits[0])} strokes")
        # comparisons looped in C (NaN compares false: outside)
        return all(map(_LE, limits[0], q)) and all(map(_LE, q, limits[1]))

    def _branches(self, branches: Any) -> np.ndarray:
        if branches is None:
            return self.model.leg_branch
        message = f"branches must be {self.model.n_legs} values of +1 or -1, got {branches!r}"
        if not is_plain_number(branches):
            raise InputError(message)
        arr = np.asarray(branches, dtype=float).reshape(-1)
        if arr.shape != (self.model.n_legs,) or not np.isin(arr, (-1.0, 1.0)).all():
            raise InputError(message)
        return arr.astype(int)

    def _mode_sign(self, mode: Any) -> int:
        valid = ["working", "other", "-1", "1", *self.model.mode_names]
        error = InputError(f"unknown assembly mode {mode!r}; valid modes: {', '.join(valid)}")
        if mode is None:
            return self._working_mode
        if isinstance(mode, str):
            text = mode.strip()
            if text == "working":
                return self._working_mode
            if text == "other":
                return -self._working_mode
            if text in ("1", "+1", "-1"):
                return int(text)
            if text in self.model.mode_names:
                return -1 if text == self.model.mode_names[0] else 1
            raise error
        if isinstance(mode, int | np.integer) and not isinstance(mode, bool) and mode in (1, -1):
            return int(mode)
        raise error

    def _linear_guess_q(self, x: np.ndarray) -> np.ndarray:
        """First-order guess of q near home: q_home + J⁻¹(home) (x − home)."""
        j_inv = np.linalg.inv(self._home_jacobian)
        # einsum, not BLAS: tiny inner dimension (see pkmkit.machines.kernels)
        return self._home_q + np.einsum("kd,ad->ka", x - self.model.home_pose, j_inv)

    def _linear_guess_pose(self, q: np.ndarray) -> np.ndarray:
        """First-order guess of the pose near home: home + J(home) (q − q_home)."""
        return self.model.home_pose + np.einsum("ka,da->kd", q - self._home_q,
                                                self._home_jacobian)

    # ---------------------------------------------------------------- inverse
    def ik(
        self,
        x: Any,
        *,
        method: str = "closed",
        branches: Any = None,
        q0: Any = None,
        full_output: bool = False,
        strokes: str = "flag",
        out: np.ndarray | None = None,
        **engine_options: Any,
    ) -> np.ndarray | InverseResult:
        """Inverse kinematics: actuator coordinates of platform poses.

        Args:
            x: pose ``(dims,)`` or poses ``(N, dims)``, m.
            method: ``"closed"`` (closed form) or ``"numeric"`` (least squares over every rod).
            branches: inverse-model branch per leg (±1); default: the working branches.
            q0: ``(n,)`` or ``(N, n)`` initial guesses for ``"numeric"`` (warm start); default:
                first-order extrapolation from the home configuration.
            full_output: return an :class:`InverseResult` (status, shortfall, diagnostics).
            strokes: actuator values outside their strokes (:mod:`pkmkit.machines.strokes`):
                ``"flag"`` (default: ``out_of_stroke`` and ``stroke_excess`` in the result, a
                :class:`~pkmkit.exceptions.StrokeWarning` for a single pose), ``"refuse"`` (NaN
                rows with status OUT_OF_STROKE; a single pose raises
                :class:`~pkmkit.exceptions.OutOfStrokeError`) or ``"ignore"``.
            out: an ``(N, n)`` float64 C-contiguous array the batch's q is written into and
                returned (also as a record's q); :mod:`pkmkit.machines.out_arrays`.
            **engine_options: forwarded to the engine (``max_iter``, ``residual_tol``, ...).

        Returns:
            q ``(n,)`` / ``(N, n)`` in m (NaN rows where the pose is out of reach), or an
            :class:`InverseResult`.

        Raises:
            InputError: mis-shaped input, non-finite single pose, bad ``branches`` or
                ``strokes``.
            UnreachablePoseError: a single pose out of reach (names the leg and the shortfall).
            ConvergenceError: a single numeric solve that failed.
            OutOfStrokeError: a single pose beyond a stroke with ``strokes="refuse"``.
        """
        if (method == "closed" and branches is None and q0 is None and not full_output
                and not engine_options and out is None):  # one plain pose: one C call
            native = native_kernels_now()
            if native is not None and self._one_pack is not None:
                q1 = native.rod_ik_one(self._one_pack, x, strokes)
                if q1 is not None:
                    return q1
            elif strokes in STROKE_MODES:  # without the extension: Python floats
                q1 = self._closed.inverse_one(x, self._default_branches)
                if q1 is not None and (strokes == "ignore" or self.within_strokes(q1)):
                    return np.array(q1)
        return self._ik_rows(x, method=method, branches=branches, q0=q0,
                             full_output=full_output, strokes=strokes, out=out,
                             **engine_options)

    @chunked
    def _ik_rows(self, x: Any, *, method: str, branches: Any, q0: Any, full_output: bool,
                 strokes: str, out: np.ndarray | None = None,
                 **engine_options: Any) -> np.ndarray | InverseResult:
        """:meth:`ik` of whatever its one-pose path does not answer (batches, options, rare
        single poses), in chunks of rows (:func:`~pkmkit.machines.chunks.chunked`)."""
        check_mode(strokes)
        xb, single = _checked_batch(x, self.dims, "pose")
        if out is not None:
            checked_out(out, x, xb, single, self.n_actuators, "ik")
        br = self._branches(branches)
        fused = full_output and method == "closed" and self._closed.fuses
        if fused:  # statuses, shortfalls and modes in the inverse's pass
            q, status, shortfall, mode = self._inverse_closed_full(xb, br, out)
            iterations = residual = None
        else:
            q, status, iterations, residual = self._inverse_rows(xb, br, method, q0,
                                                                 engine_options, out)
        q = filled(out, q)
        if single and status[0] != Status.OK:
            self._raise_inverse(xb, status[0], iterations)
        check = judge_rows(self, q, status, strokes, single, f"pose {xb[0].tolist()}",
                           full_output)
        if strokes == "refuse":
            q[status != Status.OK] = np.nan
        if not full_output:
            return restore_shape(q, single)
        if fused and strokes == "refuse":
            mode[status != Status.OK] = 0  # their q is NaN now
        result = InverseResult(
            q=q,
            status=status,
            branches=br.copy(),
            shortfall=shortfall if fused else self._closed.shortfall(xb),
            method=method,
            mode=mode if fused else self._mode_of(xb, q),
            iterations=iterations,
            residual=residual,
            out_of_stroke=None if check is None else check.out_of_stroke,
            stroke_excess=None if check is None else check.excess,
        )
        names = ("q", "status", "shortfall", "mode", "iterations", "residual", "out_of_stroke",
                 "stroke_excess")
        return _restore(result, single, names)

    def _mode_of(self, x: np.ndarray, q: np.ndarray) -> np.ndarray:
        """Sign of det A (assembly mode) of each configuration, 0 where undefined."""
        ok = np.isfinite(q).all(axis=1)
        out = np.zeros(x.shape[0], dtype=int)
        if ok.any():
            a, _ = self._closed.jacobians(x[ok], q[ok])
            out[ok] = np.sign(batched_det(a)).astype(int)
        return out

    def _branch_guess_q(self, x: np.ndarray, branches: np.ndarray) -> np.ndarray:
        """Linear guess from home; for legs on a non-working branch, the other root of the
        leg's quadratic (mirror of the carriage about the foot of the platform joint)."""
        guess = self._linear_guess_q(x)
        flip = (branches != self.model.leg_branch) & (self.model.leg_kind == SLIDE)
        if flip.any():
            along = np.einsum("kid,id->ki", x[:, None, :] - self._closed.centre0[None],
                              self._closed.axis)
            guess[:, flip] = 2.0 * along[:, flip] - guess[:, flip]
        return guess

    # ---------------------------------------------------------------- direct
    def fk_all(self, q: Any) -> AssemblyModes:
        """Every real assembly mode of actuator coordinates (closed form).

        Args:
            q: ``(n,)`` or ``(N, n)``, m.

        Returns:
            :class:`AssemblyModes`; working mode in column 0. For a single q, arrays lose the
            leading axis. Rows without any real assembly have ``status`` NO_ASSEMBLY (no error is
            raised here: zero solutions is a valid answer).
        """
        qb, single = _checked_batch(q, self.n_actuators, "q")
        finite = _valid_rows(qb)
        poses, degenerate = self._closed.direct_all(qb)
        order = [0, 1] if self._working_mode < 0 else [1, 0]
        poses = poses[:, order]
        valid = np.isfinite(poses).all(axis=2)
        # a double root (t = 0) is one assembly, on a parallel singularity: keep it once
        same = valid.all(axis=1) & (np.abs(poses[:, 0] - poses[:, 1]).max(axis=1) == 0.0)
        valid[same, 1] = False
        branches = np.zeros((*poses.shape[:2], self.n_actuators), dtype=int)
        for col in range(2):
            ok = valid[:, col]
            branches[ok, col] = self._closed.branch_signs(poses[ok, col], qb[ok])
        status = np.where(valid.any(axis=1), Status.OK, Status.NO_ASSEMBLY)
        status[degenerate] = Status.SINGULAR
        status[~finite] = Status.INVALID_INPUT
        signs = np.array([self._working_mode, -self._working_mode])
        modes = AssemblyModes(
            poses=poses, valid=valid, mode_signs=signs, labels=self.mode_labels,
            branches=branches, status=status,
        )
        return _restore(modes, single, ("poses", "valid", "branches", "status"))

    def fk(
        self,
        q: Any,
        *,
        method: str = "closed",
        mode: Any = "working",
        x0: Any = None,
        dof: str = "translation",
        full_output: bool = False,
        strokes: str = "flag",
        out: np.ndarray | None = None,
        **engine_options: Any,
    ) -> np.ndarray | DirectResult:
        """Direct kinematics in one assembly mode (default: the working mode).

        Args:
            q: ``(n,)`` or ``(N, n)`` actuator coordinates, m.
            method: ``"closed"`` or ``"numeric"``.
            mode: ``"working"``, ``"other"``, a mode name, or the sign of det A (±1).
            x0: ``(dims,)`` or ``(N, dims)`` initial poses for ``"numeric"`` (warm start);
                default: first-order extrapolation from home.
            dof: platform unknowns of the numeric solve, ``"translation"`` or ``"full"``
                (also solves the platform rotation, which the rods must then fix).
            full_output: return a :class:`DirectResult`.
            strokes: given actuator values outside their strokes: ``"flag"``, ``"refuse"`` or
                ``"ignore"``, as for :meth:`ik`.
            out: ``(N, dims)`` array the batch's poses are written into, as :meth:`ik`'s.
            **engine_options: forwarded to the engine.

        Returns:
            pose ``(dims,)`` / ``(N, dims)`` in m (NaN rows where there is no assembly in that
            mode), or a :class:`DirectResult`.

        Raises:
            InputError: mis-shaped input or non-finite single q, unknown mode.
            NoAssemblyError: a single q with no real assembly in the requested mode.
            SingularConfigurationError: a single q whose sphere centres are aligned.
            ConvergenceError: a single numeric solve that failed or reached another mode.
            OutOfStrokeError: a single q beyond a stroke with ``strokes="refuse"``.
        """
        if (method == "closed" and x0 is None and not full_output and not engine_options
                and out is None):
            # one plain configuration: one C call (closed_form_one)
            sign = self._working_mode if mode is _WORKING else self._mode_sign(mode)
            native = native_kernels_now()
            if native is not None and self._one_pack is not None:
                p1 = native.rod_fk_one(self._one_pack, q, sign, strokes)
                if p1 is not None:
                    return p1
            elif strokes in STROKE_MODES:  # without the extension: Python floats
                p1 = direct_one(self._closed, q, sign)
                if p1 is not None and (strokes == "ignore" or self.within_strokes(
                        q.tolist() if isinstance(q, np.ndarray) else q)):
                    return np.array(p1)
        return self._fk_rows(q, method=method, mode=mode, x0=x0, dof=dof,
                             full_output=full_output, strokes=strokes, out=out,
                             **engine_options)

    @chunked
    def _fk_rows(self, q: Any, *, method: str, mode: Any, x0: Any, dof: str,
                 full_output: bool, strokes: str, out: np.ndarray | None = None,
                 **engine_options: Any) -> np.ndarray | DirectResult:
        """:meth:`fk` of whatever its one-pose path does not answer, in chunks of rows."""
        check_mode(strokes)
        qb, single = _checked_batch(q, self.n_actuators, "q")
        if out is not None:
            checked_out(out, q, qb, single, self.dims, "fk")
        sign = self._mode_sign(mode)
        pose, status, rotation, iterations, residual = self._direct_rows(
            qb, sign, method, x0, dof, single, engine_options)
        status = np.asarray(status, dtype=int)
        # every row beyond MAX_COORDINATE, also those a periodic crank angle makes solvable:
        # refused as the single call does
        status[~_valid_rows(qb)] = Status.INVALID_INPUT
        if single and status[0] != Status.OK:
            self._raise_direct(qb[0], sign, status[0])
        check = judge_rows(self, qb, status, strokes, single, f"q = {qb[0].tolist()}",
                           full_output)
        ok = status == Status.OK
        if not ok.all():
            pose = np.where(ok[:, None], pose, np.nan)
            if rotation is not None:
                rotation = np.where(ok[:, None], rotation, np.nan)
        pose = filled(out, pose)
        if single and not ok[0]:
            self._raise_direct(qb[0], sign, status[0])
        if not full_output:
            return restore_shape(pose, single)
        branches = np.zeros((qb.shape[0], self.n_actuators), dtype=int)
        branches[ok] = self._closed.branch_signs(pose[ok], qb[ok])
        result = DirectResult(
            pose=pose,
            status=status,
            mode=np.where(ok, sign, 0),
            mode_label=self.mode_label(sign),
            branches=branches,
            method=method,
            rotation=rotation,
            iterations=iterations,
            residual=residual,
            out_of_stroke=None if check is None else check.out_of_stroke,
            stroke_excess=None if check is None else check.excess,
        )
        names = ("pose", "status", "mode", "branches", "rotation", "iterations", "residual",
                 "out_of_stroke", "stroke_excess")
        return _restore(result, single, names)

    def _mode_guess_pose(self, q: np.ndarray, sign: int) -> np.ndarray:
        """Linear guess from home; for the other assembly mode, its mirror about the plane
        (line) through the sphere centres — the two modes are mirror images."""
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            guess = self._linear_guess_pose(q)
            if sign == self._working_mode:
                return guess
            c, _ = self._closed.centres(q)
            if self.dims == 3:
                normal = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
            else:
                e = c[:, 1] - c[:, 0]
                normal = np.stack([-e[:, 1], e[:, 0]], axis=1)
            normal /= np.linalg.norm(normal, axis=1, keepdims=True)
            depth = np.einsum("kd,kd->k", guess - c[:, 0], normal)
            return guess - 2.0 * depth[:, None] * normal

    # ---------------------------------------------------------------- velocity
    def jacobian(
        self, x: Any = None, *, q: Any = None, branches: Any = None,
        tol: float = SINGULARITY_TOL
    ) -> Jacobians:
        """Velocity model at poses: A, B, J, singular values, conditioning, singularities.

        Args:
            x: ``(dims,)`` or ``(N, dims)`` poses, m; default: the working-mode direct model of
                ``q``.
            q: actuator coordinates at those poses; default: the inverse model (``branches``).
            branches: inverse-model branches used when ``q`` is not given.
            tol: threshold on the dimensionless singularity measures (see :class:`Jacobians`).

        Returns:
            :class:`Jacobians` (leading axis dropped for a single pose). Rows out of reach are
            NaN.

        Raises:
            InputError, UnreachablePoseError: as for :meth:`ik` (single pose); q that does not
                fit x (single pose; batched rows become NaN); a tolerance that is not > 0.
        """
        if q is None and branches is None and type(tol) is float and 0.0 < tol < math.inf:
            # one plain pose: one C call, the fields in one more when first read (velocity_one)
            native = native_kernels_now()
            if native is not None and self._one_pack is not None:
                state = native.rod_jacobian_one(self._one_pack, x, tol)
                if state is not None:
                    return native_record(self._closed, state, tol, native.rod_field)
            else:
                fast = jacobian_one(self._closed, x, tol, self._default_branches,
                                    self.within_strokes)  # same numbers, Python floats
                if fast is not None:
                    return fast
        if not (isinstance(tol, int | float | np.floating) and np.isfinite(tol) and tol > 0):
            raise InputError(f"tol must be a positive number, got {tol!r}")
        if x is None:
            x = self._poses_of_q(q)
        xb, qb, single = self._poses_and_q(x, q, branches)
        return self._jacobians(xb, qb, tol, single)

    def _poses_of_q(self, q: Any) -> np.ndarray:
        """The poses of actuator coordinates ``q`` for a velocity model asked at ``q`` alone
        (working-mode direct model; a batch keeps its NaN rows)."""
        if q is None:
            raise InputError("jacobian needs the poses x or the actuator coordinates q")
        return self.fk(q, strokes="ignore")

    def _poses_and_q(self, x: Any, q: Any, branches: Any) -> tuple[np.ndarray, np.ndarray, bool]:
        xb, single = _checked_batch(x, self.dims, "pose")
        if q is None:
            return xb, np.atleast_2d(self.ik(xb[0] if single else xb, branches=branches)), single
        qb, _q_single = _checked_batch(q, self.n_actuators, "q") if single else as_batch(
            q, self.n_actuators, "q")
        if qb.shape[0] != xb.shape[0]:
            raise InputError(f"x has {xb.shape[0]} rows but q has {qb.shape[0]}")
        # q must close every leg at x: otherwise the Jacobians describe no configuration
        with np.errstate(invalid="ignore", over="ignore"):
            d = self._closed.rod_vectors(xb, qb)
            _, rho = self._closed.centres(qb)
            error = np.abs(np.linalg.norm(d, axis=2) - rho)
        scale = 1e-9 * (1.0 + float(self.model.leg_length.max()))
        bad = ~(error <= scale).all(axis=1)
        if bad.any():
            if single:
                leg = int(np.nanargmax(np.where(np.isfinite(error[0]), error[0], np.inf)))
                raise InputError(
                    f"q = {qb[0].tolist()} does not fit pose {xb[0].tolist()}: "
                    f"{self.model.leg_names[leg]} misses its length by {error[0, leg]:.6g} m"
                )
            qb = qb.copy()
            qb[bad] = np.nan
        return xb, qb, single

    def _jacobians(self, xb: np.ndarray, qb: np.ndarray, tol: float,
                   single: bool = False) -> LazyJacobians:
        """Batched velocity model, computed field group by field group when read (see
        :mod:`pkmkit.machines.velocity`)."""
        return LazyJacobians(VelocityEvaluation(self._closed, xb, qb, tol), single)

    def jacobian_dot(self, x: Any, xd: Any, *, q: Any = None) -> JacobianRates:
        """Time derivatives of the velocity model for platform velocities ``xd`` at poses ``x``.

        Args:
            x: ``(dims,)`` or ``(N, dims)`` poses, m.
            xd: platform velocities of the same shape, m/s.
            q: actuator coordinates (default: inverse model, working branches).

        Returns:
            :class:`JacobianRates` with q̇ = J⁻¹ẋ, Ȧ, Ḃ and J̇ = A⁻¹(Ḃ − ȦJ).
        """
        xb, qb, single = self._poses_and_q(x, q, None)
        xdb, _ = _checked_batch(xd, self.dims, "xd") if single else as_batch(xd, self.dims, "xd")
        if xdb.shape[0] != xb.shape[0]:
            raise InputError(f"x has {xb.shape[0]} rows but xd has {xdb.shape[0]}")
        # rows of a batch with non-finite or absurd velocities give NaN, the others go on
        xdb = np.where(_valid_rows(xdb)[:, None], xdb, np.nan)
        jac = self._jacobians(xb, qb, SINGULARITY_TOL)
        qd = np.einsum("kij,kj->ki", jac.J_inv, xdb)
        a_dot, b_dot = self._closed.jacobian_rates(xdb, qd, xb, jac.q)
        rhs = b_dot - np.einsum("kij,kjl->kil", a_dot, jac.J)
        j_dot = np.full_like(rhs, np.nan)
        ok = np.isfinite(jac.A).all(axis=(1, 2)) & np.isfinite(rhs).all(axis=(1, 2))
        j_dot[ok] = np.linalg.solve(jac.A[ok], rhs[ok])
        rates = JacobianRates(qd=qd, A_dot=a_dot, B_dot=b_dot, J_dot=j_dot)
        return _restore(rates, single, ("qd", "A_dot", "B_dot", "J_dot"))

    def joint_motion(self, x: Any, xd: Any, xdd: Any, *, tol: float = SINGULARITY_TOL,
                     orientation: Any = None) -> JointMotion:
        """Actuator motion along poses, velocities, accelerations ``(N, dims)``
        (:func:`~pkmkit.machines.joint_motion.rod_joint_motion`; ``orientation`` must be None)."""
        if orientation is not None:
            raise InputError("a translating platform has no orientation to hold")
        return rod_joint_motion(self, x, xd, xdd, tol)

    # ---------------------------------------------------------------- structure
    def mobility(self) -> dict[str, Any]:
        """Grübler–Kutzbach count and rank-based mobility at the home configuration."""
        return {
            "grubler": grubler_count(self.model),
            "instantaneous": instantaneous_mobility(
                self.model, self.model.home_pose, self._home_q
            ),
        }
