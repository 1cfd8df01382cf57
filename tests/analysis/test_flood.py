"""Workspace grids evaluated by a flood fill from home (issue 22 §3, :mod:`pkmkit.analysis.flood`):
the kept part, its measure, inscribed box, factors and GCI are the whole grid's; the points
never evaluated are marked so, not failing."""

from __future__ import annotations

import io
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import ndimage

import pkmkit
import pkmkit.analysis.flood as flood
from pkmkit.analysis.criteria import Criteria
from pkmkit.analysis.evaluation import PoseEvaluation
from pkmkit.analysis.grids import make_grid
from pkmkit.analysis.workspace import _connected_part, compute_workspace
from pkmkit.progress import progress_display, tracked

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


# --- the fill itself, on a fake machine whose feasible set is a given mask -----------------


class _MaskMachine:
    """Feasible where ``mask`` is true at the grid point; the inverse's "solution" is the
    point itself; every ``ik`` call's starts are recorded."""

    id = "mask"
    inverse_continues = True

    def __init__(self, grid, mask, no_start=None):
        self.grid, self.mask = grid, mask
        self.no_start = no_start  # flat indices whose solution is not a start
        self.calls = []

    def ik(self, points, full_output=True, start=None):
        self.calls.append((points.copy(), None if start is None else start.copy()))
        return SimpleNamespace(solution=points.copy())

    def continuation_starts(self, points, start):  # no better start (the protocol's)
        return start

    def continues_from(self, solution):
        ok = np.ones(len(solution), dtype=bool)
        if self.no_start is not None:
            ok &= ~np.isin(self._flat(solution), self.no_start)
        return ok

    def _flat(self, points):
        index = [np.rint((points[:, k] - axis[0]) / self.grid.step).astype(int)
                 for k, axis in zip(self.grid.free, self.grid.axes, strict=True)]
        return np.ravel_multi_index(index, self.grid.shape)


def _fake_chunk(machine, points, criteria, factors=True, inverse=None):
    ok = machine.mask.ravel()[machine._flat(points)]
    n = len(points)
    return PoseEvaluation(q=points[:, :2].copy(), factors=np.ones((n, 2)),
                          condition=np.ones(n),
                          masks={"reachable": np.ones(n, bool), "strokes": ok.copy(),
                                 "bounds": ok.copy(), "condition": ok.copy(), "mode": ok.copy()})


def _grid(shape):
    upper = [0.1 * (n - 1) for n in shape]
    return make_grid([0.0] * len(shape), upper, free=list(range(len(shape))),
                     base=[0.0] * len(shape), names=["x", "y", "z"][:len(shape)],
                     resolution=max(shape))


def _flooded(monkeypatch, mask, home, no_start=None):
    grid = _grid(mask.shape)
    assert grid.shape == mask.shape
    m = _MaskMachine(grid, mask, no_start)
    monkeypatch.setattr(flood, "_evaluate_chunk", _fake_chunk)
    return grid, m, flood.flood_grid(m, grid, Criteria(), np.asarray(home, float))


@pytest.mark.parametrize("seed", range(12))
def test_the_kept_part_is_the_whole_grids_and_only_its_rim_is_evaluated(monkeypatch, seed):
    rng = np.random.default_rng(seed)
    shape = (9, 8, 7) if seed % 2 else (15, 13)
    mask = rng.random(shape) < 0.62
    home = rng.uniform(0, 0.1 * (min(shape) - 1), len(shape))
    grid, m, out = _flooded(monkeypatch, mask, home)
    kept_whole, reference = _connected_part(mask, grid, home)
    if out is None:  # no feasible seed: the whole grid keeps the largest part
        assert reference == "largest connected part (home not in it)"
        return
    ev, evaluated = out
    kept, flood_reference = _connected_part(ev.feasible.reshape(shape), grid, home)
    assert flood_reference == reference
    np.testing.assert_array_equal(kept, kept_whole)
    # evaluated: the part, its face neighbours, and the seeds' cell around home
    rim = ndimage.binary_dilation(kept, ndimage.generate_binary_structure(len(shape), 1))
    assert (evaluated.reshape(shape) >= rim).all()
    index = grid.nearest_index(home)
    cell = np.zeros(shape, bool)
    cell[tuple(slice(max(i - 1, 0), i + 2) for i in index)] = True
    assert not (evaluated.reshape(shape) & ~rim & ~cell).any()
    # no point twice; masks False and q NaN where not evaluated
    assert sum(len(p) for p, _ in m.calls) == int(evaluated.sum())
    assert not any(v[~evaluated].any() for v in ev.masks.values())
    assert np.isnan(ev.q[~evaluated]).all()


def test_each_point_starts_from_a_feasible_neighbour_the_one_behind_first(monkeypatch):
    mask = np.ones((6, 5), dtype=bool)
    mask[2, 1:] = False  # a wall: the points beyond it are reached around its end
    home = [0.0, 0.4]  # grid point (0, 4)
    no_start = [np.ravel_multi_index((1, 0), (6, 5))]
    _, m, out = _flooded(monkeypatch, mask, home, no_start=no_start)
    ev, evaluated = out
    assert evaluated.all()
    feasible = ev.feasible.reshape(mask.shape)
    seen = np.zeros(mask.shape, bool)
    seen[0, 4] = True
    for points, start in m.calls[1:]:
        index = m._flat(points)
        start = np.full_like(points, np.nan) if start is None else start  # all from home
        for flat, row in zip(index, start, strict=True):
            i = np.unravel_index(flat, mask.shape)
            if not np.isfinite(row).all():  # from home: no neighbour feasible before to start from
                neighbours = [np.ravel_multi_index(j, mask.shape) for j in _neighbours(i, mask)
                              if seen[j] and feasible[j]]
                assert set(neighbours) <= {np.ravel_multi_index((1, 0), mask.shape)}
                continue
            j = np.unravel_index(m._flat(row[None])[0], mask.shape)
            assert seen[j] and feasible[j]
            assert sum(abs(a - b) for a, b in zip(i, j, strict=True)) == 1
            behind = (i[0] - 1, i[1])
            if i[0] > 0 and seen[behind] and feasible[behind] and behind != (1, 0):
                assert j == behind  # the whole grid's continuation neighbour when it is there
        seen.ravel()[index] = True


def _neighbours(i, mask):
    for axis in range(mask.ndim):
        for step in (-1, 1):
            j = list(i)
            j[axis] += step
            if 0 <= j[axis] < mask.shape[axis]:
                yield tuple(j)


def test_large_wavefronts_are_evaluated_in_chunks(monkeypatch):
    mask = np.ones((9, 9), dtype=bool)
    mask[4, :7] = False
    whole = _flooded(monkeypatch, mask, [0.1, 0.2])[2]
    monkeypatch.setattr(flood, "EVALUATION_CHUNK", 3)
    _, m, chunked = _flooded(monkeypatch, mask, [0.1, 0.2])
    assert max(len(points) for points, _ in m.calls) == 3
    np.testing.assert_array_equal(chunked[1], whole[1])
    np.testing.assert_array_equal(chunked[0].feasible, whole[0].feasible)
    np.testing.assert_array_equal(chunked[0].q, whole[0].q)


def test_home_off_the_grid_or_no_feasible_seed_needs_the_whole_grid(monkeypatch):
    mask = np.zeros((7, 7), dtype=bool)
    mask[5:, 5:] = True
    assert _flooded(monkeypatch, mask, [0.1, 0.1])[2] is None  # home's cell all infeasible
    assert _flooded(monkeypatch, mask, [2.0, 0.1])[2] is None  # home beyond the grid


def test_the_progress_bar_counts_the_points_evaluated(monkeypatch):
    stream, bars = io.StringIO(), []

    def kept(*args, **kwargs):
        bars.append(tracked(*args, **kwargs))
        return bars[-1]

    monkeypatch.setattr(flood, "tracked", kept)
    mask = np.zeros((8, 8), dtype=bool)
    mask[:5, :5] = True
    with progress_display(True, delay=0.0, stream=stream):
        out = _flooded(monkeypatch, mask, [0.2, 0.2])[2]
    assert "flood fill from home, points evaluated" in stream.getvalue()
    assert bars[0].total == 64 and bars[0].n == int(out[1].sum()) == 25 + 10


# --- joint chains: flood against the whole grid -------------------------------------------


def _compare(m, grid, criteria=None):
    criteria = criteria or Criteria()
    fl = compute_workspace(m, grid, criteria, refine=False)
    whole = compute_workspace(m, grid, replace(criteria, whole_grid=True), refine=False)
    assert whole.evaluated is None and fl.evaluated is not None
    assert 0 < fl.points_evaluated < grid.size
    np.testing.assert_array_equal(fl.feasible, whole.feasible)
    assert fl.feasible.any() and fl.reference == whole.reference
    keep = fl.feasible
    np.testing.assert_allclose(fl.q[keep], whole.q[keep], rtol=0, atol=1e-12)
    np.testing.assert_allclose(fl.factors[keep], whole.factors[keep], rtol=1e-10)
    np.testing.assert_allclose(fl.condition[keep], whole.condition[keep], rtol=1e-10)
    ev = fl.evaluated
    for name, mask in fl.masks.items():  # the same verdicts where evaluated, none elsewhere
        np.testing.assert_array_equal(mask[ev], whole.masks[name][ev])
        assert not mask[~ev].any()
    assert np.isnan(fl.condition[~ev]).all()
    assert fl.measure == whole.measure
    assert fl.global_conditioning_index() == pytest.approx(whole.global_conditioning_index(),
                                                           rel=1e-12)
    assert fl.faces_reached() == whole.faces_reached()
    assert fl.faces_reached(2) == whole.faces_reached(2)
    assert (fl.inscribed is None) == (whole.inscribed is None)
    if fl.inscribed is not None:
        assert fl.inscribed.side == whole.inscribed.side
        np.testing.assert_array_equal(fl.inscribed.center, whole.inscribed.center)
    return fl, whole


def test_tripteor_flood_is_the_whole_grid():
    m = pkmkit.machine("tripteor-x7")
    lo, hi = m.default_box()
    grid = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                     resolution=15)
    fl = _compare(m, grid)[0]
    assert fl.reference == "home"


def test_tripteor_flood_from_the_cell_around_home():
    """Home's own grid point beyond a stroke: the fill starts from the feasible points of the
    cell around it (the study's "home (within one grid step of it)")."""
    m = pkmkit.machine("tripteor-x7")
    # a point beyond Q5's stroke (home is at its end)
    point = m.home_pose[:3] + np.array([3.8e-5, 4.4e-5, 1.01e-3])
    half = np.array([6, 6, 4]) * 0.004
    grid = make_grid(point - half, point + half, free=(0, 1, 2), base=m.home_pose,
                     names=m.pose_names, resolution=13)  # step 4 mm, a point at `point`
    fl = _compare(m, grid)[0]
    assert fl.reference == "home (within one grid step of it)"


def test_a_chain_file_in_a_plane_by_flood_is_the_whole_grid():
    m = pkmkit.load(str(EXAMPLES / "planar-3rpr.toml"))
    lo, hi = m.default_box()
    grid = make_grid(lo[:2], hi[:2], free=(0, 1), base=m.home_pose, names=m.pose_names,
                     resolution=21)
    fl, whole = _compare(m, grid)
    assert fl.points_evaluated < grid.size // 2
    # a figure draws the points never evaluated as such, not as failing a criterion
    from pkmkit.plot.maps import _CLASSES, classify  # Matplotlib: imported when run, not collected

    classes, names = classify(fl), [name for name, _ in _CLASSES]
    assert (classes[~fl.evaluated] == names.index("not evaluated")).all()
    assert (classes[fl.evaluated] == classify(whole)[fl.evaluated]).all()
    _compare(m, grid, Criteria(kappa_max=8.0))  # a tighter part, the same by both


def test_closed_form_machines_evaluate_the_whole_grid():
    m = pkmkit.machine("orthoglide")
    lo, hi = m.default_box()
    grid = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                     resolution=9)
    assert compute_workspace(m, grid, refine=False, inscribed=False).evaluated is None
    tri = pkmkit.machine("tripteor-x7")
    assert not flood.floods(tri, Criteria(connected=False))
    assert not flood.floods(tri, Criteria(whole_grid=True))
    assert not flood.floods(tri, Criteria(), scheduler="local:1")
    assert flood.floods(tri, Criteria())


def test_tripteor_flood_with_a_stiffness_criterion_and_a_wrench():
    m = pkmkit.machine("tripteor-x7")
    lo, hi = m.default_box()
    grid = make_grid(lo, hi, free=(0, 1, 2), base=m.home_pose, names=m.pose_names,
                     resolution=11)
    wrench = (0.0, 0.0, -100.0, 0.0, 0.0, 0.0)
    plain = compute_workspace(m, grid, Criteria(wrench=wrench), refine=False, inscribed=False)
    bound = float(np.median(plain.stiffness[plain.feasible]))
    crit = Criteria(min_stiffness=bound, wrench=wrench)
    fl, whole = _compare(m, grid, crit)
    assert "stiffness" in fl.masks and fl.feasible.sum() < plain.feasible.sum()
    keep = fl.feasible
    np.testing.assert_allclose(fl.stiffness[keep], whole.stiffness[keep], rtol=1e-10)
    np.testing.assert_allclose(fl.deflection[keep], whole.deflection[keep], rtol=1e-10)
    assert np.isnan(fl.stiffness[~fl.evaluated]).all()
