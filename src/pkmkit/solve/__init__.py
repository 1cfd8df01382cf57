"""The batched least-squares engine and the rod-closure problems it solves."""

from pkmkit.solve.least_squares import SolveResult, solve_least_squares
from pkmkit.solve.rod_closure import (
    InstantaneousMobility,
    closure_jacobians,
    instantaneous_mobility,
    rod_vectors,
    solve_direct,
    solve_inverse,
)

__all__ = [
    "InstantaneousMobility",
    "SolveResult",
    "closure_jacobians",
    "instantaneous_mobility",
    "rod_vectors",
    "solve_direct",
    "solve_inverse",
    "solve_least_squares",
]
