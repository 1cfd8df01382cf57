"""Joint-chain machine models: serial chains of revolute and prismatic joints closed on a
platform, an optional serial head and tool (seed 002, Guyon 2021, Ch. 3–4).

**Elements.** A chain is a sequence of *elements*. Each element places a frame ``L`` in the frame
of the previous body (the *defect matrix* D of the thesis, eq. 4.6) and, for a joint, moves the
next body by the joint's motion M about or along ``z_L`` (eq. 4.3/4.4)::

    T_chain = D_1 M_1(q_1) D_2 M_2(q_2) … D_n M_n(q_n)        (M = I for a fixed frame)

An element's frame is given by its **invariant** — the axis ``(I, J, K)`` and a point
``(A, B, C)`` in the previous frame — as in the thesis; its x axis follows (4.6),
``x_L = z_prev × z_L / ‖·‖``, except where (4.6) is undefined (axis parallel to the previous z)
where ``x_L`` is the previous x axis (the thesis's CATIA model used identity matrices there). An
optional ``spin`` turns the frame about its own z after that, and a frame may instead be given
by a full rotation (junction matrices such as (4.12)).

**Named parameters and defects** (one vector per machine). Every element contributes its
nominal values ``I<label>, J<label>, K<label>, A<label>, B<label>, C<label>`` (and ``S<label>``,
the spin, for frames) to the machine's parameter vector, and its minimal **defects** to the
defect vector, named as in the thesis by the previous-frame component they perturb:

- revolute joint: 2 orientation + 2 position defects — the two axis components and the two
  point coordinates other than the axis's largest component (axis (0, −1, 0): ``dI, dK, da,
  dc``); the point's shift along the axis and the normalisation component are not parameters;
- prismatic joint: 2 orientation defects (its direction);
- fixed frame: 2 orientation (the axis tilt) + 1 spin ``dS`` about the axis + 3 position
  (``da, db, dc``).

A defect is applied exactly as a **minimal rotation** of the nominal frame that tilts the axis
to ``z + Σ dz`` (renormalised through its largest component) about the frame's point, plus the
point's shift — numerically regular everywhere, and equal to (4.6) to first order wherever
(4.6) is defined (notes §6.2). Defects are small displacements: ``defect_twists`` gives their
first-order effect as twists in the previous frame, the columns of every identification
Jacobian.

Units: metres and radians inside; every value is SI.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.spatial.rotation import axis_rotation, left_jacobian, skew

REVOLUTE = "R"
PRISMATIC = "P"
FIXED = "F"
ELEMENT_TYPES = (REVOLUTE, PRISMATIC, FIXED)
_COMPONENTS = ("I", "J", "K")
_POINT = ("A", "B", "C")
#: Below this value of sqrt(I² + J²) the (4.6) frame is undefined and x_L = x_prev is used.
PARALLEL_TOL = 1e-9


def invariant_frame(axis: Sequence[float], point: Sequence[float], spin: float = 0.0
                    ) -> np.ndarray:
    """Homogeneous frame ``(4, 4)`` of an element from its invariant (eq. 4.6 with the regular
    fallback; see the module docstring), then turned by ``spin`` (rad) about its own z.

    Raises:
        ParameterError: an axis of zero length or non-finite values.
    """
    z = np.asarray(axis, dtype=float)
    o = np.asarray(point, dtype=float)
    norm = float(np.linalg.norm(z)) if z.shape == (3,) else 0.0
    if z.shape != (3,) or not np.isfinite(z).all() or norm == 0.0:
        raise ParameterError(f"a joint axis must be 3 finite numbers, not all zero; got {axis!r}")
    if o.shape != (3,) or not np.isfinite(o).all():
        raise ParameterError(f"a joint point must be 3 finite numbers, got {point!r}")
    z = z / norm
    across = float(np.hypot(z[0], z[1]))
    if across > PARALLEL_TOL:
        x = np.array([-z[1], z[0], 0.0]) / across
    else:
        x = np.array([1.0, 0.0, 0.0])
        x = x - (x @ z) * z
        x /= np.linalg.norm(x)
    y = np.cross(z, x)
    rot = np.column_stack([x, y, z])
    if spin:
        rot = rot @ axis_rotation(np.array([0.0, 0.0, 1.0]), np.asarray(spin))
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = o
    return out


@dataclass(frozen=True)
class ElementSpec:
    """Input description of one chain element.

    Attributes:
        name: unique name; for a joint, the joint variable's name (``"psi1"``, ``"Q1"``).
        type: ``"R"`` (revolute), ``"P"`` (prismatic) or ``"F"`` (fixed frame).
        axis: ``(I, J, K)`` in the previous frame (ignored when ``rotation`` is given).
        point: ``(A, B, C)`` in the previous frame, m.
        label: suffix of the parameter and defect names (``"21"`` → ``I21``, ``dI21``); default
            the element name.
        actuated: the joint is driven (its value is an input of the direct model).
        spin: extra rotation about the frame's own z (rad).
        rotation: a full rotation matrix ``(3, 3)`` of the frame in the previous frame, instead
            of axis/spin (junction matrices).
        home: the joint value in the home configuration (rad or m), a starting guess.
        stroke: ``(min, max)`` of the joint value (rad or m); unlimited by default.
        display: a human name for reports (``"ψ1"``); default the name.
    """

    name: str
    type: str
    axis: Sequence[float] = (0.0, 0.0, 1.0)
    point: Sequence[float] = (0.0, 0.0, 0.0)
    label: str | None = None
    actuated: bool = False
    spin: float = 0.0
    rotation: Sequence[Sequence[float]] | None = None
    home: float = 0.0
    stroke: tuple[float, float] = (-np.inf, np.inf)
    display: str | None = None


@dataclass(frozen=True)
class DefectIndex:
    """Names and first-order effects of a model's defect coordinates.

    Attributes:
        names: ``(d,)`` defect names (``"dI21"``, ``"da13"``, …).
        units: ``(d,)`` ``"1"`` for orientation components (dimensionless, ≈ rad), ``"rad"`` for
            spins, ``"m"`` for positions.
        element: ``(d,)`` index of the element each defect belongs to.
        kind: ``(d,)`` ``"orientation"``, ``"spin"`` or ``"position"``.
        component: ``(d,)`` previous-frame component index (0, 1, 2) perturbed (−1 for a spin).
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    element: np.ndarray
    kind: tuple[str, ...]
    component: np.ndarray

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of a defect by name.

        Raises:
            ParameterError: an unknown name (the message lists a few valid ones).
        """
        try:
            return self.names.index(name)
        except ValueError:
            preview = ", ".join(self.names[:12]) + (", …" if len(self.names) > 12 else "")
            raise ParameterError(f"unknown defect {name!r}; defects are named like {preview}",
                                 name) from None


@dataclass(frozen=True, eq=False)
class JointChainModel:
    """Immutable joint-chain machine model.

    Attributes:
        elements: the element specifications (every element of every chain, each once).
        frames: ``(E, 4, 4)`` actual element frames (nominal with the defects applied).
        nominal_frames: ``(E, 4, 4)`` nominal frames.
        defects: ``(d,)`` current defect values (SI), in the order of :attr:`defect_index`.
        legs: chains from the base to the platform frame, as tuples of element indices.
        leg_names: names of the legs.
        head: chain from the platform frame to the tool frame (element indices; may be empty).
        variables: names of the joint variables (every joint element, each once), in order.
        actuated: ``(n_var,)`` bool, the variable is an actuator.
        home: ``(n_var,)`` home value of every variable (rad or m).
        q_min, q_max: ``(n_var,)`` strokes.
        characteristic_length: m, scales the rotation residuals of the closures.
        defect_index: names and kinds of the defect coordinates.
    """

    #: The model indexes its own defects (:attr:`defect_index`, on its elements' invariants).
    owns_defect_index: ClassVar[bool] = True

    elements: tuple[ElementSpec, ...]
    frames: np.ndarray
    nominal_frames: np.ndarray
    defects: np.ndarray
    legs: tuple[tuple[int, ...], ...]
    leg_names: tuple[str, ...]
    head: tuple[int, ...]
    variables: tuple[str, ...]
    actuated: np.ndarray
    home: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    characteristic_length: float
    defect_index: DefectIndex
    element_variable: np.ndarray = field(repr=False, default=None)

    # ------------------------------------------------------------------ structure
    @property
    def n_variables(self) -> int:
        """Number of joint variables."""
        return len(self.variables)

    @property
    def actuator_names(self) -> tuple[str, ...]:
        """Names of the actuated variables (head included), in variable order."""
        return tuple(v for v, a in zip(self.variables, self.actuated, strict=True) if a)

    @property
    def passive_names(self) -> tuple[str, ...]:
        """Names of the passive variables, in variable order."""
        return tuple(v for v, a in zip(self.variables, self.actuated, strict=True) if not a)

    @property
    def loop_variables(self) -> np.ndarray:
        """``(n_var,)`` bool: the variable belongs to a leg (not only to the head)."""
        out = np.zeros(self.n_variables, dtype=bool)
        for leg in self.legs:
            for e in leg:
                if self.element_variable[e] >= 0:
                    out[self.element_variable[e]] = True
        return out

    def joint_counts(self) -> dict[str, int]:
        """One-DOF joints of the parallel part (legs) by type, each shared joint once."""
        seen = {e for leg in self.legs for e in leg}
        out = {REVOLUTE: 0, PRISMATIC: 0}
        for e in seen:
            t = self.elements[e].type
            if t != FIXED:
                out[t] += 1
        return out

    def element_names(self) -> tuple[str, ...]:
        """Names of the elements."""
        return tuple(e.name for e in self.elements)

    # ------------------------------------------------------------------ parameters
    def parameter_names(self) -> tuple[str, ...]:
        """Names of the nominal parameter vector: ``I, J, K, A, B, C`` (and ``S`` for fixed
        frames) of every element, suffixed by its label."""
        names = []
        for spec in self.elements:
            label = _label(spec)
            names += [f"{c}{label}" for c in (*_COMPONENTS, *_POINT)]
            if spec.type == FIXED:
                names.append(f"S{label}")
        return tuple(names)

    def parameter_values(self) -> np.ndarray:
        """Actual values of the parameter vector (axis components, point in m, spin in rad),
        read back from the actual frames."""
        out = []
        for e, spec in enumerate(self.elements):
            frame = self.frames[e]
            out += [*frame[:3, 2], *frame[:3, 3]]
            if spec.type == FIXED:
                nominal = invariant_frame(frame[:3, 2], frame[:3, 3])
                c = nominal[:3, 0] @ frame[:3, 0]
                s = nominal[:3, 1] @ frame[:3, 0]
                out.append(float(np.arctan2(s, c)))
        return np.asarray(out)

    def with_defects(self, values: np.ndarray | dict) -> JointChainModel:
        """A new model whose frames are the nominal ones with ``values`` applied exactly (a
        vector in :attr:`defect_index` order, or a mapping name → value; absent names 0)."""
        delta = self._defect_vector(values)
        frames = apply_defects(self.nominal_frames, self.defect_index, delta)
        return _replace(self, frames=_frozen(frames), defects=_frozen(delta))

    def _defect_vector(self, values) -> np.ndarray:
        if isinstance(values, dict):
            delta = np.zeros(len(self.defect_index))
            for name, value in values.items():
                delta[self.defect_index.index(name)] = float(value)
            return delta
        delta = np.asarray(values, dtype=float).reshape(-1)
        if delta.shape != (len(self.defect_index),) or not np.isfinite(delta).all():
            raise ParameterError(f"defects must be {len(self.defect_index)} finite values, got "
                                 f"shape {delta.shape}")
        return delta


def _label(spec: ElementSpec) -> str:
    return spec.label if spec.label is not None else spec.name


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def _replace(model: JointChainModel, **changes) -> JointChainModel:
    from dataclasses import replace

    return replace(model, **changes)


def defect_layout(spec: ElementSpec, frame: np.ndarray) -> list[tuple[str, str, int]]:
    """The defects of one element as ``(name, kind, component)`` for its nominal ``frame``
    (components in the previous frame; see the module docstring)."""
    label = _label(spec)
    z = frame[:3, 2]
    major = int(np.argmax(np.abs(z)))
    others = [k for k in range(3) if k != major]
    out = [(f"d{_COMPONENTS[k]}{label}", "orientation", k) for k in others]
    if spec.type == FIXED:
        out.append((f"dS{label}", "spin", -1))
        out += [(f"d{_POINT[k].lower()}{label}", "position", k) for k in range(3)]
    elif spec.type == REVOLUTE:
        out += [(f"d{_POINT[k].lower()}{label}", "position", k) for k in others]
    return out


def axis_increment(z: np.ndarray, component: int) -> np.ndarray:
    """``∂z/∂d`` for the defect perturbing axis component ``component`` of the unit axis z:
    ``e_k − (z_k / z_m) e_m`` (m the largest component, renormalised) — orthogonal to z."""
    major = int(np.argmax(np.abs(z)))
    out = np.zeros(3)
    out[component] = 1.0
    out[major] -= z[component] / z[major]
    return out


def cached_defect_twists(model: JointChainModel) -> np.ndarray:
    """:func:`defect_twists` of the model's frames ``(6, d)``, computed once per (immutable)
    model and kept on it."""
    cached = model.__dict__.get("_local_defect_twists")
    if cached is None:
        cached = _frozen(defect_twists(model.frames, model.defect_index, model.nominal_frames,
                                       model.defects))  # kept on the (shared) model
        object.__setattr__(model, "_local_defect_twists", cached)
    return cached


def defect_twists(frames: np.ndarray, index: DefectIndex, nominal: np.ndarray | None = None,
                  delta: np.ndarray | None = None) -> np.ndarray:
    """First-order effect of each defect ``(d, 6)``: the twist (v, ω) in the previous frame by
    which it moves the element's frame (left increment ``D ← exp(ξ̂ δ) D``, linear part first).

    With the ``nominal`` frames and the current defects ``delta``, the twists are the exact
    derivatives of :func:`apply_defects` at ``delta`` (not only at zero): tilting an axis that
    is already tilted also spins the frame about it (the minimal rotation from the nominal axis
    has holonomy), and an existing spin defect turns the tilt."""
    out = np.zeros((len(index), 6))
    exact = nominal is not None and delta is not None
    spins: dict[int, float] = {}
    if exact:
        for j, (e, kind) in enumerate(zip(index.element, index.kind, strict=True)):
            if kind == "spin":
                spins[int(e)] = spins.get(int(e), 0.0) + float(delta[j])
    for i, (e, kind, k) in enumerate(zip(index.element, index.kind, index.component,
                                         strict=True)):
        frame = frames[e]
        z, o = frame[:3, 2], frame[:3, 3]
        if kind == "position":
            out[i, k] = 1.0
            continue
        if kind == "spin":
            omega = z.copy()
        else:
            dz = axis_increment(z, int(k))
            omega = _cross3(z, dz)
            if exact:
                z0 = nominal[e][:3, 2]
                # d(minimal rotation z0 → z) = z × dz + s z (its spin about z)
                omega = omega - (z0 @ omega) / (1.0 + z0 @ z) * z
                spin = spins.get(int(e), 0.0)
                if spin:
                    # R = exp(σ[z]×) M N: ω = J_l(σ z) σ dz + exp(σ[z]×) ω_M
                    omega = (left_jacobian(spin * z) @ (spin * dz)
                             + axis_rotation(z, np.asarray(spin)) @ omega)
        out[i, 3:] = omega
        out[i, :3] = _cross3(o, omega)  # rotation about the frame's point o
    return out


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` of two 3-vectors (``np.cross`` costs ~10 µs of argument handling)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def apply_defects(nominal: np.ndarray, index: DefectIndex, delta: np.ndarray) -> np.ndarray:
    """Frames ``(E, 4, 4)`` with the defects ``delta`` applied exactly (module docstring)."""
    frames = np.array(nominal, dtype=float)
    for e in np.unique(index.element):
        mine = np.flatnonzero(index.element == e)
        if not np.any(delta[mine]):
            continue
        frame = nominal[e]
        z0, o0 = frame[:3, 2], frame[:3, 3]
        major = int(np.argmax(np.abs(z0)))
        z = z0.copy()
        spin = 0.0
        o = o0.copy()
        for i in mine:
            kind, k, d = index.kind[i], int(index.component[i]), delta[i]
            if kind == "orientation":
                z[k] += d
            elif kind == "position":
                o[k] += d
            else:
                spin += d
        rest = 1.0 - sum(z[k] ** 2 for k in range(3) if k != major)
        if rest <= 0:
            raise ParameterError(f"orientation defects of element {e} tilt its axis by more than "
                                 "90°; defects must be small")
        z[major] = np.copysign(np.sqrt(rest), z0[major])
        rot = _minimal_rotation(z0, z) @ frame[:3, :3]
        if spin:
            rot = axis_rotation(z, np.asarray(spin)) @ rot
        frames[e, :3, :3] = rot
        frames[e, :3, 3] = o
    return frames


def minimal_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation ``(3, 3)`` of least angle taking unit vector a to unit vector b."""
    return _minimal_rotation(a, b)


def _minimal_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation of least angle taking unit vector a to unit vector b."""
    axis = _cross3(a, b)
    s = float(np.sqrt(axis @ axis))
    c = float(a @ b)
    if s < 1e-15:
        return np.eye(3)
    k = skew(axis / s)
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _element_frame(spec: ElementSpec) -> np.ndarray:
    """The nominal ``(4, 4)`` invariant frame of one element, its type and stroke checked."""
    if spec.type not in ELEMENT_TYPES:
        raise ParameterError(f"element {spec.name!r}: type must be one of "
                             f"{', '.join(ELEMENT_TYPES)}, got {spec.type!r}", spec.name)
    try:
        frame = invariant_frame(spec.axis, spec.point, spec.spin)
    except ParameterError as exc:
        raise ParameterError(f"element {spec.name!r}: {exc}", spec.name) from None
    if spec.rotation is not None:
        from pkmkit.spatial.rotation import as_rotation_matrices

        frame[:3, :3] = as_rotation_matrices(spec.rotation, f"element {spec.name!r} "
                                             "rotation")[0]
    lo, hi = (float(v) for v in spec.stroke)
    if np.isnan(lo) or np.isnan(hi) or not lo < hi:
        raise ParameterError(f"element {spec.name!r}: stroke must be (min, max) with "
                             f"min < max, got {spec.stroke}", spec.name)
    return frame


def _chain_indices(by_name: dict[str, int], legs: Sequence[Sequence[str]],
                   leg_names: list[str], head: Sequence[str]) -> tuple[list[tuple], tuple]:
    """Element indices of each leg and of the head; unknown names and empty legs raise."""
    if len(leg_names) != len(legs):
        raise ParameterError(f"{len(legs)} legs but {len(leg_names)} leg names")
    chains = []
    for leg, chain in zip(leg_names, legs, strict=True):
        if not chain:
            raise ParameterError(f"{leg} has no element", leg)
        for name in chain:
            if name not in by_name:
                raise ParameterError(f"{leg}: unknown element {name!r}", leg)
        chains.append(tuple(by_name[n] for n in chain))
    for name in head:
        if name not in by_name:
            raise ParameterError(f"head: unknown element {name!r}", "head")
    return chains, tuple(by_name[n] for n in head)


def _defect_index(elements: Sequence[ElementSpec], nominal: np.ndarray) -> DefectIndex:
    """The defects of every element (:func:`defect_layout`) as one :class:`DefectIndex`."""
    rows = []
    for e, spec in enumerate(elements):
        rows += [(name, kind, k, e) for name, kind, k in defect_layout(spec, nominal[e])]
    return DefectIndex(
        names=tuple(r[0] for r in rows),
        units=tuple("m" if r[1] == "position" else ("rad" if r[1] == "spin" else "1")
                    for r in rows),
        element=_frozen(np.array([r[3] for r in rows], dtype=int)),
        kind=tuple(r[1] for r in rows),
        component=_frozen(np.array([r[2] for r in rows], dtype=int)),
    )


def build_chain_model(
    elements: Sequence[ElementSpec],
    legs: Sequence[Sequence[str]],
    *,
    leg_names: Sequence[str] | None = None,
    head: Sequence[str] = (),
    characteristic_length: float = 0.5,
) -> JointChainModel:
    """Validate element and chain descriptions and build a :class:`JointChainModel`.

    Args:
        elements: every element once (shared joints, such as the TriMule's ψ1, appear once and
            are named in several legs).
        legs: each leg as the names of its elements from the base to the platform frame.
        leg_names: names of the legs (default ``"leg 1"``, …).
        head: element names from the platform frame to the tool frame.
        characteristic_length: rotation-residual scale of the closures (m, > 0).

    Raises:
        ParameterError: duplicate or unknown element names, an unknown type, a bad axis, a leg
            with no element, no actuated joint, naming what and where.
    """
    names = [e.name for e in elements]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ParameterError(f"element names must be unique; repeated: {', '.join(dup)}")
    by_name = {n: i for i, n in enumerate(names)}
    frames = [_element_frame(spec) for spec in elements]
    leg_names = list(leg_names) if leg_names is not None else [f"leg {i + 1}"
                                                               for i in range(len(legs))]
    chains, head_idx = _chain_indices(by_name, legs, leg_names, head)
    used = {e for c in chains for e in c} | set(head_idx)
    unused = [names[e] for e in range(len(elements)) if e not in used]
    if unused:
        raise ParameterError(f"elements used by no leg or head: {', '.join(unused)}")
    order = [e for e in range(len(elements)) if elements[e].type != FIXED]
    variables = tuple(elements[e].name for e in order)
    element_variable = np.full(len(elements), -1)
    element_variable[order] = np.arange(len(order))
    actuated = np.array([elements[e].actuated for e in order], dtype=bool)
    if not actuated.any():
        raise ParameterError("a joint-chain machine needs at least one actuated joint")
    if not (np.isfinite(characteristic_length) and characteristic_length > 0):
        raise ParameterError("characteristic_length must be > 0", "characteristic_length")
    nominal = np.array(frames)
    index = _defect_index(elements, nominal)
    if len(set(index.names)) != len(index.names):
        raise ParameterError("defect names collide: give elements distinct labels")
    return JointChainModel(
        elements=tuple(elements),
        frames=_frozen(nominal.copy()),
        nominal_frames=_frozen(nominal),
        defects=_frozen(np.zeros(len(index))),
        legs=tuple(chains),
        leg_names=tuple(leg_names),
        head=head_idx,
        variables=variables,
        actuated=_frozen(actuated),
        home=_frozen(np.array([elements[e].home for e in order], dtype=float)),
        q_min=_frozen(np.array([elements[e].stroke[0] for e in order], dtype=float)),
        q_max=_frozen(np.array([elements[e].stroke[1] for e in order], dtype=float)),
        characteristic_length=float(characteristic_length),
        defect_index=index,
        element_variable=_frozen(element_variable),
    )
