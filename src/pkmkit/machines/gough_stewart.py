"""The Gough–Stewart platform (6-UPS hexapod): six struts of actuated length.

Base joints lie on a circle of radius ``base_radius`` in the plane z = 0, in three pairs centred
at 0°, 120°, 240° and spread by ± ``base_half_angle``; platform joints lie on a circle of radius
``platform_radius`` in the platform's plane z = 0, in three pairs centred at 60°, 180°, 300°
spread by ± ``platform_half_angle``. Leg 2k joins the base joint at 120k° − α_b to the platform
joint at 120k° − 60° + α_p, leg 2k+1 the base joint at 120k° + α_b to the platform joint at
120k° + 60° − α_p (each base pair feeds two different platform pairs: the usual triangulated
"semi-regular hexagon" layout). The actuator coordinate of leg i is its **length**, the distance
between the centres of its universal and spherical joints (m).

The home pose is the platform at ``height`` above the base, parallel to it. Defaults describe a
plausible mid-size hexapod (R_b = 500 mm, R_p = 300 mm, 800 mm high, strut lengths 650–1100 mm);
any 6-6 geometry can be given in a ``rod-legs`` machine file with ``dims = 6``.
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
    ParameterSpec("base_radius", "length", 0.5, "radius of the base joint circle", positive=True),
    ParameterSpec("platform_radius", "length", 0.3, "radius of the platform joint circle",
                  positive=True),
    ParameterSpec("base_half_angle", "angle", math.radians(10.0),
                  "half the angle between the two base joints of a pair"),
    ParameterSpec("platform_half_angle", "angle", math.radians(10.0),
                  "half the angle between the two platform joints of a pair"),
    ParameterSpec("height", "length", 0.8, "height of the platform above the base at home",
                  positive=True),
    ParameterSpec("length_min", "length", 0.65, "shortest strut length", positive=True),
    ParameterSpec("length_max", "length", 1.1, "longest strut length", positive=True),
)


def joint_layout(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Base joints ``(6, 3)`` (fixed frame) and platform joints ``(6, 3)`` (platform frame), m,
    in leg order (see the module docstring)."""
    alpha_b, alpha_p = params["base_half_angle"], params["platform_half_angle"]
    base_angles, platform_angles = [], []
    for k in range(3):
        centre = 2.0 * math.pi * k / 3.0
        base_angles += [centre - alpha_b, centre + alpha_b]
        platform_angles += [centre - math.pi / 3.0 + alpha_p, centre + math.pi / 3.0 - alpha_p]

    def circle(radius: float, angles: list[float]) -> np.ndarray:
        a = np.asarray(angles)
        return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(6)])

    return (circle(params["base_radius"], base_angles),
            circle(params["platform_radius"], platform_angles))


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of the hexapod (struts of length q, home at ``height``)."""
    if not params["length_min"] < params["length_max"]:
        raise ParameterError("length_min must be smaller than length_max", "length_min")
    for name in ("base_half_angle", "platform_half_angle"):
        if not 0.0 < params[name] < math.pi / 3.0:
            raise ParameterError(f"{name} must lie strictly between 0 and 60°", name)
    base, platform = joint_layout(params)
    legs = [LegSpec(name=f"leg {i + 1}", actuator=i, kind="strut", base=base[i],
                    platform=platform[i], length=0.0,
                    stroke=(params["length_min"], params["length_max"])) for i in range(6)]
    return build_rod_model(legs, dims=6, actuator_names=tuple(f"q{i + 1}" for i in range(6)),
                           home_pose=(0.0, 0.0, params["height"], 0.0, 0.0, 0.0))


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """A translated and tilted pose (10 % of the height off-centre, 10° about x then 5° about
    z)."""
    from pkmkit.spatial.poses import pose_from_angles

    h = params["height"]
    return {"tilted": pose_from_angles([0.1 * h, -0.05 * h, 1.05 * h], [10.0, 0.0, 5.0],
                                       "xyz", degrees=True)}


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """Positions within ± half the platform radius sideways and ± 15 % of the height."""
    half = 0.5 * params["platform_radius"]
    h = params["height"]
    return np.array([-half, -half, 0.85 * h]), np.array([half, half, 1.15 * h])


KIND = MachineKind(
    kind="gough-stewart",
    title="Gough–Stewart platform (6-UPS hexapod)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="Gough (1956), Stewart (1965); dimensions chosen for illustration",
)
