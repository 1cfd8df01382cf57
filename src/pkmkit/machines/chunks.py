"""Batch calls of the machine protocol in chunks of rows: memory bounded by the data.

A batch call builds several temporaries per row (per-rod coordinates, shortfalls, Jacobians for
the assembly modes, stroke excesses, ...): on 10⁷ poses those reach tens of times the input. The
protocol's ``ik`` and ``fk`` therefore run a batch of more than :data:`CHUNK_ROWS` rows chunk by
chunk and join the results, so that the peak memory stays within about twice the input plus the
output. Every row is computed independently of the others (closed forms, per-row engine solves),
so the chunked result is the unchunked one, bit for bit: the chunks are of nearly equal sizes (all
at least half of :data:`CHUNK_ROWS`, far above the batch size from which the compiled kernels run,
so that every chunk takes the same path as the whole batch would).

Only a NumPy array ``(N, d)`` input is chunked (a single pose or a list is passed on as it is);
row-aligned keyword arguments (``q0``, ``x0``, ``q``, ``tool_length``, a joint chain's ``start``)
with N rows are cut with it, and a call whose row-aligned arguments do not have N rows (or one)
is left whole so that it raises its own error. The caller's ``out=`` array
(:mod:`pkmkit.machines.out_arrays`) is cut into row views like them, each chunk writes its
rows of it, and it is the joined result's q (pose) itself — nothing joined into a new array;
an ``out`` that does not have N rows, or shares memory with the input, leaves the call whole
(refused there, naming the whole shapes). A class may set its own chunk size
(``chunk_rows``: the joint chains' iterative engine, :mod:`pkmkit.machines.joint_chain`), and
may run some calls whole (``unchunked_call(name, x, kwargs) -> bool``: a call whose only
memory is its input and its output, e.g. a full-pose machine's plain ``ik`` on the fused
compiled kernel, :meth:`pkmkit.machines.full_pose.FullPoseMachine.unchunked_call`) — chunking
it would only add serial work per chunk (the joining copy, Python around the kernel) to what
the threads of :func:`pkmkit.numerics.jit.run_chunks` do in parallel.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import itertools
from collections.abc import Callable
from typing import Any

import numpy as np

from pkmkit.machines.lazy_records import lazy_parts
from pkmkit.machines.results import DirectResult, InverseResult
from pkmkit.numerics.jit import use_compiled_solver

#: Rows per chunk of a batch call (the chunks of a larger batch have nearly equal sizes, each
#: between half and all of this).
CHUNK_ROWS = 1 << 16

#: Rows per chunk of the joint chains' batch calls (:func:`iterative_chunk_rows`) on the compiled
#: kernels (≈ 0.8–1.3 kB per row for ik and fk, 7.5 kB for the velocity model) and on the NumPy
#: engine (≈ 16 kB per row: three dense closure Jacobians — the engine's, the evaluation's, the
#: active rows' copy; 512-row chunks cost it 40 % more CPU, 1024 none measurable).
CHAIN_CHUNK_ROWS = 4096
NUMPY_CHAIN_CHUNK_ROWS = 1024

#: keyword arguments with one row per input row (``start``: a joint chain's warm starts;
#: ``out``: the caller's result array, :mod:`pkmkit.machines.out_arrays`, cut into views)
ROW_ARGUMENTS = ("q0", "x0", "q", "tool_length", "start", "out")

#: fields of the result records that describe the call, not a row (taken from the first chunk)
_CALL_FIELDS: dict[type, frozenset[str]] = {
    InverseResult: frozenset({"branches", "method"}),
    DirectResult: frozenset({"mode_label", "method", "passive_names"}),
}


class _Whole(Exception):
    """The chunks' results cannot be joined: run the call on the whole batch."""


def chunk_bounds(rows: int, size: int | None = None) -> list[tuple[int, int]]:
    """Start and stop of the chunks of a batch of ``rows`` rows: nearly equal chunks of at most
    ``size`` rows (default :data:`CHUNK_ROWS`)."""
    size = CHUNK_ROWS if size is None else size
    count = max(1, -(-rows // size))
    edges = [rows * k // count for k in range(count + 1)]
    return list(itertools.pairwise(edges))


def iterative_chunk_rows(machine: Any) -> int:
    """``chunk_rows`` of a machine solved by the iterative closure engine (a joint chain): its
    batch ``ik``, ``fk``, ``jacobian`` run in chunks of :data:`CHAIN_CHUNK_ROWS` rows on the
    compiled kernels, :data:`NUMPY_CHAIN_CHUNK_ROWS` on the NumPy engine — a working set of
    ≈ 3–30 MB whatever the batch, and chunks far above the batch size from which the compiled
    kernels run (every chunk takes the whole batch's path). A row's result does not depend on
    its batch (:mod:`pkmkit.numerics.rowwise`), so the chunks give the whole batch's result."""
    return CHAIN_CHUNK_ROWS if use_compiled_solver(CHAIN_CHUNK_ROWS) else NUMPY_CHAIN_CHUNK_ROWS


def _call_fields(record: Any) -> frozenset[str]:
    names: frozenset[str] = frozenset()
    for cls in type(record).__mro__:
        names |= _CALL_FIELDS.get(cls, frozenset())
    return names


class _Rows:
    """An array of the joined result, allocated once and filled chunk by chunk."""

    def __init__(self, values: np.ndarray):
        self.values = values


class _Lazy:
    """The joined storage of a record whose fields are computed when read
    (:mod:`pkmkit.machines.lazy_records`): the fields each chunk's record was given, joined
    now; the chunks' records kept, so that any other field is read from them and joined when
    the joined record's field is first read (joining them now would compute every field)."""

    def __init__(self, given: dict[str, Any], rows: int):
        self.given, self.rows = given, rows
        self.parts: list[tuple[Any, int, int]] = []


class _JoinedEvaluation:
    """The evaluation of a joined lazy record: a field is each chunk's record's field, joined
    (or, should the chunks' values not join, the field of the whole call, ``rerun()``)."""

    def __init__(self, parts: list[tuple[Any, int, int]], rows: int,
                 rerun: Callable[[], Any]):
        self._parts, self._rows, self._rerun = parts, rows, rerun

    def field(self, name: str) -> Any:
        values = [(getattr(part, name), start, stop) for part, start, stop in self._parts]
        first, _, size = values[0]
        try:
            store = _allocate(first, self._rows, size)
            for value, start, stop in values:
                _put(store, value, start, stop)
        except _Whole:  # e.g. a chunk without any solved row has no direct record
            return getattr(self._rerun(), name)
        return _build(store, first)


def _allocate(part: Any, rows: int, size: int, shared: dict | None = None) -> Any:
    """Storage for the joined result of ``rows`` rows, shaped after the first chunk's result
    ``part`` (of ``size`` rows): per-row arrays allocated once (one storage for an array two
    fields share, e.g. an inverse result's ``pose`` and its direct record's), per-row tuples
    as lists, records as dicts of their fields (the fields that describe the call left out),
    anything else kept as the first chunk has it."""
    shared = {} if shared is None else shared
    if isinstance(part, np.ndarray) and _memory(part) in shared:
        return shared[_memory(part)]
    if isinstance(part, np.ndarray) and part.ndim and part.shape[0] == size:
        # in the chunk's memory order: a (N, n) result the kernels write column by column
        # (a transposed view) is copied column by column, not transposed on every chunk
        order = "F" if part.ndim == 2 and not part.flags.c_contiguous else "C"
        shared[_memory(part)] = _Rows(np.empty((rows, *part.shape[1:]), dtype=part.dtype,
                                               order=order))
        return shared[_memory(part)]
    if isinstance(part, tuple) and len(part) == size:
        return []
    lazy = lazy_parts(part)
    if lazy is not None:
        return _Lazy({name: _allocate(value, rows, size, shared)
                      for name, value in lazy[1].items()}, rows)
    if dataclasses.is_dataclass(part):
        fixed = _call_fields(part)
        return {f.name: _allocate(getattr(part, f.name), rows, size, shared)
                for f in dataclasses.fields(part) if f.init and f.name not in fixed}
    return part


def _memory(arr: np.ndarray) -> tuple:
    """What identifies an array's elements: two fields handing out views of one array (records
    hand out read-only views, :func:`pkmkit.machines.lazy_records.read_only`) share a storage."""
    return arr.__array_interface__["data"][0], arr.shape, arr.strides, arr.dtype.str


def _put(store: Any, part: Any, start: int, stop: int, written: dict | None = None) -> None:
    """Copy the result ``part`` of the chunk ``start:stop`` into the storage (raise
    :class:`_Whole` if it does not have the first chunk's layout, or if two fields sharing a
    storage differ in this chunk; ``written``: the storages filled from this chunk)."""
    written = {} if written is None else written
    if isinstance(store, _Rows):
        if not (isinstance(part, np.ndarray) and part.dtype == store.values.dtype
                and part.shape == (stop - start, *store.values.shape[1:])):
            raise _Whole
        if part.ctypes.data == store.values[start:stop].ctypes.data and part.flags.c_contiguous:
            return  # the chunk wrote into the caller's out= (a view of it): nothing to copy
        if id(store) in written:  # a field sharing another's array: the same rows
            other = written[id(store)]
            if other is not part and other.tobytes() != part.tobytes():
                raise _Whole
            return
        written[id(store)] = part
        store.values[start:stop] = part
    elif isinstance(store, list):
        if not (isinstance(part, tuple) and len(part) == stop - start):
            raise _Whole
        store.extend(part)
    elif isinstance(store, _Lazy):
        lazy = lazy_parts(part)
        if lazy is None or lazy[1].keys() != store.given.keys():
            raise _Whole
        for name, value in store.given.items():
            _put(value, lazy[1][name], start, stop, written)
        store.parts.append((part, start, stop))
    elif isinstance(store, dict):
        if part is None:
            raise _Whole
        for name, value in store.items():
            _put(value, getattr(part, name), start, stop, written)
    elif (store is None) != (part is None):  # e.g. a record in one chunk, None in another
        raise _Whole


def _build(store: Any, first: Any, rerun: Callable[[], Any] | None = None) -> Any:
    """The joined result from its storage (``first``: the first chunk's result; ``rerun()``:
    the whole call, for a lazy record's fields that do not join)."""
    if isinstance(store, _Rows):
        return store.values
    if isinstance(store, list):
        return tuple(store)
    if isinstance(store, _Lazy):
        given = lazy_parts(first)[1]
        fields = {name: _build(value, given[name]) for name, value in store.given.items()}
        return type(first)(_JoinedEvaluation(store.parts, store.rows, rerun), **fields)
    if isinstance(store, dict):
        return dataclasses.replace(first, **{name: _build(value, getattr(first, name))
                                             for name, value in store.items()})
    return store


def _row_arguments(kwargs: dict[str, Any], rows: int) -> list[str] | None:
    """Names of the row-aligned keyword arguments to cut; None if one has neither ``rows`` rows
    nor one (the call is then left whole)."""
    cut = []
    for name in ROW_ARGUMENTS:
        value = kwargs.get(name)
        if value is None:
            continue
        if name == "out" and not (isinstance(value, np.ndarray) and value.ndim == 2
                                  and value.shape[0] == rows):
            return None  # the whole call refuses it, naming the whole shapes
        arr = np.asarray(value)
        if arr.ndim >= 1 and arr.shape[0] == rows:
            kwargs[name] = arr
            cut.append(name)
        elif arr.ndim == 2 or (arr.ndim == 1 and name == "tool_length"):
            return None
    return cut


def chunked(method: Callable[..., Any]) -> Callable[..., Any]:
    """Decorate a batch method ``method(self, x, **kwargs)`` of the protocol (``ik``, ``fk``,
    a joint chain's ``jacobian``, also called as ``jacobian(q=...)``) so that a batch of more
    than ``self.chunk_rows`` rows (default :data:`CHUNK_ROWS`) runs chunk by chunk."""

    leading = list(inspect.signature(method).parameters)[1]  # x or q

    @functools.wraps(method)
    def call(self, *args: Any, **kwargs: Any) -> Any:
        x = args[0] if len(args) == 1 else kwargs.get(leading) if not args else None
        by_q = x is None and not args and leading != "q"  # jacobian(q=...): cut with q
        if by_q:
            x = kwargs.get("q")
        if not (isinstance(x, np.ndarray) and x.ndim == 2):  # one pose: no chunk size looked
            return method(self, *args, **kwargs)  # up (a joint chain's costs a microsecond)
        size = getattr(self, "chunk_rows", None) or CHUNK_ROWS
        if x.shape[0] <= size:
            return method(self, *args, **kwargs)
        whole = getattr(self, "unchunked_call", None)
        if whole is not None and whole(method.__name__, x, kwargs):
            return method(self, *args, **kwargs)
        rows = x.shape[0]
        if not by_q:
            kwargs.pop(leading, None)
        head = () if by_q else (x,)
        cut = _row_arguments(kwargs, rows)
        if cut is None or ("out" in cut and np.shares_memory(kwargs["out"], x)):
            return method(self, *head, **kwargs)  # the whole call refuses what it must
        first = store = None
        out = kwargs.get("out") if "out" in cut else None
        try:
            for start, stop in chunk_bounds(rows, size):
                views = {name: kwargs[name][start:stop] for name in cut}
                part = method(self, *(h[start:stop] for h in head), **{**kwargs, **views})
                if start == 0:  # the caller's out= is the joined q (pose) itself
                    shared = {} if out is None else {_memory(views["out"]): _Rows(out)}
                    first, store = part, _allocate(part, rows, stop, shared)
                _put(store, part, start, stop)
                del part
        except _Whole:  # e.g. a chunk without any solved row has no direct record
            del first, store
            return method(self, *head, **kwargs)
        return _build(store, first, lambda: method(self, *head, **kwargs))

    return call
