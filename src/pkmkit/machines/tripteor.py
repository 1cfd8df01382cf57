"""Tripteor X7 (Exechon-type tripod with a 2-axis head; seed 002, Guyon 2021), as joint chains.

The parallel part follows the thesis's Chapter 4 chains (eq. 4.19) and nominal invariants
(Table 4.2), which close exactly (notes §2.7); the dimensions are those implied by the thesis's
identified values (Table 5.6): L = 1000.6254, D = 799.8675, l = 389.86, d = 290.24 mm::

    leg 1: D_ICS^L11 M(ψ1) D_R11^L21 M(θ1) D_R21^L41 M(Q1) D_R41^L51 M(φ1)           → R51
    leg 2: D_ICS^L12 M(ψ2) D_R12^L22 M(θ2) D_R22^L32 M(η2) D_R32^L42 M(Q2) D_R42^L52 M(φ2)
           D_R52^R51 Rz(−90°)                                                          → R51
    leg 3: D_ICS^L13 M(ψ3) D_R13^L23 M(θ3) D_R23^L43 M(Q3) D_R43^L53 M(φ3) D_R53^R51   → R51
    head:  T_R51^MPS D_MPS^L6 M(Q4) D_R6^L7 M(Q5) T_R7^T

(the Rz(−90°) closing leg 2 is the thesis's Mathematica ``P_R51^R512``, absent from 4.19; the
printed (4.31) D_R43^L53 is a typo: see docs/seed-errata.md). 13 one-DOF joints, 10 passive;
h = 2.

**Assumptions** (the thesis does not give them; documented in docs/joint-chains.md):

- the platform frame MPS has its z axis normal to the plane B1B2B3, its x axis along B1→B3, and
  its origin ``h`` below the triangle's centroid (Chanal 2012's B points, Fig. 2.4, give
  h = 532.229 mm and the centroid);
- the head: Q4 turns about z_MPS; Q5 about an axis parallel to y of the Q4 body, offset by
  ``c1`` = 35.1117 mm along its x (Table 5.6 puts the large wrist offset in A7, although
  Table 4.2 writes c1 in B);
- the tool frame: its z axis is the spindle axis, pointing out of the spindle, along −z_MPS at
  Q4 = Q5 = 0, its origin (the spindle gauge point) ``spindle`` below the Q5 axis; the tool point
  is the tool length along it (the thesis's two tools: 169.889 and 110.006 mm).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.machines import tripteor_forms as forms
from pkmkit.machines.machine import MachineKind
from pkmkit.machines.tripteor_forms import mps_frame, platform_points
from pkmkit.model.chains import ElementSpec, JointChainModel, build_chain_model
from pkmkit.model.parameters import ParameterSpec

PARAMETERS = (
    ParameterSpec("L", "length", 1.0006254, "distance A1–A3 between the base joints of legs 1 "
                  "and 3", positive=True),
    ParameterSpec("D", "length", 0.7998675, "distance from the line A1A3 to A2", positive=True),
    ParameterSpec("l", "length", 0.38986, "distance B1–B3 between the platform joints of legs 1 "
                  "and 3", positive=True),
    ParameterSpec("d", "length", 0.29024, "distance from the line B1B3 to B2", positive=True),
    ParameterSpec("h", "length", 0.532229, "depth of the platform frame MPS below the plane "
                  "B1B2B3 (Chanal 2012)", positive=True),
    ParameterSpec("c1", "length", 0.0351117, "offset of the Q5 axis from the Q4 axis "
                  "(Table 5.6, A7)"),
    ParameterSpec("spindle", "length", 0.2, "distance from the Q5 axis to the spindle gauge "
                  "point along the spindle (assumption)"),
    ParameterSpec("tool_length", "length", 0.169889, "default tool length (the thesis's long "
                  "tool)", positive=True),
    ParameterSpec("characteristic_length", "length", 0.5, "scale of the rotation residuals of "
                  "the closures", positive=True),
)

#: Home joint values: the notes' reconstructed configuration at Q = (982.802, 1063.747,
#: 989.454) mm, Q4 = Q5 = 0 (degrees for the revolutes) — a starting point solved exactly.
HOME = {"psi1": 0.2813, "theta1": 17.7023, "Q1": 0.982802, "phi1": -18.1040,
        "psi2": -0.4005, "theta2": 28.3439, "eta2": -0.0022, "Q2": 1.063747, "phi2": 28.6252,
        "psi3": 0.2813, "theta3": -18.3763, "Q3": 0.989454, "phi3": 17.9747, "Q4": 0.0,
        "Q5": 0.0}
#: Joint ranges of the thesis's measurements (Table 5.3; m and degrees), used as strokes.
STROKES = {"Q1": (0.975, 0.995), "Q2": (1.055, 1.075), "Q3": (0.975, 0.995), "Q4": (-15.0, 15.0),
           "Q5": (0.0, 55.0)}
DISPLAY = {"psi1": "ψ1", "theta1": "θ1", "phi1": "φ1", "psi2": "ψ2", "theta2": "θ2",
           "eta2": "η2", "phi2": "φ2", "psi3": "ψ3", "theta3": "θ3", "phi3": "φ3"}


def _home(name: str, kind: str) -> float:
    value = HOME[name]
    return math.radians(value) if kind == "R" else value


def elements(params: Mapping[str, Any]) -> list[ElementSpec]:
    """The element table (Table 4.2 with the dimensions, plus the head assumptions)."""
    big_l, big_d, small_l, small_d = params["L"], params["D"], params["l"], params["d"]

    def joint(name, kind, axis, point=(0.0, 0.0, 0.0), label="", actuated=False):
        stroke = STROKES.get(name, (-np.inf, np.inf))
        if kind == "R" and name in STROKES:
            stroke = tuple(math.radians(v) for v in stroke)
        return ElementSpec(name=name, type=kind, axis=axis, point=point, label=label,
                           actuated=actuated, home=_home(name, kind), stroke=stroke,
                           display=DISPLAY.get(name, name))

    mps = mps_frame(params)
    spindle = params["spindle"]
    return [
        joint("psi1", "R", (0, -1, 0), label="11"),
        joint("theta1", "R", (1, 0, 0), label="21"),
        joint("Q1", "P", (1, 0, 0), label="41", actuated=True),
        joint("phi1", "R", (0, 1, 0), label="51"),
        joint("psi2", "R", (1, 0, 0), (-big_d, -big_l / 2, 0.0), label="12"),
        joint("theta2", "R", (1, 0, 0), label="22"),
        joint("eta2", "R", (1, 0, 0), label="32"),
        joint("Q2", "P", (0, 0, 1), label="42", actuated=True),
        joint("phi2", "R", (0, -1, 0), label="52"),
        ElementSpec("R52_R51", "F", axis=(1, 0, 0), point=(small_d, 0.0, -small_l / 2),
                    spin=-math.pi / 2, label="62"),
        joint("psi3", "R", (0, -1, 0), (0.0, -big_l, 0.0), label="13"),
        joint("theta3", "R", (1, 0, 0), label="23"),
        joint("Q3", "P", (1, 0, 0), label="43", actuated=True),
        joint("phi3", "R", (0, 1, 0), label="53"),
        ElementSpec("R53_R51", "F", axis=(0, 0, 1), point=(small_l, 0.0, 0.0), label="63"),
        ElementSpec("R51_MPS", "F", rotation=mps[:3, :3], point=mps[:3, 3], label="MPS"),
        joint("Q4", "R", (0, 0, 1), label="6", actuated=True),
        joint("Q5", "R", (0, 1, 0), (params["c1"], 0.0, 0.0), label="7", actuated=True),
        # tool frame: z out of the spindle (−z_MPS at Q4 = Q5 = 0), origin at the gauge point
        ElementSpec("R7_T", "F", rotation=[[-1, 0, 0], [0, 0, -1], [0, -1, 0]],
                    point=(0.0, -spindle, 0.0), label="T"),
    ]


__all__ = ["HOME", "KIND", "build", "elements", "mps_frame", "platform_points"]


def build(params: Mapping[str, Any]) -> JointChainModel:
    """Joint-chain model of the Tripteor X7."""
    return build_chain_model(
        elements(params),
        legs=[["psi1", "theta1", "Q1", "phi1"],
              ["psi2", "theta2", "eta2", "Q2", "phi2", "R52_R51"],
              ["psi3", "theta3", "Q3", "phi3", "R53_R51"]],
        head=["R51_MPS", "Q4", "Q5", "R7_T"],
        characteristic_length=params["characteristic_length"])


def reference_poses(params: Mapping[str, Any], model: JointChainModel) -> dict[str, np.ndarray]:
    """Actuator vectors: the thesis's Table 5.2 first row, and a wrist-only move."""
    return {"table-5.2-row-1": np.array([0.983186, 1.064076, 0.988005, 0.0, 0.0]),
            "wrist": np.array([0.982802, 1.063747, 0.989454, math.radians(10.0),
                               math.radians(30.0)])}


KIND = MachineKind(
    kind="tripteor",
    title="Tripteor X7 (Exechon-type tripod, 2-axis head)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    source="seed 002 (Guyon 2021): Table 4.2, eq. 4.19, dimensions from Table 5.6",
    inverse_start=forms.start_unknowns,
    direct_start=forms.direct_unknowns,
)
