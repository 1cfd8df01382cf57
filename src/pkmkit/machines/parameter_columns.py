"""The machine protocol's parameter sensitivities: what each family knows of how its nominal
parameters move its tool, and which actuator change holds the tool still.

:func:`pkmkit.geometric_errors.parameter_sensitivity.parameter_sensitivity` asks the machine:

- ``machine.nominal_sensitivity(vector, positions, q, sens)`` — ``∂(tool point, rotation)/∂p``
  of nominal entries ``positions`` of the parameter vector at held actuators q, given the
  machine's analytic defect sensitivity ``sens`` there. Rod legs (:class:`RodParameterColumns`):
  the defect sensitivity composed with the parameter's change of the defect level's geometry
  (rod ends, lengths, axes in defect coordinates; central differences of the geometry builder,
  step :data:`GEOMETRY_STEP`). Joint chains (:class:`ChainParameterColumns`): described element
  by element, the element frame's twist (central differences of the frame alone) composed with
  the closure sensitivity; of a kind, central differences of the direct model, step
  ``STEP · max(1, |p|)``, the machine rebuilt on either side. A side the builder refuses gives a
  NaN column of method :data:`UNDEFINED`.
- ``machine.held_tool_actuators(q, pose, point, rotation)`` — ``−J⁺ ∂x/∂p``, the actuator change
  that keeps the tool at its pose: ``A⁻¹B`` of rod legs (the position rows only on a translating
  platform), the joint chains' ``J`` with the rotation about the tool axis left free.

Units: SI per SI unit of each parameter.
"""

from __future__ import annotations

import numpy as np

from pkmkit.exceptions import PkmError

#: Relative step of the central differences of the direct model (joint-chain kinds).
STEP = 1e-6
#: Step of the central differences of the geometry builders (composition), SI units.
GEOMETRY_STEP = 1e-6
#: The method of a column whose machine cannot be built on one side of the step (a kind at
#: the edge of its domain, such as the parallel slides of the Biglide five-bar): NaN.
UNDEFINED = "undefined"


class RodParameterColumns:
    """Nominal-parameter sensitivities of rod-leg machines (composition)."""

    def nominal_sensitivity(self, vector, positions, q: np.ndarray, sens) -> dict:
        """``{position: (point (N, 3), rotation (N, 3), method)}`` for the nominal entries
        ``positions`` of ``vector`` (module docstring); ``sens`` the
        :meth:`tool_sensitivity` at ``q (N, n)``."""
        g = self._rod_geometry_derivative(vector, positions)  # (d, k)
        pts = sens.point @ g
        rots = sens.rotation @ g
        return {i: (pts[:, :, j], rots[:, :, j], "composition" if np.isfinite(g[:, j]).all()
                    else UNDEFINED) for j, i in enumerate(positions)}

    def _rod_geometry_derivative(self, vector, positions) -> np.ndarray:
        """``(d, k)``: the first-order change of the defect level's geometry per unit nominal
        parameter, in the defect coordinates (central differences of the builder)."""
        from pkmkit.model.defect_rule import defect_index, nominal_model
        from pkmkit.model.rod_defects import rod_geometry

        index = defect_index(self)
        model = nominal_model(self)
        out = np.zeros((len(index), len(positions)))
        for j, i in enumerate(positions):
            name, h = vector.index.names[i], GEOMETRY_STEP
            try:
                g = [rod_geometry(nominal_model(self.with_parameters(
                    vector.replace({name: vector.values[i] + s * h})))) for s in (1.0, -1.0)]
            except PkmError:  # the builder refuses a side: not differentiable here
                out[:, j] = np.nan
                continue
            diff = {k: (g[0][k] - g[1][k]) / (2 * h) for k in ("base", "platform", "length",
                                                               "axis", "pivot")}
            for r, (kind, t, c) in enumerate(zip(index.kind, index.target, index.component,
                                                 strict=True)):
                if kind in ("base", "platform"):
                    out[r, j] = diff[kind][t, c]
                elif kind == "length":
                    out[r, j] = diff["length"][t]
                elif kind in ("axis", "pivot"):
                    leg = int(np.flatnonzero(model.leg_actuator == t)[0])
                    out[r, j] = diff[kind][leg, c]
        return out


class TranslationalParameterColumns(RodParameterColumns):
    """Rod legs on a translating platform: the position rows alone hold the tool."""

    def held_tool_actuators(self, q: np.ndarray, pose: np.ndarray, point: np.ndarray,
                            rotation: np.ndarray) -> np.ndarray:
        """``(N, n, p)`` ``−J⁺ ∂x/∂p`` at ``q (N, n)`` for tool motions ``point``,
        ``rotation`` ``(N, 3, p)`` (``pose (N, 6)`` the tool pose; module docstring)."""
        x = np.atleast_2d(self.fk(q, strokes="ignore"))
        j_inv = self.jacobian(x, q=q).J_inv
        return -j_inv @ point[:, :self.dims]


class FullPoseParameterColumns(RodParameterColumns):
    """Rod legs on a turning platform: position and rotation rows hold the tool."""

    def held_tool_actuators(self, q: np.ndarray, pose: np.ndarray, point: np.ndarray,
                            rotation: np.ndarray) -> np.ndarray:
        """``(N, n, p)`` ``−J⁺ ∂x/∂p`` (see :meth:`TranslationalParameterColumns.
        held_tool_actuators`)."""
        x = np.atleast_2d(self.fk(q, strokes="ignore"))
        j_inv = self.jacobian(x, q=q).J_inv
        return -j_inv @ np.concatenate([point, rotation], axis=1)


class ChainParameterColumns:
    """Nominal-parameter sensitivities of joint-chain machines."""

    def nominal_sensitivity(self, vector, positions, q: np.ndarray, sens) -> dict:
        """``{position: (point (N, 3), rotation (N, 3), method)}`` for the nominal entries
        ``positions`` of ``vector`` (module docstring); ``sens`` is not needed here."""
        from pkmkit.model.defect_rule import nominal_kind

        if nominal_kind(self) is None:
            return self._element_columns(vector, positions, q)
        return {i: self._direct_difference(vector, i, q) for i in positions}

    def held_tool_actuators(self, q: np.ndarray, pose: np.ndarray, point: np.ndarray,
                            rotation: np.ndarray) -> np.ndarray:
        """``(N, n, p)`` ``−J⁺ ∂x/∂p`` with the rotation about the tool axis (``pose[:, 3:6]``)
        left free (module docstring)."""
        jac = np.atleast_3d(self.jacobian(q=q).J)
        axis = pose[:, 3:6] / np.linalg.norm(pose[:, 3:6], axis=1)[:, None]
        proj = np.zeros((len(q), 6, 6))
        proj[:, :3, :3] = np.eye(3)
        proj[:, 3:, 3:] = np.eye(3) - axis[:, :, None] * axis[:, None, :]
        moved = np.concatenate([point, rotation], axis=1)
        return -np.linalg.pinv(proj @ jac) @ (proj @ moved)

    def _element_columns(self, vector, positions, q) -> dict:
        """Nominal invariants of an element-described chain: each moves one element frame by a
        twist (central differences of the frame alone), composed with the closure
        sensitivity."""
        from pkmkit.machines.parameter_vector import element_frame
        from pkmkit.model.chains import FIXED
        from pkmkit.solve.chains import with_column_twists
        from pkmkit.spatial.rotation import matrix_to_rotvec

        model = self.model
        owners = vector.index.owners
        by_element = {f"element {s.name}": e for e, s in enumerate(model.elements)}
        first = {}
        for i, owner in enumerate(owners):
            first.setdefault(owner, i)
        elements, twists = [], []
        for i in positions:
            e = by_element[owners[i]]
            start = first[owners[i]]
            values = vector.values[start:start + (7 if model.elements[e].type == FIXED else 6)]
            h = GEOMETRY_STEP
            frames = []
            for s in (1.0, -1.0):
                moved = values.copy()
                moved[i - start] += s * h
                frames.append(element_frame(model.elements[e], model.nominal_frames[e], moved))
            rot, o = model.nominal_frames[e][:3, :3], model.nominal_frames[e][:3, 3]
            omega = (matrix_to_rotvec(frames[0][None, :3, :3] @ rot.T)[0]
                     - matrix_to_rotvec(frames[1][None, :3, :3] @ rot.T)[0]) / (2 * h)
            do = (frames[0][:3, 3] - frames[1][:3, 3]) / (2 * h)
            elements.append(e)
            twists.append(np.concatenate([do - np.cross(omega, o), omega]))
        columns = with_column_twists(model, np.array(elements), np.array(twists))
        sens = self._chain_tool_sensitivity(q, None, columns)
        return {i: (sens.point[:, :, j], sens.rotation[:, :, j], "composition")
                for j, i in enumerate(positions)}

    def _direct_difference(self, vector, i, q):
        from pkmkit.spatial.rotation import matrix_to_rotvec, rotvec_to_matrix

        name = vector.index.names[i]
        h = STEP * max(1.0, abs(float(vector.values[i])))
        out = []
        try:
            for s in (1.0, -1.0):
                moved = self.with_parameters(vector.replace({name: vector.values[i] + s * h}))
                out.append(moved.fk(q, full_output=True, strokes="ignore", check_singular=False))
        except PkmError:  # the builder refuses a side: not differentiable here
            nan = np.full((len(q), 3), np.nan)
            return nan, nan, UNDEFINED
        dp = (out[0].pose[:, :3] - out[1].pose[:, :3]) / (2 * h)
        r_plus, r_minus = (rotvec_to_matrix(r.tool_frame[:, 3:]) for r in out)
        omega = matrix_to_rotvec(r_plus @ np.swapaxes(r_minus, 1, 2)) / (2 * h)
        return dp, omega, "central-difference"
