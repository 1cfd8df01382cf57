"""The one-pose record's stroke excess in Python floats (:func:`pkmkit.machines.strokes.
row_excess`, session 35) against the batch path's :func:`~pkmkit.machines.strokes.signed_excess`
(the oracle): the same bits on values within, at, just beyond (by less and more than
``STROKE_TOL``) and far beyond either end, NaN and infinite values, one-sided strokes; and a
joint chain's one-pose ``full_output`` record with ``strokes="ignore"`` beyond a stroke against
the batch row's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import chain_one
from pkmkit.machines.strokes import STROKE_TOL, row_excess, signed_excess, stroke_ends


def test_the_excess_is_signed_excess_to_the_bit():
    rng = np.random.default_rng(0)
    lower = np.array([0.1, -1.0, -np.inf, 0.2, -0.5])
    upper = np.array([0.9, 1.0, 0.3, np.inf, 0.5])
    strokes = stroke_ends(lower, upper)
    edges = np.concatenate([lower, upper])
    edges = edges[np.isfinite(edges)]
    near = np.concatenate([edges + d for d in (0.0, 0.5 * STROKE_TOL, -0.5 * STROKE_TOL,
                                               2 * STROKE_TOL, -2 * STROKE_TOL)])
    values = np.concatenate([rng.uniform(-3, 3, 2000), near, [np.nan, np.inf, -np.inf]])
    rows = rng.choice(values, (3000, 5))
    ref = signed_excess(rows, lower, upper)
    got = np.array([row_excess(r.tolist(), strokes) for r in rows])
    assert np.array_equal(got, ref, equal_nan=True)
    assert np.array_equal(np.signbit(got), np.signbit(ref))
    assert (ref != 0).any(axis=1).mean() > 0.5


@pytest.mark.parametrize("name", ["tripteor-x7", "trimule-600"])
def test_a_one_pose_record_beyond_a_stroke_is_the_batch_rows(name):
    pytest.importorskip("numba")
    m = pkmkit.machine(name)
    act = np.flatnonzero(m.model.actuated)
    lo, hi = m.model.q_min[act], m.model.q_max[act]
    q = lo + (hi - lo) * np.random.default_rng(1).uniform(-0.1, 1.1, (60, len(act)))
    x = m.fk(q, strokes="ignore")
    x = x[np.isfinite(x).all(axis=1)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", StrokeWarning)
        for _ in range(2):  # the second single call runs compiled
            m.ik(x[0], full_output=True, strokes="ignore")
        batch = m.ik(x, full_output=True, strokes="ignore")
        beyond = 0
        for j, pose in enumerate(x):
            one = chain_one.inverse_record(m, pose, "ignore")
            if one is None:
                continue
            assert np.array_equal(one.stroke_excess, batch.stroke_excess[j])
            beyond += bool((one.stroke_excess != 0).any())
    assert beyond >= 5
