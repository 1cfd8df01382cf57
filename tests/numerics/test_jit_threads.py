"""Threaded chunks of compiled batches (pkmkit.numerics.jit.run_chunks, thread_count)."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from pkmkit.numerics import jit


def test_thread_count_follows_the_environment(monkeypatch):
    monkeypatch.setenv("PKMKIT_THREADS", "3")
    assert jit.thread_count() == 3
    monkeypatch.delenv("PKMKIT_THREADS")
    monkeypatch.setenv("OMP_NUM_THREADS", "1")  # Dask workers: one thread
    assert jit.thread_count() == 1
    monkeypatch.setenv("PKMKIT_THREADS", "junk")
    assert jit.thread_count() == 1


def test_chunks_cover_every_row_once_on_several_threads(monkeypatch):
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    rows = 3 * jit.THREAD_ROWS + 17
    seen = np.zeros(rows, dtype=int)
    names = set()
    meet = threading.Barrier(2, timeout=60)  # the first two pieces wait for each other

    def work(start, stop):
        names.add(threading.current_thread().name)
        if start < 2 * jit.THREAD_ROWS:
            meet.wait()  # fails (BrokenBarrierError) unless two threads run pieces at once
        seen[start:stop] += 1

    jit.run_chunks(work, rows)
    assert (seen == 1).all()
    # the calling thread takes pieces too, beside one thread of the pool
    assert names == {threading.current_thread().name} | {n for n in names
                                                          if n.startswith("pkmkit")}
    assert len(names) == 2
    small = np.zeros(10, dtype=int)
    jit.run_chunks(lambda a, b: small.__setitem__(slice(a, b), small[a:b] + 1), 10)
    assert (small == 1).all()  # one chunk, in this thread


def test_one_call_hands_work_to_the_pool_once_per_helper(monkeypatch):
    """The pieces are drawn from a shared counter: a 61-piece call submits one task to the
    pool (two threads), not one per piece (≈ 30 µs each: 2 ms of CPU per 10⁶ rows)."""
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    jit.run_chunks(lambda a, b: None, 2 * jit.THREAD_ROWS)  # the pool exists
    pool = jit._helper_pool(1)
    submitted = []
    real = pool.submit
    monkeypatch.setattr(pool, "submit", lambda *a, **k: submitted.append(a) or real(*a, **k))
    pieces = []
    jit.run_chunks(lambda a, b: pieces.append((a, b)), 61 * jit.THREAD_ROWS - 5)
    assert len(submitted) == 1
    assert sorted(pieces)[0] == (0, jit.THREAD_ROWS) and len(pieces) == 61
    assert sorted(pieces)[-1][1] == 61 * jit.THREAD_ROWS - 5


def test_an_error_in_a_piece_stops_the_others_and_is_raised(monkeypatch):
    """A piece that raises: no further piece is drawn, the error reaches the caller, and no
    piece runs after run_chunks has returned (the arrays may be gone)."""
    import time

    monkeypatch.setenv("PKMKIT_THREADS", "2")
    rows = 200 * jit.THREAD_ROWS
    started = []
    lock = threading.Lock()

    def work(start, stop):
        with lock:
            started.append(start)
        if start == 2 * jit.THREAD_ROWS:
            raise ZeroDivisionError("piece 2")
        time.sleep(0.001)  # a kernel's time, without the GIL: the other thread keeps going

    with pytest.raises(ZeroDivisionError, match="piece 2"):
        jit.run_chunks(work, rows)
    count = len(started)
    assert count < 150  # the others stopped drawing (the old pool ran all 200)
    time.sleep(0.05)
    assert len(started) == count  # nothing ran after the return


def test_nested_and_concurrent_calls_do_not_wait_on_each_other(monkeypatch):
    """A piece that itself calls run_chunks (the pool's one helper busy with the outer call),
    and two threads calling at once: every row done once, no deadlock (a helper the pool has
    not started when its caller finds no piece left is withdrawn)."""
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    rows = 4 * jit.THREAD_ROWS
    inner = np.zeros((4, rows), dtype=int)

    def outer(start, stop):
        k = start // jit.THREAD_ROWS
        jit.run_chunks(lambda a, b: inner[k, a:b].__iadd__(1), rows)

    done = threading.Event()

    def run():
        jit.run_chunks(outer, rows)
        done.set()

    caller = threading.Thread(target=run, daemon=True)
    caller.start()
    assert done.wait(120), "nested run_chunks deadlocked"
    assert (inner == 1).all()
    seen = np.zeros(rows, dtype=int)
    lock = threading.Lock()

    def count(a, b):
        with lock:
            seen[a:b] += 1

    callers = [threading.Thread(target=jit.run_chunks, args=(count, rows), daemon=True)
               for _ in range(3)]
    for t in callers:
        t.start()
    for t in callers:
        t.join(120)
    assert not any(t.is_alive() for t in callers)
    assert (seen == 3).all()


def test_a_memory_chunk_of_a_protocol_call_is_spread_over_the_threads(monkeypatch):
    """``m.ik``/``m.fk`` cut a large batch into chunks of ``CHUNK_ROWS`` rows (memory bounded
    by the data) and each chunk's kernel goes through ``run_chunks``: the smallest chunk such a
    batch can have (half of ``CHUNK_ROWS``) must still be spread over two threads, or a 10⁶-row
    batch runs on one core (it did: pieces were as large as the chunks)."""
    from pkmkit.machines.chunks import CHUNK_ROWS, chunk_bounds

    monkeypatch.setenv("PKMKIT_THREADS", "2")
    smallest = min(stop - start for start, stop in chunk_bounds(CHUNK_ROWS + 1))
    assert smallest <= CHUNK_ROWS // 2 + 1
    meet = threading.Barrier(2, timeout=60)  # the two pieces run at once, or this breaks
    jit.run_chunks(lambda a, b: meet.wait(), smallest)
    pieces = []
    jit.run_chunks(lambda a, b: pieces.append((a, b)), smallest)
    assert len(pieces) >= 2


@pytest.mark.parametrize("shared", [False, True], ids=["pieces", "shared plan"])
def test_a_large_protocol_call_runs_its_kernel_on_several_threads(shared, monkeypatch):
    """End to end: a plain hexapod ``m.ik`` of 3 memory chunks runs whole — one
    ``run_chunks`` over every row (or, by default since session 35, one shared plan:
    ``jit.run_together``), no memory chunks (their joining copy ran on one thread: a third of
    the call's CPU) —, on two threads at once, and gives bit for bit the one-thread result and
    the chunked path's (``full_output``), NaN rows included."""
    import pkmkit
    from pkmkit.machines.chunks import CHUNK_ROWS

    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(7)
    x = m.home_pose + rng.uniform(-0.05, 0.05, (3 * CHUNK_ROWS, 6))
    x[5] = np.nan
    x[CHUNK_ROWS + 3, 2] += 5.0  # beyond the strokes (flagged, q kept)
    x[2 * CHUNK_ROWS + 1, 0] = 2e9  # invalid
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = m.ik(x)
    record = m.ik(x, full_output=True)  # in memory chunks
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    calls = []
    real = jit.run_chunks
    real_together = jit.run_together
    if shared:  # the native inverse's shared plan (session 35): both threads on one plan

        def spy_together(work):
            meet = threading.Barrier(2, timeout=60)  # breaks unless two threads run at once

            def traced(wait):
                meet.wait()
                work(wait)
            calls.append(x.shape[0])
            real_together(traced)

        monkeypatch.setattr(jit, "run_together", spy_together)
    monkeypatch.setattr(jit, "SHARED_INVERSE", shared)

    def spy(work, rows):
        meet = threading.Barrier(2, timeout=60)  # breaks unless two threads run at once

        def traced(a, b):
            if a < 2 * jit.THREAD_ROWS:
                meet.wait()
            work(a, b)
        calls.append(rows)
        real(traced, rows)

    monkeypatch.setattr(jit, "run_chunks", spy)
    two = m.ik(x)
    assert calls == [3 * CHUNK_ROWS]
    # bit for bit (NaN rows included), compared as bytes: the lists of 1.2 million ints the
    # comparison built before cost ≈ 1 s of CPU (docs/testing.md, "Sixth round (session 34,
    # suite3a)")
    assert one.shape == two.shape == np.shape(record.q)
    assert one.tobytes() == two.tobytes() == np.ascontiguousarray(record.q).tobytes()
    assert np.isnan(two[[5, 2 * CHUNK_ROWS + 1]]).all()
    assert np.isfinite(two[CHUNK_ROWS + 3]).all()
    assert np.isnan(two).any(axis=1).sum() == (np.asarray(record.status) != 0).sum()


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_the_fused_inverse_leaves_nan_exactly_on_the_rows_not_ok(name, monkeypatch):
    """The fused kernel writes NaN on the rows it does not solve, so ``m.ik`` skips the
    masking pass — except with ``strokes="refuse"``, which turns solved rows beyond a stroke
    into OUT_OF_STROKE after the kernel: those must be NaN too (plain and full output, whole
    batch and memory chunks)."""
    import pkmkit
    from pkmkit.machines import chunks

    monkeypatch.setenv("PKMKIT_COMPILED", "1")
    m = pkmkit.machine(name)
    rng = np.random.default_rng(3)
    home = np.asarray(m.home_pose, dtype=float)
    if m.n_actuators < 6:  # full poses the module reaches: from positions
        reached = m.ik(home[:3] + rng.uniform(-0.1, 0.1, (400, 3)), full_output=True)
        x = np.asarray(reached.pose)[np.asarray(reached.status) == 0][:200]
    else:
        x = home + rng.uniform(-0.05, 0.05, (200, 6)) * [1, 1, 1, 0.1, 0.1, 0.1]
    x = x.copy()
    x[::7, 2] += rng.uniform(0.0, 0.6, len(x[::7]))  # beyond a stroke, or out of reach
    x[3] = np.nan
    for size in (1 << 16, 64):
        monkeypatch.setattr(chunks, "CHUNK_ROWS", size)
        for strokes in ("flag", "ignore", "refuse"):
            record = m.ik(x, full_output=True, strokes=strokes)
            plain = m.ik(x, strokes=strokes)
            bad = np.asarray(record.status) != 0
            assert bad.any() and not bad.all()
            assert (np.isnan(plain).all(axis=1) == bad).all(), (strokes, size)
            assert (np.isnan(np.asarray(record.q)).all(axis=1) == bad).all(), (strokes, size)
            assert not np.isnan(plain[~bad]).any()
            if strokes == "refuse":
                assert (np.asarray(record.status) == 8).sum() >= 3  # OUT_OF_STROKE rows


@pytest.mark.parametrize("name", ["gough-stewart", "verne"])
def test_a_few_thousand_solver_rows_run_on_two_threads(name, monkeypatch):
    """The per-row solvers (the hexapod's direct model, the Verne module's position inverse)
    cost microseconds per row: their pieces are ``SOLVER_PIECE_ROWS`` rows, so a 3000-row
    batch runs on two threads at once (with ``THREAD_ROWS`` pieces it was one piece, one
    thread) and gives the one-thread result bit for bit."""
    import pkmkit

    m = pkmkit.machine(name)
    rng = np.random.default_rng(11)
    home = np.asarray(m.home_pose, dtype=float)
    if name == "verne":
        x = home[:3] + rng.uniform(-0.1, 0.1, (3000, 3))
        call = lambda: m.ik(x, full_output=True, strokes="ignore")  # noqa: E731
    else:
        q = m.ik(home + rng.uniform(-0.03, 0.03, (3000, 6)), strokes="ignore")
        call = lambda: m.fk(q, full_output=True, strokes="ignore")  # noqa: E731
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = call()
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    pieces = []
    real = jit.run_chunks

    def spy(work, rows, *args):
        meet = threading.Barrier(2, timeout=30)  # breaks unless two threads run at once

        def traced(a, b):
            pieces.append(b - a)
            if a == 0 or (b - a == jit.SOLVER_PIECE_ROWS and a < 2 * jit.SOLVER_PIECE_ROWS):
                meet.wait()
            work(a, b)
        real(traced, rows, *args)

    monkeypatch.setattr(jit, "run_chunks", spy)
    two = call()
    assert sum(pieces) == 3000 and len(pieces) == 3
    for field in ("pose", "q", "status", "iterations"):
        a, b = getattr(one, field, None), getattr(two, field, None)
        if a is not None:
            a, b = np.asarray(a), np.asarray(b)
            assert a.tobytes() == b.tobytes(), field


def test_a_large_verne_inverse_runs_whole_with_the_same_bits(monkeypatch):
    """The Verne module (six rods, three actuators: the rods' consistency decides the status)
    on 3 memory chunks of full poses it reaches, a few disturbed: the whole call on two
    threads gives the one-thread bits and the chunked record's (``full_output``) q."""
    import pkmkit
    from pkmkit.machines.chunks import CHUNK_ROWS

    m = pkmkit.machine("verne")
    rng = np.random.default_rng(12)
    reached = m.ik(np.asarray(m.home_pose)[:3] + rng.uniform(-0.1, 0.1, (3000, 3)),
                   full_output=True)
    x = np.resize(np.asarray(reached.pose), (3 * CHUNK_ROWS, 6))
    x[::97, 3] += 1e-3  # an orientation the rods cannot all take: UNREACHABLE
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = m.ik(x)
    record = m.ik(x, full_output=True)
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    calls = []
    real, real_together = jit.run_chunks, jit.run_together
    monkeypatch.setattr(jit, "run_chunks", lambda w, r, *a: calls.append(r) or real(w, r, *a))
    # the shared plan (session 35) runs every row in one call too
    monkeypatch.setattr(jit, "run_together",
                        lambda w: calls.append(3 * CHUNK_ROWS) or real_together(w))
    two = m.ik(x)
    assert calls == [3 * CHUNK_ROWS]
    status = np.asarray(record.status)
    assert (status == 0).sum() > CHUNK_ROWS and (status != 0).sum() > 1000
    assert one.tobytes() == two.tobytes() == np.asarray(record.q).tobytes()
