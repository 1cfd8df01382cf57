"""The TriMule's head rule skips the mirrors of targets where no configuration is within the
strokes (issue 22 §3, fifth pass; :mod:`pkmkit.machines.trimule_mirror`). The bound must hold
for every configuration the engine finds at a target — either branch, any assembly of the legs
— and skipping must leave the inverse model unchanged, row by row, also where the mirror wins."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.trimule_mirror import mirror_beyond_strokes

#: The study box of `pkmkit workspace trimule-600` (its default box widened once).
STUDY_BOX = (np.array([-1.32403, -1.61736, 0.0534526]), np.array([1.26296, 1.55038, 1.9013]))


@pytest.fixture(scope="module")
def trimule():
    return pkmkit.machine("trimule-600")


def _without_bound(m):
    return dataclasses.replace(m, kind=dataclasses.replace(m.kind, head_mirror_beyond=None))


def _grid(m, per_side: int) -> np.ndarray:
    lo, hi = STUDY_BOX
    axes = [np.linspace(lo[i], hi[i], per_side) for i in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.hstack([points, np.tile(m.home_pose[3:], (len(points), 1))])


def _configurations(m, x: np.ndarray) -> list:
    """Exact solutions at ``x`` from several starts (home, the head turned by ±π/2 and π,
    tilted both ways): either branch, and other assemblies of the legs."""
    out = []
    home = m.home_q
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for turn, tilt in ((0, 0), (np.pi / 2, 0.5), (-np.pi / 2, -0.5), (np.pi, 0.3),
                           (np.pi, -0.3)):
            q0 = home.copy()
            q0[3] += turn
            q0[4] += tilt
            inv = m.ik(x, q0=q0, full_output=True, strokes="ignore")
            out.append(inv.solution)
    return out


def test_the_bound_holds_for_every_configuration_found(trimule):
    m = trimule
    rng = np.random.default_rng(11)
    lo, hi = STUDY_BOX
    n = 1500
    x = np.hstack([lo + (hi - lo) * rng.random((n, 3)), np.tile(m.home_pose[3:], (n, 1))])
    x[::3, 3:] += 0.4 * rng.standard_normal((len(x[::3]), 3))
    lengths = np.full(n, m.tool_length)
    hopeless = mirror_beyond_strokes(m.params, m.model, x, lengths)
    assert 0.2 * n < hopeless.sum() < 0.9 * n
    inside_any = np.zeros(n, dtype=bool)
    naive = np.zeros(n, dtype=bool)  # the slides' ends alone, without the head's reach
    for solution in _configurations(m, x):
        solved = np.isfinite(solution).all(axis=1)
        inside = np.zeros(n, dtype=bool)
        inside[solved] = m._within_strokes(solution[solved])
        assert not (hopeless & inside).any()
        inside_any |= inside
    names = m.model.variables
    for name, base in (("Q1", (0.3, 0, 0)), ("Q2", (0, -0.4, 0)), ("Q3", (-0.3, 0, 0)),
                       ("L4", (0, 0, 0))):
        k = names.index(name)
        distance = np.linalg.norm(x[:, :3] - np.array(base), axis=1)
        naive |= (distance > m.model.q_max[k]) | (distance < m.model.q_min[k])
    # the test can fail: without the head's reach, targets reached within every stroke
    # would be judged hopeless
    assert (naive & inside_any).any() and inside_any.sum() > 20


def test_the_bound_does_not_judge_a_machine_with_defects(trimule):
    model = trimule.model
    defective = dataclasses.replace(model, defects=model.defects + 1e-5)
    x = _grid(trimule, 5)
    assert mirror_beyond_strokes(trimule.params, model, x, np.full(len(x), 0.1)).any()
    assert not mirror_beyond_strokes(trimule.params, defective, x, np.full(len(x), 0.1)).any()


def _same_inverse(a, b) -> None:
    for name in ("q", "status", "solution", "out_of_stroke", "residual"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name


def test_skipping_leaves_the_study_grid_unchanged(trimule):
    m = trimule
    x = _grid(m, 13)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = m.ik(x, full_output=True)
        slow = _without_bound(m).ik(x, full_output=True)
        # continued from the neighbouring slab, as the workspace study solves it
        slab = 13 * 13
        start = np.roll(slow.solution, slab, axis=0)
        start[:slab] = np.nan
        fast_c = m.ik(x, full_output=True, start=start)
        slow_c = _without_bound(m).ik(x, full_output=True, start=start)
    _same_inverse(fast, slow)
    _same_inverse(fast_c, slow_c)
    assert fast.iterations.sum() < slow.iterations.sum()  # mirrors not solved


def test_rows_where_the_mirror_wins_are_still_mirrored(trimule):
    """Configurations within every stroke with the head turned past a quarter turn: from
    home, the inverse reaches the branch nearer home's Q4, beyond a stroke there, and the rule
    takes the mirror — the configuration given — which the bound must not skip."""
    m = trimule
    rng = np.random.default_rng(12)
    n = 400
    lo, hi = m.model.q_min[m._actuated], m.model.q_max[m._actuated]
    q = m.home_q + (rng.random((n, 5)) - 0.5) * 0.8 * np.minimum(hi - lo, 1.0)
    q[:, :3] = lo[:3] + (hi[:3] - lo[:3]) * (0.02 + 0.96 * rng.random((n, 3)))
    q[:, 3] = rng.choice([-1, 1], n) * rng.uniform(1.9, 2.9, n)
    q[:, 4] = rng.uniform(-0.7, 0.7, n)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        direct = m.fk(q, full_output=True)
        keep = (direct.status == pkmkit.Status.OK) & ~direct.out_of_stroke
        x = direct.pose[keep]
        fast = m.ik(x, full_output=True)
        slow = _without_bound(m).ik(x, full_output=True)
    lengths = np.full(len(x), m.tool_length)
    assert not mirror_beyond_strokes(m.params, m.model, x, lengths).any()
    won = (fast.status == pkmkit.Status.OK) & (np.abs(fast.q[:, 3]) > np.pi / 2)
    assert won.sum() >= 5  # the mirror won there (far from home's Q4, within the strokes)
    _same_inverse(fast, slow)
