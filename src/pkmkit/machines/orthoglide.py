"""Orthoglide (seed 001, Wenger, Chablat & Majou 2002): three orthogonal actuated slides.

Frame origin at the isotropic point. Slide i moves its carriage along axis e_i through the
origin: carriage point ``ρ_i e_i``. Each leg is a parallelogram of length L ending at the tool
point, so ``|p − ρ_i e_i| = L`` and, in the working mode (ρ_i > p_i),

    ρ_i = p_i + sqrt(L² − |p|² + p_i²),      ρ = (L, L, L) at p = 0.

At the origin A = −L·I and B = −L·I, so J = A⁻¹B = I: the isotropic configuration where the
machine behaves like a serial PPP machine (seed 001 eq. 5). The parallelogram of leg i is offset
along e_{i+1}, so that together the three parallelograms lock every platform rotation.

The real machine uses revolute joints only (P–R–Pa–R legs); for position kinematics each
parallelogram is equivalent to two rods with spherical ends, which is the model used here.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.machines.machine import MachineKind
from pkmkit.model.parameters import ParameterSpec
from pkmkit.model.rods import LegSpec, RodModel, build_rod_model

PARAMETERS = (
    ParameterSpec("L", "length", 0.31, "leg (parallelogram) length", positive=True),
    ParameterSpec(
        "parallelogram_width",
        "length",
        0.06,
        "distance between the two rods of each parallelogram (rod model only; no effect on the "
        "translational kinematics)",
    ),
    ParameterSpec("q_min", "length", (0.1265, 0.1265, 0.1265),
                  "lower stroke limit of each actuator", size=3),
    ParameterSpec("q_max", "length", (0.3831, 0.3831, 0.3831),
                  "upper stroke limit of each actuator", size=3),
)


def build(params: Mapping[str, Any]) -> RodModel:
    """Rod model of an Orthoglide of leg length ``L`` (m)."""
    axes = np.eye(3)
    legs = [
        LegSpec(
            name=f"leg {i + 1}",
            actuator=i,
            kind="slide",
            base=(0.0, 0.0, 0.0),
            axis=axes[i],
            platform=(0.0, 0.0, 0.0),
            length=params["L"],
            branch=1,
            parallelogram_width=params["parallelogram_width"],
            stroke=(params["q_min"][i], params["q_max"][i]),
            parallelogram_direction=axes[(i + 1) % 3],
        )
        for i in range(3)
    ]
    return build_rod_model(
        legs,
        dims=3,
        actuator_names=("rho1", "rho2", "rho3"),
        home_pose=(0.0, 0.0, 0.0),
        mode_names=("origin-side", "far-side"),
    )


def reference_poses(params: Mapping[str, Any], model: RodModel) -> dict[str, np.ndarray]:
    """Two points on the cube diagonal through the isotropic point (±L/3.1 per axis)."""
    s = params["L"] / 3.1
    return {"diagonal+": np.full(3, s), "diagonal-": np.full(3, -s)}


def default_box(params: Mapping[str, Any], model: RodModel) -> tuple[np.ndarray, np.ndarray]:
    """Cube of half-side 0.65 L about the isotropic point (holds the prescribed cube)."""
    half = 0.65 * params["L"]
    return np.full(3, -half), np.full(3, half)


KIND = MachineKind(
    kind="orthoglide",
    title="Orthoglide (3-PPa, orthogonal slides)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    default_box=default_box,
    source="seed 001 (Wenger, Chablat, Majou 2002), §3.2–3.4",
)
