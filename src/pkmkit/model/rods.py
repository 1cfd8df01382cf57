"""Rod-leg machine models.

A rod-leg machine is a platform joined to actuated carriages by rods of fixed length::

    | p + R b_j − a_j(q) | = ℓ_j(q)

- **slide** leg: a carriage moves along a fixed line, ``a_j(q) = a0_j + q_k u_j``, ``ℓ_j`` fixed
  (Orthoglide, linear Delta, five-bar with prismatic actuators);
- **strut** leg: the rod itself is actuated, ``a_j`` fixed and ``ℓ_j(q) = ℓ0_j + q_k``
  (hexapod-type legs);
- **crank** leg: a rotary actuator turns an arm about the axis (P_k, w_k); the rod's base-side
  joint turns with it, ``a_j(q) = P_k + Rot(w_k, q_k)(a0_j − P_k)``, ``ℓ_j`` fixed (Delta robot).

Several legs may share one actuator (the Verne-type module: two rods per slide, each described
as a leg of its own with the same actuator); legs sharing an actuator must agree on its kind,
axis, pivot and stroke.

``dims`` is 2 (planar, translational platform), 3 (spatial, translational platform) or 6 (full
pose: the platform also rotates; poses are position + rotation vector, see
:mod:`pkmkit.spatial.poses`).

Each leg is described twice:

- the *equivalent leg* (one rod per actuator, along the midline of a parallelogram) is what the
  closed-form models and the velocity Jacobians use — exact for a platform that only translates;
- the *rods* are what the generic least-squares engine closes: a parallelogram is two rods offset
  by ± half its width, so a translational machine gives an over-constrained closure (that is also
  where geometric defects of each rod enter later).

Geometry is always stored in 3-D (z = 0 for planar machines, ``dims = 2``). All lengths in metres.
The model is an immutable value: arrays are read-only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from pkmkit.exceptions import ParameterError

SLIDE = 0
STRUT = 1
CRANK = 2
LEG_KINDS = {"slide": SLIDE, "strut": STRUT, "crank": CRANK}
#: Names of the pose coordinates of a full-pose (dims = 6) machine.
FULL_POSE_NAMES = ("x", "y", "z", "rx", "ry", "rz")


@dataclass(frozen=True)
class LegSpec:
    """Input description of one leg, used to build a :class:`RodModel`.

    Attributes:
        name: leg name (used in error messages, e.g. ``"leg 2"``).
        actuator: index of the actuator driving the leg.
        kind: ``"slide"``, ``"strut"`` or ``"crank"``.
        base: slide: carriage joint centre at q = 0; strut: fixed base joint centre; crank: the
            arm-tip joint centre at q = 0. ``(3,)`` m.
        platform: platform joint centre in the platform frame, ``(3,)`` m.
        length: slide or crank: rod length; strut: rod length at q = 0 (may be 0: q is then
            the strut's length). m.
        axis: slide direction, or crank rotation axis ``(3,)`` (normalised here); ignored for
            struts.
        branch: working branch of the inverse model, +1 or −1: for a slide the actuator
            coordinate is ``q = u·w + branch·sqrt(…)``; in general the branch is −sign of
            ``d·∂a/∂q`` (see :mod:`pkmkit.machines.closed_form`).
        parallelogram_width: distance between the two rods of a parallelogram (0: single rod), m.
        parallelogram_direction: direction of the offset between the two rods ``(3,)``.
        stroke: ``(q_min, q_max)`` limits of the actuator coordinate, m or rad (default:
            unlimited).
        pivot: crank: a point of the rotation axis ``(3,)`` m; ignored for other kinds.
    """

    name: str
    actuator: int
    kind: str
    base: Sequence[float]
    platform: Sequence[float]
    length: float
    axis: Sequence[float] | None = None
    branch: int = 1
    parallelogram_width: float = 0.0
    parallelogram_direction: Sequence[float] | None = None
    stroke: tuple[float, float] = (-np.inf, np.inf)
    pivot: Sequence[float] | None = None


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def _unit(v: Sequence[float] | None, what: str) -> np.ndarray:
    arr = np.asarray(v if v is not None else (), dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ParameterError(f"{what} must be 3 finite numbers, got {v!r}", what)
    norm = float(np.linalg.norm(arr))
    if norm == 0.0:
        raise ParameterError(f"{what} must not be the zero vector", what)
    return arr / norm


def _point(v: Sequence[float], what: str) -> np.ndarray:
    arr = np.asarray(v, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ParameterError(f"{what} must be 3 finite numbers, got {v!r}", what)
    return arr


@dataclass(frozen=True, eq=False)
class RodModel:
    """Immutable rod-leg model (see the module docstring for the equations).

    Shapes: n legs, n_act actuators (n_act ≤ n, legs may share an actuator), m rods (m ≥ n).

    Attributes:
        dims: 2 for a planar machine (motion in the x-y plane), 3 for a spatial translational
            one, 6 for a full-pose one.
        pose_names: names of the pose coordinates, ``("x", "y")``, ``("x", "y", "z")`` or
            ``("x", "y", "z", "rx", "ry", "rz")``.
        actuator_names: names of the actuator coordinates.
        leg_names: names of the legs.
        leg_actuator, leg_kind, leg_branch: ``(n,)`` int.
        leg_base, leg_axis, leg_platform: ``(n, 3)`` m (axis: unit, zero for struts).
        leg_length: ``(n,)`` m.
        leg_pivot: ``(n, 3)`` m, crank rotation centre (zero for other kinds).
        q_min, q_max: ``(n_act,)`` actuator strokes (±inf when unlimited), m or rad.
        rod_leg, rod_actuator, rod_kind: ``(m,)`` int.
        rod_base, rod_axis, rod_platform: ``(m, 3)`` m.
        rod_length: ``(m,)`` m.
        home_pose: ``(dims,)`` m, the reference (home / isotropic) configuration.
        mode_names: names of the two assembly modes, for det(A) < 0 and det(A) > 0.
        nominal: the model without geometric defects, or None when this model is nominal
            (set by :func:`pkmkit.model.defect_rule.with_defects`).
        defects: ``(d,)`` the defects (SI, :func:`~pkmkit.model.rod_defects.rod_defect_index`
            order of :attr:`nominal`) that turn :attr:`nominal` into this model; None when
            nominal.
        nominal_kind: ``(kind, params)`` the nominal model was built from when the machine was
            of a built-in kind before its defects (its parameter vector keeps the kind's
            names), else None.
    """

    #: The model does not index its own defects: their index is derived from its nominal
    #: geometry (:func:`pkmkit.model.rod_defects.rod_defect_index`).
    owns_defect_index: ClassVar[bool] = False

    dims: int
    pose_names: tuple[str, ...]
    actuator_names: tuple[str, ...]
    leg_names: tuple[str, ...]
    leg_actuator: np.ndarray
    leg_kind: np.ndarray
    leg_branch: np.ndarray
    leg_base: np.ndarray
    leg_axis: np.ndarray
    leg_platform: np.ndarray
    leg_length: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    rod_leg: np.ndarray
    rod_base: np.ndarray
    rod_axis: np.ndarray
    rod_platform: np.ndarray
    rod_length: np.ndarray
    home_pose: np.ndarray
    mode_names: tuple[str, str] = field(default=("det(A)<0", "det(A)>0"))
    leg_pivot: np.ndarray | None = None
    nominal: RodModel | None = field(default=None, repr=False)
    defects: np.ndarray | None = field(default=None, repr=False)
    nominal_kind: tuple | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.leg_pivot is None:
            object.__setattr__(self, "leg_pivot", _frozen(np.zeros((len(self.leg_names), 3))))

    @property
    def n_legs(self) -> int:
        """Number of legs (equivalent rods)."""
        return len(self.leg_names)

    @property
    def n_actuators(self) -> int:
        """Number of actuators (joint-space dimension)."""
        return len(self.actuator_names)

    @property
    def n_rods(self) -> int:
        """Number of rods closed by the generic engine."""
        return len(self.rod_leg)

    @property
    def rod_actuator(self) -> np.ndarray:
        """Actuator of each rod ``(m,)``."""
        return self.leg_actuator[self.rod_leg]

    @property
    def rod_kind(self) -> np.ndarray:
        """Kind (:data:`SLIDE` or :data:`STRUT`) of each rod ``(m,)``."""
        return self.leg_kind[self.rod_leg]

    @property
    def rod_pivot(self) -> np.ndarray:
        """Crank rotation centre of each rod's actuator ``(m, 3)`` (zero for other kinds)."""
        return self.leg_pivot[self.rod_leg]

    @property
    def planar(self) -> bool:
        """True for a planar machine (``dims == 2``)."""
        return self.dims == 2

    @property
    def full_pose(self) -> bool:
        """True when the platform pose has six coordinates (position + rotation vector)."""
        return self.dims == 6

    @property
    def actuator_kind(self) -> np.ndarray:
        """Kind (:data:`SLIDE`, :data:`STRUT`, :data:`CRANK`) of each actuator ``(n_act,)``."""
        first = [int(np.flatnonzero(self.leg_actuator == k)[0]) for k in range(self.n_actuators)]
        return self.leg_kind[first]

    @property
    def actuator_quantities(self) -> tuple[str, ...]:
        """``"angle"`` (radians inside, degrees at the boundaries) for crank actuators,
        ``"length"`` (m) for slides and struts, per actuator."""
        return tuple("angle" if k == CRANK else "length" for k in self.actuator_kind)

    def pad(self, x: np.ndarray) -> np.ndarray:
        """Platform positions ``(N, 3)`` of pose rows ``(N, dims)`` (z = 0 for planar machines,
        the first three coordinates of a full pose)."""
        if self.dims == 3:
            return x
        if self.dims == 6:
            return x[:, :3]
        out = np.zeros((x.shape[0], 3))
        out[:, : self.dims] = x
        return out


def build_rod_model(
    legs: Sequence[LegSpec],
    *,
    dims: int,
    actuator_names: Sequence[str],
    home_pose: Sequence[float],
    mode_names: tuple[str, str] = ("det(A)<0", "det(A)>0"),
    pose_names: Sequence[str] | None = None,
) -> RodModel:
    """Validate leg descriptions and build the immutable :class:`RodModel`.

    A translational machine (``dims`` 2 or 3) has exactly one leg per actuator, leg i driving
    actuator i (its closed forms use one equivalent rod per actuator). A full-pose machine
    (``dims = 6``) may have several legs per actuator (each actuator must drive at least one).

    Raises:
        ParameterError: inconsistent description (unknown kind, bad vectors, non-positive
            lengths, a planar machine with out-of-plane geometry, actuators without a leg, legs
            sharing an actuator inconsistently, ...), naming the leg and the field.
    """
    if dims not in (2, 3, 6):
        raise ParameterError(f"dims must be 2, 3 or 6, got {dims}", "dims")
    n_act = len(actuator_names)
    _check_leg_actuators(legs, dims, actuator_names)
    leg_rows = []
    rod_rows = []
    for i, leg in enumerate(legs):
        row = _leg_row(f"legs.{i}", leg, dims)
        leg_rows.append(row)
        rod_rows += _rod_rows(i, f"legs.{i}", leg, dims, row)
    _check_shared_actuators(leg_rows, actuator_names)
    home = np.asarray(home_pose, dtype=float).reshape(-1)
    if home.shape != (dims,) or not np.isfinite(home).all():
        raise ParameterError(f"home pose must be {dims} finite numbers, got {home_pose!r}", "home")
    if pose_names is not None:
        names = tuple(pose_names)
    else:
        names = FULL_POSE_NAMES if dims == 6 else ("x", "y", "z")[:dims]

    def column(rows, k, dtype=float):
        return _frozen(np.array([r[k] for r in rows], dtype=dtype))

    first_leg = [next(r for r in leg_rows if r[0] == k) for k in range(n_act)]
    return RodModel(
        dims=dims,
        pose_names=names,
        actuator_names=tuple(actuator_names),
        leg_names=tuple(leg.name for leg in legs),
        leg_actuator=column(leg_rows, 0, int),
        leg_kind=column(leg_rows, 1, int),
        leg_branch=column(leg_rows, 2, int),
        leg_base=column(leg_rows, 3),
        leg_axis=column(leg_rows, 4),
        leg_platform=column(leg_rows, 5),
        leg_length=column(leg_rows, 6),
        q_min=column(first_leg, 7),
        q_max=column(first_leg, 8),
        rod_leg=column(rod_rows, 0, int),
        rod_base=column(rod_rows, 1),
        rod_axis=column(rod_rows, 2),
        rod_platform=column(rod_rows, 3),
        rod_length=column(rod_rows, 4),
        home_pose=_frozen(home),
        mode_names=(str(mode_names[0]), str(mode_names[1])),
        leg_pivot=column(leg_rows, 9),
    )


def _check_leg_actuators(legs: Sequence[LegSpec], dims: int,
                         actuator_names: Sequence[str]) -> None:
    """Translational machines: one leg per actuator, leg i driving actuator i; full-pose
    machines: every actuator drives at least one leg, at most 6 actuators."""
    n_act = len(actuator_names)
    if dims in (2, 3):
        if len(legs) != n_act:
            raise ParameterError(
                f"each actuator needs exactly one leg: {n_act} actuators, {len(legs)} legs",
                "legs")
        if n_act != dims:
            raise ParameterError(
                f"a {dims}-D translational rod-leg machine needs {dims} actuators, got {n_act}",
                "legs",
            )
        if [leg.actuator for leg in legs] != list(range(n_act)):
            raise ParameterError(
                "each actuator must drive exactly one leg, leg i driving actuator i", "legs"
            )
        return
    used = sorted({leg.actuator for leg in legs})
    if used != list(range(n_act)):
        missing = sorted(set(range(n_act)) - set(used))
        what = (f"actuator {actuator_names[missing[0]]!r} drives no leg" if missing else
                f"legs name actuators {used} but there are {n_act}")
        raise ParameterError(f"each actuator must drive at least one leg: {what}", "legs")
    if n_act > 6:
        raise ParameterError(f"a full-pose machine has at most 6 actuators, got {n_act}",
                             "legs")


def _leg_row(where: str, leg: LegSpec, dims: int) -> tuple:
    """One leg checked: ``(actuator, kind, branch, base, axis, platform, length, q_min, q_max,
    pivot)``, points in m, ``axis`` a unit vector (zeros for a strut)."""
    if leg.kind not in LEG_KINDS:
        raise ParameterError(
            f"{where}.kind must be one of {sorted(LEG_KINDS)}, got {leg.kind!r}",
            f"{where}.kind",
        )
    kind = LEG_KINDS[leg.kind]
    base = _point(leg.base, f"{where}.base")
    platform = _point(leg.platform, f"{where}.platform")
    axis = _unit(leg.axis, f"{where}.axis") if kind != STRUT else np.zeros(3)
    pivot = _point(leg.pivot, f"{where}.pivot") if kind == CRANK else np.zeros(3)
    if kind == CRANK:
        arm = base - pivot
        if np.linalg.norm(arm - (arm @ axis) * axis) <= 1e-12 * (1.0 + np.linalg.norm(arm)):
            raise ParameterError(
                f"{where}: the crank arm (from the pivot to the base joint) has no length "
                "across the rotation axis", f"{where}.pivot")
    length = float(leg.length)
    # a strut's length at q = 0 may be 0 (q is then the strut length itself)
    if not np.isfinite(length) or length < 0 or (length == 0 and kind != STRUT):
        what = ">= 0 for a strut" if kind == STRUT else "> 0"
        raise ParameterError(f"{where}.length must be {what}, got {leg.length}",
                             f"{where}.length")
    lo, hi = (float(v) for v in leg.stroke)
    if np.isnan(lo) or np.isnan(hi) or not lo < hi:
        raise ParameterError(
            f"{where}.stroke must be (min, max) with min < max, got {leg.stroke}",
            f"{where}.stroke",
        )
    if leg.branch not in (1, -1):
        raise ParameterError(f"{where}.branch must be +1 or -1, got {leg.branch}", where)
    if dims == 2 and (base[2] != 0 or platform[2] != 0 or axis[2] != 0):
        raise ParameterError(f"{where}: a planar machine needs z = 0 geometry", where)
    if dims == 2 and kind == CRANK:
        raise ParameterError(f"{where}: crank legs are spatial (dims 3 or 6)", where)
    return (leg.actuator, kind, leg.branch, base, axis, platform, length, lo, hi, pivot)


def _rod_rows(i: int, where: str, leg: LegSpec, dims: int, row: tuple) -> list[tuple]:
    """The rods of leg ``i``: ``(leg, base, axis, platform, length)``, one rod, or the two
    rods of a parallelogram of ``leg.parallelogram_width`` (m)."""
    _, _, _, base, axis, platform, length, _, _, _ = row
    width = float(leg.parallelogram_width)
    if not np.isfinite(width) or width < 0:
        raise ParameterError(
            f"{where}.parallelogram width must be >= 0, got {width}", f"{where}.parallelogram"
        )
    if width == 0:
        return [(i, base, axis, platform, length)]
    offset = 0.5 * width * _unit(leg.parallelogram_direction, f"{where}.parallelogram")
    if dims == 2 and offset[2] != 0:
        raise ParameterError(f"{where}: a planar parallelogram must lie in the plane", where)
    return [(i, base + sign * offset, axis, platform + sign * offset, length)
            for sign in (-1.0, 1.0)]

def _check_shared_actuators(leg_rows: list, actuator_names: Sequence[str]) -> None:
    """Legs driven by one actuator must agree on its kind, axis, pivot and stroke."""
    first: dict[int, int] = {}
    for i, row in enumerate(leg_rows):
        k = row[0]
        if k not in first:
            first[k] = i
            continue
        j = first[k]
        other = leg_rows[j]
        name = actuator_names[k]
        checks = (("kind", row[1] == other[1]),
                  ("axis", np.allclose(row[4], other[4], rtol=0, atol=1e-12)),
                  ("pivot", np.allclose(row[9], other[9], rtol=0, atol=1e-12)),
                  ("stroke", row[7] == other[7] and row[8] == other[8]))
        for what, same in checks:
            if not same:
                plural = {"axis": "axes"}.get(what, what + "s")
                raise ParameterError(
                    f"legs.{j} and legs.{i} share actuator {name!r} but have different {plural}; "
                    "legs on one actuator must describe the same carriage, arm or strut",
                    f"legs.{i}.{what}")


def leg_specs(model: RodModel) -> list[LegSpec]:
    """The leg descriptions ``model`` can be rebuilt from (SI, 3-D vectors): the inverse of
    :func:`build_rod_model` for models whose parallelograms keep equal rods."""
    names = {v: k for k, v in LEG_KINDS.items()}
    specs = []
    for i in range(model.n_legs):
        rods = np.flatnonzero(model.rod_leg == i)
        width, direction = 0.0, None
        if len(rods) == 2:  # a parallelogram: rods at base ∓ offset (see build_rod_model)
            offset = 0.5 * (model.rod_base[rods[1]] - model.rod_base[rods[0]])
            width = 2.0 * float(np.linalg.norm(offset))
            direction = offset / (0.5 * width)
        kind = int(model.leg_kind[i])
        a = int(model.leg_actuator[i])
        specs.append(LegSpec(
            name=model.leg_names[i], actuator=a, kind=names[kind],
            base=model.leg_base[i].copy(), platform=model.leg_platform[i].copy(),
            length=float(model.leg_length[i]),
            axis=model.leg_axis[i].copy() if kind != STRUT else None,
            branch=int(model.leg_branch[i]), parallelogram_width=width,
            parallelogram_direction=direction,
            stroke=(float(model.q_min[a]), float(model.q_max[a])),
            pivot=model.leg_pivot[i].copy() if kind == CRANK else None))
    return specs
