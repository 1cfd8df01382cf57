"""Per-pose status codes shared by every batched computation.

Batched calls never raise for one bad row: they return NaN for that row and a status code.
``Status`` is an :class:`enum.IntEnum`, so a status array is a plain integer NumPy array that
compares with the members (``status == Status.OK``).
"""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np


class Status(IntEnum):
    """Outcome of one pose (row) of a batched call."""

    OK = 0
    #: inverse model: a leg cannot close (the pose is out of reach).
    UNREACHABLE = 1
    #: direct model: no real assembly for these actuator coordinates (or not in the requested mode).
    NO_ASSEMBLY = 2
    #: numeric engine: iteration limit reached before convergence.
    NOT_CONVERGED = 3
    #: the input row holds NaN or infinity.
    INVALID_INPUT = 4
    #: the configuration is singular for the requested quantity.
    SINGULAR = 5
    #: numeric engine: converged, but to another assembly mode / working mode than requested.
    WRONG_MODE = 6
    #: numeric engine: converged to a least-squares point whose residual is not zero.
    INCONSISTENT = 7
    #: a joint value lies outside its stroke (joint-chain machines asked to refuse such rows).
    OUT_OF_STROKE = 8

    @property
    def label(self) -> str:
        """Lower-case, hyphenated name used in JSON and CSV output (e.g. ``"no-assembly"``)."""
        return self.name.lower().replace("_", "-")


def status_labels(status: np.ndarray) -> list[str]:
    """Labels of an integer status array, flattened (shape ``(N,)`` → list of N strings)."""
    import numpy as np  # imported here: `import pkmkit` (and `pkmkit --help`) needs no NumPy

    return [Status(int(s)).label for s in np.ravel(status)]
