"""Planar five-bar with two prismatic actuators (seed 004, Chablat, Wenger & Angeles 2000).

Slide i starts at point A (i = 1) or B (i = 2) and moves its carriage along the direction
α_i: ``C = A + ρ1 (cos α1, sin α1)``, ``D = B + ρ2 (cos α2, sin α2)``. Two legs of length L join C
and D to the tool point P (each leg is a parallelogram, which keeps the tool orientation). With
A rows ``(p − c)ᵀ, (p − d)ᵀ`` and ``B = diag((p − c)·u1, (p − d)·u2)``: ``A ṗ = B ρ̇``.

Home configuration (the reference of the working mode), derived from the parameters:

- slides not parallel: P at the intersection of the two slide lines with each leg along its slide
  (C = P − L u1, D = P − L u2). For α1 = 0, α2 = 90° this is the isotropic configuration of seed
  004 where J⁻¹ = I; with A = (0, 0), B = (M, −M) it has ρ1 = ρ2 = M − L.
- parallel slides (biglide): P = (A + B)/2 + (L/√2) n with n = u rotated by −90°, i.e. both legs
  at 45° to the slides (κ(A) = 1).

The two assembly modes are P to the left or to the right of the directed line C→D
(det A = (D − C) × (P − C)).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.machines.machine import MachineKind
from pkmkit.model.parameters import ParameterSpec
from pkmkit.model.rods import LegSpec, RodModel, build_rod_model

PARAMETERS = (
    ParameterSpec("A", "length", (0.0, 0.0), "origin of slide 1 (x, y)", size=2),
    ParameterSpec("B", "length", (1.0, -1.0), "origin of slide 2 (x, y)", size=2),
    ParameterSpec("alpha1", "angle", 0.0, "direction of slide 1 from the x axis"),
    ParameterSpec("alpha2", "angle", math.pi / 2, "direction of slide 2 from the x axis"),
    ParameterSpec("L", "length", 0.5, "leg length L1 = L2", positive=True),
    ParameterSpec(
        "parallelogram_width",
        "length",
        0.05,
        "distance between the two rods of each parallelogram (rod model only)",
    ),
    ParameterSpec("q_min", "length", (-1.0, -1.0), "lower stroke limit of each actuator",
                  size=2),
    ParameterSpec("q_max", "length", (1.0, 1.0), "upper stroke limit of each actuator",
                  size=2),
)


#: |sin(α2 − α1)| below which (but not zero) the slides count as nearly parallel.
NEARLY_PARALLEL = 1e-3


def _cross(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def home_configuration(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Home tool point P and carriage points C, D, each ``(2,)`` m (see the module docstring)."""
    a, b = np.asarray(params["A"]), np.asarray(params["B"])
    u1 = np.array([math.cos(params["alpha1"]), math.sin(params["alpha1"])])
    u2 = np.array([math.cos(params["alpha2"]), math.sin(params["alpha2"])])
    length = params["L"]
    denom = _cross(u1, u2)
    if abs(denom) > 1e-9:
        if abs(denom) < NEARLY_PARALLEL:
            raise ParameterError(
                f"the slides are nearly parallel ({math.degrees(math.asin(abs(denom))):.3g}°): "
                "the home configuration (where the slide lines cross) would be "
                f"{abs(_cross(b - a, u2) / denom):.3g} m away; make them parallel "
                "(alpha1 = alpha2) or increase the angle",
                "alpha2",
            )
        s = _cross(b - a, u2) / denom
        p = a + s * u1
        return p, p - length * u1, p - length * u2
    normal = np.array([u1[1], -u1[0]])
    middle = 0.5 * (a + b)
    p = middle + length / math.sqrt(2.0) * normal
    half = length / math.sqrt(2.0) * u1
    c, d = (middle - half, middle + half) if np.dot(b - a, u1) >= 0 else (
        middle + half, middle - half)
    return p, c, d


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of the five-bar from A, B (m), α1, α2 (rad), L (m)."""
    p, c, d = home_configuration(params)
    if np.allclose(c, d):
        raise ParameterError("the home carriages coincide; move A or B apart", "B")
    legs = []
    for i, (origin, alpha, carriage) in enumerate(
        ((params["A"], params["alpha1"], c), (params["B"], params["alpha2"], d))
    ):
        u = np.array([math.cos(alpha), math.sin(alpha), 0.0])
        leg_dir = np.append(p - carriage, 0.0)
        branch = -1 if np.dot(leg_dir, u) > 0 else 1
        legs.append(
            LegSpec(
                name=f"leg {i + 1}",
                actuator=i,
                kind="slide",
                base=(origin[0], origin[1], 0.0),
                axis=u,
                platform=(0.0, 0.0, 0.0),
                length=params["L"],
                branch=branch,
                parallelogram_width=params["parallelogram_width"],
                stroke=(params["q_min"][i], params["q_max"][i]),
            parallelogram_direction=(-leg_dir[1], leg_dir[0], 0.0),
            )
        )
    return build_rod_model(
        legs,
        dims=2,
        actuator_names=("rho1", "rho2"),
        home_pose=p,
        mode_names=("right-of-CD", "left-of-CD"),
    )


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """Two poses offset from home by ±L/5 along x and y."""
    s = params["L"] / 5
    home = model.home_pose
    return {"offset+": home + np.array([s, s]), "offset-": home - np.array([s, -s])}


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """Square of half-side 1.2 L about the home pose."""
    half = 1.2 * params["L"]
    return model.home_pose - half, model.home_pose + half


KIND = MachineKind(
    kind="five-bar",
    title="Planar five-bar with two prismatic actuators (biglide / isotropic)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="seed 004 (Chablat, Wenger, Angeles 2000), §1.3–2.5",
)
