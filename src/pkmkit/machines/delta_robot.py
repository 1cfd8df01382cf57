"""The Clavel Delta robot: three rotary actuators, parallelogram forearms, translating effector.

Motor i sits on the base circle of radius R at the angle θ_i; its axis is the tangent
``w_i = (−sin θ_i, cos θ_i, 0)`` and its arm (length ``arm``) lies in the vertical radial plane.
The actuator coordinate q_i is the **arm angle below the horizontal** (radians inside, degrees at
the command line; q = 0: arm horizontal and pointing outwards, q > 0: arm tip lower), so the arm
tip is

    a_i(q) = (R + arm cos q_i) e_r,i − arm sin q_i e_z,        e_r,i = (cos θ_i, sin θ_i, 0).

A parallelogram of two rods of length ``forearm`` (spaced ``parallelogram_width`` along the motor
axis) joins it to the effector joint ``p + r e_r,i``; the parallelograms keep the effector
parallel to the base, so the pose is its position p = (x, y, z) (z up: the effector hangs below
the base, z < 0). The closure of leg i is the sphere ``|p + r e_r,i − a_i(q)| = forearm``; the
inverse model gives two arm angles per leg (knee out, the working branch, or knee in) and the
direct model two assembly modes (effector below or above the plane of the three arm-tip
centres). See :mod:`pkmkit.machines.closed_form` for the crank formulas.

Dimensions: the defaults are a plausible mid-size pick-and-place robot (R = 200 mm, r = 45 mm,
arms 350 mm, forearms 800 mm), not a particular product.
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
    ParameterSpec("R", "length", 0.2, "radius of the circle of the three motor axes (base)",
                  positive=True),
    ParameterSpec("r", "length", 0.045, "radius of the effector joint circle", positive=True),
    ParameterSpec("arm", "length", 0.35, "upper-arm length (motor axis to elbow)", positive=True),
    ParameterSpec("forearm", "length", 0.8, "forearm (parallelogram rod) length", positive=True),
    ParameterSpec("angles", "angle", tuple(math.radians(a) for a in (90.0, 210.0, 330.0)),
                  "angular positions of the three motors around the base", size=3),
    ParameterSpec("parallelogram_width", "length", 0.06,
                  "spacing of the two rods of each forearm parallelogram"),
    ParameterSpec("home_angle", "angle", math.radians(30.0),
                  "arm angle below the horizontal of the home configuration (all arms equal)"),
    ParameterSpec("q_min", "angle", tuple(math.radians(-40.0) for _ in range(3)),
                  "lower limit of each arm angle", size=3),
    ParameterSpec("q_max", "angle", tuple(math.radians(95.0) for _ in range(3)),
                  "upper limit of each arm angle", size=3),
)


def symmetric_height(params: Mapping[str, Any], angle: float) -> float:
    """Height z (m, negative below the base) of the effector on the axis x = y = 0 when every
    arm is at ``angle`` below the horizontal (the symmetric closed form):
    ``z = −arm sin q − sqrt(forearm² − (R − r + arm cos q)²)``; NaN when out of reach."""
    gap = params["R"] - params["r"] + params["arm"] * math.cos(angle)
    root = params["forearm"] ** 2 - gap * gap
    if root < 0:
        return math.nan
    return -params["arm"] * math.sin(angle) - math.sqrt(root)


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of a Delta robot from R, r, arm, forearm (m) and motor angles (rad)."""
    big_r, small_r = params["R"], params["r"]
    arm, forearm = params["arm"], params["forearm"]
    theta = np.asarray(params["angles"], dtype=float)
    radial = np.column_stack([np.cos(theta), np.sin(theta), np.zeros(3)])
    orientation = np.linalg.det(np.column_stack([radial[:, :2], np.ones(3)]))
    if abs(orientation) < 1e-9:
        raise ParameterError("the three motor angles must be distinct (mod 360°)", "angles")
    home_z = symmetric_height(params, params["home_angle"])
    if not math.isfinite(home_z):
        raise ParameterError(
            f"the forearm ({forearm:.6g} m) cannot reach the effector with the arms at the home "
            "angle: R − r + arm·cos(home_angle) exceeds it", "forearm")
    tangent = np.column_stack([-np.sin(theta), np.cos(theta), np.zeros(3)])
    lo, hi = params["q_min"], params["q_max"]
    legs = [
        LegSpec(
            name=f"leg {i + 1}",
            actuator=i,
            kind="crank",
            pivot=big_r * radial[i],
            axis=tangent[i],
            base=(big_r + arm) * radial[i],
            platform=small_r * radial[i],
            length=forearm,
            branch=1,
            parallelogram_width=params["parallelogram_width"],
            parallelogram_direction=tangent[i],
            stroke=(lo[i], hi[i]),
        )
        for i in range(3)
    ]
    # knee-out branch: at home the elbow is outside the effector joint; the branch is
    # −sign(d·∂a/∂q) there (d from the elbow to the effector joint)
    q_home = params["home_angle"]
    elbow = (big_r + arm * math.cos(q_home)) * radial - arm * math.sin(q_home) * np.array(
        [0.0, 0.0, 1.0])
    joint = small_r * radial + np.array([0.0, 0.0, home_z])
    rate = arm * (-math.sin(q_home) * radial - math.cos(q_home) * np.array([0.0, 0.0, 1.0]))
    branches = -np.sign(np.einsum("id,id->i", joint - elbow, rate)).astype(int)
    legs = [LegSpec(**{**leg.__dict__, "branch": int(b)}) for leg, b in zip(legs, branches,
                                                                             strict=True)]
    below_above = ("effector-below", "effector-above")
    names = below_above if orientation > 0 else below_above[::-1]
    return build_rod_model(legs, dims=3, actuator_names=("q1", "q2", "q3"),
                           home_pose=(0.0, 0.0, home_z), mode_names=names)


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """A pose off the axis, 40 % of the forearm length lower than the base circle's centre."""
    z = model.home_pose[2]
    reach = 0.25 * params["forearm"]
    return {"offset": np.array([reach, 0.5 * reach, z - 0.1 * params["forearm"]])}


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """|x|, |y| ≤ 0.7 forearm, and from the base plane down to arm + forearm below it."""
    reach = 0.7 * params["forearm"]
    return (np.array([-reach, -reach, -(params["arm"] + params["forearm"])]),
            np.array([reach, reach, 0.0]))


KIND = MachineKind(
    kind="delta",
    title="Delta robot (3-R(SS)2, rotary actuators)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="Clavel (1988) Delta robot; dimensions chosen for illustration",
)
