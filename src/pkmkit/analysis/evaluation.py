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
        masks: ``{name: (M,) bool}`` for every name of :data:`MASK_NAMES`.
    """

    q: np.ndarray
    factors: np.ndarray
    condition: np.ndarray
    masks: dict[str, np.ndarray]

    @property
    def feasible(self) -> np.ndarray:
        """``(M,)`` all masks true."""
        return np.logical_and.reduce(list(self.masks.values()))
