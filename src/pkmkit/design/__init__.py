"""Dimensional design: sizing rules (Orthoglide, isotropic five-bar) and optimisation."""

from pkmkit.design.five_bar import FiveBarSizing, isotropic_orientations, size_five_bar
from pkmkit.design.orthoglide import OrthoglideSizing, size_orthoglide

__all__ = [
    "FiveBarSizing",
    "OrthoglideSizing",
    "isotropic_orientations",
    "size_five_bar",
    "size_orthoglide",
]
