"""The messages of pkmkit's typed errors in the command's ``--units``.

The library states lengths in metres (``"too short by 0.294998 m"``, ``"q = [0.1, 0.1, 3.0]"``).
A command run with ``--units mm`` prints every number of its error message in millimetres: the
lengths a message marks with ``m`` (a number or a bracketed list) and the actuator vector
(``q = [...]``) or pose (``pose [...]``) of the machine the command resolved, which
:func:`remember` keeps in the click context's ``meta`` (shared by the group and its command).
"""

from __future__ import annotations

import re
from typing import Any

import click
import numpy as np

from pkmkit.model.parameters import length_scale

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|nan|inf|-inf"
_LIST = rf"\[\s*(?:(?:{_NUMBER})\s*,\s*)*(?:{_NUMBER})?\s*\]"
_OTHER_UNIT = r"(?!\s*(?:mm|in|deg|rad)\b)"
_METRES = re.compile(rf"(?<![\w.])({_NUMBER}|{_LIST}) m\b(?![/²³])")
_Q = re.compile(rf"\b(q =? ?)({_LIST}){_OTHER_UNIT}(?! m\b)")
_POSE = re.compile(rf"\b(pose |position )({_LIST}){_OTHER_UNIT}(?! m\b)")

UNITS_KEY = "pkmkit.units"
MACHINE_KEY = "pkmkit.machine"


def remember(key: str, value: Any) -> None:
    """Keep ``value`` (the units, the machine) for the error message of this command."""
    ctx = click.get_current_context(silent=True)
    if ctx is not None:
        ctx.meta[key] = value


def _numbers(text: str) -> np.ndarray:
    inner = text.strip()[1:-1].strip()
    return np.array([float(v) for v in inner.split(",")]) if inner else np.zeros(0)


def _show(values: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def in_units(message: str, meta: dict[str, Any]) -> str:
    """``message`` with its SI lengths in the units of ``meta`` (unchanged in metres)."""
    units = meta.get(UNITS_KEY)
    if units in (None, "m"):
        return message
    scale = length_scale(units)
    m = meta.get(MACHINE_KEY)

    def vector(match: re.Match, kind: str) -> str:
        values = _numbers(match.group(2))
        if m is None:
            return match.group(0)
        if kind == "q" and len(values) == m.n_actuators:
            angle = np.asarray(m.actuator_quantities) == "angle"
            shown = np.where(angle, np.degrees(values), values / scale)
            unit = units if not angle.any() else "deg" if angle.all() else f"({units}, deg)"
            return f"{match.group(1)}{_show(shown)} {unit}"
        if kind == "pose" and len(values) in (2, 3):
            return f"{match.group(1)}{_show(values / scale)} {units}"
        if kind == "pose" and len(values) == 6:
            shown = np.concatenate([values[:3] / scale, values[3:]])
            return f"{match.group(1)}{_show(shown)} ({units}, rotation vector in rad)"
        return match.group(0)

    def metres(match: re.Match) -> str:
        text = match.group(1)
        if text.startswith("["):
            return f"{_show(_numbers(text) / scale)} {units}"
        return f"{float(text) / scale:.6g} {units}"

    message = _Q.sub(lambda mt: vector(mt, "q"), message)
    message = _POSE.sub(lambda mt: vector(mt, "pose"), message)
    return _METRES.sub(metres, message)
