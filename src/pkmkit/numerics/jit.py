"""When to use the compiled (Numba) kernels instead of the NumPy reference paths.

The hot paths (closed-form inverse model, velocity model of many poses) have two
implementations: a vectorised NumPy one — the reference, used for small batches and compared
with the compiled one in the tests — and a fused per-pose loop compiled by Numba, which keeps
every intermediate in registers (no temporaries, no BLAS, one pass over memory). The compiled
path is used only for batches of at least :data:`MIN_ROWS` rows, so that single-pose calls never
pay Numba's import (≈ 0.3 s), the loading of its NumPy support on the first compiled call
(≈ 0.3–0.6 s: it imports ``scipy.linalg``) or a first compilation (cached on disk afterwards);
kernels whose NumPy path is nearly as fast run compiled only once Numba is imported
(:func:`use_compiled` with ``imports=False``).

Environment: ``PKMKIT_COMPILED=0`` forces the NumPy paths everywhere (``=1`` forces the
compiled ones for every batch size, which the tests use). Without Numba installed the NumPy
paths are used silently.

Ahead-of-time kernels: where the optional C extension :mod:`pkmkit.native` (built with the
package when a compiler is present) holds a twin of a Numba kernel (:data:`NATIVE_TWINS`: the
full-pose inverse and direct models, the position inverse of the Verne-type module, the
joint-chain closure, its velocity model's Jacobian and rates and its linearisation for the
identification, the batched small SVDs with and without rates, the rod-leg velocity
summaries, the batched closed-form inverse of rod legs with its shortfalls and det A),
:func:`kernel` returns it instead, and the call sites that
pass ``native=True`` to :func:`use_compiled` / :func:`use_compiled_solver` then need no Numba:
no import cost, so the per-pose solvers run native at every batch size.
``PKMKIT_NATIVE=0`` disables the extension (the Numba kernels run as without it);
``PKMKIT_COMPILED=0`` still means NumPy everywhere. This module is the one place that choice
is made.

Outputs: :func:`batch_output` builds large batch results on recycled memory (a dropped
output's block serves the next call of its size: no fresh pages to map and clear);
``PKMKIT_RECYCLE=0`` gives ``numpy.empty``.

Threads: the compiled kernels release the GIL, and :func:`run_chunks` spreads a large batch
over :func:`thread_count` threads (the calling one and helpers of a persistent pool) in pieces
drawn from a shared counter (a thread slowed by a competing process simply takes fewer).
``PKMKIT_THREADS=N`` sets the count; by default it is the number of cores this process may
use, or 1 where ``OMP_NUM_THREADS=1`` (Dask workers, and anyone who bounded the threads of
their numerical libraries). The rows are independent, so the results do not depend on the
count.
"""

from __future__ import annotations

import _thread
import importlib
import importlib.util
import os
import sys
from collections.abc import Callable
from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # imported when a pool is first needed (≈ 14 ms of start-up otherwise)
    from concurrent.futures import ThreadPoolExecutor

#: Smallest batch for which the compiled kernels are used (below: NumPy).
MIN_ROWS = 4096

#: Smallest batch for which the compiled solvers are used before Numba is imported.
SOLVER_ROWS = 64
#: Rows per piece of a batch spread over several threads (a batch of two pieces or more is
#: spread). Several pieces fit in one chunk of the protocol's memory chunking
#: (:data:`pkmkit.machines.chunks.CHUNK_ROWS`, 2¹⁶ rows), so a large ``m.ik``/``m.fk`` runs on
#: every thread: with pieces of 2¹⁶ rows, no chunk was ever spread and a 10⁶-row batch ran on
#: one core whatever the thread count.
THREAD_ROWS = 1 << 14
#: Rows per piece for the per-row iterative solvers (the full-pose direct model, the position
#: inverse of machines with fewer actuators than six: microseconds per row, not nanoseconds),
#: passed to :func:`run_chunks` as ``piece``: a piece of 2¹⁰ rows is milliseconds of work, so
#: a batch of a few thousand rows — the usual size of a direct-model batch — already runs on
#: every thread (with :data:`THREAD_ROWS` a 10⁴-row batch was one piece, on one thread).
SOLVER_PIECE_ROWS = 1 << 10
#: The full-pose machines' native inverse runs one shared plan on every thread instead of
#: :func:`run_chunks`' pieces (:func:`run_together`, ``native/inverse_shared.c``): rows in
#: slices of :data:`SHARED_SLICE_ROWS`, taken in blocks of :data:`SHARED_BLOCK_SLICES`
#: slices, a held slice computed again by an idle thread and written once — no thread
#: descheduled by a competing process holds the call (docs/benchmarks.md "Session 35").
#: ``SHARED_INVERSE = False`` gives the pieces (benches compare both in one process).
SHARED_INVERSE = True
SHARED_SLICE_ROWS = 32
SHARED_BLOCK_SLICES = 32

#: The Numba kernels that have a C twin of the same name and arguments in
#: ``pkmkit.native.kernels``.
NATIVE_TWINS = {
    "pkmkit.machines.full_pose_kernels": ("inverse_poses",),
    "pkmkit.machines.full_pose_direct_kernel": ("solve_rows", "solve_one"),
    "pkmkit.machines.full_pose_position_kernel": ("solve_rows",),
    "pkmkit.solve.chain_kernel": ("_solve_rows", "_jacobian_rows", "_linearise_rows"),
    "pkmkit.solve.chain_linalg": ("_closure_rates_rows", "_absorb_rows"),
    "pkmkit.numerics.svd_kernel": ("singular_values",),
    "pkmkit.numerics.svd_rates_kernel": ("singular_rates",),
    "pkmkit.machines.kernels": ("velocity3", "velocity2", "inverse", "reach_and_det"),
}
#: Twins named differently in ``pkmkit.native.kernels`` (one namespace for every module's).
NATIVE_NAMES = {("pkmkit.machines.full_pose_position_kernel", "solve_rows"): "position_rows",
                ("pkmkit.solve.chain_kernel", "_solve_rows"): "chain_rows",
                ("pkmkit.solve.chain_kernel", "_jacobian_rows"): "chain_jacobian_rows",
                ("pkmkit.solve.chain_kernel", "_linearise_rows"): "chain_linearise_rows",
                ("pkmkit.solve.chain_linalg", "_closure_rates_rows"): "closure_rates",
                ("pkmkit.solve.chain_linalg", "_absorb_rows"): "absorb",
                ("pkmkit.machines.kernels", "velocity3"): "rod_velocity3",
                ("pkmkit.machines.kernels", "velocity2"): "rod_velocity2",
                ("pkmkit.machines.kernels", "inverse"): "rod_inverse_rows",
                ("pkmkit.machines.kernels", "reach_and_det"): "rod_reach_det"}

#: Twins slower than their Numba kernel once both are loaded (GCC does not vectorise the
#: velocity summary's per-pose loop as LLVM does: ≈ 95 against 30 ns per pose): taken while
#: Numba is not imported — a fresh process then pays no Numba for them — and Numba's after.
#: The same bits either way.
NATIVE_UNTIL_NUMBA = {("pkmkit.machines.kernels", "velocity3")}

_available: bool | None = None
_native: ModuleType | bool | None = False  # False: not looked for yet
_pool: tuple[int, ThreadPoolExecutor] | None = None
_pool_lock = _thread.allocate_lock()  # _thread: built in, no import cost (threading's is)


def mode() -> str:
    """``"auto"`` (default), ``"0"`` (never compiled) or ``"1"`` (always compiled)."""
    value = os.environ.get("PKMKIT_COMPILED", "auto").strip().lower()
    return value if value in ("0", "1") else "auto"


def numba_available() -> bool:
    """Whether Numba can be imported (checked once, without importing it)."""
    global _available
    if _available is None:
        _available = importlib.util.find_spec("numba") is not None
    return _available


def native_kernels() -> ModuleType | None:
    """The C extension ``pkmkit.native.kernels``, or None when it was not built (no compiler
    at install time), or ``PKMKIT_NATIVE=0`` or ``PKMKIT_COMPILED=0`` is set."""
    global _native
    if os.environ.get("PKMKIT_NATIVE", "").strip() == "0" or mode() == "0":
        return None
    if _native is False:
        try:
            from pkmkit.native import kernels
        except ImportError:
            _native = None
        else:
            _native = kernels
    return _native


def native_kernel(module: str, name: str) -> Callable[..., Any] | None:
    """The C twin of the Numba kernel ``module.name`` (:data:`NATIVE_TWINS`) when
    :func:`native_kernels` has it, else None."""
    if name not in NATIVE_TWINS.get(module, ()) or (
            (module, name) in NATIVE_UNTIL_NUMBA and "numba" in sys.modules):
        return None
    native = native_kernels()
    # an extension built from older sources lacks the newer twins: Numba then runs them
    return None if native is None else getattr(native, NATIVE_NAMES.get((module, name), name),
                                               None)


def kernel(module: str, name: str) -> Callable[..., Any]:
    """The compiled kernel ``module.name`` to run: its C twin (:func:`native_kernel`), else
    the Numba function (``module`` imported now)."""
    native = native_kernel(module, name)
    return native if native is not None else getattr(importlib.import_module(module), name)


def use_compiled_solver(rows: int, *, native: bool = False) -> bool:
    """Whether the compiled per-pose solvers run on a batch of ``rows`` rows: an iterative solve
    costs hundreds of microseconds per pose through the NumPy engine and a few through its
    compiled kernel, so they run from :data:`SOLVER_ROWS` rows, or at any size once Numba is
    imported in the process (its import, ≈ 0.4 s of CPU with the on-disk cache, is then paid);
    ``PKMKIT_COMPILED=1`` forces them, ``=0`` (or Numba missing) never. ``native=True``
    (a solver with a C twin, run through :func:`kernel`): at every size when the extension is
    present — it costs no import."""
    choice = mode()
    if native and native_kernels() is not None:
        return choice != "0"
    if choice == "0" or not numba_available():
        return False
    return choice == "1" or rows >= SOLVER_ROWS or "numba" in sys.modules


def compiled_from_second_call(owner: Any, tag: str) -> bool:
    """Whether a single call runs its compiled solver now: yes once Numba is imported (or
    ``PKMKIT_COMPILED=1``), never without Numba or with ``PKMKIT_COMPILED=0``; otherwise the
    first call for ``owner`` (a machine, a module) and ``tag`` answers no — a one-shot call,
    the command line, does not pay Numba's import (≈ 0.4 s of CPU) — and records it on
    ``owner`` so that the next call answers yes (a loop runs compiled from its second call)."""
    if use_compiled_solver(1):
        return True
    if not use_compiled_solver(SOLVER_ROWS):
        return False
    key = f"_{tag}_called_once"
    if getattr(owner, key, False):
        return True
    object.__setattr__(owner, key, True)
    return False


def use_compiled(rows: int, *, imports: bool = True, native: bool = False) -> bool:
    """Whether a batch of ``rows`` rows should run the compiled kernels (the caller imports
    its kernel module lazily, e.g. :mod:`pkmkit.machines.kernels`).

    ``imports=False`` is for kernels whose NumPy path is within a few times the compiled one
    (the closed-form inverse of rod legs: ≈ 35 against 11 ms per 10⁶ poses): they run
    compiled only once Numba is imported in the process, because importing it and loading a
    cached kernel costs ≈ 0.6–0.9 s of CPU, which the compiled path repays only after tens of
    millions of poses — a one-shot command (``pkmkit ik --input``) stays on NumPy.
    ``PKMKIT_COMPILED=1`` still forces them. ``native=True``: a kernel with a C twin (run
    through :func:`kernel`), compiled whenever the extension is present (from
    :data:`MIN_ROWS` rows), Numba or not."""
    choice = mode()
    if choice == "0" or (choice == "auto" and rows < MIN_ROWS):
        return False
    if native and native_kernels() is not None:
        return True
    if choice == "auto" and not imports and "numba" not in sys.modules:
        return False
    return numba_available()


def thread_count() -> int:
    """Threads for large compiled batches (module docstring)."""
    value = os.environ.get("PKMKIT_THREADS", "").strip()
    if value.isdigit() and int(value) > 0:
        return int(value)
    if os.environ.get("OMP_NUM_THREADS", "").strip() == "1":
        return 1
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def run_chunks(work: Callable[[int, int], None], rows: int, piece: int = 0) -> None:
    """``work(start, stop)`` over ``range(rows)`` in pieces of ``piece`` rows (default
    :data:`THREAD_ROWS`; :data:`SOLVER_PIECE_ROWS` for per-row solvers), on
    :func:`thread_count` threads when the batch has at least two pieces (``work`` must release
    the GIL to gain anything: the compiled kernels do), else in this thread.

    The calling thread takes part: it and ``threads − 1`` threads of a persistent pool each
    draw the next piece from one shared counter until none is left (a thread slowed by a
    competing process simply takes fewer), so a call costs one hand-off per helper thread,
    not one submission and one future per piece (≈ 30 µs each, 2 ms of CPU per 10⁶ rows
    measured). An exception in any piece stops the others from drawing and is raised here
    once every helper has returned (``work`` never runs after this returns). A helper the
    pool has not started by the time the calling thread finds no piece left is withdrawn, so
    concurrent and nested calls cannot wait on each other."""
    size = piece if piece > 0 else THREAD_ROWS
    threads = thread_count()
    if threads == 1 or rows < 2 * size:
        work(0, rows)
        return
    import threading

    pieces = iter(range(0, rows, size))
    lock = threading.Lock()
    failed: list[bool] = []

    def drain() -> None:
        while True:
            with lock:
                start = None if failed else next(pieces, None)
            if start is None:
                return
            try:
                work(start, min(start + size, rows))
            except BaseException:
                failed.append(True)
                raise

    helpers = [_helper_pool(threads - 1).submit(drain)
               for _ in range(min(threads, -(-rows // size)) - 1)]
    try:
        drain()
    finally:
        # a helper still queued (the pool busy: another call, or a nested one) is withdrawn,
        # not awaited — the pieces are all drawn; a running one is waited for
        errors = [None if h.cancel() else h.exception() for h in helpers]
    for error in errors:
        if error is not None:
            raise error


def run_together(work: Callable[[bool], None]) -> None:
    """``work(True)`` in this thread beside ``work(False)`` in :func:`thread_count` − 1
    helpers of the persistent pool, returning when this thread's call returns — for kernels
    that finish the whole batch in the calling thread whatever the helpers do (the full-pose
    inverse's shared plan, ``native/inverse_shared.c``: a helper descheduled by a competing
    process holds nothing, so it is not waited for; it writes nothing once the batch is
    done). A helper the pool has not started is withdrawn; one that has finished with an
    exception has it raised here (one still running is left to finish, as such kernels
    raise only on their arguments, before taking any row)."""
    threads = thread_count()
    helpers = [_helper_pool(threads - 1).submit(work, False) for _ in range(threads - 1)]
    try:
        work(True)
    finally:
        errors = [None if h.cancel() or not h.done() else h.exception() for h in helpers]
    for error in errors:
        if error is not None:
            raise error


def _helper_pool(workers: int) -> ThreadPoolExecutor:
    """The persistent pool of ``workers`` threads that helps :func:`run_chunks`, made under a
    lock: threads calling at once for the first time get one pool, not one each (each with
    its own helpers: more threads than :func:`thread_count`). A pool replaced for a new count
    is not shut down — a call may be about to submit to it —; its idle threads end when it is
    garbage-collected."""
    global _pool
    with _pool_lock:
        if _pool is None or _pool[0] != workers:
            from concurrent.futures import ThreadPoolExecutor

            _pool = (workers, ThreadPoolExecutor(max_workers=workers,
                                                 thread_name_prefix="pkmkit"))
        return _pool[1]


def _forget_pool_in_child() -> None:
    """After ``fork``: the parent's pool has no threads in the child (its helpers would wait
    in its queue for ever, and each large batch run on one thread) and its lock may have been
    held by a parent thread: both made anew."""
    global _pool, _pool_lock
    _pool, _pool_lock = None, _thread.allocate_lock()


if hasattr(os, "register_at_fork"):  # POSIX
    os.register_at_fork(after_in_child=_forget_pool_in_child)


#: Batch outputs of at least this many bytes are built on recycled memory
#: (:func:`batch_output`): 32 MiB, glibc's largest dynamic ``mmap`` threshold — below it
#: ``malloc`` already hands a freed output's memory to the next call (the Verne module's
#: 24 MB q faults no page), above it every call maps and clears fresh pages.
RECYCLE_BYTES = 1 << 25
#: ... up to this many (256 MiB, 5.6 million hexapod poses): the idle block held between calls
#: stays bounded; a larger output is fresh memory, as from ``numpy.empty``.
RECYCLE_MAX_BYTES = 1 << 28


def batch_output(rows: int, width: int) -> Any:
    """A new uninitialised float64 array ``(rows, width)`` for a large batch's result, as
    ``numpy.empty``; from :data:`RECYCLE_BYTES` to :data:`RECYCLE_MAX_BYTES`, its memory is a
    block of the C extension (``recycled_block``) that becomes the one idle block once no
    array uses it any more, and a later call of the same size takes it again: a loop of
    ``q = m.ik(X)`` stops paying Linux's mapping and clearing of fresh pages (6–12 ns of CPU
    per hexapod pose, a third of the call; docs/benchmarks.md "Session 34"). The array is a
    view (``owndata`` False, its base holds the block), writeable, C-contiguous. At most one
    idle output stays held (:func:`release_outputs` frees it). ``PKMKIT_RECYCLE=0``, or no
    C extension: ``numpy.empty``."""
    import numpy as np

    nbytes = rows * width * 8
    block = getattr(native_kernels(), "recycled_block", None)  # None: no (or an older) build
    if (not RECYCLE_BYTES <= nbytes <= RECYCLE_MAX_BYTES or block is None
            or os.environ.get("PKMKIT_RECYCLE", "").strip() == "0"):
        return np.empty((rows, width))
    return np.frombuffer(block(nbytes), dtype=np.float64).reshape(rows, width)


def release_outputs() -> int:
    """Free the idle recycled output (:func:`batch_output`) now; its bytes."""
    release = getattr(native_kernels(), "recycled_release", None)
    return 0 if release is None else int(release())


# ``os.environ``'s own dict on POSIX (encoded keys): a membership test there costs tens of
# nanoseconds where ``os.environ.get`` costs half a microsecond (encoding, the mapping's
# methods) — what a one-pose call can afford
_ENV_DATA = getattr(os.environ, "_data", None)
_ENV_KEYS = tuple(os.environ.encodekey(k) for k in ("PKMKIT_NATIVE", "PKMKIT_COMPILED")) if (
    isinstance(_ENV_DATA, dict) and hasattr(os.environ, "encodekey")) else None


def native_kernels_now() -> ModuleType | None:
    """:func:`native_kernels` for one-pose calls: the same answer, read in ≈ 0.1 µs when
    neither ``PKMKIT_NATIVE`` nor ``PKMKIT_COMPILED`` is set (the common case), else as
    :func:`native_kernels`."""
    if _ENV_KEYS is None or _ENV_KEYS[0] in _ENV_DATA or _ENV_KEYS[1] in _ENV_DATA:
        return native_kernels()
    return native_kernels() if _native is False else _native
