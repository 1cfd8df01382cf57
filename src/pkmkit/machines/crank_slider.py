"""The crank–slider of seed 002 (Guyon 2021, §4.3, Table 4.1): the smallest hyperstatic
mechanism, a planar four-bar with a slider, modelled in space as two "legs" from the base to the
piston — leg 1: three revolutes (θ1 actuated crank, θ2, θ3), leg 2: one prismatic joint x4 —
closed on the piston frame R_F with the junction matrices of eq. (4.12)::

    D_R0^L1 M(θ1) D_R1^L2 M(θ2) D_R2^L3 M(θ3) T_R3^RF = D_R0^L4 M(x4) T_R4^RF

Nominal invariants (Table 4.1): pivot 1 axis (0, −1, 0) at the origin, pivots 2 and 3 parallel
to the previous z at L1 and L2 along x, the slider along x at L4. Its closure gives eq. (4.8):
θ1 + θ2 + θ3 = 0, L1 sin θ1 = L2 sin θ3, L1 cos θ1 + L2 cos θ3 + L3 − x4 = L4. In space the
planar mechanism is over-constrained three times (h = 3). Dimensions: those the notes use for
their rank test (L1 = 100, L2 = 300, L3 = 50, L4 = 200 mm); the thesis gives none.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.machines.machine import MachineKind
from pkmkit.model.chains import ElementSpec, JointChainModel, build_chain_model
from pkmkit.model.parameters import ParameterSpec

PARAMETERS = (
    ParameterSpec("L1", "length", 0.1, "crank length (pivot 1 to pivot 2)", positive=True),
    ParameterSpec("L2", "length", 0.3, "rod length (pivot 2 to pivot 3)", positive=True),
    ParameterSpec("L3", "length", 0.05, "offset of the piston frame from pivot 3",
                  positive=True),
    ParameterSpec("L4", "length", 0.2, "position of the slider's reference along x",
                  positive=True),
    ParameterSpec("home_angle", "angle", math.radians(30.0), "crank angle at home"),
)


def closure_values(params: Mapping[str, Any], theta1: np.ndarray) -> np.ndarray:
    """``(N, 4)`` θ1, θ2, θ3, x4 satisfying (4.8) on the branch θ3 ∈ (−π/2, π/2)."""
    theta1 = np.asarray(theta1, dtype=float)
    l1, l2 = params["L1"], params["L2"]
    theta3 = np.arcsin(l1 * np.sin(theta1) / l2)
    theta2 = -theta1 - theta3
    x4 = l1 * np.cos(theta1) + l2 * np.cos(theta3) + params["L3"] - params["L4"]
    return np.stack([theta1, theta2, theta3, x4], axis=-1)


def build(params: Mapping[str, Any]) -> JointChainModel:
    """Joint-chain model of the crank–slider."""
    if params["L1"] >= params["L2"]:
        raise ParameterError("the crank L1 must be shorter than the rod L2 (full rotation)",
                             "L1")
    home = closure_values(params, np.array(params["home_angle"]))
    elements = [
        ElementSpec("theta1", "R", axis=(0, -1, 0), label="1", actuated=True, home=home[0],
                    display="θ1"),
        ElementSpec("theta2", "R", axis=(0, 0, 1), point=(params["L1"], 0, 0), label="2",
                    home=home[1], display="θ2"),
        ElementSpec("theta3", "R", axis=(0, 0, 1), point=(params["L2"], 0, 0), label="3",
                    home=home[2], display="θ3"),
        ElementSpec("R3_RF", "F", rotation=[[1, 0, 0], [0, 0, 1], [0, -1, 0]],
                    point=(params["L3"], 0, 0), label="3F"),
        ElementSpec("x4", "P", axis=(1, 0, 0), point=(params["L4"], 0, 0), label="4",
                    home=home[3], display="x4"),
        ElementSpec("R4_RF", "F", rotation=[[0, 1, 0], [0, 0, 1], [1, 0, 0]], label="4F"),
    ]
    return build_chain_model(elements, legs=[["theta1", "theta2", "theta3", "R3_RF"],
                                             ["x4", "R4_RF"]],
                             leg_names=["crank and rod", "slider"],
                             characteristic_length=params["L2"])


def reference_poses(params: Mapping[str, Any], model: JointChainModel) -> dict[str, np.ndarray]:
    """Crank angles 0 and 90°."""
    return {"crank-0": np.array([0.0]), "crank-90": np.array([math.pi / 2])}


KIND = MachineKind(
    kind="crank-slider",
    title="Crank–slider (seed 002, Table 4.1), a hyperstatic planar mechanism in space",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    source="seed 002 (Guyon 2021) §4.3, Table 4.1, eqs. 4.8–4.12",
)
