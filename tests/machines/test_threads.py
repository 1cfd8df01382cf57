"""One built machine called from several Python threads at once (issue 22 §1–§2 paths; the
audit in docs/testing.md, "Audit of threads, session 35"; the guarantees in
docs/kinematics.md, "Threads").

The driver (:mod:`tests.machines.thread_stress`) makes threads call ``ik``, ``fk`` and
``jacobian`` of every family — one pose, a small batch, a large one (2¹⁶ rows: the helper pool
of :func:`pkmkit.numerics.jit.run_chunks`; the hexapod's and the Verne module's q on recycled
blocks, their threshold lowered here), with ``out=`` and without — half of them on one
machine object they share, half on their own copies, and compares every answer with the
single-threaded one bit for bit. Deadlocks fail after a timeout with every thread's stack.
The ordinary run covers a 3-DOF machine, a machine from a file, the hexapod and the
Verne module on two threads (large batches of 2¹⁵ rows: still two pieces or more); the
``ci`` runs every family (the Tripteor and the TriMule too) on four
threads, in this process and in fresh ones (``PYTHONFAULTHANDLER=1``; the threads then build
every lazily built state themselves), with the C extension and without (Numba)."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import pkmkit
from pkmkit.numerics import jit
from tests.machines import thread_stress

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def recycled(monkeypatch):
    """Recycled outputs from 64 KiB: the large batches' q on recycled blocks; two threads."""
    monkeypatch.delenv("PKMKIT_RECYCLE", raising=False)
    monkeypatch.setenv("PKMKIT_THREADS", "2")
    monkeypatch.setattr(jit, "RECYCLE_BYTES", 1 << 16)
    jit.release_outputs()
    yield
    jit.release_outputs()


def test_threads_get_the_single_threaded_bits(recycled):
    families = ("delta", "file:linear-delta-ch3", "gough-stewart", "verne")
    data = thread_stress.inputs(families, rows=2 * jit.THREAD_ROWS)  # still spread
    assert thread_stress.run(threads=2, families=families, data=data) == []


@pytest.mark.ci
def test_every_family_on_four_threads_twice(recycled):
    assert thread_stress.run(threads=4, rounds=2) == []


def _fresh_process(tmp_path, **env) -> subprocess.CompletedProcess:
    inputs = tmp_path / "inputs.npz"
    thread_stress.write_inputs(inputs)
    environment = {**os.environ, "PYTHONFAULTHANDLER": "1", "PKMKIT_THREADS": "2",
                   "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)]), **env}
    return subprocess.run([sys.executable, "-m", "tests.machines.thread_stress", "4", "1",
                           "--fresh", str(inputs)], capture_output=True, text=True,
                          env=environment, cwd=ROOT, timeout=1800)


@pytest.mark.ci
@pytest.mark.parametrize("native", ["", "0"], ids=["C extension", "Numba"])
def test_a_fresh_process_whose_threads_build_every_lazy_state(tmp_path, native):
    done = _fresh_process(tmp_path, PKMKIT_NATIVE=native)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stdout + done.stderr


def test_a_shared_record_read_by_threads_in_any_order():
    """A batch's lazy Jacobians record read by threads at once (fields computed on first
    read, by whichever thread comes first): every thread reads the single-threaded values."""
    m = pkmkit.machine("gough-stewart")
    x, _ = thread_stress.poses(m, 64, 3)
    names = ("J", "condition", "singular_values", "J_inv", "singularity", "det_A",
             "translation_singular_values", "parallel_measure")
    expected = {n: np.asarray(getattr(m.jacobian(x), n)).tobytes() for n in names}
    for trial in range(8):
        record = m.jacobian(x)
        got: dict[int, dict[str, bytes]] = {}
        start = threading.Barrier(4)

        def read(k: int, record=record, got=got, start=start, trial=trial) -> None:
            start.wait()
            order = names[k + trial:] + names[:k + trial]
            got[k] = {n: np.asarray(getattr(record, n)).tobytes() for n in order}

        readers = [threading.Thread(target=read, args=(k,), daemon=True) for k in range(4)]
        for t in readers:
            t.start()
        for t in readers:
            t.join(120)
        assert not any(t.is_alive() for t in readers), "readers of one record deadlocked"
        assert all(got[k] == expected for k in range(4))


def test_recycled_blocks_taken_and_dropped_by_threads_never_overlap(recycled):
    """Threads take recycled outputs of one size and drop them as fast as they can (the
    block dropped by one the next taken by another): an output in use never shares memory
    with another thread's, and what a thread wrote stays until it drops it."""
    rows, width = 4096, 6
    live: dict[int, np.ndarray] = {}
    bad: list[str] = []
    start = threading.Barrier(4)

    def churn(k: int) -> None:
        start.wait()
        for i in range(300):
            out = jit.batch_output(rows, width)
            out[:] = k * 1000 + i
            live[k] = out
            for other, theirs in list(live.items()):
                if other != k and np.shares_memory(out, theirs):
                    bad.append(f"threads {k} and {other} share an output")
            if not (out == k * 1000 + i).all():
                bad.append(f"thread {k}: its output changed under it")
            live.pop(k)
            del out

    workers = [threading.Thread(target=churn, args=(k,), daemon=True) for k in range(4)]
    for t in workers:
        t.start()
    for t in workers:
        t.join(120)
    assert not any(t.is_alive() for t in workers)
    assert bad == []
