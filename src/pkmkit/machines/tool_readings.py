"""The machine protocol's tool readings: what an instrument on the tool sees at actuator
coordinates q (:mod:`pkmkit.geometric_errors.measurements` asks the machine rather than test
its family).

- ``machine.tool_frames(q, tool_length=)`` — ``(point (N, 3), rotation (N, 3))``: the tool
  point (m) and the tool frame's rotation vector in the fixed frame (rad), NaN rows where the
  machine does not assemble. A translating platform's point is padded with zeros to 3-D and
  its rotation is zero; a joint chain's tool sits ``tool_length`` (m, default the machine's)
  along its tool axis.
- ``machine.measures_machined_parts`` — whether a machined part's measured points give
  joint-space readings (seed 003: the actuator values that put the tool on each point, and
  their derivative in the defects there, through the rods' inverse model): True for rod legs,
  False for joint chains (no such model of a hyperstatic closure).
"""

from __future__ import annotations

from typing import Any

import numpy as np


class TranslationalReadings:
    """Rod legs on a translating platform."""

    measures_machined_parts = True

    def tool_frames(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` (module docstring;
        ``tool_length`` is a joint chain's and is ignored here)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        x = np.atleast_2d(self.fk(qb))
        n, k = qb.shape[0], min(self.dims, 3)
        point = np.zeros((n, 3))
        point[:, :k] = x[:, :k]
        return point, np.zeros((n, 3))


class FullPoseReadings:
    """Rod legs on a turning platform."""

    measures_machined_parts = True

    def tool_frames(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` (module docstring;
        ``tool_length`` is ignored here)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        x = np.atleast_2d(self.fk(qb))
        point = np.zeros((qb.shape[0], 3))
        point[:, :3] = x[:, :3]
        return point, x[:, 3:6]


class ChainReadings:
    """Joint chains with heads."""

    measures_machined_parts = False

    def tool_frames(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` with the tool
        ``tool_length`` (m) along the tool axis (module docstring)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        res = self.fk(qb, tool_length=tool_length, full_output=True)
        return res.pose[:, :3], res.tool_frame[:, 3:]
