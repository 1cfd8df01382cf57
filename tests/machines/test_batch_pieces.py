"""The full-pose machines' batch inverse does not depend on how the batch is split (issue 22
§2): :func:`pkmkit.numerics.jit.run_chunks` hands pieces of ``THREAD_ROWS`` rows to whichever
thread draws them from the shared counter, and every row's answer must be the bits of the
same row solved alone — for any piece size (one row, a prime, a last piece of 2 rows,
two halves), on two and three threads, into a fresh output and into ``out=``
holding garbage (a row no piece wrote keeps the garbage and fails), statuses included."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit
from pkmkit.status import Status

ROWS = 1500


def bits(a: np.ndarray) -> bytes:
    return np.ascontiguousarray(a).tobytes()


@pytest.fixture(scope="module", params=["gough-stewart", "verne"])
def case(request):
    m = pkmkit.machine(request.param)
    rng = np.random.default_rng(34)
    x = np.tile(np.asarray(m.home_pose, dtype=float), (ROWS, 1))
    if request.param == "verne":  # full poses the module reaches: from its position inverse
        reached = m.ik(rng.uniform(-0.1, 0.1, (ROWS, 3)), full_output=True).pose
        x = np.where(np.isfinite(reached), reached, x)
    else:
        x[:, :3] += rng.uniform(-0.05, 0.05, (ROWS, 3))
        x[:, 3:] += rng.uniform(-0.1, 0.1, (ROWS, 3))
    x[7::97, 0] += 50.0  # out of reach of the Verne module's slides (struts stretch)
    x[11::131, 4] = np.nan  # invalid
    x[-1, 2] = np.nan  # the last row is not OK: its NaN is written by the last piece
    return m, np.ascontiguousarray(x)


@pytest.fixture(scope="module")
def alone(case):
    """Each row solved in a batch of its own (compiled: no split possible)."""
    m, x = case
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PKMKIT_COMPILED", "1")
        q = np.concatenate([m.ik(x[i:i + 1], strokes="ignore") for i in range(ROWS)])
        status = np.concatenate([m.ik(x[i:i + 1], strokes="ignore", full_output=True).status
                                 for i in range(ROWS)])
    assert (status == Status.OK).sum() > ROWS // 2 and (status != Status.OK).sum() >= 13
    return q, status


@pytest.mark.parametrize("threads", ["2", "3"])
@pytest.mark.parametrize("piece", [1, 2, 7, 64, 509, ROWS // 3 + 1, ROWS // 2 - 1, ROWS // 2])
def test_every_split_gives_each_row_its_own_answer(case, alone, threads, piece, monkeypatch):
    m, x = case
    q_alone, status_alone = alone
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    monkeypatch.setenv("PKMKIT_THREADS", threads)
    monkeypatch.setattr(jit, "THREAD_ROWS", piece)
    assert ROWS >= 2 * piece  # run_chunks splits (a batch under two pieces runs whole)
    assert bits(m.ik(x, strokes="ignore")) == bits(q_alone)
    out = np.full((ROWS, m.n_actuators), 1e300)
    out[::2] = np.nan  # stale garbage: every row must be written
    record = m.ik(x, strokes="ignore", full_output=True, out=out)
    assert np.shares_memory(record.q, out) and record.q.shape == out.shape  # a read-only view
    assert bits(out) == bits(q_alone)
    assert (record.status == status_alone).all()
