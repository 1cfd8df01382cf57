"""The result of evaluating workspace criteria at poses (shared by every machine family)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PoseEvaluation:
    """Criteria evaluated at M poses (flat arrays).

    Attributes:
        q: ``(M, n)`` actuator coordinates (NaN where unreachable), m.
        factors: ``(M, n)`` velocity transmission factors, decreasing.
        condition: ``(M,)``.
        masks: ``{name: (M,) bool}`` for every name of :data:`MASK_NAMES` (and
            ``"stiffness"`` with a stiffness criterion).
        stiffness: ``(M,)`` smallest translational stiffness (N/m, NaN where unreachable or
            singular) when the criteria ask for stiffness, else None.
        deflection: ``(M,)`` norm of the deflection under the criteria's wrench (m), or None.
    """

    q: np.ndarray
    factors: np.ndarray
    condition: np.ndarray
    masks: dict[str, np.ndarray]
    stiffness: np.ndarray | None = None
    deflection: np.ndarray | None = None

    @property
    def feasible(self) -> np.ndarray:
        """``(M,)`` all masks true."""
        return np.logical_and.reduce(list(self.masks.values()))
