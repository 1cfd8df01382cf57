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
