"""Threaded chunks of compiled batches (pkmkit.numerics.jit.run_chunks, thread_count)."""

from __future__ import annotations

import threading

import numpy as np

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

    def work(start, stop):
        names.add(threading.current_thread().name)
        seen[start:stop] += 1

    jit.run_chunks(work, rows)
    assert (seen == 1).all()
    assert all(name.startswith("pkmkit") for name in names)
    small = np.zeros(10, dtype=int)
    jit.run_chunks(lambda a, b: small.__setitem__(slice(a, b), small[a:b] + 1), 10)
    assert (small == 1).all()  # one chunk, in this thread


def test_a_memory_chunk_of_a_protocol_call_is_spread_over_the_threads(monkeypatch):
    """``m.ik``/``m.fk`` cut a large batch into chunks of ``CHUNK_ROWS`` rows (memory bounded
    by the data) and each chunk's kernel goes through ``run_chunks``: the smallest chunk such a
    batch can have (half of ``CHUNK_ROWS``) must still be spread over two threads, or a 10⁶-row
    batch runs on one core (it did: pieces were as large as the chunks)."""
    from pkmkit.machines.chunks import CHUNK_ROWS, chunk_bounds

    monkeypatch.setenv("PKMKIT_THREADS", "2")
    smallest = min(stop - start for start, stop in chunk_bounds(CHUNK_ROWS + 1))
    assert smallest <= CHUNK_ROWS // 2 + 1
    names = set()
    jit.run_chunks(lambda a, b: names.add(threading.current_thread().name), smallest)
    assert len([n for n in names if n.startswith("pkmkit")]) >= 1
    pieces = []
    jit.run_chunks(lambda a, b: pieces.append((a, b)), smallest)
    assert len(pieces) >= 2


def test_a_large_protocol_call_runs_its_kernel_on_several_threads(monkeypatch):
    """End to end: a hexapod ``m.ik`` of 3 memory chunks calls the kernel from the pool's
    threads, and gives the one-thread result bit for bit."""
    import pkmkit
    from pkmkit.machines.chunks import CHUNK_ROWS

    m = pkmkit.machine("gough-stewart")
    rng = np.random.default_rng(7)
    x = m.home_pose + rng.uniform(-0.05, 0.05, (3 * CHUNK_ROWS, 6))
    monkeypatch.setenv("PKMKIT_THREADS", "1")
    one = m.ik(x)
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    names = set()
    real = jit.run_chunks

    def spy(work, rows):
        def traced(a, b):
            names.add(threading.current_thread().name)
            work(a, b)
        real(traced, rows)

    monkeypatch.setattr(jit, "run_chunks", spy)
    two = m.ik(x)
    np.testing.assert_array_equal(one, two)
    assert any(name.startswith("pkmkit") for name in names)
