"""Recycled batch outputs (:func:`pkmkit.numerics.jit.batch_output`, ``native/recycled.c``,
issue 22 §2): the memory of a large output goes to the next call only once no array uses it
— never while the caller holds the output or any view of it —, at most one idle block is
kept (a loop alternates two blocks), and the hexapod's ``m.ik`` gives the same bits on
recycled memory holding an older answer (NaN rows included) as on fresh memory."""

from __future__ import annotations

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit

pytestmark = pytest.mark.skipif(jit.native_kernels() is None, reason="no C extension")

ROWS, WIDTH = 4096, 6


def address(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


@pytest.fixture
def small_blocks(monkeypatch):
    """Recycling from 64 KiB (4096 × 6 doubles is 192 KiB), no idle block left over."""
    monkeypatch.delenv("PKMKIT_RECYCLE", raising=False)
    monkeypatch.setattr(jit, "RECYCLE_BYTES", 1 << 16)
    jit.release_outputs()
    yield
    jit.release_outputs()


def test_a_dropped_output_is_reused_and_a_held_one_never(small_blocks):
    a = jit.batch_output(ROWS, WIDTH)
    assert a.shape == (ROWS, WIDTH) and a.dtype == np.float64
    assert a.flags.c_contiguous and a.flags.writeable and not a.flags.owndata
    a[:] = 1.0
    first = address(a)
    b = jit.batch_output(ROWS, WIDTH)  # a is held: new memory
    assert not np.shares_memory(a, b)
    b[:] = 2.0
    assert (a == 1.0).all()
    del a
    c = jit.batch_output(ROWS, WIDTH)  # a was dropped: its memory again
    assert address(c) == first
    view = c[10:20, 2]  # a view alone keeps the memory in use
    del c
    d = jit.batch_output(ROWS, WIDTH)
    assert not np.shares_memory(d, view) and not np.shares_memory(d, b)
    d[:] = 3.0
    assert (view == 1.0).all() and (b == 2.0).all()
    e = jit.batch_output(ROWS, WIDTH + 1)  # another size: never an idle block of this one
    assert e.shape == (ROWS, WIDTH + 1)
    del view, b, d, e  # four blocks dropped, in this order: the last one stays idle
    assert jit.release_outputs() == ROWS * (WIDTH + 1) * 8
    assert jit.release_outputs() == 0
    f = jit.batch_output(ROWS, WIDTH)  # a loop of f = batch_output(): two blocks alternate
    kept = {address(f)}
    for _ in range(4):
        f = jit.batch_output(ROWS, WIDTH)
        kept.add(address(f))
    assert len(kept) == 2


def test_small_and_huge_outputs_and_the_switch_are_plain_numpy(small_blocks, monkeypatch):
    assert jit.batch_output(10, WIDTH).flags.owndata  # under RECYCLE_BYTES
    monkeypatch.setattr(jit, "RECYCLE_MAX_BYTES", ROWS * WIDTH * 8 - 8)
    assert jit.batch_output(ROWS, WIDTH).flags.owndata  # over RECYCLE_MAX_BYTES
    monkeypatch.setattr(jit, "RECYCLE_MAX_BYTES", ROWS * WIDTH * 8)
    assert not jit.batch_output(ROWS, WIDTH).flags.owndata
    monkeypatch.setenv("PKMKIT_RECYCLE", "0")
    assert jit.batch_output(ROWS, WIDTH).flags.owndata


def test_hexapod_ik_on_recycled_memory_gives_the_fresh_bits(small_blocks, monkeypatch):
    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(3)
    x = np.tile(np.asarray(m.home_pose, dtype=float), (ROWS, 1))
    x[:, :3] += rng.uniform(-0.05, 0.05, (ROWS, 3))
    x[::50, 3] = np.nan  # NaN rows: written NaN, not left holding the older answer
    other = x + 0.01
    monkeypatch.setenv("PKMKIT_RECYCLE", "0")
    fresh = m.ik(x)
    assert fresh.flags.owndata
    monkeypatch.delenv("PKMKIT_RECYCLE")
    older = m.ik(other)  # an older answer in the block, NaN rows elsewhere
    assert not older.flags.owndata
    kept, where = older.copy(), address(older)
    del older
    again = m.ik(x)  # on the older answer's memory
    assert address(again) == where
    assert again.tobytes() == fresh.tobytes()
    assert np.isnan(again[::50]).all()
    assert not np.array_equal(kept, again, equal_nan=True)
