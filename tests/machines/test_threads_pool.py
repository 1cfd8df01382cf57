"""The helper pool of :func:`pkmkit.numerics.jit.run_chunks` when threads meet it at once
(docs/testing.md, "Audit of threads, session 35").

``_helper_pool`` made the pool on first use without a lock: threads whose first large batch
started together could each make a pool (57 of 200 trials of eight threads with a short switch
interval, on the old code), each with its own helpers — more threads than ``thread_count()``,
the executors left for the garbage collector. It is now made under a lock. A process forked
from one that used the pool makes a pool of its own (the inherited one has no threads there)."""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import sys
import threading

import pytest

from pkmkit.numerics import jit


@pytest.fixture
def fresh_pool(monkeypatch):
    old = jit._pool
    monkeypatch.setattr(jit, "_pool", None)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # threads switch often: the unlocked code's window opens
    yield
    sys.setswitchinterval(interval)
    if jit._pool is not None:
        jit._pool[1].shutdown(wait=True)
    jit._pool = old


def test_threads_asking_at_once_get_one_pool(fresh_pool):
    for _ in range(100):
        jit._pool = None
        got = []
        start = threading.Barrier(8)

        def ask(got=got, start=start):
            start.wait()
            got.append(jit._helper_pool(3))

        askers = [threading.Thread(target=ask, daemon=True) for _ in range(8)]
        for t in askers:
            t.start()
        for t in askers:
            t.join(60)
        assert len(got) == 8 and len({id(pool) for pool in got}) == 1


def _child_pool(parent_pool, answers) -> None:
    pool = jit._helper_pool(1)
    try:
        ran = pool.submit(os.getpid).result(timeout=20)
    except concurrent.futures.TimeoutError:
        ran = None
    answers.put((pool is parent_pool, ran == os.getpid()))


@pytest.mark.skipif(not hasattr(os, "register_at_fork"), reason="no fork")
def test_a_forked_child_gets_a_pool_of_its_own():
    """A child made by ``fork`` (multiprocessing's default on Linux before 3.14) inherited the
    parent's pool without its threads: a submitted helper never ran (every large batch on one
    thread in the child, silently). The child now makes its own pool."""
    parent_pool = jit._helper_pool(1)
    assert parent_pool.submit(os.getpid).result(timeout=20) == os.getpid()
    context = multiprocessing.get_context("fork")
    answers = context.Queue()
    child = context.Process(target=_child_pool, args=(parent_pool, answers))
    child.start()
    try:
        assert answers.get(timeout=120) == (False, True)
    finally:
        child.join(60)
