"""The one-pose joint-chain inverse's record (``chain_one.inverse_record``, the Numba path
behind ``m.ik(x, full_output=True)``) counts the iterations and the residual of the solve it
ran, as the batch path's row of the same pose counts them (the same Newton iterations from
the same start: the counts are equal, not close)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one
from pkmkit.machines.chain_starts import closed_starts
from pkmkit.numerics import jit
from tests.machines.test_chain_one import NAMES, batch_ik, fresh, within_stroke_poses

pytestmark = pytest.mark.skipif(not jit.numba_available() or jit.mode() == "0",
                                reason="the one-pose paths run the compiled closure")


@pytest.mark.parametrize("name", NAMES)
def test_iterations_and_residual_are_the_batch_rows(name):
    m = fresh(name)
    _, poses = within_stroke_poses(m, 12, seed=3)
    fast = 0
    # from the TriMule's closed-form start (the solution to ~1e-15) the solve often stops at
    # its first test; from the first-order start it always iterates
    floor = 0 if closed_starts(m, np.zeros((0, 6)), np.zeros(0)) is not None else 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for x in poses:
            one = chain_one.inverse_record(m, x, "ignore")
            if one is None:  # the batch path decides this pose
                continue
            fast += 1
            row = batch_ik(m, x, full_output=True, strokes="ignore")
            np.testing.assert_allclose(one.q, row.q, rtol=0, atol=1e-12)
            assert int(one.iterations) == int(row.iterations) >= floor
            assert float(one.residual) <= 1e-9 and float(row.residual) <= 1e-9
    assert fast >= len(poses) // 3
