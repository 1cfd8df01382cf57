"""A Verne-type module: three vertical slides carrying six constant-length rods, two per slide,
whose platform tilts with its position (seed 003; Fatronik/IRCCyN Verne family).

The seed describes the machine's structure — a parallel module of **six legs of constant length
joined two by two to three vertical slides**, spindle inclined 30° — but gives no dimension, so
this model's numbers are illustrative, chosen to give a machine-tool-like module (condition
number ≈ 3.5 and tilt ≤ 4° over a 400 mm cube; see docs/full-pose.md):

- the three slides stand on a circle of radius ``R`` at the angles ``angles`` (90°, 210°, 330°),
  vertical (z up); carriage k carries two rod joints spaced horizontally and tangentially to the
  circle, at the carriage height q_k;
- the platform's rod joints lie on a circle of radius ``r`` in the plane ``joint_height`` above
  the tool point (the platform frame's origin, where poses are given), in pairs at the same
  angles;
- legs 2 and 3 are **parallelograms** (carriage and platform spacings both ``width``); leg 1 is
  a **trapezoid**: its rods are ``carriage_width_1`` apart on the carriage and
  ``platform_width_1`` apart on the platform. Each parallelogram fixes one rotation of the
  platform, and leg 1's unequal spacings couple the third to the position: the platform tilts
  as it moves sideways. By symmetry the tilt is exactly zero in the plane x = 0 (through slide 1
  and the machine's axis) and nowhere else.

Actuator coordinates q_k are the carriage heights (m) above the plane z = 0 of the slides'
origins. The machine has three degrees of freedom: :meth:`~FullPoseMachine.ik` takes tool-point
positions ``(N, 3)`` (and returns the tilt it implies) or full poses it checks for consistency.
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
    ParameterSpec("R", "length", 0.6, "radius of the circle of the three vertical slides",
                  positive=True),
    ParameterSpec("r", "length", 0.2, "radius of the platform joint pairs' circle", positive=True),
    ParameterSpec("L", "length", 1.0, "length of the six rods", positive=True),
    ParameterSpec("angles", "angle", tuple(math.radians(a) for a in (90.0, 210.0, 330.0)),
                  "angular positions of the three slides (slide 1 carries the trapezoid leg)",
                  size=3),
    ParameterSpec("joint_height", "length", 0.25,
                  "height of the platform's rod joints above the tool point"),
    ParameterSpec("width", "length", 0.2, "spacing of the rods of the parallelogram legs 2 and 3",
                  positive=True),
    ParameterSpec("carriage_width_1", "length", 0.3, "spacing of leg 1's rods on its carriage",
                  positive=True),
    ParameterSpec("platform_width_1", "length", 0.24, "spacing of leg 1's rods on the platform",
                  positive=True),
    ParameterSpec("q_min", "length", (0.6, 0.6, 0.6), "lower stroke limit of each carriage",
                  size=3),
    ParameterSpec("q_max", "length", (1.6, 1.6, 1.6), "upper stroke limit of each carriage",
                  size=3),
)


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of the Verne-type module (home: tool point at the origin, untilted)."""
    theta = np.asarray(params["angles"], dtype=float)
    radial = np.column_stack([np.cos(theta), np.sin(theta), np.zeros(3)])
    tangent = np.column_stack([-np.sin(theta), np.cos(theta), np.zeros(3)])
    if abs(np.linalg.det(np.column_stack([radial[:, :2], np.ones(3)]))) < 1e-9:
        raise ParameterError("the three slide angles must be distinct (mod 360°)", "angles")
    if math.isclose(params["carriage_width_1"], params["platform_width_1"]):
        raise ParameterError(
            "leg 1 with equal carriage and platform widths is a third parallelogram: the "
            "platform would only translate (and its rotation would be over-constrained); make "
            "the widths differ", "platform_width_1")
    lift = np.array([0.0, 0.0, params["joint_height"]])
    legs = []
    half = [(0.5 * params["carriage_width_1"], 0.5 * params["platform_width_1"]),
            (0.5 * params["width"], 0.5 * params["width"]),
            (0.5 * params["width"], 0.5 * params["width"])]
    for k in range(3):
        carriage_half, platform_half = half[k]
        for rod, sign in enumerate((-1.0, 1.0)):
            legs.append(LegSpec(
                name=f"leg {k + 1} rod {rod + 1}", actuator=k, kind="slide",
                base=params["R"] * radial[k] + sign * carriage_half * tangent[k],
                platform=params["r"] * radial[k] + sign * platform_half * tangent[k] + lift,
                length=params["L"], axis=(0.0, 0.0, 1.0), branch=1,
                stroke=(params["q_min"][k], params["q_max"][k])))
    return build_rod_model(legs, dims=6, actuator_names=("q1", "q2", "q3"),
                           home_pose=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0))


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """A position off the symmetry plane (the platform tilts there); positions only — the
    orientation follows from the rods."""
    return {"offset": np.array([0.15, 0.1, -0.1])}


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """A cube of side 0.4 × the rod length centred on the home tool point."""
    half = 0.2 * params["L"]
    return np.full(3, -half), np.full(3, half)


KIND = MachineKind(
    kind="verne",
    title="Verne-type module (3 vertical slides, 6 rods, coupled tilt)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="seed 003 (Chanal et al. 2007): structure; dimensions chosen for illustration",
)
