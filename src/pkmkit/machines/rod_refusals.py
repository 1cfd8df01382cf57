"""The typed errors of a translational rod-leg machine's single-pose ``ik`` and ``fk``: a
mixin of :class:`~pkmkit.machines.machine.Machine` that turns a row's status into the error
that says why (which leg is short, which assembly mode failed)."""

from __future__ import annotations

import numpy as np

from pkmkit.exceptions import (
    ConvergenceError,
    InputError,
    NoAssemblyError,
    SingularConfigurationError,
    UnreachablePoseError,
)
from pkmkit.machines.common import MAX_COORDINATE
from pkmkit.status import Status


class RodRefusals:
    """``_raise_inverse`` / ``_raise_direct`` of a machine with ``_closed`` (its closed form),
    ``model`` and ``mode_label``."""

    def _raise_inverse(self, xb: np.ndarray, status: int, iterations) -> None:
        if status == Status.INVALID_INPUT:
            raise InputError(f"pose {xb[0].tolist()} has a coordinate beyond "
                             f"{MAX_COORDINATE:g} m")
        short = self._closed.shortfall(xb)[0]
        if status == Status.UNREACHABLE or (short > 0).any():
            leg = int(np.argmax(short))
            raise UnreachablePoseError(leg, self.model.leg_names[leg], short[leg],
                                       too_long=bool(self._closed.too_long(xb)[0, leg]))
        if status == Status.WRONG_MODE:
            raise ConvergenceError(
                "the numeric inverse model converged to another branch than requested; "
                "pass q0 closer to the wanted solution"
            )
        raise ConvergenceError(
            f"the numeric inverse model did not converge ({Status(status).label}) "
            f"after {int(iterations[0])} iterations"
        )

    def _raise_direct(self, q: np.ndarray, sign: int, status: int) -> None:
        label = self.mode_label(sign)
        if status == Status.INVALID_INPUT:
            raise InputError(f"q = {q.tolist()} has a coordinate beyond {MAX_COORDINATE:g} m")
        if status == Status.SINGULAR:
            raise SingularConfigurationError(
                f"q = {q.tolist()}: the leg sphere centres are aligned or nearly so (a parallel "
                "singularity): the direct model has no isolated solution, or none that rounding "
                "lets it resolve to 1e-9 m"
            )
        if status == Status.NO_ASSEMBLY:
            raise NoAssemblyError(
                f"q = {q.tolist()} admits no real assembly in mode {label!r}: the legs cannot "
                "meet at a common platform point"
            )
        if status == Status.WRONG_MODE:
            raise ConvergenceError(
                f"the numeric direct model converged to the other assembly mode than {label!r}; "
                "pass x0 closer to the wanted solution"
            )
        raise ConvergenceError(f"the numeric direct model failed ({Status(status).label})")
