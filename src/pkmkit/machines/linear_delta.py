"""Linear Delta with vertical slides (seed 000, Bourebbou 2019, Ch. III–IV).

Three vertical slides on a circle of radius R at angles θ_i; the carriage of slide i is at
``(R cos θ_i, R sin θ_i, q_i)``; a parallelogram of two rods of length L joins it to the nacelle
joint ``p + (r cos θ_i, r sin θ_i, 0)``. With d = R − r the closure is

    (x − d cos θ_i)² + (y − d sin θ_i)² + (z − q_i)² = L²,
    q_i = z + sqrt(L² − (x − d cos θ_i)² − (y − d sin θ_i)²)   (carriages above the nacelle, z up)

(the seed's printed (III.2)–(III.5) carry sign errors; see docs/seed-errata.md). Only
d = R − r enters the kinematics. The two assembly
modes are the nacelle below or above the plane of the three carriage joints. The parallelogram
rods are offset tangentially by ± half the pair spacing, which the thesis never gives (a
parameter here).

**Delta firmware dimensions.** LinuxCNC (``lineardeltakins``), Klipper, RepRapFirmware and Marlin
describe the machine by its *effective* radius — Klipper's ``delta_radius`` = smooth-rod offset −
effector offset − carriage offset, RepRapFirmware's ``M665 R``, Marlin's ``DELTA_RADIUS`` — and
the diagonal rod length (``arm_length``, ``M665 L``, ``DELTA_DIAGONAL_ROD``). That is this model
with ``r = 0`` and ``R`` = the effective radius: ``--set R=<delta_radius> --set r=0 --set
L=<arm_length>`` gives the same inverse and direct models, Jacobians and rods as any (R, r) with
the same R − r. Tower angles may be given in any order and at any positions (Klipper's default
210°, 330°, 90°; a firmware's angle corrections added to them); actuator i is the slide at the
i-th angle.
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
    ParameterSpec("R", "length", 0.7, "radius of the circle of the three slides", positive=True),
    ParameterSpec("r", "length", 0.15,
                  "radius of the nacelle joint circle (0: R is the firmware's effective radius)"),
    ParameterSpec("L", "length", 1.3, "rod (arm) length", positive=True),
    ParameterSpec(
        "angles",
        "angle",
        tuple(math.radians(a) for a in (0.0, 120.0, 240.0)),
        "angular positions of the three slides",
        size=3,
    ),
    ParameterSpec(
        "parallelogram_width",
        "length",
        0.1,
        "spacing of the two rods of each parallelogram (not given by the seed; rod model only)",
    ),
    ParameterSpec("q_min", "length", (0.7, 0.7, 0.7), "lower stroke limit of each actuator",
                  size=3),
    ParameterSpec("q_max", "length", (2.0, 2.0, 2.0), "upper stroke limit of each actuator",
                  size=3),
)


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of a vertical-slide linear Delta from R, r, L (m) and slide angles (rad)."""
    big_r, small_r, length = params["R"], params["r"], params["L"]
    if small_r < 0:
        raise ParameterError(
            f"r = {small_r:.6g} m: the nacelle joint radius must be >= 0 (give r = 0 and R = "
            "the effective radius R - r, as delta firmware does)", "r")
    theta = np.asarray(params["angles"], dtype=float)
    radial = np.column_stack([np.cos(theta), np.sin(theta), np.zeros(3)])
    orientation = np.linalg.det(np.column_stack([radial[:, :2], np.ones(3)]))
    if abs(orientation) < 1e-9:
        raise ParameterError("the three slide angles must be distinct (mod 360°)", "angles")
    if big_r - small_r >= length:
        raise ParameterError(
            f"R − r = {big_r - small_r:.6g} m must be smaller than L = {length:.6g} m, otherwise "
            "no pose below the slides is reachable",
            "L",
        )
    tangent = np.column_stack([-np.sin(theta), np.cos(theta), np.zeros(3)])
    legs = [
        LegSpec(
            name=f"leg {i + 1}",
            actuator=i,
            kind="slide",
            base=big_r * radial[i],
            axis=(0.0, 0.0, 1.0),
            platform=small_r * radial[i],
            length=length,
            branch=1,
            parallelogram_width=params["parallelogram_width"],
            stroke=(params["q_min"][i], params["q_max"][i]),
            parallelogram_direction=tangent[i],
        )
        for i in range(3)
    ]
    # det A = −(distance below the carriage plane) × orientation of the slide triangle
    below_above = ("nacelle-below", "nacelle-above")
    names = below_above if orientation > 0 else below_above[::-1]
    return build_rod_model(
        legs,
        dims=3,
        actuator_names=("q1", "q2", "q3"),
        home_pose=(0.0, 0.0, 0.0),
        mode_names=names,
    )


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """Corners of the seed's Table III.2 cube (x, y = ±0.25 m, z = 0 and 0.5 m)."""
    return {
        "corner(+,+,0)": np.array([0.25, 0.25, 0.0]),
        "corner(-,-,0.5)": np.array([-0.25, -0.25, 0.5]),
    }


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """|x|, |y| ≤ 0.4 L and −0.4 L ≤ z ≤ 0.65 L below the slides' origin plane."""
    length = params["L"]
    return (np.array([-0.4 * length, -0.4 * length, -0.4 * length]),
            np.array([0.4 * length, 0.4 * length, 0.65 * length]))


KIND = MachineKind(
    kind="linear-delta",
    title="Linear Delta (3-P(SS)2, vertical slides)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="seed 000 (Bourebbou 2019), §III.5 and Table III.2; §IV Table IV.1",
)
