"""Dimensional design: sizing rules (Orthoglide, isotropic five-bar) and optimisation."""

from pkmkit.design.five_bar import FiveBarSizing, isotropic_orientations, size_five_bar
from pkmkit.design.metrics import METRICS, Region, evaluate_metrics
from pkmkit.design.optimize import (
    Constraint,
    DesignProblem,
    Objective,
    OptimizationResult,
    Variable,
    optimize,
)
from pkmkit.design.orthoglide import OrthoglideSizing, size_orthoglide

__all__ = [
    "METRICS",
    "Constraint",
    "DesignProblem",
    "FiveBarSizing",
    "Objective",
    "OptimizationResult",
    "OrthoglideSizing",
    "Region",
    "Variable",
    "evaluate_metrics",
    "isotropic_orientations",
    "optimize",
    "size_five_bar",
    "size_orthoglide",
]
