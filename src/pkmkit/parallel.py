"""Run chunked, batched NumPy work serially or on a Dask cluster — same chunks, same results.

Studies that outgrow one machine (workspace and index maps at fine resolution, design sweeps and
optimisation populations, and later Monte Carlo tolerance and calibration studies) are
embarrassingly parallel: split the work into chunks, run each chunk as one batched NumPy call,
put the results back in order. This module does exactly that, with one argument choosing where:

- ``scheduler=None`` — in this process, chunk after chunk (the serial run);
- ``scheduler="tcp://host:8786"`` (any Dask scheduler address) — on that cluster;
- ``scheduler="local"`` or ``"local:N"`` — a :class:`distributed.LocalCluster` of N worker
  processes (default: one per core) with one thread each, started for the call;
- ``scheduler=client`` — an existing :class:`distributed.Client`.

The chunks and the code run on each are the same in every case, so the results are identical
to the serial run (bit for bit, provided the workers run the same pkmkit, NumPy and Numba).
Each task is one chunk: ``func(start, stop)`` over an index range, or a slice of an array, so
that large inputs are generated or sliced where they are used. Monte Carlo studies get
reproducible per-chunk random streams from :func:`chunk_seeds`, independent of the executor.

Dask is an optional dependency: ``pip install 'pkmkit[dask]'``. Dask's worker processes bound
BLAS/OpenMP threads to one (its nanny sets ``OMP_NUM_THREADS=1`` and the like), and pkmkit's hot
paths use no BLAS, so tasks do not oversubscribe the cores. The nanny also sets
``MALLOC_TRIM_THRESHOLD_=65536``, which makes glibc return every freed block to the system: the
NumPy temporaries of a chunk (hundreds of kB each) are then page-faulted in again at each
allocation and a task runs about twice as slowly as the same call in the client. Local clusters
started here get :data:`WORKER_ENVIRON` instead; for workers started elsewhere, put the same
values under ``distributed.nanny.pre-spawn-environ`` in their Dask configuration (see
docs/scaling.md).

    >>> from pkmkit.parallel import map_chunks
    >>> map_chunks(lambda a, b: list(range(a, b)), 5, chunk=2)
    [[0, 1], [2, 3], [4]]
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import os
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from pkmkit.exceptions import InputError
from pkmkit.progress import tracked

#: Default rows per task for pose-level work: large enough that the per-task overhead of Dask
#: (a few ms) is small against the batched call, small enough to spread over the workers.
DEFAULT_CHUNK = 1 << 18

_INSTALL_HINT = "install the optional Dask support: pip install 'pkmkit[dask]'"

#: Environment of the worker processes of local clusters: Dask's thread limits, and glibc
#: thresholds that keep freed NumPy temporaries in the process (256 MiB trim, 32 MiB mmap).
WORKER_ENVIRON = {"OMP_NUM_THREADS": 1, "MKL_NUM_THREADS": 1, "OPENBLAS_NUM_THREADS": 1,
                  "MALLOC_TRIM_THRESHOLD_": 1 << 28, "MALLOC_MMAP_THRESHOLD_": 1 << 25}


class SerialExecutor:
    """Runs the tasks in this process, in order."""

    description = "serial (this process)"
    workers = 1

    def map(self, func: Callable[[Any], Any], items: Sequence[Any], *,
            label: str = "") -> list[Any]:
        """``[func(item) for item in items]`` (with a progress bar in a
        :func:`pkmkit.progress.progress_display` scope)."""
        return [func(item) for item in tracked(items, total=len(items), label=label)]


class DaskExecutor:
    """Runs the tasks on a Dask cluster through a :class:`distributed.Client`."""

    def __init__(self, client: Any):
        self.client = client

    @property
    def workers(self) -> int:
        """Worker threads of the cluster (at least 1)."""
        workers = self.client.scheduler_info().get("workers", {})
        return max(1, sum(w.get("nthreads", 0) for w in workers.values()))

    @property
    def description(self) -> str:
        info = self.client.scheduler_info()
        workers = info.get("workers", {})
        threads = sum(w.get("nthreads", 0) for w in workers.values())
        return f"dask {info.get('address', '?')} ({len(workers)} workers, {threads} threads)"

    def map(self, func: Callable[[Any], Any], items: Sequence[Any], *,
            label: str = "") -> list[Any]:
        """Every ``func(item)`` as one task; results in the order of ``items``. An exception
        raised by a task is raised here (the first one, with its type)."""
        if not items:
            return []
        items = list(items)
        if any(isinstance(item, np.ndarray) for item in items):
            # data blocks go to the workers directly, not inside the task graph
            items = self.client.scatter(items)
        futures = self.client.map(func, items, pure=False)
        distributed = _require_distributed()
        for _ in tracked(distributed.as_completed(futures), total=len(futures), label=label):
            pass
        return self.client.gather(futures)


def _require_distributed():
    try:
        import distributed
    except ImportError:
        raise InputError(f"running on a Dask scheduler needs Dask: {_INSTALL_HINT}") from None
    return distributed


def _local_workers(text: str) -> int:
    count = text.partition(":")[2].strip()
    if not count:
        return os.cpu_count() or 1
    if not count.isdigit() or int(count) < 1:
        raise InputError(f"scheduler {text!r}: use 'local' or 'local:N' with N >= 1 workers")
    return int(count)


@contextlib.contextmanager
def executor(scheduler: Any = None, *, timeout: float = 10.0
             ) -> Iterator[SerialExecutor | DaskExecutor]:
    """The executor for ``scheduler`` (see the module documentation), closed on exit when it
    was created here (a client passed in is left open).

    Raises:
        InputError: Dask is not installed, the address cannot be reached within ``timeout``
            seconds, or ``scheduler`` is neither None, a string nor a Dask client.
    """
    if scheduler is None:
        yield SerialExecutor()
        return
    if not isinstance(scheduler, str):
        if hasattr(scheduler, "map") and hasattr(scheduler, "gather"):
            yield DaskExecutor(scheduler)
            return
        raise InputError(f"scheduler must be None, an address or a dask Client, got "
                         f"{type(scheduler).__name__}")
    distributed = _require_distributed()
    text = scheduler.strip()
    with contextlib.ExitStack() as stack:
        if text == "local" or text.startswith("local:"):
            address = stack.enter_context(local_cluster(_local_workers(text)))
        else:
            address = text
        try:
            client = stack.enter_context(distributed.Client(address, timeout=timeout))
        except (OSError, TimeoutError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {text!r} within "
                             f"{timeout:g} s ({exc}); start one with `dask scheduler` and "
                             "`dask worker ADDRESS`, or use --scheduler local:N") from None
        yield DaskExecutor(client)


def local_cluster(workers: int, **options: Any):
    """A :class:`distributed.LocalCluster` of ``workers`` processes with one thread each and
    the environment :data:`WORKER_ENVIRON` (use it as a context manager)."""
    import dask

    distributed = _require_distributed()
    # No dashboard, and the scheduler's HTTP server (health and metrics routes, which
    # distributed starts even without a dashboard) on a free port rather than 8787: with
    # 8787 busy, distributed would print a warning into every command's output.
    scheduler_options = {"dashboard_address": ":0", **options.pop("scheduler_kwargs", {})}
    # workers log at CRITICAL only: a worker whose heartbeat races the cluster's shutdown logs
    # a traceback (an ERROR) into the command's output; task errors still raise in the caller
    options.setdefault("silence_logs", logging.CRITICAL)
    with dask.config.set({"distributed.nanny.pre-spawn-environ": WORKER_ENVIRON}):
        return distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                        processes=True, dashboard_address=None,
                                        scheduler_kwargs=scheduler_options, **options)


def chunk_ranges(size: int, chunk: int) -> list[tuple[int, int]]:
    """``[(start, stop), ...]`` covering ``range(size)`` in pieces of ``chunk`` (the last one
    shorter)."""
    if chunk < 1:
        raise InputError(f"chunk must be >= 1, got {chunk}")
    return [(start, min(start + chunk, size)) for start in range(0, size, chunk)]


class _RangeTask:
    """``func(start, stop, *args)`` as a picklable one-argument callable."""

    def __init__(self, func: Callable[..., Any], args: tuple):
        self.func, self.args = func, args

    def __call__(self, bounds: tuple[int, int]) -> Any:
        return self.func(bounds[0], bounds[1], *self.args)


def map_chunks(func: Callable[..., Any], size: int, *, chunk: int = DEFAULT_CHUNK,
               scheduler: Any = None, args: tuple = (), label: str = "") -> list[Any]:
    """Results of ``func(start, stop, *args)`` for consecutive index ranges of ``range(size)``,
    one task per range, in order.

    Args:
        func: the work on rows ``start:stop`` (e.g. generate those grid points and evaluate
            them in one batched call). Must be picklable for Dask (module-level functions and
            objects are; cloudpickle also takes lambdas and closures).
        size: number of rows.
        chunk: rows per task.
        scheduler: where to run (see the module documentation).
        args: extra arguments passed to every task (sent once per task).
        label: what the progress bar says (see :mod:`pkmkit.progress`).
    """
    with executor(scheduler) as ex:
        return ex.map(_RangeTask(func, args), chunk_ranges(size, chunk), label=label)


class _RowsTask:
    def __init__(self, func: Callable[..., Any], args: tuple):
        self.func, self.args = func, args

    def __call__(self, rows: np.ndarray) -> Any:
        return self.func(rows, *self.args)


def map_rows(func: Callable[..., Any], rows: Any, *, chunk: int = DEFAULT_CHUNK,
             scheduler: Any = None, args: tuple = (), label: str = "") -> Any:
    """``func(rows[start:stop], *args)`` for consecutive row blocks of ``rows``, joined back
    along the first axis with :func:`concatenate` — for work that is row by row, the same
    answer as ``func(rows, *args)``."""
    rows = np.asarray(rows)
    blocks = [rows[a:b] for a, b in chunk_ranges(len(rows), chunk)]
    with executor(scheduler) as ex:
        return concatenate(ex.map(_RowsTask(func, args), blocks, label=label))


def concatenate(parts: Sequence[Any]) -> Any:
    """Join per-chunk results along their first axis: arrays, and tuples, lists, dicts or
    dataclasses of them (recursively); scalars and other values must agree across chunks."""
    first = parts[0]
    if len(parts) == 1:
        return first
    if isinstance(first, np.ndarray):
        return np.concatenate(parts)
    if dataclasses.is_dataclass(first) and not isinstance(first, type):
        return type(first)(**{f.name: concatenate([getattr(p, f.name) for p in parts])
                              for f in dataclasses.fields(first) if f.init})
    if isinstance(first, dict):
        return {k: concatenate([p[k] for p in parts]) for k in first}
    if isinstance(first, tuple | list):
        joined = [concatenate([p[k] for p in parts]) for k in range(len(first))]
        return type(first)(joined)
    if all(_same(p, first) for p in parts[1:]):
        return first
    raise InputError(f"cannot join chunk results of type {type(first).__name__}")


def _same(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except (TypeError, ValueError):
        return False


def chunk_seeds(seed: int, count: int) -> list[np.random.SeedSequence]:
    """Independent random streams for ``count`` chunks of a Monte Carlo study: chunk k draws
    from ``np.random.default_rng(chunk_seeds(seed, n)[k])``, so the samples depend on the seed
    and the chunking only, never on the executor or the order tasks run in."""
    return np.random.SeedSequence(seed).spawn(count)
