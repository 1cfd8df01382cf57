"""The elastic data of a machine: actuator stiffness, rod and link sections.

:class:`StiffnessData` holds, in SI units,

- ``actuator_stiffness`` ``(n_act,)``: N/m for slides, struts and prismatic joints, N·m/rad for
  cranks and revolute actuators — the stiffness of the drive (screw, belt, motor and gearbox)
  seen on the actuator coordinate;
- ``rod_section`` / ``rod_material``: the section of the constant-length rods of rod-leg
  machines (axial stiffness EA/ℓ each); None: rigid rods;
- ``link_section`` / ``link_material`` and per-element ``link_sections``: the beam section of the
  bodies of joint-chain machines (6×6 Euler–Bernoulli compliance each, see
  :mod:`pkmkit.stiffness.beam`); None: rigid links;
- ``notes``: where each value comes from (``"assumed"`` when the machine's source gives none).

Passive joints are ideal (no compliance). :func:`default_data` gives a built-in machine's data.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from pkmkit.exceptions import ParameterError
from pkmkit.stiffness.beam import Material, Section, parse_section

#: Assumed drive stiffness of a ball-screw slide or strut, N/m (order of magnitude of a
#: preloaded ball screw with its bearings: 100 N/µm).
ASSUMED_LINEAR = 1e8
#: Assumed torsional stiffness of a rotary actuator (motor and gearbox), N·m/rad.
ASSUMED_ROTARY = 1e5

#: Accepted range of a drive stiffness (SI); beyond it a value is a units mistake.
STIFFNESS_RANGE = (1e-3, 1e15)
#: Built-in kinds whose sources give a rod section: (section, material, source).
_ROD_SECTIONS = {
    "linear-delta": (Section.circle(0.040), Material(),
                     "rods: solid Ø 40 mm (seed 000, Table IV.1), steel E 210 GPa"),
}


@dataclass(frozen=True)
class StiffnessData:
    """Elastic data of a machine (see the module docstring)."""

    actuator_stiffness: np.ndarray
    rod_section: Section | None = None
    rod_material: Material = field(default_factory=Material)
    link_section: Section | None = None
    link_material: Material = field(default_factory=Material)
    link_sections: Mapping[str, Section] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        k = np.asarray(self.actuator_stiffness, dtype=float).reshape(-1)
        object.__setattr__(self, "actuator_stiffness", check_stiffness(k, "actuator_stiffness"))

    @property
    def assumed(self) -> bool:
        """True when some value is assumed rather than taken from the machine's source."""
        return any("assumed" in note for note in self.notes)


def check_stiffness(values: np.ndarray, what: str) -> np.ndarray:
    """Stiffness values as a read-only float array; each finite and > 0.

    Raises:
        ParameterError: a value that is negative, zero or not finite (naming its position).
    """
    arr = np.array(values, dtype=float).reshape(-1)
    for i, v in enumerate(arr):
        if not (math.isfinite(v) and v > 0):
            raise ParameterError(f"{what}[{i}] must be a finite stiffness > 0 (SI: N/m or "
                                 f"N·m/rad), got {float(v)!r}", what)
        if not STIFFNESS_RANGE[0] <= v <= STIFFNESS_RANGE[1]:
            raise ParameterError(f"{what}[{i}] = {float(v):g} is outside [{STIFFNESS_RANGE[0]:g}, "
                                 f"{STIFFNESS_RANGE[1]:g}] (SI: N/m or N·m/rad): check the units",
                                 what)
    arr.setflags(write=False)
    return arr


def _quantities(machine: Any) -> tuple[str, ...]:
    return tuple(machine.actuator_quantities)


def default_data(machine: Any) -> StiffnessData:
    """The elastic data a machine carries: for a built-in kind its source's values where they
    exist, assumed ones (said so in ``notes``) elsewhere; rigid rods and links where no section
    is known."""
    quantities = _quantities(machine)
    k = np.array([ASSUMED_ROTARY if q == "angle" else ASSUMED_LINEAR for q in quantities])
    notes = []
    if any(q != "angle" for q in quantities):
        notes.append(f"linear actuators {ASSUMED_LINEAR:.3g} N/m (assumed: ball-screw drive; "
                     "the source gives none)")
    if any(q == "angle" for q in quantities):
        notes.append(f"rotary actuators {ASSUMED_ROTARY:.3g} N·m/rad (assumed: motor and "
                     "gearbox; the source gives none)")
    kind = machine.kind.kind if machine.kind is not None else None
    from pkmkit.machines.registry import machines as presets

    if machine.id not in presets():  # a user's file of that kind: its own rods
        kind = None
    rod_section = rod_material = None
    chains = machine.elastic_members == "links"
    if kind in _ROD_SECTIONS:
        rod_section, rod_material, text = _ROD_SECTIONS[kind]
        notes.append(text)
    elif chains:
        notes.append("links rigid (the source gives no sections)")
    else:
        notes.append("rods rigid (the source gives no sections)")
    return StiffnessData(actuator_stiffness=k, rod_section=rod_section,
                         rod_material=rod_material or Material(), notes=tuple(notes))


#: Keys ``--set`` accepts for the elastic data (``pkmkit stiffness``).
SET_KEYS = ("actuator_stiffness", "rod_section", "rod_material", "link_section",
            "link_material")


def with_settings(data: StiffnessData, settings: Mapping[str, str], n_actuators: int,
                  length_scale: float = 1.0) -> StiffnessData:
    """``data`` with ``NAME=VALUE`` settings applied (text values as on the command line):
    ``actuator_stiffness=k`` or ``k1,…,kn`` (SI), ``rod_section=``/``link_section=``
    ``circle:D``, ``tube:D,d``, ``rect:b,h`` (lengths × ``length_scale`` to m) or ``rigid``,
    ``rod_material=``/``link_material=E,G`` (Pa).

    Raises:
        ParameterError: an unknown key, a wrong count, a bad value.
    """
    changes: dict[str, Any] = {}
    notes = list(data.notes)
    for key, text in settings.items():
        if key == "actuator_stiffness":
            values = _numbers(text, key)
            if len(values) == 1:
                values = values * n_actuators
            if len(values) != n_actuators:
                raise ParameterError(f"actuator_stiffness needs 1 or {n_actuators} values, got "
                                     f"{len(values)}", key)
            changes[key] = check_stiffness(np.array(values), key)
            notes = [n for n in notes if "actuators" not in n]
            notes.append(f"actuator stiffness {_short(values)} (given)")
        elif key in ("rod_section", "link_section"):
            section = None if text.strip() == "rigid" else parse_section(text, length_scale)
            changes[key] = section
            word = "rods" if key == "rod_section" else "links"
            notes = [n for n in notes if not n.startswith(word)]
            notes.append(f"{word} {'rigid' if section is None else section.label} (given)")
        elif key in ("rod_material", "link_material"):
            values = _numbers(text, key)
            if len(values) != 2:
                raise ParameterError(f"{key} needs E,G in Pa, got {text!r}", key)
            changes[key] = Material(*values)
            notes.append(f"{key} E={values[0]:.4g} Pa, G={values[1]:.4g} Pa (given)")
        else:
            raise ParameterError(f"unknown elastic setting {key!r}; valid: {', '.join(SET_KEYS)}",
                                 key)
    return replace(data, **changes, notes=tuple(notes))


def _numbers(text: str, key: str) -> list[float]:
    try:
        return [float(v) for v in str(text).split(",")]
    except ValueError:
        raise ParameterError(f"{key}: cannot read {text!r} as comma-separated numbers",
                             key) from None


def _short(values: Sequence[float]) -> str:
    unique = sorted(set(values))
    return f"{unique[0]:.4g}" if len(unique) == 1 else ", ".join(f"{v:.4g}" for v in values)
