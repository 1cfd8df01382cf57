"""Geometric defects of rod-leg machines: named small changes of rod ends, lengths and
actuators, applied exactly.

A rod machine's geometry is its rods (base-side joint at q = 0, platform joint, length) and its
actuators (slide direction, crank pivot and axis, zero offset). The defects are named like the
parameters of seed 003's six-rod module (A_i B_i and the length, Merlet's 7 per rod: 42 for a
hexapod or a Verne-type module):

- ``dA<j>x``, ``dA<j>y``, ``dA<j>z`` — base-side joint of rod j at q = 0 (m);
- ``dB<j>x``, … — platform joint of rod j in the platform frame (m);
- ``dL<j>`` — length of rod j (m);
- ``du<k><c>`` — slide direction of actuator k, its two components other than the largest
  (dimensionless, ≈ rad; the largest follows from the unit norm);
- ``dP<k>x``, … and ``dw<k><c>`` — crank pivot (m) and axis direction;
- ``dq<k>`` — zero offset of actuator k (m, or rad for a crank): the actuator reads q but is at
  q + dq.

**Levels.** For a translational machine (``dims`` 2 or 3) the rods are its *equivalent legs*
(one per actuator, a parallelogram's midline — the model its closed forms use), so a defect
keeps the platform translating: the classic "delta printer" model of radii, rod lengths, tower
angles and endstop offsets. For a full-pose machine they are its real rods. Planar machines have
no z components.

Application is exact: points and lengths add; a direction ``u`` becomes ``u + Σ δ_c e_c``
renormalised through its largest component; an offset moves the base joints along the slide,
turns them about the crank axis, or lengthens the strut.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.model.rods import CRANK, SLIDE, STRUT, RodModel, build_rod_model, leg_specs

_AXES = "xyz"


@dataclass(frozen=True)
class RodDefectIndex:
    """Names and meanings of a rod model's defect coordinates.

    Attributes:
        names: ``(d,)`` defect names (module docstring).
        units: ``(d,)`` ``"m"``, ``"rad"`` or ``"1"``.
        kind: ``(d,)`` ``"base"``, ``"platform"``, ``"length"``, ``"axis"``, ``"pivot"`` or
            ``"offset"``.
        target: ``(d,)`` rod index (base, platform, length) or actuator index (the others).
        component: ``(d,)`` coordinate index (0, 1, 2), −1 for lengths and offsets.
        level: ``"legs"`` (equivalent legs of a translational machine) or ``"rods"``.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    kind: tuple[str, ...]
    target: np.ndarray
    component: np.ndarray
    level: str

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of a defect by name (ParameterError listing some valid names otherwise)."""
        try:
            return self.names.index(name)
        except ValueError:
            preview = ", ".join(self.names[:10]) + (", …" if len(self.names) > 10 else "")
            raise ParameterError(f"unknown defect {name!r}; defects are named like {preview}",
                                 name) from None


def _rod_table(model: RodModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, str]:
    """(base, platform, length, actuator) of the defect level's rods, and the level."""
    if model.full_pose:
        return model.rod_base, model.rod_platform, model.rod_length, model.rod_actuator, "rods"
    return model.leg_base, model.leg_platform, model.leg_length, model.leg_actuator, "legs"


def rod_geometry(model: RodModel) -> dict[str, np.ndarray | str]:
    """The geometry the defects act on, as copies: ``base``, ``platform`` ``(m, 3)``,
    ``length`` ``(m,)`` of the defect level's rods (m), the per-leg ``axis`` and ``pivot``
    ``(n, 3)``, and the ``level`` (``"legs"`` or ``"rods"``)."""
    base, platform, length, _, level = _rod_table(model)
    return {"base": np.array(base, dtype=float), "platform": np.array(platform, dtype=float),
            "length": np.array(length, dtype=float),
            "axis": np.array(model.leg_axis, dtype=float),
            "pivot": np.array(model.leg_pivot, dtype=float), "level": level}


def direction_components(u: np.ndarray, space: int) -> list[int]:
    """The components of a unit direction that parametrise its defects: those other than the
    largest, within the machine's space (x, y for a planar machine)."""
    major = int(np.argmax(np.abs(u[:space])))
    return [c for c in range(space) if c != major]


def rod_defect_index(model: RodModel) -> RodDefectIndex:
    """The defect coordinates of ``model`` (see the module docstring)."""
    base, _, _, _, level = _rod_table(model)
    space = 2 if model.planar else 3
    rows = []
    for j in range(len(base)):
        for c in range(space):
            rows.append((f"dA{j + 1}{_AXES[c]}", "m", "base", j, c))
        for c in range(space):
            rows.append((f"dB{j + 1}{_AXES[c]}", "m", "platform", j, c))
        rows.append((f"dL{j + 1}", "m", "length", j, -1))
    kinds = model.actuator_kind
    for k in range(model.n_actuators):
        leg = int(np.flatnonzero(model.leg_actuator == k)[0])
        u = model.leg_axis[leg]
        if kinds[k] == CRANK:
            for c in range(3):
                rows.append((f"dP{k + 1}{_AXES[c]}", "m", "pivot", k, c))
            for c in direction_components(u, 3):
                rows.append((f"dw{k + 1}{_AXES[c]}", "1", "axis", k, c))
        elif kinds[k] == SLIDE:
            for c in direction_components(u, space):
                rows.append((f"du{k + 1}{_AXES[c]}", "1", "axis", k, c))
        unit = "rad" if kinds[k] == CRANK else "m"
        rows.append((f"dq{k + 1}", unit, "offset", k, -1))
    return RodDefectIndex(
        names=tuple(r[0] for r in rows), units=tuple(r[1] for r in rows),
        kind=tuple(r[2] for r in rows), target=np.array([r[3] for r in rows], dtype=int),
        component=np.array([r[4] for r in rows], dtype=int), level=level)


def direction_increment(u: np.ndarray, component: int, major: int | None = None
                        ) -> np.ndarray:
    """``∂u/∂δ`` for the defect perturbing component ``component`` of the unit direction u:
    ``e_c − (u_c / u_m) e_m`` — orthogonal to u. ``m`` is the component that follows from the
    unit norm: ``major`` when given (the largest component of the *nominal* direction, which
    :func:`apply_rod_defects` keeps however far the defects tilt it), else u's largest."""
    if major is None:
        major = int(np.argmax(np.abs(u)))
    out = np.zeros(3)
    out[component] = 1.0
    out[major] -= u[component] / u[major]
    return out


def axis_majors(index: RodDefectIndex, n_actuators: int) -> np.ndarray:
    """``(n_actuators,)`` the component of each actuator's direction that follows from the unit
    norm in ``index``'s parametrisation (the one its ``du``/``dw`` defects leave out: the
    nominal direction's largest), −1 for an actuator without direction defects (strut)."""
    out = np.full(n_actuators, -1, dtype=int)
    axis = np.array([k == "axis" for k in index.kind], dtype=bool)
    for k in range(n_actuators):
        comps = {int(c) for c in index.component[axis & (index.target == k)]}
        if comps:
            out[k] = min(set(range(len(comps) + 1)) - comps)
    return out


def before_offsets(model: RodModel, index: RodDefectIndex) -> tuple[RodSet, np.ndarray]:
    """The rods of ``model`` as :func:`apply_rod_defects` builds them **before** the actuator
    offsets, and the offset of each rod's actuator ``(m,)`` (m, or rad for a crank; zeros for a
    nominal model): base joints moved back along the slide / turned back about the crank axis,
    strut lengths shortened. With ``q + offset`` for ``q`` they give the same rods; their
    derivatives are those of the defect rule (defects applied to the nominal geometry)."""
    rods = rod_set(model)
    offsets = np.zeros(model.n_actuators)
    if model.defects is not None and len(model.defects) == len(index):
        is_offset = np.array([k == "offset" for k in index.kind], dtype=bool)
        offsets[index.target[is_offset]] = np.asarray(model.defects)[is_offset]
    per_rod = offsets[rods.actuator]
    if not per_rod.any():
        return rods, per_rod
    base = np.array(rods.base, dtype=float)
    length = np.array(rods.length, dtype=float)
    for j, dq in enumerate(per_rod):
        if dq == 0.0:
            continue
        if rods.kind[j] == SLIDE:
            base[j] -= dq * rods.axis[j]
        elif rods.kind[j] == CRANK:
            base[j] = rods.pivot[j] + _rodrigues(rods.axis[j], -dq, base[j] - rods.pivot[j])
        else:
            length[j] -= dq
    return replace(rods, base=base, length=length), per_rod


def _tilted(u: np.ndarray, deltas: dict[int, float]) -> np.ndarray:
    major = int(np.argmax(np.abs(u)))
    out = u.copy()
    for c, d in deltas.items():
        out[c] += d
    rest = 1.0 - sum(out[c] ** 2 for c in range(3) if c != major)
    if rest <= 0:
        raise ParameterError("a direction defect tilts an axis by more than 90°; defects must "
                             "be small")
    out[major] = np.copysign(np.sqrt(rest), u[major])
    return out


def _rodrigues(axis: np.ndarray, angle: float, v: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * (axis @ v) * (1.0 - c)


def apply_rod_defects(model: RodModel, index: RodDefectIndex, delta: np.ndarray) -> RodModel:
    """A new model with the defects ``delta`` (in ``index`` order, SI) applied exactly."""
    delta = np.asarray(delta, dtype=float).reshape(-1)
    if delta.shape != (len(index),) or not np.isfinite(delta).all():
        raise ParameterError(f"defects must be {len(index)} finite values, got {delta.shape}")
    base, platform, length, actuator, _ = (np.array(a, dtype=float) if i < 3 else a
                                               for i, a in enumerate(_rod_table(model)))
    axis = np.array(model.leg_axis, dtype=float)
    pivot = np.array(model.leg_pivot, dtype=float)
    tilts: dict[int, dict[int, float]] = {}
    offsets = np.zeros(model.n_actuators)
    for kind, t, c, d in zip(index.kind, index.target, index.component, delta, strict=True):
        if d == 0.0:
            continue
        if kind == "base":
            base[t, c] += d
        elif kind == "platform":
            platform[t, c] += d
        elif kind == "length":
            length[t] += d
        elif kind == "pivot":
            pivot[model.leg_actuator == t, c] += d
        elif kind == "axis":
            tilts.setdefault(int(t), {})[int(c)] = d
        else:
            offsets[t] = d
    for k, deltas in tilts.items():
        legs = model.leg_actuator == k
        axis[legs] = _tilted(axis[np.flatnonzero(legs)[0]], deltas)
    # actuator offsets: the real carriage sits at q + dq
    kinds = model.actuator_kind
    for j in range(len(base)):
        k = int(actuator[j])
        if offsets[k] == 0.0:
            continue
        leg = int(np.flatnonzero(model.leg_actuator == k)[0])
        if kinds[k] == SLIDE:
            base[j] += offsets[k] * axis[leg]
        elif kinds[k] == CRANK:
            base[j] = pivot[leg] + _rodrigues(axis[leg], offsets[k], base[j] - pivot[leg])
        else:
            length[j] += offsets[k]
    if np.any(length <= 0) and not (model.leg_kind == STRUT).all():
        raise ParameterError("a length defect makes a rod length non-positive")
    return with_rod_geometry(model, base, platform, length, axis, pivot)


def with_rod_geometry(model: RodModel, base: np.ndarray, platform: np.ndarray,
                      length: np.ndarray, axis: np.ndarray, pivot: np.ndarray) -> RodModel:
    """A new model with the defect level's rods (equivalent legs of a translational machine,
    real rods of a full-pose one) given: ``base``, ``platform`` ``(m, 3)``, ``length`` ``(m,)``
    (m), and the per-leg actuator ``axis`` (unit) and crank ``pivot`` ``(n, 3)``. Everything
    else (strokes, branches, home pose, names) is kept."""
    level = _rod_table(model)[4]
    if level == "legs":
        specs = leg_specs(model)
        legs = [replace(s, base=base[i], platform=platform[i], length=float(length[i]),
                        axis=axis[i] if s.axis is not None else None,
                        pivot=pivot[i] if s.pivot is not None else None)
                for i, s in enumerate(specs)]
        return build_rod_model(legs, dims=model.dims, actuator_names=model.actuator_names,
                               home_pose=model.home_pose, mode_names=model.mode_names,
                               pose_names=model.pose_names)
    rod_axis = axis[model.rod_leg]
    return replace(model, rod_base=_frozen(base), rod_platform=_frozen(platform),
                   rod_length=_frozen(length), leg_axis=_frozen(axis),
                   leg_pivot=_frozen(pivot), rod_axis=_frozen(rod_axis))


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class RodSet:
    """The rods a defect model acts on (equivalent legs or real rods), as arrays.

    Attributes:
        base, platform: ``(m, 3)`` joints (base side at q = 0; platform frame), m.
        length: ``(m,)`` m. kind: ``(m,)`` SLIDE/STRUT/CRANK. actuator: ``(m,)``.
        axis, pivot: ``(m, 3)`` the actuator's direction and crank pivot, per rod.
    """

    base: np.ndarray
    platform: np.ndarray
    length: np.ndarray
    kind: np.ndarray
    actuator: np.ndarray
    axis: np.ndarray
    pivot: np.ndarray


def rod_set(model: RodModel) -> RodSet:
    """The rods of ``model``'s defect level (equivalent legs for translational machines)."""
    if model.full_pose:
        return RodSet(model.rod_base, model.rod_platform, model.rod_length, model.rod_kind,
                      model.rod_actuator, model.rod_axis, model.rod_pivot)
    return RodSet(model.leg_base, model.leg_platform, model.leg_length, model.leg_kind,
                  model.leg_actuator, model.leg_axis, model.leg_pivot)
