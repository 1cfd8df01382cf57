"""Seed 002's identified geometry of the Tripteor X7 (Table 5.6) as a machine, evaluated.

The thesis identifies 52 parameters (Table 5.5) from laser-tracker readings and prints their
values (Table 5.6, L1982–1999): direction components I, J, K (dimensionless) and positions A,
B, C (mm) of the D matrices between the joint frames; where a nominal value exists (A12, B12,
A62, C62, A63, A7) the entry is absolute, elsewhere it is a defect (notes §6). This module
puts those values on pkmkit's Tripteor (its frames follow Table 4.2, and its element points
carry the same nominal A, B, C), and asks what the thesis's model could not: do the identified
defects let the machine assemble, and what do its gauges do?

- :data:`TABLE_5_6`: the table as printed (blank entries absent), in SI.
- :func:`table_5_6_defects`: pkmkit's defects from it (absolute entries minus pkmkit's nominal
  point), and the entries pkmkit has no defect for (a position along a joint's own axis: a
  gauge of that joint's variable, :data:`~pkmkit.calibration.studies.TABLE_5_5`).
- :func:`evaluate_table_5_6`: the machine with those defects, its closures solved in least
  squares over configurations across the workspace; the defects' part outside the compatible
  subspace (the part no real, rigid machine can have); each defect's effect on the tool point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pkmkit.calibration.studies import TABLE_5_5
from pkmkit.geometric_errors.compatibility import compatibility, compatibility_configurations
from pkmkit.geometric_errors.model import defect_set

#: Table 5.6 (seed 002, L1982–1999): row label of pkmkit's element (the thesis's D matrix
#: index: ``"21"`` is D_R11^L21, ``"62"`` D_R52^R51, ``"6"`` D_MPS^L6, ``"7"`` D_R6^L7) →
#: column (I, J, K dimensionless; A, B, C in m) → value as printed.
TABLE_5_6: dict[str, dict[str, float]] = {
    "21": {"J": -0.0001, "A": -0.0315e-3, "B": -0.0007e-3, "C": 0.1448e-3},
    "41": {"J": 0.1827},
    "51": {"A": -0.0077e-3, "B": -0.0373e-3, "C": 0.0316e-3},
    "12": {"J": -0.0007, "K": -0.0040, "A": -799.8675e-3, "B": -500.3127e-3, "C": 0.0143e-3},
    "22": {"J": -0.0003, "K": -0.1191, "A": 0.1024e-3, "B": 0.0091e-3, "C": 0.1523e-3},
    "32": {"J": 0.0151, "K": 0.0015, "A": 0.0459e-3, "B": -0.0636e-3, "C": 0.0073e-3},
    "52": {"I": -0.0013, "K": 0.0012, "A": 0.0484e-3, "B": 0.0019e-3, "C": 0.0686e-3},
    "62": {"J": 0.0013, "A": 290.2436e-3, "B": -0.0047e-3, "C": -195.0289e-3},
    "13": {"A": -0.7288e-3, "C": 0.0313e-3},
    "23": {"J": -0.0002, "A": -0.0581e-3, "B": 0.0082e-3, "C": 0.5062e-3},
    "43": {"J": -0.0010},
    "53": {"A": 0.1194e-3, "B": -0.0750e-3, "C": -0.0553e-3},
    "63": {"A": 389.8632e-3, "B": 0.0139e-3, "C": -0.1284e-3},
    "6": {"A": -0.0031e-3, "B": 0.3245e-3},
    "7": {"I": -0.0002, "K": -0.0005, "A": 35.1117e-3, "B": -0.2166e-3, "C": 0.0700e-3},
}
#: The entries Table 5.6 gives as absolute values (the others are defects).
ABSOLUTE = ("A12", "B12", "A62", "C62", "A63", "A7")


def table_5_6_defects(machine) -> tuple[dict[str, float], dict[str, float]]:
    """pkmkit's defects of ``machine`` (a Tripteor X7) from Table 5.6 (name → SI), and the
    entries that are gauges of a joint variable (thesis name → SI; a position along the
    joint's own axis, which pkmkit's minimal parametrisation does not have).

    An absolute entry becomes its difference from the nominal point of pkmkit's element with
    the same label."""
    points = {e.label: np.asarray(e.point, dtype=float) for e in machine.model.elements}
    names = set(defect_set(machine).names)
    defects, gauges = {}, {}
    for row, columns in TABLE_5_6.items():
        for column, value in columns.items():
            key = f"{column}{row}"
            if key in ABSOLUTE:
                value = value - float(points[row]["ABC".index(column)])
            name = TABLE_5_5.get(key)
            if name is None:
                gauges[key] = value
            elif name in names:
                defects[name] = value
            else:  # a Table 5.5 name this machine does not have
                raise KeyError(f"Table 5.6 entry {key} maps to {name}, unknown to "
                               f"{machine.id}")
    return defects, gauges


@dataclass
class Table56Study:
    """Outcome of :func:`evaluate_table_5_6` (SI)."""

    defects: dict[str, float]
    gauges: dict[str, float]
    configurations: int
    closure: dict[str, float]
    compatible_closure: dict[str, float]
    incompatible_norm: float
    incompatible_largest: list[tuple[str, float]]
    tool_change: dict[str, float]
    no_effect_on_tool: list[str]
    equal_to_nominal: list[str]
    largest_effect: list[tuple[str, float]]
    machine: Any = field(repr=False, default=None)

    def summary(self) -> dict[str, Any]:
        """JSON-ready numbers (µm for lengths)."""
        um = 1e6
        return {
            "defects": len(self.defects), "gauges": sorted(self.gauges),
            "configurations": self.configurations,
            "closure_um": {k: v * um for k, v in self.closure.items()},
            "compatible_closure_um": {k: v * um for k, v in self.compatible_closure.items()},
            "incompatible_um": self.incompatible_norm * um,
            "incompatible_largest_um": [(n, v * um) for n, v in self.incompatible_largest],
            "tool_change_um": {k: v * um for k, v in self.tool_change.items()},
            "no_effect_on_tool": self.no_effect_on_tool,
            "equal_to_nominal": self.equal_to_nominal,
            "largest_effect_um": [(n, v * um) for n, v in self.largest_effect],
        }


def _closure_stats(machine, q: np.ndarray) -> tuple[dict[str, float], np.ndarray]:
    res = machine.fk(q, full_output=True, strokes="ignore")
    closure = np.asarray(res.closure_residual, dtype=float)
    pose = np.asarray(res.pose, dtype=float)
    return {"mean": float(np.nanmean(closure)), "max": float(np.nanmax(closure))}, pose


#: The difference of the thesis's two tool lengths (169.889 − 110.006 mm, L1835): its tracker
#: read both tips, so a defect that only tilts the tool axis is seen through it.
TOOL_LENGTH_DIFFERENCE = 0.169889 - 0.110006


def _tips_moved(pose: np.ndarray, reference: np.ndarray) -> float:
    """Largest displacement (m) of either tool tip (the long tool's, the pose's point, and the
    short tool's, :data:`TOOL_LENGTH_DIFFERENCE` back along the axis) over the rows."""
    long_tip = pose[:, :3] - reference[:, :3]
    short_tip = long_tip - TOOL_LENGTH_DIFFERENCE * (pose[:, 3:6] - reference[:, 3:6])
    return float(np.nanmax(np.maximum(np.linalg.norm(long_tip, axis=1),
                                      np.linalg.norm(short_tip, axis=1))))


def evaluate_table_5_6(machine=None, *, n_configurations: int = 40, seed: int = 0,
                       effect_rtol: float = 1e-3) -> Table56Study:
    """The Tripteor with Table 5.6's defects, evaluated over ``n_configurations``
    configurations spread across the workspace (those of the compatibility test).

    Returns the closure residuals of the least-squares assembly (how far the legs miss each
    other: 0 for a machine that can exist), those of the same defects projected on the
    compatible subspace (the check that the projection assembles), the incompatible part of
    the defects (its norm in closure metres — the defects scaled by the closure residual each
    causes per unit — and the defects that carry most of it), the tool-point change against
    the nominal machine, and each defect's effect on the tool tips the thesis read (the
    nominal machine with that defect alone, at its identified value, the head turned at random
    in ±30°): a defect whose effect stays below ``effect_rtol`` of its size (a position; a
    direction component times the machine's characteristic length) acts at second order
    only — at first order it moves passive joints alone, and tool readings cannot identify it,
    whatever value an identification gives it.
    """
    import pkmkit

    machine = machine or pkmkit.machine("tripteor-x7")
    defects, gauges = table_5_6_defects(machine)
    q = compatibility_configurations(machine, n_configurations, seed=seed)
    thesis = machine.with_defects(defects)
    closure, pose = _closure_stats(thesis, q)
    _, nominal_pose = _closure_stats(machine, q)
    change = np.linalg.norm(pose[:, :3] - nominal_pose[:, :3], axis=1)
    # the compatible subspace, in closure metres per defect (the test's column scales)
    comp = compatibility(machine, q=q, reference_nominal=True)  # D_ICS^L11 held, as the thesis
    d = np.array([defects.get(n, 0.0) for n in comp.names])
    scaled = comp.scale * d
    basis = comp.scale[:, None] * comp.basis
    coef, *_ = np.linalg.lstsq(basis, scaled, rcond=None)
    incompatible = scaled - basis @ coef
    compatible = dict(zip(comp.names, (basis @ coef) / comp.scale, strict=True))
    compatible.update({n: v for n, v in defects.items() if n not in compatible})
    projected = machine.with_defects(compatible)
    compatible_closure, _ = _closure_stats(projected, q)
    order = np.argsort(-np.abs(incompatible))
    largest = [(comp.names[i], float(incompatible[i])) for i in order[:5]
               if abs(incompatible[i]) > 1e-12]
    rng = np.random.default_rng(seed)
    q_head = q.copy()
    head = np.asarray(machine.angular_actuators, dtype=bool)
    q_head[:, head] = rng.uniform(-np.pi / 6, np.pi / 6, (len(q), int(head.sum())))
    _, head_pose = _closure_stats(machine, q_head)
    units = dict(zip(defect_set(machine).names, defect_set(machine).units, strict=True))
    length = float(machine.model.characteristic_length)
    effect, first_order = [], []
    for name in sorted(n for n, v in defects.items() if v != 0.0):
        _, alone = _closure_stats(machine.with_defects({name: defects[name]}), q_head)
        moved = _tips_moved(alone, head_pose)
        effect.append((name, moved))
        size = abs(defects[name]) * (1.0 if units[name] == "m" else length)
        if moved >= effect_rtol * size:
            first_order.append(name)
    return Table56Study(
        defects=defects, gauges=gauges, configurations=len(q), closure=closure,
        compatible_closure=compatible_closure,
        incompatible_norm=float(np.linalg.norm(incompatible)),
        incompatible_largest=largest,
        tool_change={"mean": float(np.mean(change)), "max": float(np.max(change))},
        no_effect_on_tool=[n for n, _ in effect if n not in first_order],
        equal_to_nominal=sorted(n for n, v in defects.items() if v == 0.0),
        largest_effect=sorted(effect, key=lambda item: -item[1])[:5], machine=thesis)


def table_5_6_machine_text(machine=None) -> str:
    """The Tripteor X7 machine file with Table 5.6's defects as its ``[defects]`` table (the
    gauges left out, they are no geometry): loads with ``pkmkit.load`` or on the command line,
    and assembles in least squares (its closures do not meet: :func:`evaluate_table_5_6`)."""
    import pkmkit
    from pkmkit.io.machine_defects import machine_text_with_defects
    from pkmkit.machines.registry import preset_path

    machine = machine or pkmkit.machine("tripteor-x7")
    defects, gauges = table_5_6_defects(machine)
    names = defect_set(machine).names
    delta = np.array([defects.get(n, 0.0) for n in names])
    note = ("seed 002's identified geometry (Table 5.6, L1982-1999) on pkmkit's Tripteor X7: "
            "absolute entries minus pkmkit's nominal points; left out as gauges of joint "
            f"variables: {', '.join(sorted(gauges))}. Its closures do not meet (least-squares "
            "assembly): see docs/tripteor-x7.md")
    return machine_text_with_defects(preset_path(machine.id), machine, delta, note=note)
