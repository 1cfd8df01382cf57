"""TriMule 600 (Tianjin University; seed 002, Guyon 2021, §3.4, Table 3.2), as joint chains.

A 5-axis hybrid machine: a hyperstatic parallel part with a 4th, unactuated, instrumented leg,
and an A/C head with an eccentricity. The thesis's figures are lost and it gives no dimension;
the frames below are rebuilt from its equations (3.26)–(3.31) — they reproduce its projected
closures (3.26) term by term — and the dimensions are plausible choices (docs/trimule.md).

**Base frame** (ICS): origin A4; x along the shared first revolute ψ1 (the "ring"); A1 = (L/2,
0, 0), A3 = (−L/2, 0, 0) on it; A2 = (0, −H, 0); at zero joint values every leg points along +z
(from the base towards the platform and the part).

**Legs** (joint axes at zero joint values, base frame)::

    leg 1: ψ1 (−x, A4) θ1 (−y, A1) Q1 (z) η1 (z) κ1 (−x) φ1 (−y)   → platform, B1 = P − l/2 x_P
    leg 2: ψ2 (−x, A2) θ2 (−y, A2) Q2 (z) η2 (z) κ2 (−y) φ2 (+x)   → platform, B2 = P + h y_P
    leg 3: ψ1          θ3 (−y, A3) Q3 (z) η3 (z) κ3 (−x) φ3 (+y)   → platform, B3 = P + l/2 x_P
    leg 4: ψ1          θ4 (−y, A4) L4 (z)                            → platform P

(ψ1 is one joint named in legs 1, 3 and 4; η, κ, φ meet at B_i, a nominal spherical joint).
19 one-DOF joints, 16 passive; h = 2. The platform frame MPS has its origin at P (the end of
leg 4), z along leg 4, x from B1 to B3, y towards B2: ``R_P = Rx(−ψ1) Rz(π) Ry(θ4)``.

**Head**: Q4 about z_P through P; Q5 about the y axis of the Q4 body through (c2, 0, c1) (c1
along the Q4 axis, c2 the eccentricity); the tool frame's z axis is the spindle axis (z_P at
Q4 = Q5 = 0), its origin the spindle gauge point ``spindle`` beyond the Q5 axis; the tool point
is ``tool_length`` further along it. Closed forms of all of it: :mod:`~pkmkit.machines.
trimule_forms`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.machines import trimule_forms as forms
from pkmkit.machines.machine import MachineKind
from pkmkit.model.chain_layout import chain_from_layout, chains_from_layout
from pkmkit.model.chains import ElementSpec, JointChainModel, build_chain_model
from pkmkit.model.parameters import ParameterSpec

PARAMETERS = (
    ParameterSpec("L", "length", 0.60, "distance A1–A3 along the shared ψ1 axis (A4 midway)",
                  positive=True),
    ParameterSpec("H", "length", 0.40, "distance from A4 to A2, normal to the ψ1 axis",
                  positive=True),
    ParameterSpec("l", "length", 0.25, "distance B1–B3 (P midway)", positive=True),
    ParameterSpec("h", "length", 0.15, "distance from P to B2, normal to B1B3", positive=True),
    ParameterSpec("c1", "length", 0.20, "from P along the Q4 axis to the foot of the Q5 axis"),
    ParameterSpec("c2", "length", 0.03, "eccentricity: offset of the Q5 axis from the Q4 axis"),
    ParameterSpec("spindle", "length", 0.12, "from the Q5 axis to the spindle gauge point, "
                  "along the spindle"),
    ParameterSpec("tool_length", "length", 0.10, "default tool length beyond the gauge point",
                  positive=True),
    ParameterSpec("L4_home", "length", 1.0, "length of the measured leg at home (ψ1 = θ4 = 0)",
                  positive=True),
    ParameterSpec("characteristic_length", "length", 0.5, "scale of the rotation residuals of "
                  "the closures", positive=True),
)

#: Ranges of the instrumented leg (m, degrees) over which the actuator strokes are sized: with
#: the head at Q4 = Q5 = 0 the tool point then covers a Ø 600 mm × 300 mm cylinder about the
#: home tool axis (z from 1240 to 1540 mm; tests/machines/test_trimule.py).
MEASURED_RANGE = {"L4": (0.85, 1.15), "psi1": (-15.0, 15.0), "theta4": (-15.0, 15.0)}
#: Head strokes (degrees).
HEAD_STROKES = {"Q4": (-180.0, 180.0), "Q5": (-45.0, 45.0)}
#: Joint limits of the passive joints of the instrumented leg (m, degrees).
MEASURED_LIMITS = {"L4": (0.7, 1.3), "psi1": (-30.0, 30.0), "theta4": (-30.0, 30.0)}
DISPLAY = {"psi1": "ψ1", "theta1": "θ1", "eta1": "η1", "kappa1": "κ1", "phi1": "φ1",
           "psi2": "ψ2", "theta2": "θ2", "eta2": "η2", "kappa2": "κ2", "phi2": "φ2",
           "theta3": "θ3", "eta3": "η3", "kappa3": "κ3", "phi3": "φ3", "theta4": "θ4"}
#: The measured passive joints of leg 4.
MEASURED = ("L4", "psi1", "theta4")
LEGS = {"leg 1": ["psi1", "theta1", "Q1", "eta1", "kappa1", "phi1", "P1"],
        "leg 2": ["psi2", "theta2", "Q2", "eta2", "kappa2", "phi2", "P2"],
        "leg 3": ["psi1", "theta3", "Q3", "eta3", "kappa3", "phi3", "P3"],
        "leg 4 (measured)": ["psi1", "theta4", "L4", "P4"]}
HEAD = ["Q4", "Q5", "T"]
_FLIP = ((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0))  # Rz(π)


def actuator_strokes(params: Mapping[str, Any]) -> dict[str, tuple[float, float]]:
    """Strokes (m) of Q1, Q2, Q3: their extremes over :data:`MEASURED_RANGE` (a 9×9×9 grid
    with the corners), widened to whole multiples of 5 mm."""
    grids = [np.linspace(*MEASURED_RANGE["L4"], 9)] + [
        np.radians(np.linspace(*MEASURED_RANGE[k], 9)) for k in ("psi1", "theta4")]
    mesh = [g.reshape(-1) for g in np.meshgrid(*grids, indexing="ij")]
    q = forms.actuators(params, *mesh)
    step = 0.005
    return {name: (math.floor(q[:, i].min() / step) * step, math.ceil(q[:, i].max() / step) * step)
            for i, name in enumerate(("Q1", "Q2", "Q3"))}


def _layout(params: Mapping[str, Any]) -> tuple[list[list[ElementSpec]], list[ElementSpec]]:
    """The legs and head drawn at zero joint values (base frame; platform frame for the head),
    with home values and strokes."""
    big, small, hb, hs = params["L"], params["l"], params["H"], params["h"]
    home = forms.passive_joints(params, params["L4_home"], 0.0, 0.0)
    q_home = forms.actuators(params, params["L4_home"], 0.0, 0.0)[0]
    home = {k: float(v[0]) for k, v in home.items()}
    home.update(Q1=q_home[0], Q2=q_home[1], Q3=q_home[2], Q4=0.0, Q5=0.0)
    strokes = actuator_strokes(params)
    strokes.update({k: tuple(math.radians(v) for v in r) for k, r in HEAD_STROKES.items()})
    strokes.update({k: (tuple(math.radians(v) for v in r) if k != "L4" else r)
                    for k, r in MEASURED_LIMITS.items()})
    a1, a2, a3 = (big / 2, 0.0, 0.0), (0.0, -hb, 0.0), (-big / 2, 0.0, 0.0)
    x, y, z = (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    mx, my = (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)

    def joint(name, kind, axis, point, label, actuated=False):
        return ElementSpec(name=name, type=kind, axis=axis, point=point, label=label,
                           actuated=actuated, home=home[name],
                           stroke=strokes.get(name, (-np.inf, np.inf)),
                           display=DISPLAY.get(name, name))

    def platform(name, point, label):
        return ElementSpec(name=name, type="F", rotation=_FLIP, point=point, label=label)

    psi1 = joint("psi1", "R", mx, (0, 0, 0), "11")
    legs = [
        [psi1, joint("theta1", "R", my, a1, "21"), joint("Q1", "P", z, a1, "31", True),
         joint("eta1", "R", z, a1, "41"), joint("kappa1", "R", mx, a1, "51"),
         joint("phi1", "R", my, a1, "61"), platform("P1", (big / 2 - small / 2, 0, 0), "71")],
        [joint("psi2", "R", mx, a2, "12"), joint("theta2", "R", my, a2, "22"),
         joint("Q2", "P", z, a2, "32", True), joint("eta2", "R", z, a2, "42"),
         joint("kappa2", "R", my, a2, "52"), joint("phi2", "R", x, a2, "62"),
         platform("P2", (0, -hb + hs, 0), "72")],
        [psi1, joint("theta3", "R", my, a3, "23"), joint("Q3", "P", z, a3, "33", True),
         joint("eta3", "R", z, a3, "43"), joint("kappa3", "R", mx, a3, "53"),
         joint("phi3", "R", y, a3, "63"), platform("P3", (-big / 2 + small / 2, 0, 0), "73")],
        [psi1, joint("theta4", "R", my, (0, 0, 0), "24"), joint("L4", "P", z, (0, 0, 0), "34"),
         platform("P4", (0, 0, 0), "74")],
    ]
    q5_point = (params["c2"], 0.0, params["c1"])
    head = [joint("Q4", "R", z, (0, 0, 0), "6", True), joint("Q5", "R", y, q5_point, "7", True),
            ElementSpec("T", "F", rotation=np.eye(3),
                        point=(params["c2"], 0.0, params["c1"] + params["spindle"]), label="T")]
    return legs, head


def elements(params: Mapping[str, Any]) -> list[ElementSpec]:
    """The element table: every element once, invariants relative to the previous element."""
    legs, head = _layout(params)
    return chains_from_layout(legs) + chain_from_layout(head)


def build(params: Mapping[str, Any]) -> JointChainModel:
    """Joint-chain model of the TriMule 600."""
    if params["h"] >= params["H"]:
        raise ParameterError("h (P to B2) must be smaller than H (A4 to A2): leg 2 must lean "
                             "towards the platform", "h")
    if params["l"] >= params["L"]:
        raise ParameterError("l (B1–B3) must be smaller than L (A1–A3)", "l")
    return build_chain_model(elements(params), legs=list(LEGS.values()),
                             leg_names=list(LEGS), head=HEAD,
                             characteristic_length=params["characteristic_length"])


def reference_poses(params: Mapping[str, Any], model: JointChainModel) -> dict[str, np.ndarray]:
    """Actuator vectors (Q1, Q2, Q3 in m, Q4, Q5 in rad) of a few configurations of the
    measured leg: tilted about ψ1, about θ4, and retracted with the head turned."""
    out = {}
    for name, (length, psi, theta, q4, q5) in {
            "tilt-psi1": (1.0, 10.0, 0.0, 0.0, 0.0),
            "tilt-theta4": (1.0, 0.0, -10.0, 0.0, 0.0),
            "retracted-head": (0.9, 5.0, 5.0, 90.0, 30.0)}.items():
        q = forms.actuators(params, length, math.radians(psi), math.radians(theta))[0]
        out[name] = np.array([*q, math.radians(q4), math.radians(q5)])
    return out


KIND = MachineKind(
    kind="trimule",
    title="TriMule 600 (hyperstatic 4-leg parallel part with a measured leg, A/C head)",
    parameters=PARAMETERS,
    build=build,
    reference_poses=reference_poses,
    source="seed 002 (Guyon 2021) §3.4: Table 3.2, eqs. 3.24–3.36; dimensions assumed",
    head_flip=("Q4", "Q5"),
    inverse_start=forms.start_unknowns,
    direct_start=forms.direct_unknowns,
)
