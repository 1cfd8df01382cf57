"""The full-pose machines' batch inverse does not depend on how the batch is split (issue 22
§2): :func:`pkmkit.numerics.jit.run_chunks` hands pieces of ``THREAD_ROWS`` rows to whichever
thread draws them from the shared counter, and every row's answer must be the bits of the
same row solved alone — for any piece size (one row, a prime, a last piece of 2 rows,
two halves), on two and three threads, into a fresh output and into ``out=``
holding garbage (a row no piece wrote keeps the garbage and fails), statuses included.

Since session 35 the native inverse of a large batch runs a shared plan instead
(``native/inverse_shared.c``: slices claimed by compare-and-swap, a held slice computed again
by an idle thread and written once): the same bits for any slice and block size, an idle
thread taking exactly the free slices of held blocks from their ends and writing over no
claimed one, the calling thread waiting for a claimed slice's copy — each checked with the
plan's flags set by hand (planted bugs: a last row left out, the skip of slices another thief
took, the caller's wait — each fails here)."""

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


# The shared plan (session 35, ``native/inverse_shared.c``): every thread on one plan, slices
# claimed by compare-and-swap, a held slice computed again by an idle thread and written once.
# Small slices and blocks (1, 3, 7 rows; 1, 2, 5 slices per block) so that 1 500 rows make
# many blocks and the threads meet inside blocks.

needs_shared = pytest.mark.skipif(
    getattr(jit.native_kernels(), "inverse_poses_shared", None) is None,
    reason="the C extension (with inverse_poses_shared) is not built")


@needs_shared
@pytest.mark.parametrize("threads", ["2", "3"])
@pytest.mark.parametrize("slice_rows, block", [(1, 1), (1, 5), (3, 2), (7, 5), (37, 2)])
def test_the_shared_plan_gives_each_row_its_own_answer(case, alone, threads, slice_rows, block,
                                                       monkeypatch):
    m, x = case
    q_alone, status_alone = alone
    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    monkeypatch.setenv("PKMKIT_THREADS", threads)
    monkeypatch.setattr(jit, "SHARED_SLICE_ROWS", slice_rows)
    monkeypatch.setattr(jit, "SHARED_BLOCK_SLICES", block)
    monkeypatch.setattr(jit, "THREAD_ROWS", 1)
    calls = []
    real = jit.run_together
    monkeypatch.setattr(jit, "run_together", lambda work: (calls.append(1), real(work)))
    assert bits(m.ik(x, strokes="ignore")) == bits(q_alone)
    out = np.full((ROWS, m.n_actuators), 1e300)
    out[::2] = np.nan  # stale garbage: every row must be written
    record = m.ik(x, strokes="ignore", full_output=True, out=out)
    assert bits(out) == bits(q_alone)
    assert (record.status == status_alone).all()
    assert len(calls) == 2  # both calls ran the shared plan


def _plan_flags(plan: bytearray, block_slices: int) -> np.ndarray:
    """The plan's slice flags as a writable uint8 view ``(blocks, stride)`` (the layout of
    inverse_shared.c: from the first 64-byte aligned byte, the header, the block counter's
    line, then one line per block), and its block counter."""
    raw = np.frombuffer(plan, dtype=np.uint8)
    base = (-raw.ctypes.data) % 64
    stride = -(-block_slices // 64) * 64
    blocks = (raw.size - 3 * 64) // stride  # the buffer has 64 bytes of slack for the alignment
    return (raw[base + 128:base + 128 + blocks * stride].reshape(blocks, stride),
            raw[base + 64:base + 72].view(np.int64))


@pytest.fixture
def direct(case):
    """The kernel, its arguments (rods, actuators), x and q's width, for calling the C kernel
    directly."""
    m, x = case
    captured = []

    def capture(work):  # the kernel and its arguments but q, status, plan and wait
        cells = dict(zip(work.__code__.co_freevars,
                         [c.cell_contents for c in work.__closure__], strict=True))
        captured.append((cells["kernel"], list(cells["args"][1:-3])))
        real(work)

    real = jit.run_together
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PKMKIT_THREADS", "2")
        mp.setenv("PKMKIT_COMPILED", "1")
        mp.setattr(jit, "SHARED_SLICE_ROWS", 4)
        mp.setattr(jit, "SHARED_BLOCK_SLICES", 3)
        mp.setattr(jit, "THREAD_ROWS", 1)
        mp.setattr(jit, "run_together", capture)
        m.ik(x, strokes="ignore")
    kernel, rods = captured[0]
    return kernel, rods, x, m.n_actuators


@needs_shared
def test_an_idle_thread_takes_the_free_slices_of_held_blocks_and_nothing_else(direct, alone):
    """Every block taken by owners that stopped: some slices written (flag 2), one being
    written (1), the rest free — the thief computes exactly the free slices (their rows get
    the row's own bits), from each block's end, and writes no row of a slice claimed before."""
    kernel, rods, x, width = direct
    q_alone, _ = alone
    native = jit.native_kernels()
    plan = native.inverse_plan(ROWS, 4, 3)  # 375 slices, 125 blocks
    flags, counter = _plan_flags(plan, 3)
    counter[0] = 125  # every block has an owner
    flags[::2, 0] = 2  # owners that wrote their first slice and were descheduled
    flags[5, :3] = (2, 1, 0)  # one owner in the middle of writing its second slice
    flags[1, 2] = 2  # another thief took the last slice of a block whose owner never began
    claimed = np.zeros(375, dtype=bool)
    claimed[0:375:6] = True
    claimed[16] = claimed[15] = claimed[5] = True
    q = np.full((ROWS, width), 1e300)
    kernel(x, *rods, q, np.empty(0, dtype=np.int64), plan, False)  # a helper: no waiting
    rows_claimed = np.repeat(claimed, 4)[:ROWS]
    assert (q[rows_claimed] == 1e300).all()  # nothing written over a claimed slice
    assert bits(q[~rows_claimed]) == bits(q_alone[~rows_claimed])
    assert (flags[:125, :3] == 2).sum() == 375 - 1 and flags[5, 1] == 1
    kernel(x, *rods, q, np.empty(0, dtype=np.int64), plan, False)  # a late helper
    assert (q[rows_claimed] == 1e300).all()  # writes nothing: every slice is claimed


@needs_shared
def test_the_calling_thread_returns_only_once_a_claimed_slice_is_written(direct, alone):
    """A slice claimed by another thread (flag 1) is waited for: the caller returns after the
    other thread's copy and flag 2, and its q holds that copy."""
    import threading
    import time

    kernel, rods, x, width = direct
    q_alone, _ = alone
    native = jit.native_kernels()
    plan = native.inverse_plan(ROWS, 4, 3)
    flags, _ = _plan_flags(plan, 3)
    flags[0, 0] = 1  # rows 0-3 claimed by a thread that has not copied them yet
    q = np.full((ROWS, width), 1e300)
    started = threading.Event()

    def writer():
        started.wait()
        time.sleep(0.2)  # a writer descheduled between its claim and its copy
        q[:4] = q_alone[:4]
        flags[0, 0] = 2

    other = threading.Thread(target=writer)
    other.start()
    started.set()
    kernel(x, *rods, q, np.empty(0, dtype=np.int64), plan, True)
    returned = q.copy()  # what the caller got when the kernel returned
    other.join()
    assert bits(returned) == bits(q_alone)


@needs_shared
def test_the_shared_kernel_refuses_a_wrong_plan_or_status(direct):
    kernel, rods, x, width = direct
    native = jit.native_kernels()
    q = np.empty((ROWS, width))
    with pytest.raises(ValueError, match="plan"):
        kernel(x, *rods, q, np.empty(0, dtype=np.int64), native.inverse_plan(ROWS - 1, 4, 3),
               True)
    with pytest.raises(ValueError, match="plan"):
        kernel(x, *rods, q, np.empty(0, dtype=np.int64), bytearray(16), True)
    with pytest.raises(TypeError, match="plan"):
        kernel(x, *rods, q, np.empty(0, dtype=np.int64), bytes(4096), True)
    with pytest.raises(ValueError, match="status"):
        kernel(x, *rods, q, np.empty(7, dtype=np.int64), native.inverse_plan(ROWS, 4, 3), True)
    with pytest.raises(ValueError, match="slice_rows"):
        native.inverse_plan(ROWS, 0, 3)
