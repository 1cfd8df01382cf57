"""Figures (matplotlib)."""

from pkmkit.plot.drawing import draw_machine, machine_geometry

__all__ = ["draw_machine", "machine_geometry"]
