"""The :class:`JointChainMachine`: legs of revolute and prismatic joints closed on a platform,
a serial head and a tool — the hyperstatic machines of seed 002 (Tripteor X7, TriMule 600, the
crank–slider) and any such machine from a file.

Every geometric quantity lives in the model's element frames and their named parameters and
defects (:mod:`pkmkit.model.chains`); the kinematics are the batched closure of
:mod:`pkmkit.solve.chains`, solved in least squares by the engine (exactly when the geometry is
compatible, with the residual reported when it is not).

Conventions: the **pose** of a joint-chain machine is its tool point and tool axis, rows
``(x, y, z, i, j, k)`` (m, unit vector): the tool point lies ``tool_length`` along the z axis of
the tool frame, and the tool axis is that z axis. Actuator coordinates are the actuated joint
variables, legs first then head (rad for revolutes, m for prismatic joints).
"""

from __future__ import annotations

import warnings
from collections import defaultdict
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from pkmkit.exceptions import (
    ClosureMissError,
    ConvergenceError,
    InputError,
    OutOfStrokeError,
    ParameterError,
    SingularConfigurationError,
    StrokeWarning,
)
from pkmkit.machines.chain_checks import (
    closure_conditioning,
    leg_misses,
    miss_message,
    stroke_violations,
)
from pkmkit.machines.chain_inverse_record import inverse_record
from pkmkit.machines.chain_jacobians import (  # noqa: F401  (re-exported)
    RANK_RCOND,
    SINGULAR_TOL,
    ChainJacobians,
    ChainVelocity,
    HyperstatismCount,
)
from pkmkit.machines.chain_results import (
    ChainDirectResult,
    ChainInverseResult,
    single_row,
)
from pkmkit.machines.chain_starts import default_start, inverse_starts
from pkmkit.machines.chunks import chunked, iterative_chunk_rows
from pkmkit.machines.common import (
    MAX_COORDINATE,
    MachineKind,
    _checked_batch,
    _rows_like,
)
from pkmkit.machines.common import _valid_rows as valid_rows
from pkmkit.machines.error_faces import ChainErrors
from pkmkit.machines.export_layouts import ChainLayout
from pkmkit.machines.head_branches import head_flip_variables, nearest_head_branch
from pkmkit.machines.inverse_rows import ChainInverseRows
from pkmkit.machines.measurement_models import ChainMeasurement
from pkmkit.machines.out_arrays import checked_out, filled
from pkmkit.machines.protocol import MachineFace
from pkmkit.machines.strokes import signed_excess
from pkmkit.machines.warm_starts import ChainWarmStart
from pkmkit.machines.workspace_reports import ChainReports
from pkmkit.model.chains import JointChainModel
from pkmkit.numerics.arrays import restore_shape
from pkmkit.numerics.jit import native_kernel, use_compiled_solver
from pkmkit.solve.chains import (
    chain_pose,
    solve_closure,
    solve_machine_inverse,
    tool_frame,
)
from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix
from pkmkit.status import Status

#: A closure is exact when its largest residual is below this (m).
CLOSURE_TOL = 1e-9
POSE_NAMES = ("x", "y", "z", "i", "j", "k")
#: What the direct and inverse models do with joint values outside their strokes.
STROKE_MODES = ("flag", "refuse", "ignore")


@dataclass(frozen=True, eq=False)
class JointChainMachine(ChainVelocity, ChainErrors, ChainMeasurement, ChainLayout, ChainReports,
                        ChainWarmStart, ChainInverseRows, MachineFace):
    """A hyperstatic (or isostatic) machine of joint chains (see the module docstring).

    Attributes:
        id, name, kind, params, description, source, extra_poses: as for
            :class:`~pkmkit.machines.machine.Machine` (``extra_poses`` hold actuator vectors:
            a joint-chain machine's reference configurations are given in joint space).
        model: the :class:`~pkmkit.model.chains.JointChainModel`.
        tool_length: default distance of the tool point along the tool frame's z axis (m).
    """

    family: ClassVar[str] = "chain"
    chunk_rows = property(iterative_chunk_rows)  # batch calls in chunks (issue 22 §6)

    id: str
    name: str
    kind: MachineKind | None
    params: Mapping[str, Any]
    model: JointChainModel
    description: str = ""
    source: str = ""
    extra_poses: Mapping[str, np.ndarray] = field(default_factory=dict)
    tool_length: float = 0.0

    def __post_init__(self) -> None:
        model = self.model
        act = np.flatnonzero(model.actuated)
        loop = model.loop_variables
        object.__setattr__(self, "_actuated", act)
        object.__setattr__(self, "_passive", np.flatnonzero(~model.actuated & loop))
        home = self._solve_home()
        object.__setattr__(self, "_home", home)

    def _solve_home(self) -> dict[str, np.ndarray]:
        """Close the legs at the home joint values: exactly for a compatible geometry, in least
        squares (reported by :attr:`home_closure_residual`) for a machine with defects."""
        model = self.model
        values = model.home.copy()
        start = chain_pose(model, model.legs[0], values[:, None])
        u0 = np.concatenate([start.p[:, 0], matrix_to_rotvec(start.R[:, :, 0])[0],
                             values[self._passive]])[None]
        # the compiled closure once Numba is loaded (an identification rebuilds the machine at
        # every step); never imported for this one row
        res = solve_closure(model, values[None], u0, unknown_variables=self._passive,
                            compute_rank=False, compiled=_closure_compiled(1))
        converged = res.status[0] == Status.OK or (
            res.status[0] == Status.INCONSISTENT and model.defects.any())
        if not converged:
            raise ParameterError(
                f"machine {self.id!r}: the legs do not close at the home joint values (closure "
                f"residual {res.residual[0]:.3g} m after {res.iterations[0]} iterations); check "
                "the geometry and the home values of the passive joints")
        values[self._passive] = res.u[0, 6:]
        return {"values": values, "platform": res.u[0, :6].copy(),
                "residual": float(res.residual[0])}

    #: The inverse model is the engine's (from a start), not a closed form.
    closed_form_inverse: ClassVar[bool] = False
    #: ``ik(x, start=...)`` continues from a neighbouring point's complete solution.
    inverse_continues: ClassVar[bool] = True
    #: Defects may be incompatible with the (hyperstatic) closure.
    incompatible_defects: ClassVar[bool] = True

    @property
    def length_scale(self) -> float:
        """L (m): the model's closure scale (see the protocol's ``length_scale``)."""
        return float(self.model.characteristic_length)

    @property
    def home_closure_residual(self) -> float:
        """Largest closure residual at home (m): ~0 for a compatible geometry."""
        return self._home["residual"]

    # ---------------------------------------------------------------- properties
    @property
    def dims(self) -> int:
        """Pose width: tool point and tool axis (6 numbers, 5 degrees of freedom)."""
        return 6

    @property
    def pose_names(self) -> tuple[str, ...]:
        """``("x", "y", "z", "i", "j", "k")``: tool point then unit tool axis."""
        return POSE_NAMES

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """Names of the actuated joints (legs, then head)."""
        return self.model.actuator_names

    @property
    def actuated_columns(self) -> np.ndarray:
        """``(n,)`` int: the actuators' columns among the joint variables (``full_values``)."""
        return self._actuated

    @property
    def n_actuators(self) -> int:
        """Number of actuated joints."""
        return len(self._actuated)

    @property
    def passive_names(self) -> tuple[str, ...]:
        """Names of the passive joints of the legs."""
        return tuple(self.model.variables[i] for i in self._passive)

    @property
    def home_values(self) -> np.ndarray:
        """``(n_variables,)`` every joint variable at home (actuated and passive; m, rad), in
        ``model.variables`` order."""
        return self._home["values"].copy()

    @property
    def home_platform(self) -> np.ndarray:
        """``(6,)`` the platform pose at home (position m, rotation vector rad)."""
        return self._home["platform"].copy()

    @property
    def passive_variables(self) -> np.ndarray:
        """``(n_p,)`` indices (in ``model.variables``) of the passive joint variables solved by
        the closure, in :attr:`passive_names` order."""
        return self._passive

    @property
    def actuator_quantities(self) -> tuple[str, ...]:
        """``"angle"`` for revolute actuators, ``"length"`` for prismatic ones."""
        return tuple("angle" if self.element_of(i).type == "R" else "length"
                     for i in self._actuated)

    def element_of(self, variable: int):
        """The element (joint) of ``model.elements`` that joint variable ``variable`` moves."""
        e = int(np.flatnonzero(self.model.element_variable == variable)[0])
        return self.model.elements[e]

    @property
    def home_q(self) -> np.ndarray:
        """Actuator coordinates of the home configuration."""
        return self._home["values"][self._actuated].copy()

    @property
    def home_pose(self) -> np.ndarray:
        """Tool point and axis of the home configuration ``(6,)``: ``fk(home_q)``, solved once
        per machine (a workspace study reads it several times: each read was a one-pose solve,
        and the second one loaded the one-pose kernels, hence Numba, in a fresh process)."""
        pose = self.__dict__.get("_home_pose")
        if pose is None:
            pose = self.fk(self.home_q)
            object.__setattr__(self, "_home_pose", pose)
        return pose.copy()

    @property
    def home_passive(self) -> np.ndarray:
        """Passive joint values of the home configuration."""
        return self._home["values"][self._passive].copy()

    def reference_poses(self) -> dict[str, np.ndarray]:
        """Named reference *actuator vectors*, ``home`` first."""
        out = {"home": self.home_q}
        out.update({k: np.asarray(v, dtype=float) for k, v in self.extra_poses.items()})
        return out

    def default_box(self, per_axis: int = 5) -> tuple[np.ndarray, np.ndarray]:
        """Tool-point region ``(lower (3,), upper (3,))`` (m) for workspace studies: the box of
        the tool points reached with the legs' actuators on a ``per_axis``-point grid of their
        strokes (±3 % of home where a stroke is unlimited) and the head at home, widened by
        10 % of its extent on each side (at least 1 cm)."""
        act = np.flatnonzero(self.model.actuated)
        loop = [j for j, v in enumerate(act) if self.model.loop_variables[v]]
        home = self.home_q
        axes = []
        for j in loop:
            lo, hi = self.model.q_min[act[j]], self.model.q_max[act[j]]
            if not (np.isfinite(lo) and np.isfinite(hi)):
                lo, hi = home[j] - 0.03 * abs(home[j]), home[j] + 0.03 * abs(home[j])
            axes.append(np.linspace(lo, hi, per_axis))
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(loop))
        q = np.tile(home, (len(grid), 1))
        q[:, loop] = grid
        # compiled once Numba is loaded (an identification's bound); not imported for this alone
        points = self.fk(q, full_output=True, strokes="ignore", check_singular=False,
                         compiled=_closure_compiled(1)).pose[:, :3]
        points = np.vstack([points[np.isfinite(points).all(axis=1)], self.home_pose[:3]])
        lower, upper = points.min(axis=0), points.max(axis=0)
        pad = np.maximum(0.1 * (upper - lower), 0.01)
        return lower - pad, upper + pad

    def with_params(self, **overrides: Any) -> JointChainMachine:
        """A new machine of the same kind with some parameters changed (SI units)."""
        if self.kind is None:
            raise ParameterError(f"machine {self.id!r} is described element by element; edit "
                                 "its machine file or apply defects (with_defects)")
        from pkmkit.model.parameters import resolve_parameters

        params = resolve_parameters(self.kind.parameters, {**self.params, **overrides}, self.id)
        model = self.kind.build(params)
        return type(self)(id=self.id, name=self.name, kind=self.kind, params=dict(params),
                          model=model, description=self.description, source=self.source,
                          extra_poses=self.kind.reference_poses(params, model),
                          tool_length=float(params.get("tool_length", 0.0)))

    # ---------------------------------------------------------------- helpers
    def full_values(self, q: np.ndarray) -> np.ndarray:
        """``(N, n_var)`` every joint variable: home's, with the actuators at ``q (N, n)``."""
        values = np.tile(self._home["values"], (q.shape[0], 1))
        values[:, self._actuated] = q
        return values

    def _tool_lengths(self, tool_length: Any, rows: int) -> np.ndarray:
        if tool_length is None:
            return np.full(rows, float(self.tool_length))
        arr = np.asarray(tool_length, dtype=float).reshape(-1)
        if arr.size == 1:
            arr = np.full(rows, float(arr[0]))
        if arr.shape != (rows,) or not np.isfinite(arr).all():
            raise InputError(f"tool_length must be one finite value or one per row ({rows})")
        return arr

    # ---------------------------------------------------------------- direct
    @chunked
    def fk(self, q: Any, *, x0: Any = None, start: Any = None, tool_length: Any = None,
           full_output: bool = False, strokes: str = "flag", check_singular: bool | None = None,
           max_misfit: float | None = None, out: np.ndarray | None = None,
           **engine_options: Any) -> np.ndarray | ChainDirectResult:
        """Direct model: the legs' closure (platform pose and passive joints) then the head.

        Args:
            q: ``(n,)`` or ``(N, n)`` actuator coordinates (legs then head).
            x0: a warm-start pose, as on every machine: a joint chain's closure cannot start
                from one (UnsupportedOperationError); ``(6 + n_p)`` values per row are the
                deprecated name of ``start`` (:mod:`pkmkit.machines.warm_starts`).
            start: warm start of the closure: ``(6 + n_p,)`` or ``(N, 6 + n_p)`` platform
                position, rotation vector and passive joints (e.g. the previous solution along a
                path); default (and rows of ``start`` that are not finite) the home one.
            tool_length: tool length(s) along the tool axis (m); default the machine's.
            full_output: return a :class:`ChainDirectResult`.
            strokes: joint values outside their strokes (the actuators given, the passive
                joints found): ``"flag"`` (default) computes the configuration, marks the rows
                (``out_of_stroke``, ``messages``) and, for a single row, warns
                (:class:`~pkmkit.exceptions.StrokeWarning`) — the geometry is right, the machine
                cannot go there; ``"refuse"`` makes those rows NaN with status OUT_OF_STROKE
                (a single row raises :class:`~pkmkit.exceptions.OutOfStrokeError`); ``"ignore"``
                does not look.
            check_singular: check the closure's Jacobian (platform and passive joints) at the
                solution: rows where σ_min/σ_max falls below :data:`SINGULAR_TOL` (a parallel
                singularity: the actuators do not determine the passive joints) get status
                SINGULAR, values kept; a single row raises SingularConfigurationError.
                Default: on for a single row, off for a batch (one SVD per row).
            max_misfit: largest closure residual (m) accepted as an assembly: default the
                engine's tolerance for a nominal geometry, unbounded for one with defects
                (whose least-squares misfit cannot be told from actuator values out of reach
                but by its size — bound it, e.g. by a multiple of ``home_closure_residual``).
            **engine_options: forwarded to the engine (``max_iter``, ``residual_tol``, …).

        Returns:
            tool point and axis ``(6,)`` / ``(N, 6)``, or a :class:`ChainDirectResult`. A machine
            with incompatible defects has no exact closure: its rows are the least-squares closure
            (status INCONSISTENT, ``closure_residual`` > 0), as a real hyperstatic machine deforms
            to assemble — up to ``max_misfit`` if given. For a nominal geometry any misfit means the
            actuator values admit no assembly. Such rows have status NO_ASSEMBLY, NaN, and
            ``messages`` name the leg that misses the platform and by how much.

        Raises:
            InputError: mis-shaped q, a non-finite single q, an unknown ``strokes`` mode.
            ClosureMissError: a single q whose legs do not close (a NoAssemblyError naming the
                leg, its miss and the residual).
            OutOfStrokeError: a single q beyond a stroke with ``strokes="refuse"``.
            SingularConfigurationError: a single q at a singular closure.
        """
        if out is None and (fast := self._fk_one(q, strokes, check_singular, x0, start,
                                                 tool_length, full_output, max_misfit,
                                                 engine_options)):
            return fast[0]  # one plain configuration: one compiled call (machines/chain_one.py)
        if strokes not in STROKE_MODES:
            raise InputError(f"strokes must be one of {', '.join(STROKE_MODES)}, got {strokes!r}")
        qb, single = _checked_batch(q, self.n_actuators, "q")
        n = qb.shape[0]
        values, res, status, valid = self._closure_rows(qb, x0, start, max_misfit,
                                                        engine_options)
        report = self._direct_report(values, res, status, valid, strokes,
                                     single if check_singular is None else check_singular)
        usable = report["usable"]
        pose, frame = self.tool_rows(res, values, tool_length, usable)
        pose = filled(out if out is None else checked_out(out, q, qb, single, 6, "fk"), pose)
        if single:
            self._raise_single(qb[0], status[0], report, res.residual[0])
        if not full_output:
            return restore_shape(pose, single)
        platform = res.u[:, :6].copy()
        passive = res.u[:, 6:].copy()
        platform[~usable] = np.nan
        passive[~usable] = np.nan
        out = ChainDirectResult(pose=pose, tool_frame=frame, platform=platform, passive=passive,
                                passive_names=self.passive_names,
                                closure_residual=res.residual, status=status,
                                iterations=res.iterations,
                                out_of_stroke=report["out_of_stroke"],
                                messages=tuple(report["messages"]),
                                mode=np.zeros(n, dtype=int))
        return single_row(out) if single else out

    def _closure_rows(self, qb: np.ndarray, x0: Any, start: Any, max_misfit: float | None,
                      engine_options: dict) -> tuple:
        """The legs' closure of every row: ``(values (N, n_joints), engine result,
        status (N,), valid (N,))``, the passive joints found written into ``values``."""
        n = qb.shape[0]
        values = self.full_values(qb)
        given, keyword = self._closure_start(x0, start)
        if given is None:
            u0 = self._default_start(qb, values)
        else:
            u0 = _rows_like(given, 6 + len(self._passive), keyword, n).copy()
            unset = ~np.isfinite(u0).all(axis=1)
            if unset.any():  # rows without a start begin where a missing one does
                u0[unset] = self._default_start(qb[unset], values[unset])
        valid = valid_rows(qb)
        u0[~valid] = np.nan
        engine_options.setdefault("compute_rank", False)
        engine_options.setdefault("compiled", _closure_compiled(n))
        with np.errstate(invalid="ignore", over="ignore"):
            res = solve_closure(self.model, values, u0, unknown_variables=self._passive,
                                **engine_options)
        status = res.status.copy()
        # at (or next to) a singular closure Gauss–Newton converges only linearly: a row that
        # ran out of iterations with the legs closed is an assembly
        tol = engine_options.get("residual_tol", CLOSURE_TOL)
        status[(status == Status.NOT_CONVERGED) & (res.residual <= tol)] = Status.OK
        status[status == Status.NOT_CONVERGED] = Status.NO_ASSEMBLY
        # a nominal geometry closes exactly wherever it assembles; with defects the misfit is
        # theirs unless the caller bounds it
        if max_misfit is None:
            max_misfit = np.inf if self.model.defects.any() else tol
        status[(status == Status.INCONSISTENT) & (res.residual > max_misfit)] = (
            Status.NO_ASSEMBLY)
        status[~valid] = Status.INVALID_INPUT
        values[:, self._passive] = res.u[:, 6:]
        return values, res, status, valid

    def tool_rows(self, res, values: np.ndarray, tool_length: Any,
                   usable: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``pose (N, 6)`` (tool point and axis at ``tool_length``) and ``frame (N, 6)``
        (spindle nose point and rotation vector) of closed rows, NaN where not usable; ``res``:
        anything with ``u (N, 6 + n_p)``, the closure (platform, passive joints)."""
        rot = rotvec_to_matrix(np.nan_to_num(res.u[:, 3:6])).transpose(1, 2, 0)
        tool = tool_frame(self.model, rot, np.nan_to_num(res.u[:, :3]).T, values.T)
        lengths = self._tool_lengths(tool_length, res.u.shape[0])
        axis = tool.R[:, 2].T
        pose = np.concatenate([tool.p.T + lengths[:, None] * axis, axis], axis=1)
        frame = np.concatenate([tool.p.T, matrix_to_rotvec(tool.R.transpose(2, 0, 1))], axis=1)
        for arr in (pose, frame):
            arr[~usable] = np.nan
        return pose, frame

    def _direct_report(self, values: np.ndarray, res, status: np.ndarray, valid: np.ndarray,
                       strokes: str, check_singular: bool) -> dict[str, Any]:
        """Per-row diagnoses of a direct model (updates ``status`` in place): the legs' misses
        of rows without assembly, stroke violations, singular closures."""
        model = self.model
        n = values.shape[0]
        # the diagnoses of the rows that have any (a batch's rows are mostly silent)
        parts: defaultdict[int, list[str]] = defaultdict(list)
        failed = np.flatnonzero(status == Status.NO_ASSEMBLY)
        misses = {}
        if failed.size:
            trans, rot = leg_misses(model, values[failed], res.u[failed, :6])
            for j, i in enumerate(failed):
                leg, text = miss_message(model, trans[j], rot[j])
                misses[int(i)] = (leg, trans[j, leg], rot[j, leg])
                # one unit in one sentence: the misses are in mm, so is the residual
                parts[i].append(f"the legs do not close: {text}; largest closure residual "
                                f"{res.residual[i] * 1e3:.3g} mm")
        for i in np.flatnonzero(status == Status.INVALID_INPUT):
            parts[i].append("an actuator value is not finite or beyond "
                            f"{MAX_COORDINATE:g}")
        usable = (status == Status.OK) | (status == Status.INCONSISTENT)
        out_of_stroke = np.zeros(n, dtype=bool)
        first_violation: dict[int, tuple[int, float]] = {}
        if strokes != "ignore":
            for variables, rows in ((self._actuated, valid), (self._passive, usable)):
                bad, texts = stroke_violations(model, values, variables, rows & ~out_of_stroke)
                rows_bad = np.flatnonzero(bad)
                sub = values[rows_bad][:, variables]
                first = np.argmax(signed_excess(sub, model.q_min[variables],
                                                model.q_max[variables]) != 0, axis=1)
                for i, k, value in zip(rows_bad.tolist(), first.tolist(),
                                       sub[np.arange(rows_bad.size), first].tolist(),
                                       strict=True):
                    parts[i].append(texts[i])
                    first_violation[i] = (int(variables[k]), value)
                out_of_stroke |= bad
            if strokes == "refuse":
                status[out_of_stroke] = Status.OUT_OF_STROKE
                usable &= ~out_of_stroke
        if check_singular and usable.any():
            rows = np.flatnonzero(usable)
            ratio = closure_conditioning(model, values[rows], res.u[rows, :6], self._passive,
                                         self.expected_rank())
            for i, value in zip(rows, ratio, strict=True):
                if value < SINGULAR_TOL:
                    status[i] = Status.SINGULAR
                    parts[i].append(f"singular closure (σ_min/σ_max of its Jacobian "
                                    f"{value:.2g} < {SINGULAR_TOL:g}): the actuators do not "
                                    "determine the passive joints and the platform there")
        keep = usable | (status == Status.SINGULAR)
        return {"usable": keep, "out_of_stroke": out_of_stroke, "misses": misses,
                "violations": first_violation, "messages": _joined(parts, n)}

    def _raise_single(self, q: np.ndarray, status: int, report: dict, residual: float) -> None:
        """The typed error (or warning) of a single-row direct model."""
        message = report["messages"][0]
        if status == Status.INVALID_INPUT:
            raise InputError(f"q = {q.tolist()} has a coordinate beyond {MAX_COORDINATE:g}")
        if status == Status.NO_ASSEMBLY:
            leg, trans, rot = report["misses"][0]
            raise ClosureMissError(
                f"q = {q.tolist()}: {message}; the actuator values may be out of the workspace, "
                "or pass x0 nearer the solution", leg, self.model.leg_names[leg], trans, rot,
                residual)
        if status == Status.OUT_OF_STROKE:
            variable, value = report["violations"][0]
            raise OutOfStrokeError(message, self.model.variables[variable], value,
                                   (self.model.q_min[variable], self.model.q_max[variable]))
        if status == Status.SINGULAR:
            raise SingularConfigurationError(f"q = {q.tolist()}: {message}")
        if report["out_of_stroke"][0]:
            warnings.warn(message, StrokeWarning, stacklevel=3)

    def _default_start(self, qb: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Starts ``(N, 6 + n_p)`` of the direct model
        (:func:`pkmkit.machines.chain_starts.default_start`)."""
        return default_start(self, qb, values)

    # ---------------------------------------------------------------- inverse
    @chunked
    def ik(self, x: Any, *, q0: Any = None, tool_length: Any = None, full_output: bool = False,
           strokes: str = "flag", start: Any = None, out: np.ndarray | None = None,
           **engine_options: Any) -> np.ndarray | ChainInverseResult:
        """Inverse model: actuator coordinates that put the tool point and axis at ``x``.

        Args:
            x: ``(6,)`` or ``(N, 6)`` tool point (m) and tool axis (normalised here).
            q0: warm start for the actuators (the other unknowns from home); other branches
                of the head are reached from other starts. Default: the kind's closed-form
                start where it has one and it answers (the TriMule), else home moved to first
                order towards each target (:func:`~pkmkit.machines.chain_starts.inverse_starts`),
                solved again from home where that fails or leaves the legs' home assembly modes.
            tool_length: tool length(s) (m); default the machine's.
            full_output: return a :class:`ChainInverseResult` (its ``direct`` the direct
                model at the solution).
            strokes: joints of the solution (actuators and passive joints) outside their
                strokes: ``"flag"`` (default; a single row warns with
                :class:`~pkmkit.exceptions.StrokeWarning`), ``"refuse"`` (NaN rows; a single row
                raises :class:`~pkmkit.exceptions.OutOfStrokeError`) or ``"ignore"``; the direct
                result of ``full_output`` carries the messages.
            start: ``(6 + n_var,)`` or ``(N, 6 + n_var)`` warm start of every unknown —
                platform position, rotation vector, every joint variable in the model's order:
                a previous result's ``solution`` (e.g. at a neighbouring point: continuation).
                Rows not finite take the default start (or ``q0``); rows that do not converge
                from their start are solved again from home; revolute actuators stay on the turn
                nearest ``q0`` (home). One plain pose with a plain ``start`` row (and
                ``full_output``) takes the one-pose path (:mod:`pkmkit.machines.chain_one`):
                the same answer, the ``solution`` the next call's ``start``.
            out: ``(N, n)`` array a batch's q is written into and returned, as on every family
                (:mod:`pkmkit.machines.out_arrays`; ``fk``'s ``out`` takes its ``(N, 6)``).

        Returns:
            q ``(n,)`` / ``(N, n)``; with ``full_output`` a :class:`ChainInverseResult` (which
            still unpacks as the former tuple ``(q, direct)``, with a DeprecationWarning).

        Raises:
            InputError: mis-shaped input, an axis of zero length, an unknown ``strokes`` mode.
            ConvergenceError: a single target the engine could not reach exactly.
            OutOfStrokeError: a single target reached beyond a stroke with ``strokes="refuse"``.
        """
        if out is None and (fast := self._ik_one(x, q0, tool_length, full_output, strokes, start,
                                                 engine_options)):
            return fast[0]  # one plain pose: one compiled call (machines/chain_one.py)
        if strokes not in STROKE_MODES:
            raise InputError(f"strokes must be one of {', '.join(STROKE_MODES)}, got {strokes!r}")
        xb, single = _checked_batch(x, 6, "pose")
        n = xb.shape[0]
        res, status, q, joint_values, lengths = self._inverse_solve(xb, single, q0, tool_length,
                                                                    engine_options, start)
        q = filled(out if out is None else checked_out(out, x, xb, single, self.n_actuators,
                                                       "ik"), q)
        joints = np.flatnonzero(self.model.loop_variables | self.model.actuated)
        bad, texts = (stroke_violations(self.model, joint_values, joints, status == Status.OK,
                                        messages=single)
                      if strokes != "ignore" else (np.zeros(n, dtype=bool), [""] * n))
        if strokes == "refuse":
            status[bad] = Status.OUT_OF_STROKE
        q[status != Status.OK] = np.nan
        if single:
            self._judge_single_inverse(xb[0], status[0], res.residual[0], joint_values[0],
                                       joints, texts[0], bad[0])
        if not full_output:
            return restore_shape(q, single)
        return inverse_record(self, res, status, q, lengths, strokes, bad, single)

    def _inverse_solve(self, xb: np.ndarray, single: bool, q0: Any, tool_length: Any,
                       engine_options: dict, start: Any = None) -> tuple:
        """The engine's inverse of every row: ``(result, status (N,), q (N, n),
        joint values (N, n_joints), tool lengths (N,))``, revolute actuators on the turn
        nearest their start."""
        norms = np.linalg.norm(xb[:, 3:], axis=1)
        bad_axis = ~(norms > 0)
        if single and bad_axis[0]:
            raise InputError("the tool axis (components 4-6 of the pose) must not be zero")
        targets = xb.copy()
        with np.errstate(invalid="ignore", divide="ignore"):
            targets[:, 3:] /= norms[:, None]
        n = xb.shape[0]
        values = np.tile(self._home["values"], (n, 1))
        if q0 is not None:
            values[:, self._actuated] = _rows_like(q0, self.n_actuators, "q0", n)
        u_home = np.concatenate([np.tile(self._home["platform"], (n, 1)), values], axis=1)
        u0, started = self._inverse_starts(start, u_home)
        lengths = self._tool_lengths(tool_length, n)
        warm = started.copy() if q0 is None else None  # a caller's start, the default branch
        if q0 is None:  # the default start: home moved to first order towards each target,
            # solved again from home where it fails or leaves the legs' home modes
            u0 = u0.copy()  # without start= it is u_home itself
            u0[~started] = inverse_starts(self, targets[~started], lengths[~started])
            started[:] = True
        for u in (u0, u_home):
            u[~valid_rows(xb) | bad_axis] = np.nan
        engine_options.setdefault("compute_rank", False)
        engine_options.setdefault("compiled", _closure_compiled(n))

        def solve(t: np.ndarray, u: np.ndarray, tool: np.ndarray):
            with np.errstate(invalid="ignore", over="ignore"):
                return solve_machine_inverse(self.model, t, u, tool_length=tool,
                                             **engine_options)

        res = self._solve_inverse_from(solve, targets, u0, u_home, started, lengths, warm)
        if q0 is None:  # the default start's branch of the head, whatever the start
            self._nearest_branch(solve, targets, res, lengths, started, u_home, warm)
        else:  # a caller's start: a two-branch head keeps the branch nearest the start's turn
            if (flip := head_flip_variables(self.kind, self.model.variables)) is not None:
                res = nearest_head_branch(solve, targets, lengths, res, u0[:, 6 + flip[0]], flip,
                                          lambda u, r: self._within_strokes(u, u0[r, 6:]))
        status = res.status.copy()
        status[status == Status.INCONSISTENT] = Status.UNREACHABLE
        status[~valid_rows(xb) | bad_axis] = Status.INVALID_INPUT
        q = res.u[:, 6:][:, self._actuated].copy()
        # revolute actuators: the turn nearest the start (the engine may step a full turn)
        turn = np.array([q == "angle" for q in self.actuator_quantities])
        start = values[:, self._actuated][:, turn]
        q[:, turn] = start + np.angle(np.exp(1j * (q[:, turn] - start)))
        joint_values = res.u[:, 6:].copy()
        joint_values[:, self._actuated] = q
        return res, status, q, joint_values, lengths

    def _judge_single_inverse(self, x: np.ndarray, status: int, residual: float,
                              values: np.ndarray, joints: np.ndarray, text: str,
                              beyond: bool) -> None:
        """A single target: refused beyond a stroke (OutOfStrokeError naming the joint),
        not reached (ConvergenceError), or reached beyond a stroke (StrokeWarning)."""
        if status == Status.OUT_OF_STROKE:
            k = int(joints[np.flatnonzero(signed_excess(
                values[None, joints], self.model.q_min[joints], self.model.q_max[joints])[0])[0]])
            raise OutOfStrokeError(f"the inverse model of {x.tolist()}: {text}",
                                   self.model.variables[k], values[k],
                                   (self.model.q_min[k], self.model.q_max[k]))
        if status != Status.OK:
            raise ConvergenceError(
                f"the inverse model did not reach the tool point and axis {x.tolist()} "
                f"(residual {residual:.3g} m, {Status(int(status)).label}): the target "
                "may be out of the workspace; pass q0 near the wanted branch")
        if beyond:
            warnings.warn(f"the inverse model of {x.tolist()}: {text}", StrokeWarning,
                          stacklevel=3)

    def mobility(self) -> dict[str, Any]:
        """The same as :meth:`hyperstatism`, as a dict (for ``pkmkit show``)."""
        return {"hyperstatism": self.hyperstatism()}

    def passive_values(self, q: Any) -> dict[str, np.ndarray]:
        """Passive joints by name at actuator coordinates ``q`` (rad or m)."""
        res = self.fk(q, full_output=True)
        return {name: res.passive[..., i] for i, name in enumerate(self.passive_names)}


def _closure_compiled(rows: int) -> bool:
    """Whether a batch of ``rows`` rows runs the compiled closure: its C twin
    (:mod:`pkmkit.solve.chain_rows`, the same bits as the Numba kernel, no import) at every
    size when the extension is built, else Numba under
    :func:`~pkmkit.numerics.jit.use_compiled_solver`'s rule — so the kernel a batch takes does
    not depend on whether the process imported Numba before."""
    from pkmkit.solve.chain_rows import KERNEL

    return use_compiled_solver(rows, native=native_kernel(KERNEL, "_solve_rows") is not None)


def _joined(parts: Mapping[int, list[str]], n: int) -> list[str]:
    """One message per row of ``n``: the diagnoses of each row in ``parts`` joined by "; ",
    ``""`` for the others."""
    messages = [""] * n
    for i, texts in parts.items():
        messages[i] = "; ".join(texts)
    return messages


def machine_with_tool(m: JointChainMachine, tool_length: float) -> JointChainMachine:
    """The same machine with another default tool length (m)."""
    return replace(m, tool_length=float(tool_length))
