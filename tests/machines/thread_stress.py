"""Threads calling built machines at once: the driver of tests/machines/test_threads*.py.

:func:`cases` lists, for every family (3-DOF rod machines, the hexapod, the Verne module, the
Tripteor, the TriMule, a machine loaded from a file), the calls a user's threads make —
``ik``, ``fk``, ``jacobian`` of one pose, of a small batch and of a large one (2¹⁶ rows where a
row costs under a microsecond or two, so that :func:`pkmkit.numerics.jit.run_chunks` spreads it
over its pool and the hexapod's q lands on a recycled block; fewer rows for the iterative
joint-chain solves, which still cross the per-row solvers' pieces), with ``out=`` and without.
Each call returns its answer as a tuple of arrays. :func:`run` makes ``threads`` threads call
every case ``rounds`` times in an order of their own, half of them on one machine object they
share and half on copies each thread loads itself, and compares each answer with the
single-threaded one bit for bit (the arrays' bytes: NaN rows included).

As a script, ``python -m tests.machines.thread_stress THREADS ROUNDS [--fresh INPUTS.npz]
[--timeout=SECONDS]`` prints ``ok`` or the differences (exit status 1); ``--fresh``: the inputs
read from a file (:func:`write_inputs`) and the threads started before any single-threaded call
of the process, so that every lazily built state (the extension's load, caches, kernel
modules, the pool, the built machines) is first built by competing threads; the references are
computed afterwards."""

from __future__ import annotations

import faulthandler
import os
import random
import shutil
import sys
import tempfile
import threading
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import pkmkit
from pkmkit.exceptions import StrokeWarning
from pkmkit.machines import built_machines, registry
from pkmkit.numerics import jit

FAMILIES = ("orthoglide", "delta", "gough-stewart", "verne", "tripteor-x7", "trimule-600",
            "file:linear-delta-ch3")
#: Rows of the large batches: cheap closed forms and compiled solves / the iterative chains.
BIG_ROWS, CHAIN_ROWS, SMALL_ROWS = 1 << 16, 2048, 16
#: Seconds after which a thread still running is a failure (a deadlock, or a livelock).
TIMEOUT = 600.0

Case = tuple[str, Callable[[object], tuple[np.ndarray, ...]]]


def load(family: str, folder: Path) -> object:
    """A new machine of ``family`` (``file:<preset>``: the preset's file copied to ``folder``
    under another name and loaded from there)."""
    if not family.startswith("file:"):
        return pkmkit.machine(family)
    path = folder / f"copied-{family[5:]}.toml"
    if not path.exists():
        shutil.copyfile(registry.preset_path(family[5:]), path)
    return registry.load(path)


def poses(m, rows: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``rows`` configurations q around home (±5 mm or mrad per actuator) and their poses."""
    q_home = np.asarray(m.ik(m.home_pose), dtype=float)
    q = q_home + np.random.default_rng(seed).uniform(-5e-3, 5e-3, (rows, q_home.size))
    return m.fk(q, strokes="ignore"), q


def inputs(families: tuple[str, ...] = FAMILIES,
           rows: int = BIG_ROWS) -> dict[str, np.ndarray]:
    """The poses and configurations of the large batches (the others are their first rows):
    ``x:<family>``, ``q:<family>``, ``rows`` rows (:data:`CHAIN_ROWS` for the joint chains);
    built single-threaded (:func:`write_inputs` keeps them for a fresh process)."""
    folder = Path(tempfile.mkdtemp(prefix="pkmkit-threads-"))
    try:
        data = {}
        for f in families:
            chain = f.startswith(("tripteor", "trimule"))
            data[f"x:{f}"], data[f"q:{f}"] = poses(load(f, folder),
                                                   CHAIN_ROWS if chain else rows, 1)
        return data
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _jacobian(record) -> tuple[np.ndarray, ...]:
    return (np.asarray(record.J), np.asarray(record.condition),
            np.asarray(record.singular_values))


def _full(result) -> tuple[np.ndarray, ...]:
    return (np.asarray(result.q), np.asarray(result.status))


def cases(family: str, x_big: np.ndarray, q_big: np.ndarray) -> list[Case]:
    """The calls on a machine of ``family`` (module docstring), on the batch ``x_big`` (its
    configurations ``q_big``) and its first rows; each takes the machine."""
    big = x_big.shape[0]
    x_small, q_small = x_big[:SMALL_ROWS].copy(), q_big[:SMALL_ROWS].copy()
    jac_rows = 256 if big == CHAIN_ROWS else 1 << 12
    x0, q0 = x_big[0].copy(), q_big[0].copy()

    def with_out(method: str, data: np.ndarray, width: int):
        def call(machine):
            out = np.full((data.shape[0], width), -1.0)
            got = getattr(machine, method)(data, out=out)
            assert np.shares_memory(got, out), f"{method}(out=) did not answer in out"
            return (out,)
        return call

    return [
        (f"{family} ik one", lambda machine: (machine.ik(x0),)),
        (f"{family} ik {SMALL_ROWS}", lambda machine: (machine.ik(x_small),)),
        (f"{family} ik {big}", lambda machine: (machine.ik(x_big),)),
        (f"{family} ik {big} out=", with_out("ik", x_big, q_big.shape[1])),
        (f"{family} ik {SMALL_ROWS} full",
         lambda machine: _full(machine.ik(x_small, full_output=True))),
        (f"{family} fk one", lambda machine: (machine.fk(q0),)),
        (f"{family} fk {SMALL_ROWS}", lambda machine: (machine.fk(q_small),)),
        (f"{family} fk {big}", lambda machine: (machine.fk(q_big),)),
        (f"{family} fk {big} out=", with_out("fk", q_big, x_big.shape[1])),
        (f"{family} jacobian one", lambda machine: _jacobian(machine.jacobian(x0))),
        (f"{family} jacobian {SMALL_ROWS}",
         lambda machine: _jacobian(machine.jacobian(x_small))),
        (f"{family} jacobian {jac_rows}",
         lambda machine: _jacobian(machine.jacobian(x_big[:jac_rows]))),
    ]


def same_bits(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
    return len(a) == len(b) and all(
        x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        for x, y in zip(a, b, strict=True))


def run(threads: int = 4, rounds: int = 1, families: tuple[str, ...] = FAMILIES,
        data: dict[str, np.ndarray] | None = None, fresh: bool = False,
        timeout: float = TIMEOUT) -> list[str]:
    """The stress run (module docstring) on ``data`` (:func:`inputs`, built now if None); the
    list of its failures (empty: every answer of every thread equals the single-threaded one
    bit for bit). ``fresh``: the threads run before any single-threaded call (the machines
    they share loaded by the first thread that needs each), the references after. A thread
    still running after ``timeout`` seconds is reported with every thread's stack
    (faulthandler, on stderr)."""
    warnings.simplefilter("ignore", StrokeWarning)
    if fresh and os.environ.get("PKMKIT_NATIVE") == "0" and jit.numba_available():
        import numba  # noqa: F401  (the engine choice settled; its kernels load in the threads)
    data = inputs(families) if data is None else data
    table = {f: cases(f, data[f"x:{f}"], data[f"q:{f}"]) for f in families}
    folder = Path(tempfile.mkdtemp(prefix="pkmkit-threads-"))
    try:
        return _run(threads, rounds, families, table, fresh, timeout, folder)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _references(table, families, folder) -> dict[str, tuple[np.ndarray, ...]]:
    own = {f: load(f, folder) for f in families}
    return {name: call(own[f]) for f in families for name, call in table[f]}


def _run(threads, rounds, families, table, fresh, timeout, folder) -> list[str]:
    if not fresh:  # a first pass settles the engine (Numba imported by a first compiled call)
        _references(table, families, folder)
        # the machines built again in the engine state the threads see (a joint chain closes
        # its legs at home by the compiled closure once Numba is imported: other last bits)
        built_machines.forget()
    reference = {} if fresh else _references(table, families, folder)
    shared: dict[str, object] = {}
    lock = threading.Lock()

    def shared_machine(f: str):
        with lock:  # the first thread that needs it loads it (fresh: while others load theirs)
            if f not in shared:
                shared[f] = load(f, folder)
            return shared[f]

    answers: dict[int, list[tuple[str, tuple[np.ndarray, ...]]]] = {}
    errors: dict[int, BaseException] = {}
    start = threading.Barrier(threads)

    def worker(k: int) -> None:
        try:
            order = [(f, name, call) for f in families for name, call in table[f]] * rounds
            random.Random(k).shuffle(order)
            start.wait()
            own: dict[str, object] = {}
            got = []
            for f, name, call in order:
                if f not in own:
                    own[f] = shared_machine(f) if k % 2 == 0 else load(f, folder)
                got.append((name, call(own[f])))
            answers[k] = got
        except BaseException as error:  # reported below, with the thread
            errors[k] = error

    pool = [threading.Thread(target=worker, args=(k,), daemon=True, name=f"stress-{k}")
            for k in range(threads)]
    for t in pool:
        t.start()
    deadline = time.monotonic() + timeout
    for t in pool:
        t.join(max(0.0, deadline - time.monotonic()))
    stuck = [t.name for t in pool if t.is_alive()]
    if stuck:
        faulthandler.dump_traceback(all_threads=True)
        return [f"threads {stuck} still running after {timeout:.0f} s: a deadlock, a livelock "
                "or work far slower than expected (Numba compiling from an empty cache on a "
                "loaded machine): the stacks above, on stderr, tell which"]
    failures = [f"thread {k}: {type(e).__name__}: {e}" for k, e in sorted(errors.items())]
    if fresh:
        reference = _references(table, families, folder)
    for k, got in sorted(answers.items()):
        failures += [f"thread {k}: {name} differs from the single-threaded answer"
                     for name, value in got if not same_bits(value, reference[name])]
    return failures


def write_inputs(path: str | Path, families: tuple[str, ...] = FAMILIES) -> None:
    """:func:`inputs` saved for ``python -m tests.machines.thread_stress ... --fresh PATH``."""
    np.savez(path, **inputs(families))


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    fresh_data = None
    if "--fresh" in sys.argv:  # the inputs from a file: no pkmkit call before the threads
        with np.load(args[2]) as saved:
            fresh_data = {k: saved[k] for k in saved.files}
    jit.RECYCLE_BYTES = 1 << 16  # the large batches' q on recycled blocks (3 MiB at 2¹⁶ rows)
    limit = [float(a.split("=", 1)[1]) for a in sys.argv if a.startswith("--timeout=")]
    found = run(int(args[0]) if args else 4, int(args[1]) if len(args) > 1 else 1,
                data=fresh_data, fresh=fresh_data is not None,
                timeout=limit[0] if limit else TIMEOUT)
    print("\n".join(found) if found else "ok")
    sys.exit(1 if found else 0)
