"""The paired Newton solve of the position inverse (issue 22 §5): a machine whose every actuator
carries two slide rods (the Verne-type module) solves for its rotation alone — the two rods of
an actuator must give the same coordinate — and runs the Levenberg–Marquardt solve only on the
rows it leaves (``full_pose_position_kernel.solve_paired`` and its C twin).

Oracles: the Levenberg–Marquardt solve of every row (``PKMKIT_POSITION_PAIRED=0``, the former
path) — the same statuses and out-of-stroke flags on 10⁵ positions with edge-of-reach,
beyond-stroke, far and invalid rows, q and pose within 1e-12 where OK; the forward model (``m.fk``
of the answer); the rods' closed-form coordinates (NumPy ``rod_coordinates_numpy`` on the pose
found); the hopeless-row test (a row the paired solve answers is never hopeless)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import pkmkit
from pkmkit.machines.common import _valid_rows
from pkmkit.machines.slide_columns import slide_columns
from pkmkit.status import Status

try:
    from pkmkit.native import kernels as _kernels
except ImportError:  # built without a compiler
    _kernels = None


def _ik(m, p, monkeypatch, paired):
    monkeypatch.setenv("PKMKIT_POSITION_PAIRED", "1" if paired else "0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return m.ik(p, full_output=True, strokes="flag")


def _edge(m, inside, outside, monkeypatch):
    """Bisection between positions the former solve reaches and far ones: ``(just inside,
    just outside)`` of its reach."""
    for _ in range(45):
        mid = 0.5 * (inside + outside)
        ok = _ik(m, mid, monkeypatch, paired=False).status == Status.OK
        inside[ok] = mid[ok]
        outside[~ok] = mid[~ok]
    return inside, outside


@pytest.fixture(scope="module")
def verne():
    return pkmkit.machine("verne")


@pytest.fixture(scope="module")
def positions(verne):
    """10⁵ positions: most about home, some spread to ±0.6 m (many beyond reach), far ones,
    rows reached only beyond the strokes, invalid rows (NaN, inf, beyond 1e9); the edge rows
    are added by the test (they need the former solve)."""
    rng = np.random.default_rng(34)
    p = rng.uniform(-0.25, 0.25, (100_000, 3))
    p[:20_000] = rng.uniform(-0.6, 0.6, (20_000, 3))
    p[20_000:20_050] *= 20.0
    beyond = verne.home_q + np.linspace(1.05, 1.4, 30)[:, None] * (verne.model.q_max
                                                                  - verne.home_q)
    p[20_050:20_080] = verne.fk(beyond, strokes="ignore", full_output=True).pose[:, :3]
    p[7::997] = np.nan
    p[11::1009, 2] = np.inf
    p[13::1013, 0] = -1e300
    p[17::1019, 1] = 2e9
    return p


@pytest.fixture(scope="module")
def records(verne, positions):
    """The former and the paired solve of the positions with 60 edge rows (30 just inside, 30
    just outside the former solve's reach)."""
    with pytest.MonkeyPatch.context() as mp:
        rng = np.random.default_rng(5)
        inside = rng.uniform(-0.1, 0.1, (30, 3))
        direction = rng.normal(size=(30, 3))
        outside = inside + 3.0 * direction / np.linalg.norm(direction, axis=1)[:, None]
        inside, outside = _edge(verne, inside, outside, mp)
        p = positions.copy()
        p[30_000:30_060] = np.concatenate([inside, outside])
        return p, _ik(verne, p, mp, paired=False), _ik(verne, p, mp, paired=True)


def _answered(m, p):
    """``(N,)`` the rows the paired solve answers (the machine's first pass)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PKMKIT_POSITION_PAIRED", "1")
        options = {"compute_rank": False, "max_iter": 30}
        _, paired, _ = m._compiled_rows(p, _valid_rows(p), options, True)
    return paired


def _branch_flips(m, old, new):
    """``(N,)`` the rows where one solve says OK and the other WRONG_MODE at a pose where a rod
    is at the end of its reach (its radicand ℓ² − |w|² + (e·w)² below 1e-9 m², where its two
    branches meet): there the former solve's branch check is decided by rounding — NumPy below
    its batch threshold, Numba above once Numba is imported, so even the former solve's status
    there depends on the batch (the paired solve answers such a row OK, a closure on the
    working branch with every radicand > 0, and spares it that check)."""
    either = np.isin(old.status, (Status.OK, Status.WRONG_MODE))
    flips = either & np.isin(new.status, (Status.OK, Status.WRONG_MODE)) & (
        old.status != new.status)
    rows = np.flatnonzero(flips)
    pose = np.where(np.isfinite(new.pose[rows]), new.pose[rows], old.pose[rows])
    w = m._forms.platform_points(pose) - m.model.rod_base[None]
    along = np.einsum("njk,jk->nj", w, m.model.rod_axis)
    radicand = m.model.rod_length ** 2 - np.einsum("njk,njk->nj", w, w) + along ** 2
    assert (radicand.min(axis=1) < 1e-9).all(), radicand.min(axis=1)
    return flips


def test_the_same_statuses_and_answers_as_the_former_solve(verne, records):
    """Every status and out-of-stroke flag the same on 10⁵ rows (edge rows included) but the
    branch flips at the end of a rod's reach (:func:`_branch_flips`: at most 10, edge rows
    only); q and pose within 1e-12 where OK, NaN where not; the outcomes all present."""
    _, old, new = records
    flips = _branch_flips(verne, old, new)
    np.testing.assert_array_equal(new.status[~flips], old.status[~flips])
    assert flips.sum() <= 10 and (flips[30_000:30_060].sum() == flips.sum())
    keep = ~flips
    np.testing.assert_array_equal(new.out_of_stroke[keep], old.out_of_stroke[keep])
    np.testing.assert_array_equal(np.isnan(new.q[keep]), np.isnan(old.q[keep]))
    np.testing.assert_array_equal(np.isnan(new.pose[keep]), np.isnan(old.pose[keep]))
    ok = (new.status == Status.OK) & keep
    np.testing.assert_allclose(new.q[ok], old.q[ok], rtol=0, atol=1e-12)
    np.testing.assert_allclose(new.pose[ok], old.pose[ok], rtol=0, atol=1e-12)
    seen = set(new.status.tolist())
    assert {Status.OK, Status.UNREACHABLE, Status.NOT_CONVERGED, Status.INVALID_INPUT} <= seen
    assert new.out_of_stroke[ok].any()
    edge = new.status[30_000:30_060] == Status.OK
    assert edge[:30].all() and not edge[30:].any()


def test_it_answers_nearly_every_reachable_row_in_few_steps(verne, records):
    """The paired solve answers ≥ 99 % of the OK rows (a wrong derivative or combination
    would leave them to the former solve, which hides it from the comparison above) and every
    row within ±0.25 m of home (the default box is ±0.2 m) in ≤ 4 Newton steps, 3.3 or fewer
    on average (one from the start table inside its square: test_position_start.py)."""
    p, _, new = records
    paired = _answered(verne, p)
    ok = new.status == Status.OK
    assert not (paired & ~ok).any()
    assert paired.sum() >= 0.99 * ok.sum()
    inner = (np.abs(p) <= 0.25).all(axis=1)
    assert paired[inner].all() and inner.sum() > 70_000
    assert new.iterations[inner].max() <= 4
    assert new.iterations[inner].mean() <= 3.3


def test_its_rows_close_every_rod_and_the_forward_model_returns_them(verne, records):
    """On the rows it answers: each rod's closed-form coordinate at the pose found (NumPy, the
    working branches) is its actuator's q within 1e-12 m; the forward model of q gives back
    the position and the orientation within 1e-9."""
    p, _, new = records
    paired = _answered(verne, p)
    pose, q = new.pose[paired], new.q[paired]
    rods = verne._forms.rod_coordinates_numpy(pose, verne._forms.rod_branch)
    np.testing.assert_allclose(rods, q[:, verne.model.rod_actuator], rtol=0, atol=1e-12)
    sample = np.flatnonzero(paired)[::50]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        back = verne.fk(new.q[sample], strokes="ignore", full_output=True)
    np.testing.assert_allclose(back.pose, new.pose[sample], rtol=0, atol=1e-9)


def test_a_row_it_answers_is_never_hopeless(verne, records):
    """The hopeless-row test runs only on the rows the paired solve leaves: a row it answers
    closes every rod, so the test (a rod farther than its reach from its slide's line) would
    have said no there."""
    p, _, _ = records
    paired = _answered(verne, p)
    assert paired.sum() > 50_000
    assert not (verne._surely_unreachable(p) & paired).any()


def test_rows_are_independent(verne, records, monkeypatch):
    """A row's answer does not depend on its neighbours or the batch's size: the same bits in
    a reversed batch, in a batch of 7 rows and alone."""
    p, _, new = records
    rows = np.r_[0:2000, 30_000:30_060]
    sub = p[rows]
    rev = _ik(verne, sub[::-1], monkeypatch, paired=True)
    small = np.concatenate([_ik(verne, sub[k:k + 7], monkeypatch, paired=True).q
                            for k in range(0, 63, 7)])
    alone = np.concatenate([np.atleast_2d(_ik(verne, sub[k:k + 1], monkeypatch,
                                               paired=True).q) for k in range(0, 63, 9)])
    want = new.q[rows]
    np.testing.assert_array_equal(rev.q[::-1], want)
    np.testing.assert_array_equal(small, want[:63])
    np.testing.assert_array_equal(alone, want[0:63:9])


def test_a_machine_without_pairs_keeps_the_former_solve():
    """The paired solve is declared by the rods (three actuators, two slide rods each), not by
    the machine's name: a six-rod Delta-like machine with one rod per actuator has none."""
    from tests.machines.test_full_pose import _full_pose_delta

    assert _full_pose_delta()._paired_geometry() is None
    assert pkmkit.machine("verne")._paired_geometry() is not None


@pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
def test_c_and_numba_write_the_same_bits(verne, records):
    """The C twin and the Numba kernel in the paired mode: the same bits in every output,
    the answered-row flags included."""
    numba_kernel = pytest.importorskip("pkmkit.machines.full_pose_position_kernel")
    from pkmkit.machines.full_pose_position_solve import solve

    p, _, _ = records
    p = p[17_000:21_000]
    data = verne.direct_kernel()
    opts = np.concatenate([data.options({"max_iter": 30}), [12, 2e-6], [1.0]])
    jt_inv = np.linalg.inv(verne._home_jacobian[:3])
    outs = [solve(verne._paired_geometry(), p, None, opts, skip=~_valid_rows(p),
                  home=data.home, jt_inv=jt_inv, function=f, paired=True)
            for f in (_kernels.position_rows, numba_kernel.solve_rows)]
    for a, b in zip(*outs, strict=True):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
        np.testing.assert_array_equal(a[~np.isnan(a)].view(np.int64),
                                      b[~np.isnan(b)].view(np.int64))
    assert outs[0][4].sum() > 2000 and (~outs[0][4]).sum() > 100


@pytest.mark.skipif(_kernels is None, reason="pkmkit.native.kernels was not built")
@pytest.mark.parametrize("change", ["strut", "branch", "opts", "out"])
def test_the_c_kernel_refuses_a_bad_paired_call(verne, change):
    """Paired mode on a rod that is not a slide, or without a branch of ±1 in column 15; an
    option vector other than (9,) or (10,); an output other than 9 or 10 columns: ValueError,
    ``out`` untouched."""
    p = np.zeros((4, 3))
    geom = verne._paired_geometry().copy()
    data = verne.direct_kernel()
    opts = np.concatenate([data.options({}), [0, np.inf], [1.0]])
    out = np.full((4, 10), 5.0)
    if change == "strut":
        geom[3, 13] = 1.0
    elif change == "branch":
        geom[2, 15] = 0.0
    elif change == "opts":
        opts = np.append(opts, 0.0)
    else:
        out = np.full((4, 11), 5.0)
    with pytest.raises(ValueError):
        _kernels.position_rows(p, np.empty((4, 6)), False, np.zeros(4, dtype=bool), geom,
                               data.home, np.eye(3), opts, out)
    assert (out == 5.0).all()


def test_slide_columns_spare_the_sort_only_when_no_row_shares_a_line(verne):
    """The early exit (no two rows with the same first coordinate across the slides): None
    for distinct rows; rows sharing x but not the line still None (the full sort decides);
    rows on one line (including −0.0 against 0.0) still grouped."""
    p = np.array([[0.1, 0.0, 0.0], [0.1, 0.2, 0.0], [0.2, 0.0, 0.1]])
    assert slide_columns(verne.model, p) is None
    assert slide_columns(verne.model, p[[0, 2]]) is None
    line = np.array([[0.1, 0.0, 0.0], [0.3, 0.1, 0.0], [0.1, -0.0, 0.2]])
    columns = slide_columns(verne.model, line)
    assert columns is not None and columns.rows.size == 2
    np.testing.assert_array_equal(columns.of[[0, 2]], [columns.of[0]] * 2)


def _lines_by_unique(m, p):
    """The oracle of :func:`slide_columns`: np.unique over every valid row's foot across the
    axis (broadcast arithmetic, the reduction along rows): ``(first rows, each row's line)``
    with the invalid rows and those beyond the span their own lines (None when none shared)."""
    from pkmkit.machines.slide_columns import LINE_SPAN

    d = m.model.rod_axis[0]
    span = LINE_SPAN * (1.0 + float(np.max(m.model.rod_length)))
    with np.errstate(invalid="ignore"):
        valid = _valid_rows(p) & (np.abs(p).max(axis=1) <= span)
    good = np.flatnonzero(valid)
    across = p[good] - (p[good] @ d / (d @ d))[:, None] * d
    _, first, inverse = np.unique(across + 0.0, axis=0, return_index=True,
                                  return_inverse=True)
    if first.size == good.size:
        return None
    return good[first], good, inverse.reshape(-1)


@pytest.mark.parametrize("kind", ["grid", "table", "invalid", "far", "distinct"])
def test_slide_columns_against_np_unique(verne, kind):
    """The lines found (their first rows, each row's line, the shifts) are np.unique's on a
    grid, a rounded table with a few shared lines, rows with NaN/inf/beyond-span cells, and
    distinct rows (None), the hashes' shortcuts (the whole-batch span test, the sort before
    the argsort) included."""
    rng = np.random.default_rng(8)
    if kind == "grid":
        g = np.linspace(-0.1, 0.1, 7)
        p = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    else:
        p = np.round(rng.uniform(-0.05, 0.05, (20_000, 3)), 3 if kind != "distinct" else 9)
    if kind == "invalid":
        p[::97, 1] = np.nan
        p[5::101, 2] = -np.inf
    if kind == "far":
        p[3::89, 0] = 1e6
    columns = slide_columns(verne.model, p)
    want = _lines_by_unique(verne, p)
    if want is None:
        assert columns is None
        return
    first, good, line = want
    assert columns is not None
    solved = columns.rows[columns.of]  # the row each row takes its answer from
    np.testing.assert_array_equal(solved[good], first[line])
    alone = np.setdiff1d(np.arange(p.shape[0]), good)
    np.testing.assert_array_equal(solved[alone], alone)
    d = verne.model.rod_axis[0]
    np.testing.assert_allclose(columns.shift[good], (p[good] - p[solved[good]]) @ d / (d @ d),
                               rtol=0, atol=1e-15)
    assert (columns.shift[alone] == 0.0).all()


def test_a_few_shared_lines_are_solved_row_by_row(verne, monkeypatch):
    """A table whose shared lines spare fewer than LINE_SHARE of its rows solves every row on
    its own (each row's bits those of the row alone); a grid solves one row per line (every
    row of a line has its first row's rotation, to the bit)."""
    rng = np.random.default_rng(6)
    p = rng.uniform(-0.2, 0.2, (400, 3))
    p[1:4] = p[0] + np.array([0.0, 0.0, 1.0]) * np.array([[0.01], [0.02], [0.03]])
    together = _ik(verne, p, monkeypatch, paired=True)
    alone = np.concatenate([_ik(verne, p[k:k + 1], monkeypatch, paired=True).pose
                            for k in range(4)])
    np.testing.assert_array_equal(together.pose[:4], alone)
    g = np.linspace(-0.15, 0.15, 9)
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    pose = _ik(verne, grid, monkeypatch, paired=True).pose.reshape(9, 9, 9, 6)
    np.testing.assert_array_equal(pose[..., 3:], np.broadcast_to(pose[:, :, :1, 3:],
                                                                 pose[..., 3:].shape))
