"""What the elastostatic models ask a machine: which members are elastic and how a
configuration is given (part of the machine protocol, :class:`StiffnessModel`).

The virtual-joint models of :mod:`pkmkit.stiffness` differ by family where the physics does:
rod-leg machines (translating or full-pose platforms) have rods — axial springs between ball
joints — and are evaluated at poses (their inverse model is a closed form); joint-chain machines
have links — 6×6 beam springs — and are evaluated at actuator coordinates (the forward model
places the passive joints). These properties say so, so that the stiffness code never tests the
family.
"""

from __future__ import annotations

#: The elastic members of each family: ``"rods"`` (axial springs) or ``"links"`` (beams).
ELASTIC_MEMBERS = {"translational": "rods", "full-pose": "rods", "chain": "links"}

#: Twist coordinates of a compliance matrix: translation then rotation.
TWIST_NAMES = ("dx", "dy", "dz", "rx", "ry", "rz")


class StiffnessModel:
    """Mixin of the stiffness part of the protocol (needs ``family``, ``dims`` and
    ``orientation_fixed`` from the class)."""

    @property
    def elastic_members(self) -> str:
        """``"rods"``: the machine's elastic members are rods with a ball joint at each end
        (an axial spring each, data ``rod_section``); ``"links"``: bodies of joint chains
        (6×6 beam springs, data ``link_section`` and per-element sections)."""
        return ELASTIC_MEMBERS[self.family]

    @property
    def stiffness_from_actuators(self) -> bool:
        """True when the stiffness is evaluated at actuator coordinates (joint chains: the
        forward model gives the passive joints; a tool pose goes through the inverse model
        first); False when at poses (rod legs)."""
        return self.elastic_members == "links"

    @property
    def twist_names(self) -> tuple[str, ...]:
        """Names of the twist coordinates of the machine's stiffness: ``dx, dy[, dz]`` for a
        translating platform (its compliance is that of a point), ``dx … rz`` otherwise."""
        return TWIST_NAMES[: self.dims] if self.orientation_fixed else TWIST_NAMES
