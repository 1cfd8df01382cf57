"""The head-branch rule skips mirrors that cannot be chosen (issue 22 §3, fourth pass): on the
Tripteor, whose Q4 stroke (±15°) reaches less than a quarter turn from home, a row beyond a
stroke with Q4 near home had its mirror (Q4 + π) solved for nothing — the mirror is beyond Q4's
stroke and farther from home. Skipping those solves gives the same inverse model, row by row,
in fewer iterations; the TriMule (Q4 ±180°) solves them as before."""

from __future__ import annotations

import importlib
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid

warm_starts = importlib.import_module("pkmkit.machines.warm_starts")


def _points(m, box, resolution):
    lo, hi = (np.array(b) for b in box)
    return make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                     resolution=resolution).points


def _solved_every_mirror(monkeypatch):
    rule = warm_starts.nearest_head_branch

    def every(*args, **kwargs):
        kwargs["turn_reach"] = np.inf
        return rule(*args, **kwargs)

    monkeypatch.setattr(warm_starts, "nearest_head_branch", every)


@pytest.mark.parametrize("box", [((-0.160, -0.584, 1.818), (-0.039, -0.488, 1.858)),
                                 ((-1.066, -1.315, 1.508), (0.867, 0.231, 2.153))])
def test_the_tripteor_skips_mirrors_beyond_q4s_stroke(box, monkeypatch):
    m = pkmkit.machine("tripteor-x7")
    # the first-order start: with the closed-form start (session 34) a mirror starts from its
    # own solution and costs no iteration, so the counts below could not tell it was skipped
    object.__setattr__(m, "_closed_start_ok", False)
    x = _points(m, box, 13)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        new = m.ik(x, full_output=True)
        _solved_every_mirror(monkeypatch)
        old = m.ik(x, full_output=True)
    np.testing.assert_array_equal(new.status, old.status)
    np.testing.assert_array_equal(new.out_of_stroke, old.out_of_stroke)
    np.testing.assert_array_equal(new.q, old.q)
    np.testing.assert_array_equal(new.solution, old.solution)
    assert new.out_of_stroke.sum() > 0.3 * len(x)
    assert (new.iterations <= old.iterations).all()
    assert (new.iterations < old.iterations).sum() > 0.3 * len(x)  # the mirrors not solved


def test_the_trimule_solves_its_mirrors_as_before(monkeypatch):
    m = pkmkit.machine("trimule-600")
    x = _points(m, ((-1.324, -1.617, 0.053), (1.263, 1.550, 1.901)), 7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        new = m.ik(x, full_output=True)
        _solved_every_mirror(monkeypatch)
        old = m.ik(x, full_output=True)
    np.testing.assert_array_equal(new.iterations, old.iterations)
    np.testing.assert_array_equal(new.q, old.q)
