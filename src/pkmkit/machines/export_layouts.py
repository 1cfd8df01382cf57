"""The layout a machine declares to the export formats (:mod:`pkmkit.export`), so that a
format's table of what it supports reads one protocol attribute instead of testing the family.

``export_layout`` is one of :data:`EXPORT_LAYOUTS`: ``"translational"`` (rods on a translating
3-D platform), ``"planar"`` (rods on a platform in the x-y plane, 2 actuators),
``"full-pose"`` (rods on a 6-DOF platform) or ``"chain"`` (serial R/P chains closed on the
platform, which no rod format expresses).
"""

from __future__ import annotations

from typing import ClassVar

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


class ChainLayout:
    """Joint chains."""

    #: Always ``"chain"``.
    export_layout: ClassVar[str] = "chain"
