"""What a machine says about the poses a workspace check rejects, and which indices its
velocity model defines, per family — so that :mod:`pkmkit.analysis.region_check` and
:mod:`pkmkit.analysis.indices` ask the machine instead of testing its family.

- :attr:`velocity_split`: True when the velocity model is ``A ẋ = B q̇`` leg by leg (rod legs:
  the indices include the distances to parallel and serial singularities, from A and B);
  False when J comes from a closure (joint chains: the indices of J alone).
- :meth:`unreachable_reason`, :meth:`out_of_stroke_reason`: the row among rejected samples to
  show and the sentence saying why (a rod machine names the leg too short and by how much, or
  the actuator beyond its stroke; a joint chain's closure names neither).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np


class RodReports:
    """Rod legs: per-leg shortfalls and per-actuator strokes."""

    #: A rod machine's velocity model is split leg by leg (``A ẋ = B q̇``).
    velocity_split: ClassVar[bool] = True

    def unreachable_reason(self, points: np.ndarray) -> tuple[int, str]:
        """``(k, why)``: the sample of ``points (M, dims)`` (all out of reach) whose leg falls
        shortest, and that leg's shortfall (m)."""
        short = self.ik(points, full_output=True, strokes="ignore").shortfall
        k = int(np.nanargmax(short.max(axis=1)))
        leg = int(np.nanargmax(short[k]))
        return k, f"{self.model.leg_names[leg]} too short by {short[k, leg]:.6g} m"

    def out_of_stroke_reason(self, q: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                             names: Any) -> tuple[int, str]:
        """``(k, why)``: the row of ``q (M, n)`` (all beyond a limit) furthest beyond one, the
        actuator (``names``), its value and the excess over ``lower``/``upper`` (m)."""
        excess = np.maximum(lower - q, q - upper)
        k, a = np.unravel_index(int(np.nanargmax(excess)), excess.shape)
        side = "below q_min" if q[k, a] < lower[a] else "above q_max"
        return int(k), (f"{names[a]} = {q[k, a]:.6g} m is {side} by {excess[k, a]:.6g} m")


class ChainReports:
    """Joint chains: a closure that fails, or a joint (actuator or passive) beyond its range."""

    #: A joint chain's J comes from its closure (no A, B split).
    velocity_split: ClassVar[bool] = False

    def unreachable_reason(self, points: np.ndarray) -> tuple[int, str]:
        """``(0, why)``: the first sample; the closure names no leg."""
        return 0, f"the inverse model closes no loop there ({len(points)} samples)"

    def out_of_stroke_reason(self, q: np.ndarray, lower: np.ndarray, upper: np.ndarray,
                             names: Any) -> tuple[int, str]:
        """``(0, why)``: the first row; passive joints count too, so no actuator is named."""
        return 0, f"a joint (actuator or passive) leaves its range ({len(q)} samples)"
