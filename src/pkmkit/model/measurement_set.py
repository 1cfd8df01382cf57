"""A set of calibration measurements of one type, in SI units, with where each row came from.

Measurement types (``kind``) and their readings (``values``):

- ``"point"`` — tool point ``(x, y, z)`` in the measurement frame (m): laser tracker;
- ``"pose"`` — tool point and tool-frame orientation ``(x, y, z, rx, ry, rz)`` (m, rotation
  vector in rad);
- ``"ballbar"`` — bar length ``(length,)`` (m) between a fixed pivot (``pivot``) and the tool
  ball;
- ``"height"`` — probe reading ``(z,)`` (m): the height of the tool point above a flat bed;
- ``"part"`` — a tool-centre point ``(x, y, z)`` measured on a machined part in the part frame
  (m), tied to the straight commanded path (``commanded``: start and end, machine frame) that
  machined it (seed 003).

Every row but a part's has the actuator coordinates ``q`` at which it was taken (m, rad).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError

KINDS = ("point", "pose", "ballbar", "height", "part")
#: Readings per row of each kind.
READING_WIDTH = {"point": 3, "pose": 6, "ballbar": 1, "height": 1, "part": 3}


@dataclass(frozen=True)
class MeasurementSet:
    """Measurements of one kind (see the module docstring).

    Attributes:
        kind: the measurement type.
        values: ``(N, r)`` readings, SI.
        q: ``(N, n)`` actuator coordinates (m or rad), None for machined parts.
        tool_length: ``(N,)`` tool length of each row (m), or None (the machine's default).
        tool: ``(N,)`` tool labels, or None.
        pivot: ``(N, 3)`` ball-bar pivot (m), nominal position, or None.
        path: ``(N,)`` commanded-path labels of a machined part, or None.
        commanded: ``(N, 6)`` commanded path of each part row, start and end (m), or None.
        labels: ``(N,)`` where each row came from (``"file.csv:12"`` or ``"row 12"``).
        source: the file (or a description).
    """

    kind: str
    values: np.ndarray
    q: np.ndarray | None = None
    tool_length: np.ndarray | None = None
    tool: tuple[str, ...] | None = None
    pivot: np.ndarray | None = None
    path: tuple[str, ...] | None = None
    commanded: np.ndarray | None = None
    labels: tuple[str, ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"unknown measurement type {self.kind!r}; valid types: "
                             f"{', '.join(KINDS)}")
        values = np.atleast_2d(np.asarray(self.values, dtype=float))
        n = values.shape[0]
        if values.shape[1] != READING_WIDTH[self.kind]:
            raise InputError(f"{self.kind} readings need {READING_WIDTH[self.kind]} values per "
                             f"row, got {values.shape[1]}")
        object.__setattr__(self, "values", values)
        if not self.labels:
            object.__setattr__(self, "labels", tuple(f"row {i + 1}" for i in range(n)))
        checks = {"q": 2, "tool_length": 1, "pivot": 2, "commanded": 2}
        for name, ndim in checks.items():
            arr = getattr(self, name)
            if arr is None:
                continue
            arr = np.asarray(arr, dtype=float)
            if arr.ndim == 1 and ndim == 2:
                arr = arr[None]
            if arr.shape[0] != n:
                raise InputError(f"{name} has {arr.shape[0]} rows but there are {n} readings")
            object.__setattr__(self, name, arr)
        if self.kind == "part" and (self.commanded is None or self.path is None):
            raise InputError("machined-part measurements need their commanded paths")
        if self.kind == "ballbar" and self.pivot is None:
            raise InputError("ball-bar measurements need their pivot positions")
        if self.kind != "part" and self.q is None:
            raise InputError(f"{self.kind} measurements need the actuator coordinates q")

    def __len__(self) -> int:
        return self.values.shape[0]

    def subset(self, rows: Any) -> MeasurementSet:
        """The rows ``rows`` (indices or a boolean mask), as a new set."""
        idx = np.arange(len(self))[rows]

        def pick(a):
            if a is None:
                return None
            if isinstance(a, tuple):
                return tuple(a[i] for i in idx)
            return a[idx]

        return replace(self, values=self.values[idx], q=pick(self.q),
                       tool_length=pick(self.tool_length), tool=pick(self.tool),
                       pivot=pick(self.pivot), path=pick(self.path),
                       commanded=pick(self.commanded), labels=pick(self.labels))

    def split(self, n_first: int, *, seed: int | None = None) -> tuple[MeasurementSet,
                                                                        MeasurementSet]:
        """Two disjoint sets: ``n_first`` rows (at random with a seed, else the first ones) and
        the rest — e.g. identification and validation."""
        idx = np.arange(len(self))
        if seed is not None:
            idx = np.random.default_rng(seed).permutation(idx)
        first = np.sort(idx[:n_first])
        rest = np.sort(idx[n_first:])
        return self.subset(first), self.subset(rest)
