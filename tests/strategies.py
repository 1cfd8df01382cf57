"""Hypothesis strategies for random machines of every kind, and helpers to test them.

- :func:`linear_deltas`, :func:`orthoglides`, :func:`five_bars`: the built-in kinds with random
  dimensions (both five-bar families: crossing slides and parallel "biglide" slides);
- :func:`rod_leg_specs`: random ``rod-legs`` machine files — slide legs (single rods or
  parallelograms) and actuated struts, planar and spatial — built around a reachable,
  well-conditioned home pose; :func:`rod_legs_toml` writes one as a machine file (in m or mm,
  optionally moved by a rigid motion) and :func:`load_text` loads it through ``pkmkit.load``;
- :data:`FAMILIES`: the above by name (tests parametrize over them); :func:`machines`: any.

Every strategy draws only machines whose home configuration is reachable and away from
singularities; tests then draw poses near home with :func:`near_home`. How many examples run is
the settings profile's business (``tests/conftest.py``: ``dev`` locally, ``ci`` in CI).
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass, field

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st

import pkmkit

unit_floats = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def linear_deltas(draw):
    """Vertical-slide linear Deltas: R, r, L and the three slide angles at random."""
    big_r = draw(st.floats(0.3, 1.0))
    small_r = draw(st.floats(0.05, 0.25))
    length = big_r - small_r + draw(st.floats(0.3, 1.0))
    a1 = draw(st.floats(80.0, 160.0))
    a2 = a1 + draw(st.floats(80.0, 160.0))
    assume(360.0 - a2 > 60.0)
    return pkmkit.machine("linear-delta", R=big_r, r=small_r, L=length,
                          angles=tuple(np.radians([0.0, a1, a2])),
                          parallelogram_width=draw(st.floats(0.0, 0.15)))


@st.composite
def orthoglides(draw):
    """Orthoglides of random leg length (and parallelogram width)."""
    length = draw(st.floats(0.1, 1.5))
    return pkmkit.machine("orthoglide", L=length,
                          parallelogram_width=draw(st.floats(0.0, 0.3)) * length,
                          q_min=(-10.0,) * 3, q_max=(10.0,) * 3)


@st.composite
def five_bars(draw):
    """Five-bars with crossing slides (random directions, A, B, L) or parallel slides."""
    length = draw(st.floats(0.2, 1.5))
    a = (draw(st.floats(-0.5, 0.5)), draw(st.floats(-0.5, 0.5)))
    alpha1 = draw(st.floats(-60.0, 60.0))
    if draw(st.booleans()):  # crossing slides
        alpha2 = alpha1 + draw(st.floats(25.0, 155.0))
        b = (a[0] + draw(st.floats(0.5, 1.5)) * length, a[1] - draw(st.floats(0.5, 1.5)) * length)
    else:  # biglide: parallel slides, legs at 45° at home
        alpha2 = alpha1
        gap = draw(st.floats(1.0, 2.0)) * length
        b = (a[0] + gap * math.cos(math.radians(alpha1)),
             a[1] + gap * math.sin(math.radians(alpha1)))
    return pkmkit.machine("five-bar", A=a, B=b, alpha1=math.radians(alpha1),
                          alpha2=math.radians(alpha2), L=length,
                          q_min=(-10.0, -10.0), q_max=(10.0, 10.0))


def _unit(v):
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


@dataclass
class LegDraw:
    kind: str
    base: np.ndarray
    axis: np.ndarray | None
    platform: np.ndarray
    length: float
    branch: int
    width: float = 0.0
    direction: np.ndarray | None = None


@dataclass
class RodLegSpec:
    """A random rod-legs machine, in metres, around its home pose."""

    dims: int
    home: np.ndarray
    legs: list[LegDraw] = field(default_factory=list)
    mode_names: tuple[str, str] = ("det(A)<0", "det(A)>0")


@st.composite
def rod_leg_specs(draw, dims=None, kinds=("slide", "strut")):
    """Random rod-legs machines: per leg a rod direction at home, a rod length, a platform
    offset, and for a slide an axis making at least 25° with the rod (no serial singularity) or
    for a strut an extension; rod directions well spread (no parallel singularity at home)."""
    dims = draw(st.sampled_from([2, 3])) if dims is None else dims
    n = dims
    scale = draw(st.floats(0.2, 2.0))
    home = np.zeros(3)
    home[:dims] = [draw(unit_floats) * scale for _ in range(dims)]
    rods = np.array([_unit([draw(unit_floats) for _ in range(dims)] + [0.0] * (3 - dims))
                     for _ in range(n)])
    assume(np.isfinite(rods).all() and (np.linalg.norm(rods, axis=1) > 0.5).all())
    # well spread: |det| of the unit rod directions
    with np.errstate(all="ignore"):
        spread = abs(np.linalg.det(rods[:, :dims]))
    assume(spread > 0.3)
    spec = RodLegSpec(dims=dims, home=home[:dims])
    for i in range(n):
        kind = draw(st.sampled_from(kinds))
        length = scale * draw(st.floats(0.5, 1.5))
        platform = np.zeros(3)
        platform[:dims] = [0.2 * scale * draw(unit_floats) for _ in range(dims)]
        joint = home + platform  # platform joint at home
        if kind == "slide":
            # the slide axis within 60° of the rod (either way): no serial singularity
            w = np.array([draw(unit_floats) for _ in range(dims)] + [0.0] * (3 - dims))
            w_perp = w - (w @ rods[i]) * rods[i]
            assume(np.linalg.norm(w_perp) > 1e-3)
            tilt = math.radians(draw(st.floats(0.0, 60.0)))
            axis = _unit(draw(st.sampled_from([1.0, -1.0])) * math.cos(tilt) * rods[i]
                         + math.sin(tilt) * _unit(w_perp))
            carriage = joint - length * rods[i]
            q0 = scale * draw(unit_floats)
            base = carriage - q0 * axis
            branch = -1 if (rods[i] @ axis) > 0 else 1
            width = draw(st.sampled_from([0.0, 0.0, 0.1 * scale]))
            direction = None
            if width and dims == 3:
                cross = np.cross(rods[i], axis)
                direction = _unit(cross if np.linalg.norm(cross) > 1e-6 else w_perp)
            elif width:
                direction = np.array([-rods[i][1], rods[i][0], 0.0])
            spec.legs.append(LegDraw("slide", base, axis, platform, length, branch, width,
                                     direction))
        else:
            extension = scale * draw(st.floats(0.0, 0.4))
            base = joint - (length + extension) * rods[i]
            spec.legs.append(LegDraw("strut", base, None, platform, length, 1))
    return spec


def _fmt(v, scale=1.0, dims=3):
    return "[" + ", ".join(repr(float(c) * scale) for c in np.asarray(v)[:dims]) + "]"


def rod_legs_toml(spec: RodLegSpec, units: str = "m", rotation=None, translation=None) -> str:
    """The machine file of ``spec``; lengths written in ``units``; the whole machine (base,
    axes, platform offsets, home) optionally moved by a rotation matrix and a translation."""
    dims = spec.dims
    rot = np.eye(3) if rotation is None else np.asarray(rotation)
    shift = np.zeros(3) if translation is None else np.asarray(translation)
    s = 1000.0 if units == "mm" else 1.0

    def point(p):
        return rot @ np.append(p, [0.0] * (3 - len(p))) + shift

    home = point(spec.home)
    lines = ["[machine]", 'kind = "rod-legs"', f'units = "{units}"', f"dims = {dims}",
             f"home = {_fmt(home, s, dims)}",
             f'mode_names = ["{spec.mode_names[0]}", "{spec.mode_names[1]}"]']
    for leg in spec.legs:
        lines += ["[[legs]]", f'type = "{leg.kind}"', f"base = {_fmt(point(leg.base), s, dims)}",
                  f"platform = {_fmt(rot @ leg.platform, s, dims)}",
                  f"length = {leg.length * s!r}"]
        if leg.kind == "slide":
            lines += [f"axis = {_fmt(rot @ leg.axis, 1.0, dims)}", f"branch = {leg.branch}"]
            if leg.width:
                lines.append(f"parallelogram = {{ width = {leg.width * s!r}, direction = "
                             f"{_fmt(rot @ leg.direction, 1.0, dims)} }}")
    return "\n".join(lines) + "\n"


def load_text(text: str, suffix: str = ".toml") -> pkmkit.Machine:
    """``pkmkit.load`` of a machine file written to a temporary file."""
    handle, path = tempfile.mkstemp(suffix=suffix, prefix="random-machine-")
    try:
        with os.fdopen(handle, "w") as f:
            f.write(text)
        return pkmkit.load(path)
    finally:
        os.unlink(path)


@st.composite
def rod_leg_machines(draw, dims=None, kinds=("slide", "strut")):
    """Random rod-legs machines loaded from their machine file."""
    spec = draw(rod_leg_specs(dims=dims, kinds=kinds))
    try:
        m = load_text(rod_legs_toml(spec))
    except pkmkit.PkmError:
        assume(False)  # e.g. rods that let the platform turn: refused or warned about
        raise
    return m


#: Machine families, each a strategy; property tests are parametrized over them so that every
#: family gets the profile's number of examples (a single ``one_of`` draws some rarely).
FAMILIES = {
    "linear-delta": linear_deltas(),
    "orthoglide": orthoglides(),
    "five-bar": five_bars(),
    "rod-legs slides": rod_leg_machines(kinds=("slide",)),
    "rod-legs struts": rod_leg_machines(kinds=("strut",)),
    "rod-legs mixed": rod_leg_machines(),
}


def machines():
    """Any machine: a built-in kind with random dimensions or a random machine file."""
    return st.one_of(*FAMILIES.values())


def near_home(draw, m: pkmkit.Machine, fraction: float = 0.15) -> np.ndarray:
    """A pose within ``fraction`` × (shortest rod) of home (each coordinate)."""
    h = fraction * float(m.model.leg_length.min())
    return m.home_pose + np.array([draw(unit_floats) * h for _ in range(m.dims)])


def well_posed(m: pkmkit.Machine, x: np.ndarray, kappa_max: float = 1e3) -> bool:
    """x reachable, regular and not badly conditioned (so finite differences are meaningful)."""
    try:
        jac = m.jacobian(x)
    except pkmkit.PkmError:  # a single pose out of reach or singular raises
        return False
    return bool(jac.reachable and jac.status == "regular" and np.isfinite(jac.condition)
                and jac.condition < kappa_max and jac.serial_measure > 0.05
                and jac.parallel_measure > 0.05)
