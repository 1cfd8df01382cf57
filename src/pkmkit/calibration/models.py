"""Residual models of the calibration: what each measurement type predicts for a machine with
defects, minus what was measured, with the analytic Jacobians with respect to the machine's
defects and to the *setup parameters* of the measurement (the instrument frame, the part
placement, the ball-bar pivots, the bed plane).

Residual ``r = predicted − measured`` per observation (row of a :class:`MeasurementSet`):

- **point** (3 rows, m): ``P(q; δ) − F(x_meas)``. ``P`` is the tool point — for a joint-chain
  machine ``tool_length`` along its tool axis, for a full-pose rod machine ``tool_length`` below
  the platform origin along the platform's −z (the spindle), for a translational machine the
  platform point shifted by ``tool_length`` along −z. ``F`` maps the measurement frame to the
  machine frame: a fixed registration ``F₀`` (identity by default), and, with
  ``frame="identify"``, a rigid correction ``y ↦ exp(ρ)(y − c) + c + t`` about the centroid c of
  the points (6 setup parameters ``frame_rx … frame_z``);
- **pose** (6 rows): the point rows, then ``log(R(q; δ) R_measᵀ)`` (rad) with the measured
  orientation mapped by the same frame;
- **ballbar** (1 row, m): ``|P(q; δ) − c_k| − ℓ``, c_k the pivot of the row — each distinct
  pivot is 3 setup parameters (``pivot1_x`` …), started at its nominal position;
- **height** (1 row, m): ``z_P − (z₀ + a (x_P − x̄) + b (y_P − ȳ)) − h``: the probe reads the
  tool's height ``h`` above a flat bed of unknown height z₀ and slopes a, b (``bed_z``,
  ``bed_ax``, ``bed_ay``);
- **part** (n rows, actuator units): seed 003's joint-space error. The measured tool centre
  ``x_part`` is placed in the machine frame by ``P = Rz(φ) x_part + Δ`` (``part_x``,
  ``part_y``, ``part_z``, ``part_phi``: the unknown placement of the part on the CMM), mapped
  through the inverse model of the machine with defects, ``V = IGM(P; δ)``, and compared with
  the path the nominal controller commanded in joint space (the commanded straight line through
  the nominal inverse model, sampled every 0.5 mm): the residual is ``V`` minus its closest
  point on that curve, whose norm is the distance ``d_mi`` of the seed. Its Jacobian is the
  normal part ``(I − t tᵀ) ∂V/∂(δ, placement)`` (t the curve's unit tangent; moving along the
  curve does not change the distance to first order).

The Jacobians with respect to the defects come from
:func:`pkmkit.geometric_errors.model.tool_sensitivity` and
:func:`pkmkit.geometric_errors.measurements.measurement_jacobian` (analytic, through the closure).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.calibration.registration import Registration
from pkmkit.exceptions import InputError, PkmError
from pkmkit.geometric_errors.model import tool_sensitivity
from pkmkit.machines.measurement_models import ToolFrames
from pkmkit.model.measurement_set import MeasurementSet
from pkmkit.spatial.rotation import (
    inverse_left_jacobian,
    left_jacobian,
    matrix_to_rotvec,
    rotvec_to_matrix,
    skew,
)

#: How the residual models close a joint chain's legs (:meth:`fk` options).
CLOSURE = {"compiled": True, "strokes": "ignore"}
#: Spacing of the samples of a commanded path in Cartesian space (m).
PATH_SPACING = 5e-4


@dataclass(frozen=True)
class SetupParameters:
    """Parameters of the measurement set-up identified with the machine (all additive; a
    frame rotation is a rotation vector).

    Attributes:
        names, units (``"m"``, ``"rad"`` or ``"1"``), scale (typical magnitude, SI),
        initial values (SI).
    """

    names: tuple[str, ...] = ()
    units: tuple[str, ...] = ()
    scale: np.ndarray = field(default_factory=lambda: np.zeros(0))
    initial: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return len(self.names)


#: The tool at N configurations (:class:`pkmkit.machines.measurement_models.ToolFrames`):
#: point ``(N, 3)``, rotation ``(N, 3, 3)`` (or None), their defect Jacobians ``(N, 3, d)``
#: (or None), the closure's warm start (or None).
ToolState = ToolFrames


def tool_state(machine, q: np.ndarray, tool_length: np.ndarray | None, *, jacobian: bool,
               rotation: bool = False, x0: np.ndarray | None = None,
               closure_options: dict | None = None, keep: dict | None = None) -> ToolState:
    """Tool point (and rotation) of ``machine`` at ``q`` ``(N, n)``, with defect Jacobians on
    request (the machine's :meth:`tool_frames` / :meth:`tool_frames_linearised`,
    :mod:`pkmkit.machines.measurement_models`). With ``jacobian``, rows where the machine does
    not assemble are NaN (never an exception).

    ``x0``: a warm start of a joint-chain machine's closure (platform pose and passive joints,
    ``ToolState.start`` of a previous call at the same q) for residual-only evaluations;
    ``closure_options``: engine options of those closures (e.g. a loose ``xtol`` to emulate an
    inexact inner solver); ``keep``: a dict that receives the defect sensitivity
    (``keep["sensitivity"]``, :func:`pkmkit.geometric_errors.model.tool_sensitivity`) of a
    ``jacobian`` evaluation."""
    # a joint chain's closures run in the compiled kernel (pkmkit.solve.chain_kernel), from
    # the last solution, the Jacobian's as well (with the engine's default options); the
    # strokes were checked once (identify.check_measurements): flags would change nothing
    options = {**CLOSURE, **(closure_options or {})}
    try:
        if jacobian:
            sens = tool_sensitivity(machine, q, tool_length=tool_length, start=x0, **CLOSURE)
            if keep is not None:
                keep["sensitivity"] = sens
            return machine.tool_frames_linearised(q, sens, tool_length, rotation=rotation)
        return machine.tool_frames(q, tool_length, rotation=rotation, start=x0, **options)
    except PkmError:
        if not jacobian:
            raise
        return _nan_state(machine, q, rotation)


def _nan_state(machine, q, rotation) -> ToolState:
    from pkmkit.geometric_errors.model import defect_set

    n, d = q.shape[0], len(defect_set(machine))
    nan3 = np.full((n, 3), np.nan)
    return ToolState(nan3, np.full((n, 3, 3), np.nan) if rotation else None,
                     np.full((n, 3, d), np.nan), np.full((n, 3, d), np.nan))


class ResidualModel:
    """Base of the per-kind residual models (see the module docstring).

    Attributes:
        data: the measurements. width: residual rows per observation.
        setup: the set-up parameters. sigma: ``(N, width)`` standard deviation of each
            residual row (SI), the weights of the least squares.
    """

    width = 3

    def __init__(self, machine, data: MeasurementSet, sigma: np.ndarray):
        self.machine = machine
        self.data = data
        self.sigma = np.broadcast_to(np.asarray(sigma, dtype=float),
                                     (len(data), self.width)).copy()
        self.setup = SetupParameters()
        self._cache: tuple | None = None
        self._sensitivity: tuple | None = None
        self._warm: np.ndarray | None = None
        #: engine options of a joint-chain machine's residual-only closures
        self.closure_options: dict = {}

    def _tool(self, machine, *, jacobian: bool, rotation: bool = False) -> ToolState:
        """:func:`tool_state` at the measured configurations, cached for the last machine (the
        set-up fit evaluates one machine many times)."""
        c = self._cache
        if c is not None and c[0] is machine and (c[1] or not jacobian) and (c[2] or not
                                                                            rotation):
            return c[3]
        keep: dict = {}
        state = tool_state(machine, self.data.q, self.data.tool_length, jacobian=jacobian,
                           rotation=rotation, x0=self._warm,
                           closure_options=self.closure_options, keep=keep)
        self._cache = (machine, jacobian, rotation, state)
        if "sensitivity" in keep:
            self._sensitivity = (machine, keep["sensitivity"])
        if state.start is not None:
            self._warm = state.start
        return state

    def sensitivity(self, machine) -> Any:
        """The defect sensitivity at the measured configurations of the last Jacobian
        evaluation, if it was of ``machine`` (the same object), else None."""
        s = self._sensitivity
        return s[1] if s is not None and s[0] is machine else None

    def residuals(self, machine, setup: np.ndarray, *, jacobian: bool
                  ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
        """``r (N, w)``, ``∂r/∂δ (N, w, d)`` and ``∂r/∂setup (N, w, s)`` (None without
        ``jacobian``)."""
        raise NotImplementedError

    def errors(self, r: np.ndarray) -> np.ndarray:
        """Magnitude of each observation's error ``(N,)`` (SI) for statistics."""
        return np.linalg.norm(r[:, :3], axis=1)

    def refit_setup_for_validation(self) -> bool:
        """Whether the set-up belongs to the artefact (refitted on a validation set) rather
        than to the instrument station (carried over)."""
        return False

    @property
    def rigid_motion_free(self) -> Any:
        """Whether a rigid motion of the whole machine leaves these measurements unchanged
        once the set-up parameters are refitted (an identified instrument frame, identified
        ball-bar pivots, a bed plane): the tool points are then determined only up to that
        free rigid motion (a gauge). A ``(6,)`` mask (translations x, y, z, rotations about
        x, y, z) where only some of them are free."""
        return False


class _FramedModel(ResidualModel):
    """Point and pose models: readings in an instrument frame."""

    def __init__(self, machine, data, sigma, *, registration: Registration | None,
                 identify_frame: bool):
        super().__init__(machine, data, sigma)
        reg = registration or Registration.identity()
        self.registration = reg
        self.y0 = reg.apply(data.values[:, :3])
        self.rot0 = (reg.rotation[None] @ rotvec_to_matrix(data.values[:, 3:6])
                     if data.kind == "pose" else None)
        self.centre = self.y0.mean(axis=0)
        self.identify_frame = identify_frame
        if identify_frame:
            self.setup = SetupParameters(
                names=("frame_rx", "frame_ry", "frame_rz", "frame_x", "frame_y", "frame_z"),
                units=("rad", "rad", "rad", "m", "m", "m"),
                scale=np.array([1e-3, 1e-3, 1e-3, 1e-3, 1e-3, 1e-3]), initial=np.zeros(6))

    @property
    def rigid_motion_free(self) -> bool:
        return bool(self.identify_frame)

    def frame(self, setup: np.ndarray) -> Registration:
        """The full measurement-to-machine transform for set-up values ``setup``."""
        if not self.identify_frame:
            return self.registration
        rot = rotvec_to_matrix(setup[None, :3])[0]
        correction = Registration(rot, self.centre + setup[3:6] - rot @ self.centre,
                                  np.zeros((0, 3)), np.zeros(0))
        return correction.compose(self.registration)

    def _mapped(self, setup):
        if not self.identify_frame:
            return self.y0, np.zeros((len(self.y0), 3, 0)), None
        rot = rotvec_to_matrix(setup[None, :3])[0]
        y = (self.y0 - self.centre) @ rot.T + self.centre + setup[3:6]
        dy = np.zeros((len(y), 3, 6))
        # exp(ρ + dρ) ≈ exp(J_l(ρ) dρ) exp(ρ): d(exp(ρ) v) = −[exp(ρ) v]× J_l(ρ) dρ
        dy[:, :, :3] = -skew(y - self.centre - setup[3:6]) @ left_jacobian(setup[:3])
        dy[:, :, 3:] = np.eye(3)
        return y, dy, rot


class PointModel(_FramedModel):
    """Tool-point readings (laser tracker)."""

    width = 3

    def residuals(self, machine, setup, *, jacobian):
        state = self._tool(machine, jacobian=jacobian)
        y, dy, _ = self._mapped(setup)
        r = state.point - y
        if not jacobian:
            return r, None, None
        return r, state.dpoint, -dy


class PoseModel(_FramedModel):
    """Tool-point and orientation readings (6-D tracker probe)."""

    width = 6

    def residuals(self, machine, setup, *, jacobian):
        state = self._tool(machine, jacobian=jacobian, rotation=True)
        y, dy, rot = self._mapped(setup)
        measured = self.rot0 if rot is None else rot[None] @ self.rot0
        # rows the machine did not assemble: identity there (a zero matrix, as nan_to_num gave,
        # made SciPy raise 'non-positive determinant' for the whole run), NaN residuals after
        lost = ~(np.isfinite(state.rotation).all(axis=(1, 2))
                 & np.isfinite(state.point).all(axis=1))
        with np.errstate(invalid="ignore"):
            diff = np.where(lost[:, None, None], np.eye(3), state.rotation) @ measured.transpose(
                0, 2, 1)
            r_rot = matrix_to_rotvec(diff)
        r_rot[lost] = np.nan
        r = np.concatenate([state.point - y, r_rot], axis=1)
        if not jacobian:
            return r, None, None
        # log(exp(ω) M) = r + J_l⁻¹(r) ω, log(M exp(−δ)) = r − J_r⁻¹(r) δ (first order in ω, δ)
        jl_inv = inverse_left_jacobian(np.nan_to_num(r_rot))
        jd = np.concatenate([state.dpoint, jl_inv @ state.drotation], axis=1)
        js = np.zeros((len(r), 6, len(self.setup)))
        if self.identify_frame:
            js[:, :3] = -dy
            js[:, 3:, :3] = -inverse_left_jacobian(-np.nan_to_num(r_rot)) @ left_jacobian(
                setup[:3])
        return r, jd, js

    def errors(self, r):
        return np.linalg.norm(r[:, :3], axis=1)


class BallbarModel(ResidualModel):
    """Ball-bar lengths from pivots whose positions are identified with the machine."""

    width = 1

    def __init__(self, machine, data, sigma, *, identify_pivots: bool = True):
        super().__init__(machine, data, sigma)
        keys = [tuple(np.round(p, 9)) for p in data.pivot]
        unique = list(dict.fromkeys(keys))
        self.pivot_index = np.array([unique.index(k) for k in keys])
        self.pivots0 = np.array(unique, dtype=float)
        self.identify_pivots = identify_pivots
        if identify_pivots:
            names = tuple(f"pivot{k + 1}_{c}" for k in range(len(unique)) for c in "xyz")
            self.setup = SetupParameters(names=names, units=("m",) * len(names),
                                         scale=np.full(len(names), 1e-3),
                                         initial=self.pivots0.reshape(-1).copy())

    def refit_setup_for_validation(self) -> bool:
        return True

    @property
    def rigid_motion_free(self) -> bool:
        return bool(self.identify_pivots)

    def pivots(self, setup):
        return setup.reshape(-1, 3) if self.identify_pivots else self.pivots0

    def residuals(self, machine, setup, *, jacobian):
        state = self._tool(machine, jacobian=jacobian)
        centre = self.pivots(setup)[self.pivot_index]
        bar = state.point - centre
        length = np.linalg.norm(bar, axis=1)
        r = (length - self.data.values[:, 0])[:, None]
        if not jacobian:
            return r, None, None
        unit = bar / length[:, None]
        jd = np.einsum("kc,kcd->kd", unit, state.dpoint)[:, None, :]
        js = np.zeros((len(r), 1, len(self.setup)))
        if self.identify_pivots:
            for c in range(3):
                js[np.arange(len(r)), 0, 3 * self.pivot_index + c] = -unit[:, c]
        return r, jd, js

    def errors(self, r):
        return np.abs(r[:, 0])


class HeightModel(ResidualModel):
    """Height-probe readings above a flat bed of unknown height and slopes."""

    width = 1

    def __init__(self, machine, data, sigma):
        super().__init__(machine, data, sigma)
        nominal = tool_state(machine, data.q, data.tool_length, jacobian=False).point
        self.centre = np.nanmean(nominal[:, :2], axis=0)
        z0 = float(np.nanmean(nominal[:, 2] - data.values[:, 0]))
        self.setup = SetupParameters(names=("bed_z", "bed_ax", "bed_ay"),
                                     units=("m", "1", "1"), scale=np.array([1e-3, 1e-3, 1e-3]),
                                     initial=np.array([z0, 0.0, 0.0]))

    def refit_setup_for_validation(self) -> bool:
        return True

    @property
    def rigid_motion_free(self) -> bool:
        # the bed's height and slopes absorb z and the tilts; x, y and the spin about z
        # do not change a height above a flat bed
        return True

    def residuals(self, machine, setup, *, jacobian):
        state = self._tool(machine, jacobian=jacobian)
        p = state.point
        dx, dy = p[:, 0] - self.centre[0], p[:, 1] - self.centre[1]
        bed = setup[0] + setup[1] * dx + setup[2] * dy
        r = (p[:, 2] - bed - self.data.values[:, 0])[:, None]
        if not jacobian:
            return r, None, None
        jd = (state.dpoint[:, 2] - setup[1] * state.dpoint[:, 0]
              - setup[2] * state.dpoint[:, 1])[:, None, :]
        js = np.stack([-np.ones(len(r)), -dx, -dy], axis=1)[:, None, :]
        return r, jd, js

    def errors(self, r):
        return np.abs(r[:, 0])


class PartModel(ResidualModel):
    """Seed 003's machined part: joint-space distance to the commanded path."""

    def __init__(self, machine, data, sigma):
        if machine.dims == 6 and not machine.position_controlled:
            raise InputError(
                f"machined-part identification needs a machine positioned by its tool point "
                f"(translational or position-controlled); {machine.id!r} is not one")
        self.width = machine.n_actuators
        super().__init__(machine, data, sigma)
        self.paths = self._command_paths(machine, data)
        self.setup = SetupParameters(names=("part_x", "part_y", "part_z", "part_phi"),
                                     units=("m", "m", "m", "rad"),
                                     scale=np.array([1e-3, 1e-3, 1e-3, 1e-3]),
                                     initial=initial_placement(data))

    def refit_setup_for_validation(self) -> bool:
        return True

    @property
    def rigid_motion_free(self) -> np.ndarray:
        """The placement absorbs the translations and the turn about z (a mask in
        :func:`~pkmkit.calibration.uncertainty.rigid_motion_basis`'s order)."""
        return np.array([True, True, True, False, False, True])

    @staticmethod
    def _command_paths(machine, data) -> dict[str, np.ndarray]:
        out = {}
        for label in dict.fromkeys(data.path):
            rows = [i for i, p in enumerate(data.path) if p == label]
            seg = data.commanded[rows[0]]
            if not np.allclose(data.commanded[rows], seg):
                raise InputError(f"path {label!r}: its rows give different commanded segments "
                                 f"({data.labels[rows[0]]} and others)")
            start, end = seg[:3], seg[3:]
            length = float(np.linalg.norm(end - start))
            if not length > 0:
                raise InputError(f"path {label!r} has zero length ({data.labels[rows[0]]})")
            count = max(20, int(np.ceil(length / PATH_SPACING)) + 1)
            pts = start + np.linspace(0.0, 1.0, count)[:, None] * (end - start)
            q = np.atleast_2d(_ik(machine, pts))
            if not np.isfinite(q).all():
                raise InputError(f"path {label!r} ({data.labels[rows[0]]}): the commanded line "
                                 "leaves the workspace of the nominal machine")
            out[label] = q
        return out

    def placed(self, setup: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Measured tool centres in the machine frame ``(N, 3)`` and ∂/∂placement
        ``(N, 3, 4)``."""
        c, s = np.cos(setup[3]), np.sin(setup[3])
        x = self.data.values
        rx = np.stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1], x[:, 2]], axis=1)
        p = rx + setup[:3]
        dp = np.zeros((len(x), 3, 4))
        dp[:, :, :3] = np.eye(3)
        dp[:, 0, 3] = -rx[:, 1]
        dp[:, 1, 3] = rx[:, 0]
        return p, dp

    def residuals(self, machine, setup, *, jacobian):
        from pkmkit.geometric_errors.measurements import measurement_jacobian

        p, dp = self.placed(setup)
        v = np.atleast_2d(_ik(machine, p))
        r = np.full(v.shape, np.nan)
        tangent = np.zeros(v.shape)
        for label, curve in self.paths.items():
            rows = np.array([i for i, q in enumerate(self.data.path) if q == label])
            foot, t = _closest_on_polyline(curve, v[rows])
            r[rows] = v[rows] - foot
            tangent[rows] = t
        if not jacobian:
            return r, None, None
        ok = np.isfinite(v).all(axis=1)
        n, w = v.shape
        jd = np.full((n, w, 0), np.nan)
        proj = np.eye(w)[None] - tangent[:, :, None] * tangent[:, None, :]
        try:
            jv = measurement_jacobian(machine, "part", None, {"points": _positions(machine, p)})
            dq_dp = _dq_dp(machine, p)
        except PkmError:
            ok[:] = False
        if not ok.all():
            from pkmkit.geometric_errors.model import defect_set

            d = len(defect_set(machine))
            return r, np.full((n, w, d), np.nan), np.full((n, w, 4), np.nan)
        jd = proj @ jv
        js = proj @ (dq_dp @ dp)
        return r, jd, js

    def errors(self, r):
        return np.linalg.norm(r, axis=1)


def _positions(machine, p: np.ndarray) -> np.ndarray:
    return p[:, :machine.dims] if machine.dims < 3 else p


def _ik(machine, p: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore"):
        return machine.ik(_positions(machine, p))


def _dq_dp(machine, p: np.ndarray) -> np.ndarray:
    """``∂q/∂p`` ``(N, n, 3)`` at tool points (fixed geometry)."""
    jac = machine.jacobian(_positions(machine, p))
    if machine.dims == 6:
        return np.linalg.inv(jac.J[:, :3, :])
    out = np.zeros((p.shape[0], machine.n_actuators, 3))
    out[:, :, :machine.dims] = jac.J_inv
    return out


def _closest_on_polyline(curve: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The foot of each point ``(M, n)`` on the polyline ``(K, n)`` (on the line of its nearest
    segment) and that segment's unit tangent."""
    a, b = curve[:-1], curve[1:]
    ab = b - a
    len2 = np.einsum("kn,kn->k", ab, ab)
    ap = points[:, None, :] - a[None]
    t = np.clip(np.einsum("mkn,kn->mk", ap, ab) / len2[None], 0.0, 1.0)
    foot = a[None] + t[:, :, None] * ab[None]
    dist = np.linalg.norm(points[:, None, :] - foot, axis=2)
    dist = np.where(np.isfinite(dist), dist, np.inf)
    k = np.argmin(dist, axis=1)
    unit = ab / np.sqrt(len2)[:, None]
    # the foot on the nearest segment's line, not clamped to its ends: the residual stays
    # normal to the local tangent (so that its Jacobian is (I − t tᵀ) ∂V), also where the
    # nearest point of the polyline would be a vertex
    along = np.einsum("mn,mn->m", points - a[k], unit[k])
    return a[k] + along[:, None] * unit[k], unit[k]


def initial_placement(data: MeasurementSet) -> np.ndarray:
    """Part placement ``(Δx, Δy, Δz, φ)`` that best puts the measured tool centres on their
    commanded lines (Cartesian least squares; the start of the identification)."""
    from scipy.optimize import least_squares

    start, end = data.commanded[:, :3], data.commanded[:, 3:]
    direction = (end - start) / np.linalg.norm(end - start, axis=1)[:, None]
    x = data.values
    guess = np.zeros(4)

    def residual(v):
        c, s = np.cos(v[3]), np.sin(v[3])
        p = np.stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1], x[:, 2]], axis=1)
        d = p + v[:3] - start
        return (d - np.einsum("ij,ij->i", d, direction)[:, None] * direction).ravel()

    # the along-path offset of the part is unobservable from lines along one direction only:
    # a small ridge keeps the start well posed; the identification refines it
    sol = least_squares(lambda v: np.concatenate([residual(v), 1e-6 * v]), guess,
                        method="lm", xtol=1e-15, ftol=1e-15)
    return sol.x


def make_model(machine, data: MeasurementSet, sigma: np.ndarray, *,
               registration: Registration | None = None, identify_frame: bool = False
               ) -> ResidualModel:
    """The residual model of ``data``'s kind (see the module docstring)."""
    if data.kind == "point":
        return PointModel(machine, data, sigma, registration=registration,
                          identify_frame=identify_frame)
    if data.kind == "pose":
        if machine.orientation_fixed:
            raise InputError(f"{machine.id!r} only translates: full-pose measurements have "
                             "nothing to measure in its orientation; use point measurements")
        return PoseModel(machine, data, sigma, registration=registration,
                         identify_frame=identify_frame)
    if registration is not None or identify_frame:
        raise InputError(f"a measurement frame applies to point and pose measurements, not to "
                         f"{data.kind} measurements")
    if data.kind == "ballbar":
        return BallbarModel(machine, data, sigma)
    if data.kind == "height":
        return HeightModel(machine, data, sigma)
    return PartModel(machine, data, sigma)
