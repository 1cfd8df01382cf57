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
from pkmkit.machines.full_pose_forms import FullPoseForms
from pkmkit.machines.machine import (
    HOME_TOL,
    MAX_COORDINATE,
    SINGULARITY_TOL,
    MachineKind,
    _checked_batch,
    _restore,
    _rows_like,
    _valid_rows,
)
from pkmkit.machines.modes import ModeNaming
from pkmkit.machines.protocol import MachineFace
from pkmkit.machines.results import (
    DirectResult,
    InverseResult,
    JacobianRates,
    Jacobians,
    PoseSolutions,
    Singularity,
)
from pkmkit.machines.strokes import check_mode, judge_rows, refuse_absurd_home
from pkmkit.model.mobility import grubler_count
from pkmkit.model.parameters import is_plain_number, resolve_parameters
from pkmkit.model.rods import SLIDE, STRUT, RodModel
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
#: Iteration limit of the position inverse (fewer actuators than six) from its first-order
#: guess; rows still short of a solution after it are NOT_CONVERGED.
POSITION_MAX_ITER = 30


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


def _stroke_fields(check) -> dict[str, Any]:
    """``out_of_stroke`` and ``stroke_excess`` of a result from a stroke check (or None)."""
    if check is None:
        return {"out_of_stroke": None, "stroke_excess": None}
    return {"out_of_stroke": check.out_of_stroke, "stroke_excess": check.excess}


def _pose_distance(a: np.ndarray, b: np.ndarray, length: float) -> np.ndarray:
    """Distance between pose rows: position difference plus L × rotation angle (m)."""
    from scipy.spatial.transform import Rotation

    angle = (Rotation.from_rotvec(a[..., 3:].reshape(-1, 3))
             * Rotation.from_rotvec(b[..., 3:].reshape(-1, 3)).inv()).magnitude()
    return np.linalg.norm(a[..., :3] - b[..., :3], axis=-1) + length * angle.reshape(
        a.shape[:-1])


@dataclass(frozen=True, eq=False)
class FullPoseMachine(ModeNaming, MachineFace):
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
            radius = float(np.linalg.norm(self.model.rod_platform, axis=1).mean())
            object.__setattr__(self, "characteristic_length", radius if radius > 0 else 1.0)
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
        from pkmkit.machines.machine import build_machine

        params = resolve_parameters(self.kind.parameters, {**self.params, **overrides}, self.id)
        rebuilt = build_machine(self.kind, params, id=self.id, name=self.name,
                                description=self.description, source=self.source)
        extra = {k: v for k, v in self.extra_poses.items() if k not in rebuilt.extra_poses}
        kept = {"characteristic_length": self.characteristic_length} if self.length_given else {}
        return replace(rebuilt, extra_poses={**rebuilt.extra_poses, **extra}, **kept)

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
        bad = ~np.isfinite(q).all(axis=1)
        twist = (np.where(bad[:, None], self._home_q, q) - self._home_q) @ self._home_jacobian.T
        guess = np.empty((q.shape[0], 6))
        guess[:, :3] = self._home_pose[:3] + twist[:, :3]
        guess[:, 3:] = compose_rotvec(twist[:, 3:], np.broadcast_to(self._home_pose[3:],
                                                                    (q.shape[0], 3)))
        guess[bad] = np.nan
        return guess

    # ---------------------------------------------------------------- inverse
    def ik(
        self,
        x: Any,
        *,
        branches: Any = None,
        q0: Any = None,
        full_output: bool = False,
        strokes: str = "flag",
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
        check_mode(strokes)
        arr = np.asarray(x, dtype=float) if not isinstance(x, np.ndarray) else x
        width = arr.shape[-1] if arr.ndim in (1, 2) else 6
        if width == 3 and self.position_controlled:
            return self._ik_position(arr, q0, branches, full_output, engine_options, strokes)
        xb, single = _checked_batch(x, 6, "pose")
        sigma = self._branches(branches)
        with np.errstate(invalid="ignore", over="ignore"):
            q_rod = self._forms.rod_coordinates(xb, sigma)
            q, spread = self._forms.combine(q_rod)
        status = np.full(xb.shape[0], int(Status.OK))
        unreachable = ~np.isfinite(q_rod).all(axis=1)
        inconsistent = ~unreachable & ~(spread <= self._consistency_tol())
        status[unreachable | inconsistent] = Status.UNREACHABLE
        status[~_valid_rows(xb)] = Status.INVALID_INPUT
        q[status != Status.OK] = np.nan
        if single and status[0] != Status.OK:
            self._raise_inverse(xb, status[0], spread[0])
        check = judge_rows(self, q, status, strokes, single, f"pose {xb[0].tolist()}",
                           full_output)
        q[status != Status.OK] = np.nan
        if not full_output:
            return restore_shape(q, single)
        result = InverseResult(q=q, status=status, branches=sigma.copy(),
                               shortfall=self._forms.shortfall(xb), method="closed",
                               mode=self._mode_of(xb, q), **_stroke_fields(check))
        return _restore(result, single, ("q", "status", "shortfall", "mode", "out_of_stroke",
                                         "stroke_excess"))

    def _ik_position(self, arr, q0, branches, full_output, engine_options, strokes="flag"):
        pb, single = _checked_batch(arr, 3, "position")
        n = self.n_actuators
        if q0 is None:
            # first order from home: the position rows of J(home) are square (n = 3)
            j_t = self._home_jacobian[:3]
            dq = np.linalg.lstsq(j_t, (pb - self._home_pose[:3]).T, rcond=None)[0].T
            guess_q = self._home_q + dq
        else:
            guess_q = _rows_like(q0, n, "q0", pb.shape[0])
        guess_pose = self.first_order_pose(guess_q)
        u0 = np.concatenate([guess_q, guess_pose[:, 3:]], axis=1)
        hopeless = self._surely_unreachable(pb)
        u0[~_valid_rows(pb) | hopeless] = np.nan
        engine_options.setdefault("compute_rank", False)
        if q0 is None:
            # from the first-order guess a reachable position converges in ≤ 11 iterations
            # (10⁵ random positions of the Verne module); the rows still crawling after
            # POSITION_MAX_ITER are beyond reach
            engine_options.setdefault("max_iter", POSITION_MAX_ITER)
        with np.errstate(invalid="ignore", over="ignore"):
            result = solve_position_inverse(self.model, pb, u0, **engine_options)
        q = result.u[:, :n].copy()
        pose = np.concatenate([pb, result.u[:, n:]], axis=1)
        status = result.status.copy()
        status[status == Status.INCONSISTENT] = Status.UNREACHABLE
        ok = status == Status.OK
        if branches is not None or ok.any():
            # the engine may land on another branch or assembly mode: say so
            sigma = self._branches(branches)
            expected = np.full(pb.shape[0], False)
            with np.errstate(invalid="ignore", over="ignore"):
                q_rod = self._forms.rod_coordinates(pose[ok], sigma)
                back, _ = self._forms.combine(q_rod)
            expected[ok] = np.abs(back - q[ok]).max(axis=1) <= 1e-7
            status[ok & ~expected] = Status.WRONG_MODE
        status[hopeless] = Status.UNREACHABLE
        status[~_valid_rows(pb)] = Status.INVALID_INPUT
        bad = status != Status.OK
        q[bad] = np.nan
        pose[bad] = np.nan
        if single and bad[0]:
            if status[0] == Status.INVALID_INPUT:
                raise InputError(f"position {pb[0].tolist()} has a coordinate beyond "
                                 f"{MAX_COORDINATE:g} m")
            if status[0] == Status.WRONG_MODE:
                raise ConvergenceError(
                    "the inverse model converged to another branch or assembly mode than the "
                    "working one; pass q0 closer to the wanted solution")
            raise UnreachablePoseError(-1, "the rods", float(result.residual[0]), detail=(
                f"the rods cannot close at position {pb[0].tolist()} (least-squares residual "
                f"{float(result.residual[0]):.6g} m)"))
        check = judge_rows(self, q, status, strokes, single, f"position {pb[0].tolist()}",
                           full_output, stacklevel=4)
        bad = status != Status.OK
        q[bad] = np.nan
        pose[bad] = np.nan
        if not full_output:
            return restore_shape(q, single)
        sigma = self._branches(branches)
        shortfall = np.full((pb.shape[0], self.model.n_rods), np.nan)
        shortfall[~bad] = self._forms.shortfall(pose[~bad])  # at the orientation found
        out = InverseResult(q=q, status=status, branches=sigma, shortfall=shortfall,
                            method="numeric", mode=self._mode_of(pose, q),
                            iterations=result.iterations, residual=result.residual, pose=pose,
                            **_stroke_fields(check))
        return _restore(out, single, ("q", "status", "shortfall", "mode", "iterations",
                                      "residual", "pose", "out_of_stroke", "stroke_excess"))

    def _surely_unreachable(self, positions: np.ndarray) -> np.ndarray:
        """``(N,)`` positions no orientation can serve: a slide rod whose platform joint, at most
        ``|b|`` from the platform point whatever the rotation, stays farther than the rod's
        length from its slide's line (``dist(p, line) − |b| > L``). A sufficient test only: it
        spares the iterative solve the hopeless rows of a workspace grid."""
        m = self.model
        slides = np.flatnonzero(m.rod_kind == SLIDE)
        out = np.zeros(positions.shape[0], dtype=bool)
        if slides.size == 0:
            return out
        with np.errstate(invalid="ignore"):
            rel = positions[:, None, :] - m.rod_base[slides][None]
            along = np.einsum("nsk,sk->ns", rel, m.rod_axis[slides])
            perp = rel - along[..., None] * m.rod_axis[slides][None]
            dist = np.linalg.norm(perp, axis=2)
            reach = np.linalg.norm(m.rod_platform[slides], axis=1) + m.rod_length[slides]
            out = (dist > reach[None] * (1 + 1e-9)).any(axis=1)
        return out & _valid_rows(positions)

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
        ok = np.isfinite(q).all(axis=1) & np.isfinite(x).all(axis=1)
        out = np.zeros(x.shape[0], dtype=int)
        if ok.any() and self.model.n_rods == 6:
            a, _ = self._forms.jacobians(x[ok], q[ok])
            out[ok] = np.sign(np.linalg.det(a)).astype(int)
        return out

    # ---------------------------------------------------------------- direct
    def fk(
        self,
        q: Any,
        *,
        x0: Any = None,
        full_output: bool = False,
        strokes: str = "flag",
        **engine_options: Any,
    ) -> np.ndarray | DirectResult:
        """Direct kinematics by the least-squares engine over every rod, from ``x0`` (a warm
        start, one pose or one per row) or from the first-order guess J(home)(q − q_home).

        Returns:
            poses ``(6,)`` / ``(N, 6)`` (NaN rows where the engine found no assembly), or a
            :class:`DirectResult`.

        ``strokes`` (``"flag"``, ``"refuse"``, ``"ignore"``) treats given actuator values
        outside their strokes as :meth:`ik` does.

        Raises:
            InputError: mis-shaped input or non-finite single q.
            NoAssemblyError: a single q with no assembly reached from the guess.
            OutOfStrokeError: a single q beyond a stroke with ``strokes="refuse"``.
        """
        check_mode(strokes)
        qb, single = _checked_batch(q, self.n_actuators, "q")
        guess = (self.first_order_pose(qb) if x0 is None
                 else _rows_like(x0, 6, "x0", qb.shape[0]))
        guess[~_valid_rows(qb)] = np.nan
        engine_options.setdefault("compute_rank", False)
        with np.errstate(invalid="ignore", over="ignore"):
            result = solve_direct(self.model, qb, guess, dof="full", **engine_options)
        pose = result.u.copy()
        status = result.status.copy()
        status[status == Status.INCONSISTENT] = Status.NO_ASSEMBLY
        status[~_valid_rows(qb)] = Status.INVALID_INPUT
        check = None
        if not single or status[0] == Status.OK:
            check = judge_rows(self, qb, status, strokes, single, f"q = {qb[0].tolist()}",
                               full_output)
        ok = status == Status.OK
        pose[~ok] = np.nan
        if single and not ok[0]:
            if status[0] == Status.INVALID_INPUT:
                raise InputError(f"q = {qb[0].tolist()} has a coordinate beyond "
                                 f"{MAX_COORDINATE:g}")
            if status[0] == Status.NO_ASSEMBLY:
                raise NoAssemblyError(
                    f"q = {qb[0].tolist()}: no assembly found from the guess (closure residual "
                    f"{result.residual[0]:.3g} m); the rods may not meet, or pass x0")
            raise ConvergenceError(f"the direct model did not converge "
                                   f"({Status(int(status[0])).label})")
        if not full_output:
            return restore_shape(pose, single)
        mode = self._mode_of(pose, qb)
        out = DirectResult(pose=pose, status=status, mode=mode,
                           mode_label=self.mode_labels[0], branches=np.zeros(
                               (qb.shape[0], self.model.n_legs), dtype=int),
                           method="numeric", iterations=result.iterations,
                           residual=result.residual, **_stroke_fields(check))
        return _restore(out, single, ("pose", "status", "mode", "branches", "iterations",
                                      "residual", "out_of_stroke", "stroke_excess"))

    def fk_all(self, q: Any, *, tol: float = 1e-10) -> PoseSolutions:
        """Every real assembly mode of actuator coordinates ``q`` (a six-rod machine): the
        all-solutions solver of :mod:`pkmkit.solve.six_rod_direct` (a certified parameter
        homotopy over the 40 complex solutions of a general 6-6 platform), with the base joints
        placed by the actuators (slides move them, cranks turn them).

        Args:
            q: ``(n,)`` or ``(N, n)`` actuator coordinates.
            tol: rod-length tolerance of the refined solutions (m, relative to the size).

        Returns:
            :class:`~pkmkit.machines.results.PoseSolutions` (single q: leading axis dropped).

        Raises:
            InputError: mis-shaped q, or a machine that does not have exactly six rods.
        """
        from pkmkit.solve.rod_closure import rod_base_points
        from pkmkit.solve.six_rod_direct import six_rod_direct_all

        if self.model.n_rods != 6:
            raise InputError(
                f"every assembly mode is computed for six-rod platforms; {self.id!r} has "
                f"{self.model.n_rods} rods (use fk with a guess for the others)")
        qb, single = _checked_batch(q, self.n_actuators, "q")
        finite = _valid_rows(qb)
        base = rod_base_points(self.model, np.nan_to_num(qb).T).transpose(2, 1, 0)
        lengths = self.model.rod_length[None] + np.where(
            self.model.rod_kind[None] == STRUT, np.nan_to_num(qb)[:, self.model.rod_actuator],
            0.0)
        base[~finite] = np.nan
        solutions = six_rod_direct_all(base, self.model.rod_platform, lengths, tol=tol)
        poses = np.atleast_3d(solutions.poses).reshape(qb.shape[0], -1, 6)
        count = np.atleast_1d(solutions.count)
        # the working mode: the solution the engine reaches from home's first-order guess
        working = np.full(qb.shape[0], -1)
        engine = self.fk(qb, full_output=True) if finite.any() else None
        if engine is not None:
            gap = np.linalg.norm(poses[:, :, :3] - engine.pose[:, None, :3], axis=2)
            with np.errstate(invalid="ignore"):
                near = np.nanargmin(np.where(np.isnan(gap), np.inf, gap), axis=1)
                close = np.take_along_axis(gap, near[:, None], 1)[:, 0] <= 1e-6 * (
                    1.0 + float(self.model.rod_length.max()))
            working[close] = near[close]
        sign = np.zeros(poses.shape[:2], dtype=int)
        valid = ~np.isnan(poses[..., 0])
        if valid.any():
            rows, cols = np.nonzero(valid)
            a, _ = self._forms.jacobians(poses[rows, cols], qb[rows])
            sign[rows, cols] = np.sign(np.linalg.det(a)).astype(int)
        status = np.atleast_1d(solutions.status).copy()
        status[~finite] = Status.INVALID_INPUT
        out = PoseSolutions(
            poses=poses, count=count, working=working, mode_sign=sign,
            residual=np.atleast_2d(solutions.residual).reshape(qb.shape[0], -1),
            condition=np.atleast_2d(solutions.condition).reshape(qb.shape[0], -1),
            multiplicity=np.atleast_2d(solutions.multiplicity).reshape(qb.shape[0], -1),
            n_finite=np.atleast_1d(solutions.n_finite), status=status)
        if single:
            return PoseSolutions(**{k: v[0] for k, v in out.__dict__.items()})
        return out

    # ---------------------------------------------------------------- velocity
    def jacobian(self, x: Any, *, q: Any = None, branches: Any = None,
                 tol: float = SINGULARITY_TOL) -> FullPoseJacobians:
        """Velocity model at full poses (see :class:`FullPoseJacobians`).

        Args:
            x: ``(6,)`` or ``(N, 6)`` poses (or positions ``(3,)``/``(N, 3)`` for a machine
                with fewer than six actuators).
            q: actuator coordinates at those poses (default: the inverse model).
            branches: inverse-model branches when q is not given.
            tol: threshold of the singularity measures.
        """
        if not (isinstance(tol, int | float | np.floating) and np.isfinite(tol) and tol > 0):
            raise InputError(f"tol must be a positive number, got {tol!r}")
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
        jac = self._jacobians(xb, qb, float(tol))
        names = ("A", "B", "J", "J_inv", "singular_values", "condition", "det_A", "det_B",
                 "parallel_measure", "serial_measure", "singularity", "q", "mode",
                 "J_homogeneous", "translation_singular_values", "rotation_singular_values")
        return _restore(jac, single, names)

    def _jacobians(self, xb: np.ndarray, qb: np.ndarray, tol: float) -> FullPoseJacobians:
        n, size = self.n_actuators, xb.shape[0]
        length = float(self.characteristic_length)
        ok = np.isfinite(qb).all(axis=1) & np.isfinite(xb).all(axis=1)
        m = self.model.n_rods
        a = np.full((size, m, 6), np.nan)
        b = np.full((size, m, n), np.nan)
        if ok.any():
            a[ok], b[ok] = self._forms.jacobians(xb[ok], qb[ok])
        # singularity measures: unit rows, moments over L; base-joint motion vs rod direction
        with np.errstate(invalid="ignore", divide="ignore"):
            dist = np.linalg.norm(a[:, :, :3], axis=2)
            unit = a / dist[:, :, None]
            unit[:, :, 3:] /= length
            sv_a = np.full((size, 6), np.nan)
            sv_a[ok] = np.linalg.svd(unit[ok], compute_uv=False)[:, :6]
            parallel = sv_a[:, -1] / sv_a[:, 0]
            speed = self._base_joint_speeds(qb)
            strut = self.model.rod_kind == STRUT
            cos = np.abs(np.take_along_axis(b, self.model.rod_actuator[None, :, None], 2)[:, :, 0]
                         ) / (dist * speed)
            cos[:, strut] = 1.0
            serial = cos.min(axis=1)
        j = np.full((size, 6, n), np.nan)
        if ok.any():
            j[ok] = self._solve_j(a[ok], b[ok])
        det_a = np.full(size, np.nan)
        if m == 6 and ok.any():
            det_a[ok] = np.linalg.det(a[ok])
        flags = np.where(serial < tol, int(Singularity.SERIAL), 0)
        flags |= np.where(parallel < tol, int(Singularity.PARALLEL), 0)
        at_parallel = (flags & Singularity.PARALLEL).astype(bool)
        j[at_parallel] = np.nan
        scale = np.array([1.0, 1.0, 1.0, length, length, length])
        j_h = j * scale[None, :, None]
        sv = self._singular_values(j_h)
        sv_t = self._singular_values(j[:, :3])
        sv_r = self._singular_values(j[:, 3:])
        with np.errstate(invalid="ignore", divide="ignore"):
            condition = sv[:, 0] / sv[:, -1]
            j_inv = np.full((size, n, 6), np.nan)
            good = ok & ~at_parallel
            if good.any():
                j_inv[good] = np.linalg.pinv(b[good]) @ a[good]
        det_b = np.full(size, np.nan)
        if m == n and ok.any():
            det_b[ok] = np.linalg.det(b[ok])
        return FullPoseJacobians(
            A=a, B=b, J=j, J_inv=j_inv, singular_values=sv, condition=condition, det_A=det_a,
            det_B=det_b, parallel_measure=parallel, serial_measure=serial, singularity=flags,
            tolerance=tol, q=qb, mode=np.sign(np.nan_to_num(det_a)).astype(int),
            J_homogeneous=j_h, characteristic_length=length,
            translation_singular_values=sv_t, rotation_singular_values=sv_r)

    def jacobian_dot(self, x: Any, xd: Any, *, q: Any = None) -> JacobianRates:
        """Time derivatives of the velocity model along a motion through poses ``x``.

        Args:
            x: ``(6,)`` / ``(N, 6)`` poses (positions ``(3,)`` / ``(N, 3)`` for a machine with
                fewer than six actuators: the orientation its rods impose is found).
            xd: the platform twists ``(6,)`` / ``(N, 6)`` = (v in m/s, ω in rad/s, both in the
                base frame, v of the platform reference point); for a machine with fewer than
                six actuators, also the velocities of the position ``(3,)`` / ``(N, 3)`` (its
                twist then follows from its rods).
            q: actuator coordinates at ``x`` (default: the inverse model).

        Returns:
            :class:`~pkmkit.machines.results.JacobianRates`: ``qd (N, n)`` the actuator rates,
            ``A_dot (N, m, 6)``, ``B_dot (N, m, n)`` and ``J_dot (N, 6, n)`` with
            ``J̇ = A⁻¹(Ḃ − ȦJ)`` (least squares ``A⁺`` beyond six rods), so that the platform's
            acceleration twist is ``J q̈ + J̇ q̇``.

        Raises:
            InputError: mis-shaped or non-finite input, a twist a position-controlled machine
                cannot follow (its rods do not allow it: the rates disagree by more than 1e-9
                relative).
        """
        jac = self.jacobian(x, q=q) if q is not None else self.jacobian(x)
        single = np.ndim(jac.condition) == 0
        poses = np.atleast_2d(self._poses_of(x, jac))
        j = np.atleast_3d(jac.J) if not single else jac.J[None]
        a = jac.A[None] if single else jac.A
        b = jac.B[None] if single else jac.B
        qb = np.atleast_2d(jac.q)
        size = poses.shape[0]
        try:
            xdb = np.asarray(xd, dtype=float)
        except (TypeError, ValueError) as exc:
            raise InputError(f"xd must be an array of numbers: {exc}") from None
        xdb = xdb[None] if xdb.ndim == 1 else xdb
        widths = (6, 3) if self.position_controlled else (6,)
        if xdb.ndim != 2 or xdb.shape[1] not in widths or xdb.shape[0] != size:
            raise InputError(f"xd must have shape ({size}, {' or '.join(map(str, widths))}) to "
                             f"match x, got {np.shape(xd)}")
        if not np.isfinite(xdb).all():
            raise InputError("xd must be finite")
        if (np.abs(xdb) > 1e9).any():
            raise InputError("xd has a component beyond 1e9 (m/s or rad/s): check the units")
        with np.errstate(invalid="ignore"):
            if xdb.shape[1] == 3:
                qd = np.full((size, self.n_actuators), np.nan)
                ok = np.isfinite(j).all(axis=(1, 2))
                qd[ok] = np.linalg.solve(j[ok, :3], xdb[ok][:, :, None])[:, :, 0]
                twist = np.einsum("kij,kj->ki", j, qd)
            else:
                twist = xdb
                qd = np.einsum("kij,kj->ki", np.linalg.pinv(b) @ a, twist)
                if self.position_controlled:
                    back = np.einsum("kij,kj->ki", j, qd)
                    off = np.abs(back - twist).max(axis=1) > 1e-9 * (
                        1 + np.abs(twist).max(axis=1))
                    if (off & np.isfinite(back).all(axis=1)).any():
                        k = int(np.flatnonzero(off)[0])
                        raise InputError(f"twist row {k} is not one the rods of {self.id!r} "
                                         "allow; give the velocity of the position (3 values)")
        a_dot, b_dot = self._forms.jacobian_rates(poses, qb, twist, qd)
        rhs = b_dot - np.einsum("kij,kjl->kil", a_dot, j)
        j_dot = np.full((size, 6, self.n_actuators), np.nan)
        ok = np.isfinite(a).all(axis=(1, 2)) & np.isfinite(rhs).all(axis=(1, 2))
        if ok.any():
            j_dot[ok] = self._solve_j(a[ok], rhs[ok])
        rates = JacobianRates(qd=qd, A_dot=a_dot, B_dot=b_dot, J_dot=j_dot)
        if single:
            return JacobianRates(**{k: v[0] for k, v in rates.__dict__.items()})
        return rates

    def _poses_of(self, x: Any, jac: FullPoseJacobians) -> np.ndarray:
        """The full poses a velocity model was taken at (positions completed by the inverse
        model for a position-controlled machine)."""
        arr = np.asarray(x, dtype=float)
        if self.position_controlled and arr.shape[-1] == 3:
            return np.asarray(self.ik(arr, full_output=True).pose)
        return arr

    @staticmethod
    def _solve_j(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """J = A⁻¹B (six rods) or the least-squares A⁺B (more rods)."""
        if a.shape[1] == 6:
            return np.linalg.solve(a, b)
        return np.linalg.pinv(a) @ b

    @staticmethod
    def _singular_values(mat: np.ndarray) -> np.ndarray:
        k = min(mat.shape[1], mat.shape[2])
        out = np.full((mat.shape[0], k), np.nan)
        ok = np.isfinite(mat).all(axis=(1, 2))
        if ok.any():
            out[ok] = np.linalg.svd(mat[ok], compute_uv=False)
        return out

    def _base_joint_speeds(self, q: np.ndarray) -> np.ndarray:
        """``|∂a_j/∂q|`` ``(N, m)`` (1 for struts, whose base joints do not move)."""
        from pkmkit.solve.rod_closure import actuator_rates

        rates = actuator_rates(self.model, np.nan_to_num(q).T)  # (3, m, N)
        speed = np.linalg.norm(rates, axis=0).T
        speed[:, self.model.rod_kind == STRUT] = 1.0
        return speed

    # ---------------------------------------------------------------- structure
    def mobility(self) -> dict[str, Any]:
        """Grübler–Kutzbach count and rank-based mobility at the home configuration."""
        return {
            "grubler": grubler_count(self.model),
            "instantaneous": instantaneous_mobility(self.model, self._home_pose,
                                                    self._home_q),
        }
