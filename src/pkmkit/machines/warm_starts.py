"""One meaning of ``fk``'s warm start on every family (issue 19): ``x0`` is a *pose* — rows of
what ``fk`` returns — from which the direct model starts. A rod machine's closure unknowns are
its platform pose, so ``x0`` starts it; a joint chain's are its platform pose **and** passive
joints, which a tool pose (point and axis) does not give: a joint chain takes them as
``start`` (``6 + n_passive`` values per row: platform position, rotation vector, passive joints
— a previous :class:`~pkmkit.machines.chain_results.ChainDirectResult`'s ``platform`` and
``passive`` side by side) and refuses a pose ``x0`` with
:class:`~pkmkit.exceptions.UnsupportedOperationError`. Its former ``x0`` of ``6 + n_passive``
values still works for one release, with a :class:`DeprecationWarning`.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError, UnsupportedOperationError


class ChainWarmStart:
    """The joint chains' ``start`` and their deprecated ``x0``."""

    def _closure_start(self, x0: Any, start: Any) -> tuple[Any, str]:
        """``(warm start or None, the keyword it came by)`` of :meth:`fk`.

        Raises:
            InputError: both given. UnsupportedOperationError: a pose ``x0`` (width 6 where
                the closure needs ``6 + n_passive``).
        """
        if x0 is None:
            return start, "start"
        if start is not None:
            raise InputError("give the closure's warm start as start= alone (x0 is its "
                             "deprecated name)")
        width = np.shape(x0)[-1] if np.ndim(x0) else 1
        unknowns = 6 + len(self.passive_names)
        if width == self.dims and width != unknowns:
            raise UnsupportedOperationError(
                "fk from a warm-start pose x0", self.id, self.family,
                "its closure's unknowns are the platform pose and the passive joints, which a "
                f"tool pose does not give: pass those {unknowns} values per row as start= "
                "(a previous direct result's platform and passive)")
        warnings.warn("x0 of a joint chain's fk is deprecated: pass the platform pose and "
                      "passive joints as start= (x0 is a warm-start pose on every machine)",
                      DeprecationWarning, stacklevel=3)
        return x0, "x0"
