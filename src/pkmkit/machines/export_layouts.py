"""The layout a machine declares to the export formats (:mod:`pkmkit.export`), so that a
format's table of what it supports reads one protocol attribute instead of testing the family.

``export_layout`` is one of :data:`EXPORT_LAYOUTS`: ``"translational"`` (rods on a translating
3-D platform), ``"planar"`` (rods on a platform in the x-y plane, 2 actuators),
``"full-pose"`` (rods on a 6-DOF platform) or ``"chain"`` (serial R/P chains closed on the
platform, which no rod format expresses).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pkmkit.machines.head_branches import head_flip_variables

#: Every machine's ``export_layout`` is one of these.
EXPORT_LAYOUTS = ("translational", "planar", "full-pose", "chain")


class TranslationalLayout:
    """A translating platform: 3-D, or planar when its poses have two coordinates."""

    @property
    def export_layout(self) -> str:
        """``"planar"`` for a machine with 2-D poses, else ``"translational"``."""
        return "planar" if self.dims == 2 else "translational"


class FullPoseLayout:
    """A 6-DOF rod platform."""

    #: Always ``"full-pose"``.
    export_layout: ClassVar[str] = "full-pose"


@dataclass(frozen=True)
class ChainTables:
    """A joint-chain machine as the tables a format writes out (SI: m, rad), its calibrated
    defects applied: pkmkit's chain product ``T = D_1 M_1(q_1) D_2 M_2(q_2) …``
    (:mod:`pkmkit.model.chains`) element by element.

    Attributes:
        element_names: ``(E,)`` pkmkit's element names; element_types: ``(E,)`` ``"R"``,
            ``"P"`` or ``"F"``.
        rotations, positions: ``(E, 3, 3)`` and ``(E, 3)`` each element's frame D_e in the
            previous one (``model.frames``).
        element_variable: ``(E,)`` the joint variable of each element (−1 for a fixed frame).
        legs, leg_names: the chains from the base to the platform frame (element indices).
        head: the chain from the platform frame to the tool frame.
        variables: ``(V,)`` names of the joint variables; revolute: ``(V,)`` bool.
        actuated, passive: variable indices of the actuators (pkmkit's actuator order) and of
            the passive joints the closure solves.
        q_min, q_max: ``(V,)`` strokes (±inf when unlimited); checked: ``(V,)`` the joints
            whose strokes pkmkit's models check (the actuators and the legs' joints).
        home_values: ``(V,)`` every joint at home; home_platform: ``(6,)`` platform position and
            rotation vector at home.
        closure_length: the closures' characteristic length L (m); tool_length: m.
        home_misfit: the legs' least-squares closure residual at home (m; ~0 when the defects
            are compatible).
        head_flip: ``(turn, tilt)`` variable indices of a two-branch head (the inverse model's
            branch rule, :mod:`pkmkit.machines.head_branches`), or None.
    """

    element_names: tuple[str, ...]
    element_types: tuple[str, ...]
    rotations: np.ndarray
    positions: np.ndarray
    element_variable: np.ndarray
    legs: tuple[tuple[int, ...], ...]
    leg_names: tuple[str, ...]
    head: tuple[int, ...]
    variables: tuple[str, ...]
    revolute: np.ndarray
    actuated: np.ndarray
    passive: np.ndarray
    q_min: np.ndarray
    q_max: np.ndarray
    checked: np.ndarray
    home_values: np.ndarray
    home_platform: np.ndarray
    closure_length: float
    tool_length: float
    home_misfit: float
    head_flip: tuple[int, int] | None = None


class ChainLayout:
    """Joint chains."""

    #: Always ``"chain"``.
    export_layout: ClassVar[str] = "chain"

    def chain_tables(self) -> ChainTables:
        """The machine's chains as tables for the export formats (:class:`ChainTables`)."""
        model = self.model
        var = np.asarray(model.element_variable, dtype=int)
        types = tuple(e.type for e in model.elements)
        revolute = np.zeros(len(model.variables), dtype=bool)
        revolute[var[np.array([t == "R" for t in types])]] = True
        return ChainTables(
            element_names=tuple(e.name for e in model.elements), element_types=types,
            rotations=np.array(model.frames[:, :3, :3]), positions=np.array(model.frames[:, :3, 3]),
            element_variable=var, legs=tuple(model.legs), leg_names=tuple(model.leg_names),
            head=tuple(model.head), variables=tuple(model.variables), revolute=revolute,
            actuated=np.flatnonzero(model.actuated), passive=np.array(self.passive_variables),
            q_min=np.array(model.q_min, dtype=float), q_max=np.array(model.q_max, dtype=float),
            checked=np.asarray(model.loop_variables | model.actuated, dtype=bool),
            home_values=self.home_values, home_platform=self.home_platform,
            closure_length=float(model.characteristic_length),
            tool_length=float(self.tool_length), home_misfit=float(self.home_closure_residual),
            head_flip=head_flip_variables(self.kind, tuple(model.variables)))
