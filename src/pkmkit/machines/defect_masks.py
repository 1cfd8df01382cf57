"""The machine protocol's defect groups: which defects sit where in the mechanism, as masks
over the defect vector (``machine.defects()`` order), so that defect selection never tests
the family (:mod:`pkmkit.geometric_errors.selection` asks the machine).

- ``machine.loop_defect_mask()`` — ``(d,)`` bool, the defect belongs to a closed loop: every
  defect of rod legs; the legs' elements of a joint chain, not its serial head;
- ``machine.reference_joint_defect_mask()`` — ``(d,)`` bool, the defects of the joint the
  fixed frame is aligned with and kept nominal (the first element of a joint chain's first leg:
  D_ICS^L11 of the Tripteor, D_R0^L1 of the crank–slider); none for rod legs.
"""

from __future__ import annotations

import numpy as np


class RodDefectMasks:
    """Rod legs: every defect is in a loop; no reference joint."""

    def loop_defect_mask(self) -> np.ndarray:
        """``(d,)`` bool, all True (module docstring)."""
        from pkmkit.model.defect_rule import defect_index

        return np.ones(len(defect_index(self)), dtype=bool)

    def reference_joint_defect_mask(self) -> np.ndarray:
        """``(d,)`` bool, all False (module docstring)."""
        from pkmkit.model.defect_rule import defect_index

        return np.zeros(len(defect_index(self)), dtype=bool)


class ChainDefectMasks:
    """Joint chains: the legs' elements are in loops, the head's are not; the first element of
    the first leg is the reference joint."""

    def loop_defect_mask(self) -> np.ndarray:
        """``(d,)`` bool: the defect's element is in a leg (module docstring)."""
        model = self.model
        in_legs = {e for leg in model.legs for e in leg}
        return np.array([e in in_legs for e in model.defect_index.element], dtype=bool)

    def reference_joint_defect_mask(self) -> np.ndarray:
        """``(d,)`` bool: the defect's element is the first of the first leg."""
        first = self.model.legs[0][0]
        return np.asarray(self.model.defect_index.element) == first
