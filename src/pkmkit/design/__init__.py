"""Dimensional design: sizing rules (Orthoglide, isotropic five-bar, linear Delta) and
optimisation of any machine."""

from pkmkit.design.design_space import ScalarParameter, scalar_parameters, with_values
from pkmkit.design.five_bar import FiveBarSizing, isotropic_orientations, size_five_bar
from pkmkit.design.linear_delta import LinearDeltaSizing, size_linear_delta
from pkmkit.design.metrics import METRIC_QUANTITIES, METRICS, Region, evaluate_metrics
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
    "METRIC_QUANTITIES",
    "Constraint",
    "DesignProblem",
    "FiveBarSizing",
    "LinearDeltaSizing",
    "Objective",
    "OptimizationResult",
    "OrthoglideSizing",
    "Region",
    "ScalarParameter",
    "Variable",
    "evaluate_metrics",
    "isotropic_orientations",
    "optimize",
    "scalar_parameters",
    "size_five_bar",
    "size_linear_delta",
    "size_orthoglide",
    "with_values",
]
