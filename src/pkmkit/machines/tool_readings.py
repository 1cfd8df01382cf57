"""The machine protocol's tool readings: what an instrument on the tool sees at actuator
coordinates q (:mod:`pkmkit.geometric_errors.measurements` asks the machine rather than test
its family).

- ``machine.tool_readings(q, tool_length=)`` — ``(point (N, 3), rotation (N, 3))``: the tool
  point (m) and the tool frame's rotation vector in the fixed frame (rad), NaN rows where the
  machine does not assemble. A translating platform's point is padded with zeros to 3-D and
  its rotation is zero; a joint chain's tool sits ``tool_length`` (m, default the machine's)
  along its tool axis.
- ``machine.measures_machined_parts`` — whether a machined part's measured points give
  joint-space readings (seed 003: the actuator values that put the tool on each point, and
  their derivative in the defects there, through the rods' inverse model): True for rod legs,
  False for joint chains (no such model of a hyperstatic closure);
  ``machine.part_actuators(points)`` and ``machine.part_sensitivity(points)`` are those readings
  and their derivative ``∂q/∂δ`` at the measured points ``(N, 3)`` (or full poses ``(N, 6)``
  for six actuators): ``−(∂r/∂u)⁺ ∂r/∂δ`` with u the actuators (and a turning platform's
  rotation when only positions are measured: the rods fix it). Joint chains refuse them
  (:class:`~pkmkit.exceptions.UnsupportedOperationError`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pkmkit.exceptions import UnsupportedOperationError


class TranslationalReadings:
    """Rod legs on a translating platform."""

    measures_machined_parts = True

    def tool_readings(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` (module docstring;
        ``tool_length`` is a joint chain's and is ignored here)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        x = np.atleast_2d(self.fk(qb))
        n, k = qb.shape[0], min(self.dims, 3)
        point = np.zeros((n, 3))
        point[:, :k] = x[:, :k]
        return point, np.zeros((n, 3))

    def part_actuators(self, points: np.ndarray) -> np.ndarray:
        """``(N, n)`` actuator values that put the tool on measured points ``(N, ≥ dims)``
        (m; NaN rows where unreachable)."""
        return np.atleast_2d(self.ik(points[:, :self.dims]))

    def part_sensitivity(self, points: np.ndarray) -> np.ndarray:
        """``(N, n, d)`` ``∂q/∂δ`` at measured points ``(N, ≥ dims)`` (module docstring):
        each rod's residual moves its own actuator."""
        from pkmkit.model.defect_rule import defect_index
        from pkmkit.solve.rod_closure import defect_columns

        n, dims = points.shape[0], self.dims
        position = np.zeros((n, 3))
        position[:, :dims] = points[:, :dims]
        q = np.atleast_2d(self.ik(points[:, :dims]))
        _, cols = defect_columns(self.model, defect_index(self), position, None, q)
        jac = self.jacobian(points[:, :dims], q=q)
        dist = np.linalg.norm(jac.A, axis=2)
        dr_dq = -np.diagonal(jac.B, axis1=1, axis2=2) / dist  # (N, n)
        return -cols / dr_dq[:, :, None]


class FullPoseReadings:
    """Rod legs on a turning platform."""

    measures_machined_parts = True

    def tool_readings(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` (module docstring;
        ``tool_length`` is ignored here)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        x = np.atleast_2d(self.fk(qb))
        point = np.zeros((qb.shape[0], 3))
        point[:, :3] = x[:, :3]
        return point, x[:, 3:6]

    def part_actuators(self, points: np.ndarray) -> np.ndarray:
        """``(N, n)`` actuator values that put the tool on measured points ``(N, 3)`` or full
        poses ``(N, 6)`` (m, rad; NaN rows where unreachable)."""
        return np.atleast_2d(self.ik(points))

    def part_sensitivity(self, points: np.ndarray) -> np.ndarray:
        """``(N, n, d)`` ``∂q/∂δ`` at measured points ``(N, 3)`` or poses ``(N, 6)`` (module
        docstring)."""
        from pkmkit.machines.full_pose_forms import FullPoseForms
        from pkmkit.model.defect_rule import defect_index
        from pkmkit.solve.rod_closure import defect_columns
        from pkmkit.spatial.rotation import rotvec_to_matrix

        inv = self.ik(points, full_output=True)
        pose = points if points.shape[1] == 6 else np.atleast_2d(inv.pose)
        q = np.atleast_2d(inv.q)
        rot = rotvec_to_matrix(pose[:, 3:])
        _, cols = defect_columns(self.model, defect_index(self), pose[:, :3], rot, q)
        a, b = FullPoseForms(self.model).jacobians(pose, q)
        dist = np.linalg.norm(a[:, :, :3], axis=2)[:, :, None]
        # residual r = |d| − ℓ: ∂r/∂q = −B/|d|, ∂r/∂ω = A_ω/|d|
        unknowns = -b / dist
        if points.shape[1] == 3:  # the orientation follows the rods: it is an unknown too
            unknowns = np.concatenate([unknowns, a[:, :, 3:] / dist], axis=2)
        du = -np.linalg.pinv(unknowns) @ cols
        return du[:, :self.n_actuators]


class ChainReadings:
    """Joint chains with heads."""

    measures_machined_parts = False

    def tool_readings(self, q: Any, *, tool_length: Any = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """``(point (N, 3), rotation (N, 3))`` at ``q (n,)``/``(N, n)`` with the tool
        ``tool_length`` (m) along the tool axis (module docstring)."""
        qb = np.atleast_2d(np.asarray(q, dtype=float))
        res = self.fk(qb, tool_length=tool_length, full_output=True)
        return res.pose[:, :3], res.tool_frame[:, 3:]

    def part_actuators(self, points: np.ndarray) -> np.ndarray:
        """Refused (module docstring).

        Raises:
            UnsupportedOperationError: always.
        """
        raise self._no_parts("machined-part readings")

    def part_sensitivity(self, points: np.ndarray) -> np.ndarray:
        """Refused (module docstring).

        Raises:
            UnsupportedOperationError: always.
        """
        raise self._no_parts("machined-part sensitivity")

    def _no_parts(self, what: str) -> UnsupportedOperationError:
        return UnsupportedOperationError(
            what, self.id, self.family,
            "machined-part (joint-space) measurements are defined for rod machines (seed 003); "
            "use point or pose measurements for a joint-chain machine")
