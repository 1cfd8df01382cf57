"""One position inverse per line along a common slide axis (:mod:`pkmkit.machines.slide_columns`,
used by the Verne module's ``ik`` of positions): the rows that follow their line's solved row
by a shift get what a solve of their own gives — the same statuses (reachable, unreachable,
wrong branch, invalid), modes and stroke flags, q and pose to 1e-12 — on a grid across the
reach and on rows just inside and just outside it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import pkmkit
from pkmkit.machines import full_pose_position as position
from pkmkit.machines.slide_columns import common_slide_axis, slide_columns
from pkmkit.model.rods import SLIDE, STRUT
from pkmkit.status import Status

FIELDS = ("status", "mode", "out_of_stroke")


def _one_by_one(m, positions, monkeypatch):
    """``m.ik`` of the batch with every row solved on its own (no lines)."""
    with monkeypatch.context() as patch:
        patch.setattr(position, "slide_columns", lambda model, rows: None)
        res = m.ik(positions, full_output=True)
    return {name: np.asarray(getattr(res, name))
            for name in (*FIELDS, "q", "pose", "iterations")}


def _boundary_rows(m, z_values):
    """Positions just inside and just outside the reach (1e-4 and 1e-7 m either side) along
    three horizontal rays from home, at each height of ``z_values``: the reach edge found by
    bisection on rows solved one at a time."""
    home = m.home_pose[:3]
    rows = []
    for angle in (0.3, 2.0, 4.4):
        ray = np.array([np.cos(angle), np.sin(angle), 0.0])
        inside, outside = 0.0, 2.0
        assert m.ik((home + outside * ray)[None], full_output=True).status[0] != Status.OK
        while outside - inside > 1e-9:
            mid = 0.5 * (inside + outside)
            ok = m.ik((home + mid * ray)[None], full_output=True).status[0] == Status.OK
            inside, outside = (mid, outside) if ok else (inside, mid)
        for gap in (-1e-4, -1e-7, 1e-7, 1e-4):
            rows += [home + (inside + gap) * ray + [0.0, 0.0, z] for z in z_values]
    return np.array(rows)


@pytest.mark.parametrize("compiled", ["1", "0"])
def test_rows_along_a_slide_line_get_their_own_solution(compiled, monkeypatch):
    """A grid over x-y-z across the Verne module's reach (every status present), rows at the
    reach's edge and invalid rows: the batch (one solve per line) against each row solved on
    its own, compiled and NumPy paths. Fails on a wrong shift, a shift of the wrong sign, a
    line merged across two x-y positions or an orientation not carried over."""
    monkeypatch.setenv("PKMKIT_COMPILED", compiled)
    m = pkmkit.machine("verne")
    step = 0.09 if compiled == "1" else 0.18
    xy = np.arange(-0.81, 0.82, step)
    z = m.home_pose[2] + np.array([-0.35, -0.1, 0.0, 0.27, 0.5])
    grid = np.stack(np.meshgrid(xy, xy, z, indexing="ij"), -1).reshape(-1, 3)
    edge = _boundary_rows(m, z - m.home_pose[2])
    home = m.home_pose[:3]
    invalid = np.concatenate([[[np.nan, 0.0, 0.1], [0.0, np.inf, 0.1], [0.1, 0.1, 2e9]],
                              home + np.array([[0, 0, 1e5], [0, 0, 1e7], [0, 0, 1e3]])])
    positions = np.concatenate([grid, edge, invalid])
    columns = slide_columns(m.model, positions)
    assert columns is not None and len(columns.rows) * 4 < len(positions)
    batch = m.ik(positions, full_output=True)
    alone = _one_by_one(m, positions, monkeypatch)
    for name in FIELDS:
        np.testing.assert_array_equal(np.asarray(getattr(batch, name)), alone[name], name)
    status = np.asarray(batch.status)
    assert {Status.OK, Status.UNREACHABLE, Status.NOT_CONVERGED,
            Status.INVALID_INPUT} <= set(status.tolist())
    edge_rows = slice(len(grid), len(grid) + len(edge))
    edge_ok = (status[edge_rows] == Status.OK).reshape(3, 4, -1)
    assert edge_ok[:, :2].all() and not edge_ok[:, 2:].any()  # the edge is where it was found
    np.testing.assert_allclose(batch.q, alone["q"], atol=1e-12, equal_nan=True)
    np.testing.assert_allclose(batch.pose, alone["pose"], atol=1e-12, equal_nan=True)
    ok = status == Status.OK
    assert np.abs(np.asarray(batch.iterations)[ok] - alone["iterations"][ok]).max() <= 1


def test_the_common_axis_and_the_lines():
    """The Verne module's slides share +z; a tilted slide, a strut or an idle actuator leave
    none (each row solved on its own). The lines group exactly the rows with the same
    component across the axis, shifts measured from the row solved."""
    m = pkmkit.machine("verne")
    np.testing.assert_array_equal(common_slide_axis(m.model), [0.0, 0.0, 1.0])
    assert common_slide_axis(pkmkit.machine("gough-stewart").model) is None
    verne = {name: getattr(m.model, name)
             for name in ("rod_axis", "rod_kind", "rod_actuator", "n_actuators")}
    assert common_slide_axis(SimpleNamespace(**verne)) is not None
    tilted = m.model.rod_axis.copy()
    tilted[3] = [0.0, 1e-9, 1.0]
    assert common_slide_axis(SimpleNamespace(**{**verne, "rod_axis": tilted})) is None
    kinds = m.model.rod_kind.copy()
    kinds[0] = STRUT
    assert common_slide_axis(SimpleNamespace(**{**verne, "rod_kind": kinds})) is None
    d = np.array([0.0, 0.6, 0.8])
    model = SimpleNamespace(rod_axis=np.tile(d, (4, 1)), rod_kind=np.full(4, SLIDE),
                            rod_actuator=np.array([0, 1, 2, 2]), n_actuators=3,
                            rod_length=np.ones(4))
    np.testing.assert_array_equal(common_slide_axis(model), d)
    idle = SimpleNamespace(**{**vars(model), "n_actuators": 4})
    assert common_slide_axis(idle) is None
    feet = np.array([[0.1, 0.0, 0.0], [0.0, 0.3, -0.4], [0.2, 0.0, 0.0]])
    t = np.array([0.0, 0.5, -1.25, 2.0])
    positions = (feet[:, None] + t[None, :, None] * d).reshape(-1, 3)
    positions[5] = np.nan
    columns = slide_columns(model, positions)
    assert columns is not None
    of = columns.rows[columns.of]
    good = np.isfinite(positions).all(axis=1)
    np.testing.assert_allclose(positions[good],
                               positions[of[good]] + columns.shift[good, None] * d, atol=1e-15)
    assert columns.of[5] == len(columns.rows) - 1 and columns.rows[-1] == 5
    assert slide_columns(model, feet) is None  # no two rows on one line
    far = np.concatenate([feet, feet + 300.0 * d])  # beyond LINE_SPAN machine lengths
    assert slide_columns(model, far) is None
