"""Exports of a pkmkit machine to the tools around it: a LinuxCNC kinematics module, a Klipper
printer section, a MuJoCo model, a URDF tree with its loop closures. See ``docs/export.md``.

Each format is one module with one public function returning the file's text; a machine a format
cannot express raises :class:`~pkmkit.export.base.UnsupportedExportError` (what and why).
"""

from pkmkit.export.base import UnsupportedExportError

__all__ = ["UnsupportedExportError"]
