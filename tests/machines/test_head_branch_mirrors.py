"""Which mirrors the head-branch rule takes on the TriMule 600 (issue 22 §3, sixth pass: the
analysis behind the proposed "genuine mirror only" rule, docs/benchmarks.md).

The rule (machines/head_branches.py) solves a row again from its head flipped (Q4 + π, −Q5)
and takes that *mirror solve* where only it is within the strokes, or both or neither are and
its Q4 is strictly nearer home's. The mirror solve is a fresh inverse solve: it may land on
another assembly of the legs, or away from Q4 + π, and still be taken. A *genuine* mirror has
Q4 within FLIP_MARGIN of the kept Q4 + π (mod 2π) and the legs' mode signature
(``mode_signature``) of the kept solution. These tests pin what the rule does today:

- a mirror taken because only it is within the strokes is always genuine (so restricting the
  rule to genuine mirrors cannot change the strokes mask, the volume or the factors over the
  workspace);
- non-genuine mirrors are taken, all with both solutions beyond the strokes (the rows a
  restriction would change: thousands on the study's grids, docs/benchmarks.md) — this test
  fails when the rule changes, to update the analysis.
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

import pkmkit
from pkmkit.analysis.grids import make_grid
from pkmkit.machines.head_branches import FLIP_MARGIN, wrapped

warm_starts = importlib.import_module("pkmkit.machines.warm_starts")

#: The TriMule's default study box (``pkmkit workspace trimule-600``'s widened frame), m.
STUDY_BOX = ((-1.32403, -1.61736, 0.0534526), (1.26296, 1.55038, 1.9013))


def _taken_mirrors(m, points, monkeypatch):
    """Every mirror solve of ``m.ik(points)``: ``(kept u, mirror u, taken)`` stacked."""
    rule = warm_starts.nearest_head_branch
    seen = []

    def recording(solve, targets, lengths, res, reference, flip, *args, **kwargs):
        before = res.u.copy()
        calls = []

        def solve_and_keep(t, u0, tool):
            out = solve(t, u0, tool)
            calls.append((t.copy(), out.u.copy()))
            return out

        rule(solve_and_keep, targets, lengths, res, reference, flip, *args, **kwargs)
        index = {row.tobytes(): k for k, row in enumerate(targets)}  # grid points: distinct
        for t, other in calls:
            rows = np.array([index[row.tobytes()] for row in t], dtype=int)
            kept = before[rows]
            taken = (res.u[rows] == other).all(axis=1) & ~(res.u[rows] == kept).all(axis=1)
            seen.append((kept, other, taken))
        return res

    monkeypatch.setattr(warm_starts, "nearest_head_branch", recording)
    m.ik(points)
    return tuple(np.concatenate(parts) for parts in zip(*seen, strict=True))


@pytest.fixture(scope="module")
def trimule():
    return pkmkit.machine("trimule-600")


def test_taken_mirrors_off_the_branch_are_all_beyond_the_strokes(trimule, monkeypatch):
    m = trimule
    lo, hi = (np.array(b) for b in STUDY_BOX)
    points = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                       resolution=13).points
    kept, mirror, taken = _taken_mirrors(m, points, monkeypatch)
    q4 = 6 + m.model.variables.index("Q4")
    genuine = ((np.abs(wrapped(mirror[:, q4] - kept[:, q4] - np.pi)) <= FLIP_MARGIN)
               & (m.mode_signature(mirror) == m.mode_signature(kept)).all(axis=1))
    kept_in, mirror_in = m._within_strokes(kept), m._within_strokes(mirror)
    assert taken.sum() > 0
    # taken for the strokes (only the mirror within them): always a genuine mirror
    assert genuine[taken & mirror_in & ~kept_in].all()
    assert (taken & mirror_in & ~kept_in).any()
    # taken while not genuine: there are such rows, and both solutions are beyond the strokes
    off = taken & ~genuine
    assert off.any()
    assert not (kept_in[off] | mirror_in[off]).any()
