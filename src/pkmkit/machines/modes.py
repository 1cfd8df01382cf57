"""Assembly-mode names and sample poses shared by the rod-leg machine classes.

A rod-leg machine (:class:`~pkmkit.machines.machine.Machine`,
:class:`~pkmkit.machines.full_pose.FullPoseMachine`) names its assembly modes by the sign of
det A (``model.mode_names``: negative sign first) and knows the sign at home
(``_working_mode``); both classes read them through this mixin.
"""

from __future__ import annotations

import numpy as np


class ModeNaming:
    """Mixin: needs ``model.mode_names``, ``_working_mode``, ``home_pose``, ``extra_poses``."""

    @property
    def working_mode(self) -> int:
        """Sign of det A in the working assembly mode (the one containing the home pose)."""
        return self._working_mode

    @property
    def mode_labels(self) -> tuple[str, str]:
        """Assembly-mode names, working mode first."""
        neg, pos = self.model.mode_names
        return (neg, pos) if self._working_mode < 0 else (pos, neg)

    def mode_label(self, sign: int) -> str:
        """Name of the assembly mode with det A of sign ``sign`` (±1)."""
        return self.model.mode_names[0 if sign < 0 else 1]

    def in_working_mode(self, jacobians, tol: float) -> np.ndarray:
        """``(N,)`` bool: the configurations of a velocity model (``jacobian(...)``) lie in the
        working assembly mode (sign of det A) at least ``tol`` from a parallel singularity
        (``parallel_measure``). Every machine answers it (a joint chain from its closure)."""
        with np.errstate(invalid="ignore"):
            return ((np.sign(jacobians.det_A) == self.working_mode)
                    & (jacobians.parallel_measure >= tol))

    def reference_poses(self) -> dict[str, np.ndarray]:
        """Named sample poses, ``home`` first, each ``(dims,)`` (m, and rad for rotations)."""
        poses = {"home": self.home_pose}
        poses.update({k: np.asarray(v, dtype=float) for k, v in self.extra_poses.items()})
        return poses
